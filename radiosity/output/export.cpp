// radiosity/output/export.cpp - surfaces tessellated with their radiosity, lightmap atlases, and
// the GLB and PLY encoders (with a small JSON writer of their own: no third-party library).
#include "radiosity/output/export.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/output/render.h"

namespace mbr {

long ExportMesh::vertex_count() const {
    long n = 0;
    for (const ExportSurface& s : surfaces) n += long(s.vertices.size());
    return n;
}

long ExportMesh::triangle_count() const {
    long n = 0;
    for (const ExportSurface& s : surfaces) n += long(s.triangles.size());
    return n;
}

namespace {

// export_resolution's rule for a field of `level`.
int grid_intervals(const Surface& surface, int level, int tessellation, int max_resolution) {
    // 2^level intervals, twice; the level is at most the quadtree's depth, but guard the shift.
    long n = level >= 20 ? long(max_resolution) : 2L << level;
    n = std::max(n, 2L);
    if (surface.kind() != Surface::Kind::PlanarQuad) n = std::max(n, long(tessellation));
    return int(std::max(1L, std::min(n, long(max_resolution))));
}

}  // namespace

int export_resolution(const Surface& surface, const SplineField* field, int tessellation,
                      int max_resolution) {
    const int level = field && !field->empty() ? field->level() : 0;
    return grid_intervals(surface, level, tessellation, max_resolution);
}

namespace {

Vec3 rounded_to_float(Vec3 p) {
    return {double(float(p.x)), double(float(p.y)), double(float(p.z))};
}

// One surface's grid, B at its vertices and its triangles.
ExportSurface tessellate_surface(const Scene& scene, const RadiosityView& view, int i,
                                 int max_resolution) {
    const SceneSurface& ss = scene.surfaces[size_t(i)];
    ExportSurface out;
    out.name = ss.name;
    out.material = ss.material >= 0 && size_t(ss.material) < scene.materials.size()
                       ? scene.materials[size_t(ss.material)].name
                       : std::string();
    out.surface = i;
    const bool has_field = i < view.size() && !view.empty(i);
    const SplineField* field = has_field ? view.surface(i).field : nullptr;
    const int n = export_resolution(ss.surface, field, scene.settings.tessellation, max_resolution);
    out.resolution = n;
    const int side = n + 1;
    out.vertices.resize(size_t(side) * side);
    for (int b = 0; b <= n; ++b)
        for (int a = 0; a <= n; ++a) {
            ExportVertex& v = out.vertices[size_t(b) * side + a];
            // Exact end points: a / n is 1 exactly at a = n.
            v.uv = {double(a) / n, double(b) / n};
            v.position = ss.surface.point(v.uv.x, v.uv.y);
            v.normal = normalize(ss.surface.normal(v.uv.x, v.uv.y));
            v.radiosity = has_field ? view.at(i, v.uv.x, v.uv.y) : Rgb{};
        }
    out.triangles.reserve(size_t(n) * n * 2);
    auto add = [&](std::uint32_t p, std::uint32_t q, std::uint32_t r) {
        // The area and the winding of the triangle as a viewer sees it: from float positions.
        const Vec3 x0 = rounded_to_float(out.vertices[p].position);
        const Vec3 x1 = rounded_to_float(out.vertices[q].position);
        const Vec3 x2 = rounded_to_float(out.vertices[r].position);
        const Vec3 c = cross(x1 - x0, x2 - x0);
        const double longest =
            std::max({length_squared(x1 - x0), length_squared(x2 - x1), length_squared(x0 - x2)});
        if (!(length(c) > 1e-10 * longest)) return;  // zero area (a pole), or NaN
        const Vec3 facing =
            out.vertices[p].normal + out.vertices[q].normal + out.vertices[r].normal;
        if (dot(c, facing) >= 0)
            out.triangles.push_back({p, q, r});
        else
            out.triangles.push_back({p, r, q});
    };
    for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
            const auto k00 = std::uint32_t(b * side + a), k10 = k00 + 1;
            const auto k01 = std::uint32_t(k00 + side), k11 = k01 + 1;
            add(k00, k10, k11);
            add(k00, k11, k01);
        }
    return out;
}

}  // namespace

ExportMesh tessellate_for_export(const Scene& scene, const RadiosityView& view,
                                 int max_resolution) {
    MBR_CHECK(max_resolution >= 1);
    ExportMesh mesh;
    mesh.surfaces.resize(scene.surfaces.size());
    parallel_for(int(scene.surfaces.size()), [&](int i) {
        mesh.surfaces[size_t(i)] = tessellate_surface(scene, view, i, max_resolution);
    });
    return mesh;
}

Rgb display_colour(Rgb radiosity, double exposure) {
    Rgb out;
    for (int c = 0; c < 3; ++c) out[c] = clip_to_display(exposure * radiosity[c] / Pi);
    return out;
}

std::array<std::uint8_t, 3> display_colour_srgb8(Rgb radiosity, double exposure) {
    const Rgb d = display_colour(radiosity, exposure);
    std::array<std::uint8_t, 3> out{};
    for (int c = 0; c < 3; ++c)
        out[size_t(c)] = static_cast<std::uint8_t>(std::lround(255 * linear_to_srgb(d[c])));
    return out;
}

// ---- Lightmaps --------------------------------------------------------------------------

bool valid_lightmap_size(int size) {
    return size >= min_lightmap_size && size <= max_lightmap_size && (size & (size - 1)) == 0;
}

Vec2 LightmapLayout::texcoord(int k, Vec2 uv) const {
    const double x = tile_x(k) + gutter + uv.x * inner;
    const double y = tile_y(k) + gutter + (1 - uv.y) * inner;
    return {x / size, y / size};
}

namespace {

// The layout without the checks: tile may come out too small.
LightmapLayout layout_of(int surfaces, int size) {
    LightmapLayout l;
    l.size = size;
    l.surfaces = surfaces;
    l.columns = 1;
    while (long(l.columns) * l.columns < surfaces) ++l.columns;
    l.tile = size / l.columns;
    l.gutter = l.tile >= 16 ? 2 : 1;
    l.inner = l.tile - 2 * l.gutter;
    return l;
}

}  // namespace

LightmapLayout lightmap_layout(int surfaces, int size) {
    if (!valid_lightmap_size(size))
        throw std::invalid_argument(
            "a lightmap's size must be a power of two in " + std::to_string(min_lightmap_size) +
            ".." + std::to_string(max_lightmap_size) + ", not " + std::to_string(size));
    if (surfaces < 1) throw std::invalid_argument("a lightmap needs at least one surface");
    const LightmapLayout l = layout_of(surfaces, size);
    if (l.inner < 2)
        throw std::invalid_argument("a " + std::to_string(size) + " x " + std::to_string(size) +
                                    " lightmap is too small for " + std::to_string(surfaces) +
                                    " surfaces (each tile needs 2 x 2 texels inside a gutter)");
    return l;
}

int smallest_lightmap_size(int surfaces) {
    for (int size = min_lightmap_size; size <= max_lightmap_size; size *= 2)
        if (layout_of(std::max(surfaces, 1), size).inner >= 2) return size;
    return 0;
}

Image bake_lightmap(const RadiosityView& view, const LightmapLayout& layout) {
    MBR_CHECK(layout.surfaces == view.size() && layout.inner >= 2);
    Image image(layout.size, layout.size);
    const int rows = (layout.surfaces + layout.columns - 1) / layout.columns;
    const int inner = layout.inner;
    // One row of tiles per item: the tiles' texels do not overlap.
    parallel_for(rows * layout.tile, [&](int y_in_rows) {
        const int row = y_in_rows / layout.tile, ty = y_in_rows % layout.tile;
        const int r = std::clamp(ty - layout.gutter, 0, inner - 1);
        const double v = 1 - (r + 0.5) / inner;
        for (int col = 0; col < layout.columns; ++col) {
            const int k = row * layout.columns + col;
            if (k >= layout.surfaces) break;
            const int x0 = layout.tile_x(k), y = layout.tile_y(k) + ty;
            for (int tx = 0; tx < layout.tile; ++tx) {
                const int a = std::clamp(tx - layout.gutter, 0, inner - 1);
                // The gutter repeats the inner edge: the same (u, v), the same value.
                const double u = (a + 0.5) / inner;
                image.at(x0 + tx, y) = (1 / Pi) * view.at(k, u, v);
            }
        }
    });
    return image;
}

Lightmap make_lightmap(const RadiosityView& view, int size, double exposure) {
    Lightmap m;
    m.layout = lightmap_layout(view.size(), size);
    Image texels = bake_lightmap(view, m.layout);
    // tone_map's rule, in place: a 4096 x 4096 atlas is 400 MB of doubles, and a copy another.
    for (Rgb& p : texels.pixels)
        for (int c = 0; c < 3; ++c) p[c] = linear_to_srgb(clip_to_display(exposure * p[c]));
    m.png = encode_png(texels);
    return m;
}

double export_bytes(const Scene& scene, int lightmap_size) {
    // The field's level is at most the quadtree's depth, or a textured emission's level.
    const int level = std::max(scene.settings.max_depth, 5);
    double vertices = 0;
    for (const SceneSurface& s : scene.surfaces) {
        const int n =
            grid_intervals(s.surface, level, scene.settings.tessellation, max_export_resolution);
        vertices += double(n + 1) * double(n + 1);
    }
    // Per vertex: ExportVertex and two triangles' indices, the file's floats and indices (as
    // built and as copied into the file), with room for the strings' growth.
    const double per_vertex = sizeof(ExportVertex) + 2 * 12 + 2 * (4 * 12 + 24) + 64;
    const double texels = double(lightmap_size) * double(lightmap_size);
    return vertices * per_vertex + texels * (sizeof(Rgb) + 3 + 3);
}

// ---- JSON ---------------------------------------------------------------------------------

namespace {

// A number as JSON: the shortest of %.15g, %.16g, %.17g that reads back as the same double
// (so a float's value, widened to double, is written exactly). Non-finite values have no JSON
// spelling; callers pass finite ones only.
std::string json_number(double x) {
    MBR_CHECK(std::isfinite(x));
    if (x == 0) return "0";  // and -0
    char text[40];
    for (int digits = 15; digits <= 17; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, x);
        if (std::strtod(text, nullptr) == x) break;
    }
    return text;
}

// Length of the valid UTF-8 sequence at s[i], or 0 when the bytes there are not one.
size_t utf8_sequence(std::string_view s, size_t i) {
    const auto byte = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char c = byte(i);
    if (c < 0x80) return 1;
    size_t n = 0;
    unsigned cp = 0, least = 0;
    if ((c & 0xE0) == 0xC0)
        n = 2, cp = c & 0x1F, least = 0x80;
    else if ((c & 0xF0) == 0xE0)
        n = 3, cp = c & 0x0F, least = 0x800;
    else if ((c & 0xF8) == 0xF0)
        n = 4, cp = c & 0x07, least = 0x10000;
    else
        return 0;
    if (i + n > s.size()) return 0;
    for (size_t k = 1; k < n; ++k) {
        if ((byte(i + k) & 0xC0) != 0x80) return 0;
        cp = cp << 6 | (byte(i + k) & 0x3F);
    }
    if (cp < least || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
    return n;
}

// A string as JSON: quotes, escapes for '"', '\\' and control bytes, and U+FFFD for a byte that
// is not part of valid UTF-8 (glTF's JSON must be UTF-8; a name from an OBJ file may not be).
std::string json_string(std::string_view s) {
    std::string out = "\"";
    for (size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += char(c);
            ++i;
        } else if (c < 0x20) {
            char esc[8];
            std::snprintf(esc, sizeof esc, "\\u%04x", unsigned(c));
            out += esc;
            ++i;
        } else if (const size_t n = utf8_sequence(s, i)) {
            out.append(s.substr(i, n));
            i += n;
        } else {
            out += "\xEF\xBF\xBD";
            ++i;
        }
    }
    return out + '"';
}

// Compact JSON written in order: commas between members and elements come by themselves.
class JsonWriter {
public:
    JsonWriter& begin_object() { return open('{'); }
    JsonWriter& end_object() { return close('}'); }
    JsonWriter& begin_array() { return open('['); }
    JsonWriter& end_array() { return close(']'); }
    /// The next member's name; its value follows.
    JsonWriter& key(std::string_view name) {
        separate();
        out_ += json_string(name);
        out_ += ':';
        after_key_ = true;
        return *this;
    }
    JsonWriter& value(std::string_view s) { return raw(json_string(s)); }
    JsonWriter& value(const char* s) { return raw(json_string(s)); }
    JsonWriter& value(double x) { return raw(json_number(x)); }
    JsonWriter& value(long x) { return raw(std::to_string(x)); }
    JsonWriter& value(int x) { return raw(std::to_string(x)); }
    JsonWriter& value(size_t x) { return raw(std::to_string(x)); }
    JsonWriter& value(bool b) { return raw(b ? "true" : "false"); }
    /// A complete JSON value written by another writer, as it is.
    JsonWriter& value(const JsonWriter& json) { return raw(json.text()); }
    /// key(name) then value(v).
    template <class T>
    JsonWriter& member(std::string_view name, const T& v) {
        key(name);
        return value(v);
    }
    const std::string& text() const {
        MBR_CHECK(open_.empty());
        return out_;
    }

private:
    JsonWriter& open(char c) {
        separate();
        out_ += c;
        open_.push_back(true);
        return *this;
    }
    JsonWriter& close(char c) {
        MBR_CHECK(!open_.empty() && !after_key_);
        open_.pop_back();
        out_ += c;
        return *this;
    }
    JsonWriter& raw(const std::string& text) {
        separate();
        out_ += text;
        return *this;
    }
    // A comma before every member or element but the first of its object or array.
    void separate() {
        if (after_key_) {
            after_key_ = false;
            return;
        }
        if (open_.empty()) return;
        if (!open_.back()) out_ += ',';
        open_.back() = false;
    }
    std::string out_;
    std::vector<bool> open_;  // per open object or array: nothing written in it yet
    bool after_key_ = false;
};

// ---- GLB ----------------------------------------------------------------------------------

void put_u32(std::string& out, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out += char((v >> (8 * k)) & 0xFF);
}

void put_u16(std::string& out, std::uint16_t v) {
    out += char(v & 0xFF);
    out += char(v >> 8);
}

void put_f32(std::string& out, float f) {
    std::uint32_t bits = 0;
    static_assert(sizeof bits == sizeof f, "float is 32 bits");
    std::memcpy(&bits, &f, sizeof f);
    put_u32(out, bits);
}

void pad_to_4(std::string& out, char with) {
    while (out.size() % 4) out += with;
}

constexpr int gl_float = 5126, gl_unsigned_short = 5123, gl_unsigned_int = 5125;
constexpr int gl_array_buffer = 34962, gl_element_array_buffer = 34963;
constexpr int gl_linear = 9729, gl_clamp_to_edge = 33071;

// The BIN chunk being built, with its buffer views and accessors as JSON.
struct GlbBuilder {
    std::string bin;
    JsonWriter views, accessors;
    int n_views = 0, n_accessors = 0;

    GlbBuilder() {
        views.begin_array();
        accessors.begin_array();
    }
    // A buffer view of `bytes`, 4-byte aligned; target 0 for none (an image).
    int add_view(const std::string& bytes, int target) {
        pad_to_4(bin, '\0');
        views.begin_object()
            .member("buffer", 0)
            .member("byteOffset", bin.size())
            .member("byteLength", bytes.size());
        if (target) views.member("target", target);
        views.end_object();
        bin += bytes;
        return n_views++;
    }
    // An accessor of `count` float vectors of `width` components, with min and max when asked
    // (computed from the floats as stored, so that they are exactly the data's).
    int add_floats(const std::vector<float>& data, int width, bool bounds) {
        MBR_CHECK(width >= 2 && width <= 4 && data.size() % size_t(width) == 0 && !data.empty());
        std::string bytes;
        bytes.reserve(data.size() * 4);
        for (float f : data) put_f32(bytes, f);
        const int view = add_view(bytes, gl_array_buffer);
        const char* type = width == 2 ? "VEC2" : width == 3 ? "VEC3" : "VEC4";
        accessors.begin_object()
            .member("bufferView", view)
            .member("componentType", gl_float)
            .member("count", data.size() / size_t(width))
            .member("type", type);
        if (bounds) {
            std::vector<float> lo(data.begin(), data.begin() + width), hi = lo;
            for (size_t i = 0; i < data.size(); ++i) {
                lo[i % size_t(width)] = std::min(lo[i % size_t(width)], data[i]);
                hi[i % size_t(width)] = std::max(hi[i % size_t(width)], data[i]);
            }
            accessors.key("min").begin_array();
            for (float f : lo) accessors.value(double(f));
            accessors.end_array().key("max").begin_array();
            for (float f : hi) accessors.value(double(f));
            accessors.end_array();
        }
        accessors.end_object();
        return n_accessors++;
    }
    // The indices accessor: UNSIGNED_SHORT when every index fits, else UNSIGNED_INT.
    int add_indices(const std::vector<std::array<std::uint32_t, 3>>& triangles, size_t n_vertices) {
        MBR_CHECK(!triangles.empty());
        const bool small = n_vertices <= 65535;
        std::string bytes;
        for (const auto& t : triangles)
            for (std::uint32_t k : t) {
                MBR_CHECK(k < n_vertices);
                if (small)
                    put_u16(bytes, std::uint16_t(k));
                else
                    put_u32(bytes, k);
            }
        const int view = add_view(bytes, gl_element_array_buffer);
        accessors.begin_object()
            .member("bufferView", view)
            .member("componentType", small ? gl_unsigned_short : gl_unsigned_int)
            .member("count", triangles.size() * 3)
            .member("type", "SCALAR")
            .end_object();
        return n_accessors++;
    }
};

float finite_float(double x) {
    const float f = float(x);
    return std::isfinite(f) ? f : 0.0f;
}

}  // namespace

std::string encode_glb(const ExportMesh& mesh, const GlbOptions& options) {
    MBR_CHECK(options.exposure > 0 && std::isfinite(options.exposure));
    const Lightmap* lightmap = options.lightmap;
    GlbBuilder glb;
    JsonWriter meshes, nodes;
    meshes.begin_array();
    nodes.begin_array();
    int n_meshes = 0;
    for (const ExportSurface& s : mesh.surfaces) {
        if (s.triangles.empty()) continue;  // glTF accessors need at least one element
        const size_t nv = s.vertices.size();
        std::vector<float> position, normal, colour, radiosity, texcoord;
        position.reserve(3 * nv);
        normal.reserve(3 * nv);
        radiosity.reserve(3 * nv);
        for (const ExportVertex& v : s.vertices) {
            for (int c = 0; c < 3; ++c) {
                position.push_back(finite_float(v.position[c]));
                radiosity.push_back(finite_float(v.radiosity[c]));
            }
            // Unit length in float: normalised again after rounding each component.
            const Vec3 n = rounded_to_float(v.normal);
            const Vec3 unit = length(n) > 0 ? n / length(n) : Vec3{0, 0, 1};
            for (int c = 0; c < 3; ++c) normal.push_back(float(unit[c]));
            if (lightmap) {
                const Vec2 t = lightmap->layout.texcoord(s.surface, v.uv);
                texcoord.push_back(float(t.x));
                texcoord.push_back(float(t.y));
            } else {
                const Rgb d = display_colour(v.radiosity, options.exposure);
                for (int c = 0; c < 3; ++c) colour.push_back(float(d[c]));
            }
        }
        const int a_position = glb.add_floats(position, 3, true);
        const int a_normal = glb.add_floats(normal, 3, false);
        const int a_radiosity = glb.add_floats(radiosity, 3, false);
        const int a_extra =
            lightmap ? glb.add_floats(texcoord, 2, false) : glb.add_floats(colour, 3, false);
        const int a_indices = glb.add_indices(s.triangles, nv);
        meshes.begin_object().member("name", s.name).key("primitives").begin_array();
        meshes.begin_object().key("attributes").begin_object();
        meshes.member("POSITION", a_position).member("NORMAL", a_normal);
        meshes.member(lightmap ? "TEXCOORD_0" : "COLOR_0", a_extra);
        meshes.member("_RADIOSITY", a_radiosity).end_object();
        meshes.member("indices", a_indices).member("material", 0).member("mode", 4);
        meshes.end_object().end_array();
        meshes.key("extras").begin_object().member("mbr_resolution", s.resolution);
        meshes.end_object().end_object();
        nodes.begin_object().member("name", s.name).member("mesh", n_meshes);
        nodes.key("extras").begin_object();
        nodes.member("mbr_surface", s.surface).member("mbr_material", s.material);
        if (lightmap) {
            const LightmapLayout& l = lightmap->layout;
            nodes.key("mbr_lightmap_tile").begin_array();
            nodes.value(l.tile_x(s.surface)).value(l.tile_y(s.surface));
            nodes.value(l.tile).value(l.tile).end_array();
        }
        nodes.end_object().end_object();
        ++n_meshes;
    }
    meshes.end_array();
    nodes.end_array();
    int image_view = -1;
    if (lightmap && n_meshes > 0) image_view = glb.add_view(lightmap->png, 0);
    glb.views.end_array();
    glb.accessors.end_array();
    pad_to_4(glb.bin, '\0');

    JsonWriter material;
    material.begin_array().begin_object().member("name", "mbr radiosity (unlit)");
    material.key("pbrMetallicRoughness").begin_object();
    material.key("baseColorFactor").begin_array();
    for (int c = 0; c < 4; ++c) material.value(1);
    material.end_array();
    if (lightmap) material.key("baseColorTexture").begin_object().member("index", 0).end_object();
    material.member("metallicFactor", 0).member("roughnessFactor", 1).end_object();
    material.key("extensions").begin_object().key("KHR_materials_unlit").begin_object();
    material.end_object().end_object().end_object().end_array();

    JsonWriter json;
    json.begin_object();
    json.key("asset").begin_object().member("version", "2.0").member("generator", "mbr export");
    json.key("extras").begin_object();
    json.member("mbr_colour_rule",
                lightmap ? "baseColorTexture = sRGB(min(1, exposure * B / pi)); _RADIOSITY = B"
                         : "COLOR_0 = min(1, exposure * B / pi), linear; _RADIOSITY = B");
    json.member("mbr_exposure", options.exposure);
    json.member("mbr_radiosity_scale", Pi / options.exposure);
    json.end_object().end_object();
    json.member("scene", 0);
    json.key("scenes").begin_array().begin_object();
    if (!options.scene_name.empty()) json.member("name", options.scene_name);
    if (n_meshes > 0) {  // a scene's node list, when given, must not be empty
        json.key("nodes").begin_array();
        for (int k = 0; k < n_meshes; ++k) json.value(k);
        json.end_array();
    }
    json.end_object().end_array();
    if (n_meshes > 0) {
        json.key("extensionsUsed").begin_array().value("KHR_materials_unlit").end_array();
        json.member("nodes", nodes).member("meshes", meshes).member("materials", material);
        json.member("accessors", glb.accessors);
        if (lightmap) {
            JsonWriter images, samplers, textures;
            images.begin_array().begin_object().member("name", "mbr lightmap");
            images.member("bufferView", image_view).member("mimeType", "image/png");
            images.end_object().end_array();
            samplers.begin_array().begin_object().member("magFilter", gl_linear);
            samplers.member("minFilter", gl_linear).member("wrapS", gl_clamp_to_edge);
            samplers.member("wrapT", gl_clamp_to_edge).end_object().end_array();
            textures.begin_array().begin_object().member("name", "mbr lightmap");
            textures.member("sampler", 0).member("source", 0).end_object().end_array();
            json.member("images", images).member("samplers", samplers);
            json.member("textures", textures);
        }
        JsonWriter buffers;
        buffers.begin_array().begin_object().member("byteLength", glb.bin.size());
        buffers.end_object().end_array();
        json.member("bufferViews", glb.views).member("buffers", buffers);
    }
    json.end_object();
    std::string text = json.text();
    pad_to_4(text, ' ');

    const size_t total = 12 + 8 + text.size() + (glb.bin.empty() ? 0 : 8 + glb.bin.size());
    if (total > std::numeric_limits<std::uint32_t>::max())
        throw std::length_error("the GLB file would be " + std::to_string(total) +
                                " bytes, beyond the format's 4 GiB");
    std::string out;
    out.reserve(total);
    out += "glTF";
    put_u32(out, 2);
    put_u32(out, std::uint32_t(total));
    put_u32(out, std::uint32_t(text.size()));
    out += "JSON";
    out += text;
    if (!glb.bin.empty()) {
        put_u32(out, std::uint32_t(glb.bin.size()));
        out += std::string("BIN\0", 4);
        out += glb.bin;
    }
    MBR_CHECK(out.size() == total);
    return out;
}

// ---- PLY ----------------------------------------------------------------------------------

namespace {

// A name as one word of a PLY comment line: blanks and control bytes as '_'.
std::string comment_word(const std::string& s) {
    std::string out = s.empty() ? "-" : s;
    for (char& c : out)
        if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7F) c = '_';
    return out;
}

}  // namespace

std::string encode_ply(const ExportMesh& mesh, double exposure) {
    MBR_CHECK(exposure > 0 && std::isfinite(exposure));
    const long nv = mesh.vertex_count(), nt = mesh.triangle_count();
    if (nv > long(std::numeric_limits<std::int32_t>::max()))
        throw std::length_error("a PLY file's int indices cannot count " + std::to_string(nv) +
                                " vertices");
    std::string out =
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment mbr export: the solved radiosity of " +
        std::to_string(mesh.surfaces.size()) +
        " surfaces, each its own grid of vertices\n"
        "comment red green blue: 8-bit sRGB of min(1, exposure * B / pi), exposure " +
        json_number(exposure) +
        "\n"
        "comment radiosity_r radiosity_g radiosity_b: B, linear, emission included\n";
    long first_vertex = 0, first_face = 0;
    for (const ExportSurface& s : mesh.surfaces) {
        out += "comment surface " + std::to_string(s.surface) + " " + comment_word(s.name) +
               " material " + comment_word(s.material) + " vertices " +
               std::to_string(first_vertex) + " " + std::to_string(s.vertices.size()) + " faces " +
               std::to_string(first_face) + " " + std::to_string(s.triangles.size()) + "\n";
        first_vertex += long(s.vertices.size());
        first_face += long(s.triangles.size());
    }
    out += "element vertex " + std::to_string(nv) +
           "\n"
           "property float x\nproperty float y\nproperty float z\n"
           "property float nx\nproperty float ny\nproperty float nz\n"
           "property uchar red\nproperty uchar green\nproperty uchar blue\n"
           "property float radiosity_r\nproperty float radiosity_g\nproperty float radiosity_b\n"
           "element face " +
           std::to_string(nt) +
           "\n"
           "property list uchar int vertex_indices\n"
           "end_header\n";
    out.reserve(out.size() + size_t(nv) * 39 + size_t(nt) * 13);
    for (const ExportSurface& s : mesh.surfaces)
        for (const ExportVertex& v : s.vertices) {
            for (int c = 0; c < 3; ++c) put_f32(out, finite_float(v.position[c]));
            for (int c = 0; c < 3; ++c) put_f32(out, finite_float(v.normal[c]));
            for (std::uint8_t c : display_colour_srgb8(v.radiosity, exposure)) out += char(c);
            for (int c = 0; c < 3; ++c) put_f32(out, finite_float(v.radiosity[c]));
        }
    std::uint32_t base = 0;
    for (const ExportSurface& s : mesh.surfaces) {
        for (const auto& t : s.triangles) {
            out += char(3);
            for (std::uint32_t k : t) put_u32(out, base + k);
        }
        base += std::uint32_t(s.vertices.size());
    }
    return out;
}

}  // namespace mbr
