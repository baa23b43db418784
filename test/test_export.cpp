// test/test_export.cpp - the export for viewers (radiosity/output/export.h, `mbr export`): the
// tessellation rule, the GLB and PLY files read back by readers of this test's own (a small JSON
// parser, the GLB chunks, accessors and buffer views, PLY's header and binary body), the colour
// rule undone and compared with RadiosityView::at at vertices whose (u, v) the rule gives, the
// lightmap atlas's tiles and texels, and the tool end to end on the Cornell box.
//
// Independent references: fields whose values are known in closed form (B-splines reproduce
// linear functions, so a field can be B(u, v) = (u, v, 1) s exactly), the surfaces' own point()
// and normal(), and stb_image's PNG decoder for the lightmap.
#include <stb_image.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "math/bspline.h"
#include "radiosity/output/export.h"
#include "radiosity/output/render.h"
#include "test/file_bytes.h"
#include "test/report.h"
#include "test/run_program.h"

using namespace mbr;

namespace {

// ---- A small JSON reader: objects, arrays, strings, numbers, true, false, null --------------

struct Json {
    enum class Type { Null, Bool, Number, String, Array, Object } type = Type::Null;
    bool boolean = false;
    double number = 0;
    std::string string;
    std::vector<Json> array;
    std::map<std::string, Json> object;

    bool has(const std::string& key) const { return type == Type::Object && object.count(key) > 0; }
    const Json& operator[](const std::string& key) const {
        INFO("JSON member " << key);
        REQUIRE(has(key));
        return object.at(key);
    }
    const Json& operator[](size_t i) const {
        REQUIRE(type == Type::Array);
        REQUIRE(i < array.size());
        return array[i];
    }
    size_t size() const { return type == Type::Array ? array.size() : object.size(); }
    long integer() const {
        REQUIRE(type == Type::Number);
        REQUIRE(number == std::floor(number));
        return long(number);
    }
};

class JsonParser {
public:
    explicit JsonParser(const std::string& text) : s_(text) {}
    Json parse() {
        Json v = value();
        blanks();
        REQUIRE(i_ == s_.size());
        return v;
    }

private:
    void blanks() {
        while (i_ < s_.size() && std::strchr(" \t\r\n", s_[i_]) && s_[i_]) ++i_;
    }
    char peek() {
        blanks();
        REQUIRE(i_ < s_.size());
        return s_[i_];
    }
    void expect(char c) {
        INFO("JSON at byte " << i_ << ": expected " << c);
        REQUIRE(peek() == c);
        ++i_;
    }
    void word(const char* w) {
        REQUIRE(s_.compare(i_, std::strlen(w), w) == 0);
        i_ += std::strlen(w);
    }
    std::string string_value() {
        expect('"');
        std::string out;
        while (true) {
            REQUIRE(i_ < s_.size());
            const char c = s_[i_++];
            if (c == '"') return out;
            REQUIRE(static_cast<unsigned char>(c) >= 0x20);  // control bytes must be escaped
            if (c != '\\') {
                out += c;
                continue;
            }
            REQUIRE(i_ < s_.size());
            const char e = s_[i_++];
            if (e == 'u') {
                REQUIRE(i_ + 4 <= s_.size());
                const unsigned cp = unsigned(std::stoul(s_.substr(i_, 4), nullptr, 16));
                i_ += 4;
                REQUIRE(cp < 0x80);  // the writer escapes control bytes only
                out += char(cp);
            } else {
                const char* from = "\"\\/bfnrt";
                const char* to = "\"\\/\b\f\n\r\t";
                const char* at = std::strchr(from, e);
                REQUIRE(at != nullptr);
                out += to[at - from];
            }
        }
    }
    Json value() {
        Json v;
        const char c = peek();
        if (c == '{') {
            v.type = Json::Type::Object;
            ++i_;
            if (peek() == '}') {
                ++i_;
                return v;
            }
            while (true) {
                const std::string key = string_value();
                REQUIRE(v.object.count(key) == 0);  // no duplicate members
                expect(':');
                v.object[key] = value();
                if (peek() == ',') {
                    ++i_;
                    continue;
                }
                expect('}');
                return v;
            }
        }
        if (c == '[') {
            v.type = Json::Type::Array;
            ++i_;
            if (peek() == ']') {
                ++i_;
                return v;
            }
            while (true) {
                v.array.push_back(value());
                if (peek() == ',') {
                    ++i_;
                    continue;
                }
                expect(']');
                return v;
            }
        }
        if (c == '"') {
            v.type = Json::Type::String;
            v.string = string_value();
            return v;
        }
        if (c == 't' || c == 'f') {
            v.type = Json::Type::Bool;
            v.boolean = c == 't';
            word(c == 't' ? "true" : "false");
            return v;
        }
        if (c == 'n') {
            word("null");
            return v;
        }
        // A number: JSON's grammar, read by strtod.
        const size_t start = i_;
        while (i_ < s_.size() && std::strchr("+-0123456789.eE", s_[i_]) && s_[i_]) ++i_;
        REQUIRE(i_ > start);
        v.type = Json::Type::Number;
        v.number = std::strtod(s_.substr(start, i_ - start).c_str(), nullptr);
        return v;
    }
    const std::string& s_;
    size_t i_ = 0;
};

// ---- GLB ----------------------------------------------------------------------------------

std::uint32_t le_u32(const std::string& b, size_t at) {
    REQUIRE(at + 4 <= b.size());
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(b[at + size_t(k)]);
    return v;
}

std::uint32_t be_u32(const std::string& b, size_t at) {
    REQUIRE(at + 4 <= b.size());
    std::uint32_t v = 0;
    for (size_t k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(b[at + k]);
    return v;
}

float le_f32(const std::string& b, size_t at) {
    const std::uint32_t bits = le_u32(b, at);
    float f = 0;
    std::memcpy(&f, &bits, 4);
    return f;
}

// A GLB file's JSON and BIN chunks, after checking the header and the chunks' lengths.
struct Glb {
    Json json;
    std::string bin;
};

Glb parse_glb(const std::string& bytes) {
    REQUIRE(bytes.size() >= 20);
    CHECK(bytes.compare(0, 4, "glTF") == 0);
    CHECK(le_u32(bytes, 4) == 2);
    CHECK(le_u32(bytes, 8) == bytes.size());
    const std::uint32_t json_length = le_u32(bytes, 12);
    CHECK(json_length % 4 == 0);
    CHECK(bytes.compare(16, 4, "JSON") == 0);
    REQUIRE(20 + size_t(json_length) <= bytes.size());
    Glb glb;
    const std::string text = bytes.substr(20, json_length);
    // Padded with blanks (0x20) only.
    CHECK(text.find_last_not_of(' ') + 1 + 3 >= text.size());
    glb.json = JsonParser(text).parse();
    size_t at = 20 + json_length;
    if (at < bytes.size()) {
        const std::uint32_t bin_length = le_u32(bytes, at);
        CHECK(bin_length % 4 == 0);
        CHECK(bytes.compare(at + 4, 4, std::string("BIN\0", 4)) == 0);
        REQUIRE(at + 8 + bin_length == bytes.size());
        glb.bin = bytes.substr(at + 8, bin_length);
    }
    const size_t declared = size_t(glb.json["buffers"][0]["byteLength"].integer());
    CHECK(declared <= glb.bin.size());
    CHECK(glb.bin.size() - declared < 4);
    return glb;
}

// The bytes a buffer view covers, checked to lie inside the BIN chunk and to be aligned.
std::string view_bytes(const Glb& glb, long view_index) {
    const Json& view = glb.json["bufferViews"][size_t(view_index)];
    CHECK(view["buffer"].integer() == 0);
    const size_t offset = view.has("byteOffset") ? size_t(view["byteOffset"].integer()) : 0;
    const size_t length = size_t(view["byteLength"].integer());
    CHECK(offset % 4 == 0);
    REQUIRE(offset + length <= glb.bin.size());
    return glb.bin.substr(offset, length);
}

// An accessor's values (as doubles) and its number of components.
struct AccessorData {
    std::vector<double> values;
    int width = 0;
    long count = 0;
};

AccessorData read_accessor(const Glb& glb, long index) {
    const Json& a = glb.json["accessors"][size_t(index)];
    const std::string type = a["type"].string;
    AccessorData d;
    d.width = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : 4;
    d.count = a["count"].integer();
    REQUIRE(d.count > 0);
    const long component = a["componentType"].integer();
    const size_t size = component == 5126 || component == 5125 ? 4 : component == 5123 ? 2 : 0;
    REQUIRE(size > 0);
    const size_t offset = a.has("byteOffset") ? size_t(a["byteOffset"].integer()) : 0;
    const std::string bytes = view_bytes(glb, a["bufferView"].integer());
    REQUIRE(offset + size_t(d.count) * size_t(d.width) * size <= bytes.size());
    for (long k = 0; k < d.count * d.width; ++k) {
        const size_t at = offset + size_t(k) * size;
        if (component == 5126)
            d.values.push_back(le_f32(bytes, at));
        else if (component == 5125)
            d.values.push_back(le_u32(bytes, at));
        else
            d.values.push_back(static_cast<unsigned char>(bytes[at]) |
                               static_cast<unsigned char>(bytes[at + 1]) << 8);
    }
    return d;
}

// ---- Scenes and fields whose values are known ----------------------------------------------

// B(u, v) = s (u, v, 1) + offset exactly: the Greville abscissae reproduce linear functions,
// sum_k 2^-j (k + m/2) N_m(2^j s - k) = s (as test_render.cpp's linear_field).
SplineField linear_field(int m, int level, double s, double offset = 0) {
    SplineField f(m, level);
    const int first = first_touching_index(m), n = touching_count(m, level);
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l)
            f.set_coefficient(k, l,
                              {s * std::ldexp(k + 0.5 * m, -level) + offset,
                               s * std::ldexp(l + 0.5 * m, -level) + offset, s + offset});
    return f;
}

Rgb linear_value(double u, double v, double s, double offset = 0) {
    return {s * u + offset, s * v + offset, s + offset};
}

// A quad, a sphere (with its poles), an inward cylinder, a disk and a quad without a field.
Scene shapes_scene() {
    Scene scene;
    scene.materials.push_back({"grey", Texture::constant({0.5, 0.5, 0.5}), Texture()});
    scene.materials.push_back(
        {"lamp", Texture::constant({0.5, 0.5, 0.5}), Texture::constant({100, 100, 100})});
    scene.surfaces.push_back(
        {"floor", Surface::planar_quad({0, 0, 0}, {0, 0, 2}, {3, 0, 2}, {3, 0, 0}), 0});
    scene.surfaces.push_back(
        {"ball", Surface::sphere({1, 1, 1}, {0, 1, 0}, {1, 0, 0}, 0.5, 0, Pi, 0, 2 * Pi), 0});
    scene.surfaces.push_back(
        {"tube", Surface::cylinder({2, 0, 1}, {0, 1, 0}, {1, 0, 0}, 0.3, 1, 0, 2 * Pi, true), 0});
    scene.surfaces.push_back(
        {"lamp", Surface::disk({1, 2, 1}, {0, -1, 0}, {1, 0, 0}, 0, 0.4, 0, 2 * Pi), 1});
    scene.surfaces.push_back(
        {"unlit", Surface::planar_quad({0, 0, 3}, {1, 0, 3}, {1, 1, 3}, {0, 1, 3}), 0});
    scene.settings.tessellation = 12;
    return scene;
}

// Fields of shapes_scene: known linear ones of several levels, the lamp far above 1, the last
// surface without a field.
std::vector<SplineField> shapes_fields() {
    std::vector<SplineField> f;
    f.push_back(linear_field(4, 3, 2.0));                      // floor: level 3, n = 16
    f.push_back(linear_field(3, 1, 1.5, 0.1));                 // ball: level 1, n = max(4, 12) = 12
    f.push_back(linear_field(4, 4, 0.8));                      // tube: level 4, n = 32
    f.push_back(SplineField::constant(4, 0, {120, 110, 90}));  // lamp: n = max(2, 12)
    f.push_back(SplineField());                                // unlit: none, n = 2
    return f;
}

double relative_difference(Rgb a, Rgb b) {
    double worst = 0;
    for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::fabs(a[c] - b[c]) / std::max(std::fabs(b[c]), 1e-30));
    return worst;
}

// Vertex indices of the corners and the centre of an (n+1) x (n+1) grid, with their (u, v).
struct KnownVertex {
    long index;
    double u, v;
};
std::vector<KnownVertex> known_vertices(int n) {
    const long side = n + 1;
    return {{0, 0, 0},
            {n, 1, 0},
            {side * n + n, 1, 1},
            {side * n, 0, 1},
            {side * (n / 2) + n / 2, double(n / 2) / n, double(n / 2) / n}};
}

}  // namespace

TEST_CASE(
    "export: the grid is twice the field's knots, curved surfaces at least the "
    "tessellation, at most 256",
    "[export]") {
    const Surface quad = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    const Surface ball = Surface::sphere({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 1, 0, Pi, 0, 2 * Pi);
    const Surface disk = Surface::disk({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 0, 1, 0, 2 * Pi);
    for (int level = 0; level <= 8; ++level) {
        const SplineField f(4, level);
        CHECK(export_resolution(quad, &f, 16) == std::min(2 << level, 256));
        CHECK(export_resolution(ball, &f, 16) == std::min(std::max(2 << level, 16), 256));
        CHECK(export_resolution(disk, &f, 24) == std::min(std::max(2 << level, 24), 256));
    }
    CHECK(export_resolution(quad, nullptr, 16) == 2);
    const SplineField none;
    CHECK(export_resolution(quad, &none, 16) == 2);
    CHECK(export_resolution(ball, nullptr, 16) == 16);
    CHECK(export_resolution(ball, nullptr, 1000) == 256);
    const SplineField fine(4, 6);
    CHECK(export_resolution(quad, &fine, 16, 32) == 32);
}

TEST_CASE(
    "export: the tessellation puts B at the grid's vertices, faces the front and drops "
    "the poles' empty triangles",
    "[export]") {
    const Scene scene = shapes_scene();
    const std::vector<SplineField> fields = shapes_fields();
    const RadiosityView view(fields);
    const ExportMesh mesh = tessellate_for_export(scene, view);
    REQUIRE(mesh.surfaces.size() == scene.surfaces.size());
    const int expected_n[] = {16, 12, 32, 12, 2};
    long vertices = 0, triangles = 0;
    for (size_t i = 0; i < mesh.surfaces.size(); ++i) {
        const ExportSurface& s = mesh.surfaces[i];
        CAPTURE(s.name);
        CHECK(s.name == scene.surfaces[i].name);
        CHECK(s.material == scene.material_of(int(i)).name);
        CHECK(s.surface == int(i));
        REQUIRE(s.resolution == expected_n[i]);
        const int n = s.resolution;
        REQUIRE(s.vertices.size() == size_t(n + 1) * size_t(n + 1));
        for (int b = 0; b <= n; ++b)
            for (int a = 0; a <= n; ++a) {
                const ExportVertex& v = s.vertices[size_t(b) * size_t(n + 1) + size_t(a)];
                CHECK(v.uv.x == double(a) / n);
                CHECK(v.uv.y == double(b) / n);
                CHECK(length(v.position - scene.surfaces[i].surface.point(v.uv.x, v.uv.y)) == 0);
                CHECK(std::fabs(length(v.normal) - 1) < 1e-12);
                CHECK(v.radiosity == view.at(int(i), v.uv.x, v.uv.y));
            }
        // Triangles: in range, non-degenerate, counter-clockwise seen from the front.
        for (const auto& t : s.triangles) {
            for (std::uint32_t k : t) REQUIRE(k < s.vertices.size());
            const Vec3 p0 = s.vertices[t[0]].position, p1 = s.vertices[t[1]].position,
                       p2 = s.vertices[t[2]].position;
            const Vec3 c = cross(p1 - p0, p2 - p0);
            CHECK(length(c) > 0);
            CHECK(dot(c, s.vertices[t[0]].normal + s.vertices[t[1]].normal +
                             s.vertices[t[2]].normal) > 0);
        }
        const size_t cells = size_t(n) * size_t(n);
        // Every cell gives two triangles, except where a row of vertices meets in one point:
        // the sphere's two poles and the disk's centre, whose cells give one each.
        if (s.name == "ball")
            CHECK(s.triangles.size() == 2 * cells - 2 * size_t(n));
        else if (s.name == "lamp")
            CHECK(s.triangles.size() == 2 * cells - size_t(n));
        else
            CHECK(s.triangles.size() == 2 * cells);
        vertices += long(s.vertices.size());
        triangles += long(s.triangles.size());
    }
    CHECK(mesh.vertex_count() == vertices);
    CHECK(mesh.triangle_count() == triangles);
    // The field's known values at the floor's corners and centre.
    for (const KnownVertex& k : known_vertices(16))
        CHECK(relative_difference(mesh.surfaces[0].vertices[size_t(k.index)].radiosity,
                                  linear_value(k.u, k.v, 2.0)) < 1e-12);
    // No field: black.
    for (const ExportVertex& v : mesh.surfaces[4].vertices) CHECK(v.radiosity == Rgb{});
}

TEST_CASE(
    "export: the GLB reads back: header, chunks, accessors, exact bounds and B at known "
    "vertices",
    "[export]") {
    const Scene scene = shapes_scene();
    const std::vector<SplineField> fields = shapes_fields();
    const RadiosityView view(fields);
    const ExportMesh mesh = tessellate_for_export(scene, view);
    GlbOptions options;
    options.exposure = 2.5;
    options.scene_name = "shapes \"test\"\n";
    const std::string bytes = encode_glb(mesh, options);
    const Glb glb = parse_glb(bytes);
    const Json& j = glb.json;

    CHECK(j["asset"]["version"].string == "2.0");
    CHECK(j["asset"]["generator"].string == "mbr export");
    // The rule's scale, recorded: B = COLOR_0 x mbr_radiosity_scale where COLOR_0 < 1.
    const double scale = j["asset"]["extras"]["mbr_radiosity_scale"].number;
    CHECK(scale == Approx(Pi / 2.5).epsilon(1e-15));
    CHECK(j["asset"]["extras"]["mbr_exposure"].number == 2.5);
    CHECK(j["scenes"][0]["name"].string == "shapes \"test\"\n");
    REQUIRE(j["extensionsUsed"].size() == 1);
    CHECK(j["extensionsUsed"][0].string == "KHR_materials_unlit");
    REQUIRE(j["materials"].size() == 1);
    const Json& material = j["materials"][0];
    CHECK(material["extensions"].has("KHR_materials_unlit"));
    for (size_t c = 0; c < 4; ++c)
        CHECK(material["pbrMetallicRoughness"]["baseColorFactor"][c].number == 1);
    CHECK_FALSE(material["pbrMetallicRoughness"].has("baseColorTexture"));
    CHECK_FALSE(j.has("images"));

    // One node and one mesh per surface, named after it, in scene order.
    const Json& nodes = j["nodes"];
    REQUIRE(nodes.size() == scene.surfaces.size());
    REQUIRE(j["scenes"][0]["nodes"].size() == nodes.size());
    double worst_colour = 0, worst_radiosity = 0;
    for (size_t i = 0; i < nodes.size(); ++i) {
        const ExportSurface& s = mesh.surfaces[i];
        CAPTURE(s.name);
        CHECK(j["scenes"][0]["nodes"][i].integer() == long(i));
        CHECK(nodes[i]["name"].string == s.name);
        CHECK(nodes[i]["extras"]["mbr_surface"].integer() == long(i));
        CHECK(nodes[i]["extras"]["mbr_material"].string == s.material);
        const Json& m = j["meshes"][size_t(nodes[i]["mesh"].integer())];
        CHECK(m["name"].string == s.name);
        REQUIRE(m["primitives"].size() == 1);
        const Json& p = m["primitives"][0];
        CHECK(p["mode"].integer() == 4);
        CHECK(p["material"].integer() == 0);
        const Json& at = p["attributes"];
        CHECK_FALSE(at.has("TEXCOORD_0"));
        const AccessorData pos = read_accessor(glb, at["POSITION"].integer());
        const AccessorData nor = read_accessor(glb, at["NORMAL"].integer());
        const AccessorData col = read_accessor(glb, at["COLOR_0"].integer());
        const AccessorData rad = read_accessor(glb, at["_RADIOSITY"].integer());
        const AccessorData idx = read_accessor(glb, p["indices"].integer());
        for (const AccessorData* d : {&pos, &nor, &col, &rad}) {
            CHECK(d->width == 3);
            CHECK(d->count == long(s.vertices.size()));
        }
        // Small meshes use 16-bit indices.
        CHECK(j["accessors"][size_t(p["indices"].integer())]["componentType"].integer() == 5123);
        CHECK(idx.width == 1);
        CHECK(idx.count == long(3 * s.triangles.size()));
        // POSITION's min and max are exactly the data's.
        const Json& acc = j["accessors"][size_t(at["POSITION"].integer())];
        for (int c = 0; c < 3; ++c) {
            double lo = HUGE_VAL, hi = -HUGE_VAL;
            for (long k = 0; k < pos.count; ++k) {
                lo = std::min(lo, pos.values[size_t(3 * k + c)]);
                hi = std::max(hi, pos.values[size_t(3 * k + c)]);
            }
            CHECK(acc["min"][size_t(c)].number == lo);
            CHECK(acc["max"][size_t(c)].number == hi);
        }
        // Unit normals; positions and normals as the surface gives them (to float precision).
        for (long k = 0; k < pos.count; ++k) {
            const Vec3 x{pos.values[size_t(3 * k)], pos.values[size_t(3 * k + 1)],
                         pos.values[size_t(3 * k + 2)]};
            const Vec3 nn{nor.values[size_t(3 * k)], nor.values[size_t(3 * k + 1)],
                          nor.values[size_t(3 * k + 2)]};
            CHECK(std::fabs(length(nn) - 1) < 1e-6);
            const ExportVertex& v = s.vertices[size_t(k)];
            CHECK(length(x - scene.surfaces[i].surface.point(v.uv.x, v.uv.y)) < 1e-6);
            CHECK(dot(nn, scene.surfaces[i].surface.normal(v.uv.x, v.uv.y)) > 1 - 1e-6);
        }
        // Indices in range, triangles facing the normals.
        for (long t = 0; t < idx.count / 3; ++t) {
            Vec3 p3[3], nsum;
            for (int c = 0; c < 3; ++c) {
                const double k = idx.values[size_t(3 * t + c)];
                REQUIRE(k < double(pos.count));
                const size_t v = size_t(k);
                p3[c] = {pos.values[3 * v], pos.values[3 * v + 1], pos.values[3 * v + 2]};
                nsum += Vec3{nor.values[3 * v], nor.values[3 * v + 1], nor.values[3 * v + 2]};
            }
            CHECK(dot(cross(p3[1] - p3[0], p3[2] - p3[0]), nsum) > 0);
        }
        // Colours at the corners and the centre: the rule undone against RadiosityView::at.
        for (const KnownVertex& kv : known_vertices(s.resolution)) {
            const Rgb b = view.at(int(i), kv.u, kv.v);
            const size_t k = size_t(kv.index);
            const Rgb colour{col.values[3 * k], col.values[3 * k + 1], col.values[3 * k + 2]};
            const Rgb exact{rad.values[3 * k], rad.values[3 * k + 1], rad.values[3 * k + 2]};
            CAPTURE(kv.u, kv.v, b, colour, exact);
            for (int c = 0; c < 3; ++c) {
                CHECK(colour[c] >= 0);
                CHECK(colour[c] <= 1);
                if (b[c] * 2.5 / Pi < 1) {
                    const double undone = colour[c] * scale;
                    const double rel = std::fabs(undone - b[c]) / std::max(b[c], 1e-30);
                    worst_colour = std::max(worst_colour, b[c] == 0 ? undone : rel);
                } else {
                    CHECK(colour[c] == 1);  // clipped, as the render clips
                }
            }
            worst_radiosity = std::max(worst_radiosity,
                                       b == Rgb{} ? max_abs(exact) : relative_difference(exact, b));
        }
    }
    CHECK(worst_colour < 1e-6);
    CHECK(worst_radiosity < 1e-6);
    mbr::test::report() << "GLB read-back: largest relative difference of COLOR_0 x pi / "
                        << "exposure " << worst_colour << ", of _RADIOSITY " << worst_radiosity
                        << " (" << bytes.size() << " bytes)\n";
}

TEST_CASE("export: a grid of more than 65535 vertices takes 32-bit indices", "[export]") {
    Scene scene;
    scene.materials.push_back({"grey", Texture::constant({0.5, 0.5, 0.5}), Texture()});
    scene.surfaces.push_back(
        {"big", Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}), 0});
    const std::vector<SplineField> fields{linear_field(2, 8, 1.0)};  // n = 256: 257^2 vertices
    const ExportMesh mesh = tessellate_for_export(scene, RadiosityView(fields));
    REQUIRE(mesh.surfaces[0].vertices.size() == 257u * 257u);
    const Glb glb = parse_glb(encode_glb(mesh));
    const long indices = glb.json["meshes"][0]["primitives"][0]["indices"].integer();
    CHECK(glb.json["accessors"][size_t(indices)]["componentType"].integer() == 5125);
    const AccessorData idx = read_accessor(glb, indices);
    // The grid's last vertex, (n, n), is used: beyond 16 bits.
    CHECK(*std::max_element(idx.values.begin(), idx.values.end()) == 257.0 * 257 - 1);
}

TEST_CASE("export: the PLY reads back: header, vertices, sRGB colours, exact B and faces",
          "[export]") {
    const Scene scene = shapes_scene();
    const std::vector<SplineField> fields = shapes_fields();
    const RadiosityView view(fields);
    const ExportMesh mesh = tessellate_for_export(scene, view);
    const double exposure = 1.7;
    const std::string ply = encode_ply(mesh, exposure);
    const size_t header_end = ply.find("end_header\n");
    REQUIRE(header_end != std::string::npos);
    std::istringstream header(ply.substr(0, header_end));
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(header, line)) lines.push_back(line);
    REQUIRE(lines.size() > 4);
    CHECK(lines[0] == "ply");
    CHECK(lines[1] == "format binary_little_endian 1.0");
    CHECK(lines[2].rfind("comment mbr export", 0) == 0);
    long n_vertices = -1, n_faces = -1, surface_comments = 0;
    std::vector<std::string> vertex_properties, face_properties;
    std::vector<std::string>* properties = nullptr;
    for (const std::string& l : lines) {
        std::istringstream words(l);
        std::string w;
        words >> w;
        if (w == "element") {
            std::string what;
            long count = 0;
            words >> what >> count;
            if (what == "vertex") n_vertices = count, properties = &vertex_properties;
            if (what == "face") n_faces = count, properties = &face_properties;
        } else if (w == "property") {
            REQUIRE(properties != nullptr);
            properties->push_back(l.substr(9));
        } else if (w == "comment") {
            words >> w;
            if (w == "surface") ++surface_comments;
        }
    }
    CHECK(surface_comments == long(mesh.surfaces.size()));
    CHECK(n_vertices == mesh.vertex_count());
    CHECK(n_faces == mesh.triangle_count());
    CHECK(vertex_properties ==
          std::vector<std::string>{"float x", "float y", "float z", "float nx", "float ny",
                                   "float nz", "uchar red", "uchar green", "uchar blue",
                                   "float radiosity_r", "float radiosity_g", "float radiosity_b"});
    CHECK(face_properties == std::vector<std::string>{"list uchar int vertex_indices"});
    // The body: 12 floats' worth less 9 bytes per vertex (39 bytes), 13 bytes per face.
    const size_t body = header_end + std::strlen("end_header\n");
    REQUIRE(ply.size() == body + size_t(n_vertices) * 39 + size_t(n_faces) * 13);

    size_t at = body;
    double worst = 0;
    long first = 0;
    for (size_t i = 0; i < mesh.surfaces.size(); ++i) {
        const ExportSurface& s = mesh.surfaces[i];
        for (const KnownVertex& kv : known_vertices(s.resolution)) {
            const size_t v = body + size_t(first + kv.index) * 39;
            const Rgb b = view.at(int(i), kv.u, kv.v);
            const Vec3 x{le_f32(ply, v), le_f32(ply, v + 4), le_f32(ply, v + 8)};
            CHECK(length(x - scene.surfaces[i].surface.point(kv.u, kv.v)) < 1e-6);
            const Rgb exact{le_f32(ply, v + 27), le_f32(ply, v + 31), le_f32(ply, v + 35)};
            worst = std::max(worst, b == Rgb{} ? max_abs(exact) : relative_difference(exact, b));
            // The 8-bit colour is mbr render's pixel for that B.
            Image one(1, 1, b * (1 / Pi));
            const Rgb pixel = tone_map(one, exposure).pixels[0];
            for (int c = 0; c < 3; ++c)
                CHECK(static_cast<unsigned char>(ply[v + 24 + size_t(c)]) ==
                      std::lround(255 * pixel[c]));
        }
        first += long(s.vertices.size());
    }
    CHECK(worst < 1e-6);
    // Faces: three indices each, in the range of all vertices and of their own surface.
    at = body + size_t(n_vertices) * 39;
    long base = 0;
    for (const ExportSurface& s : mesh.surfaces) {
        for (size_t t = 0; t < s.triangles.size(); ++t, at += 13) {
            REQUIRE(ply[at] == 3);
            for (size_t c = 0; c < 3; ++c) {
                const long k = long(le_u32(ply, at + 1 + 4 * c));
                CHECK(k >= base);
                CHECK(k < base + long(s.vertices.size()));
                CHECK(k - base == long(s.triangles[t][c]));
            }
        }
        base += long(s.vertices.size());
    }
    CHECK(at == ply.size());
}

TEST_CASE("export: lightmap tiles, gutters, texels at their centres, and the GLB's texture",
          "[export]") {
    // The layout rule.
    CHECK(valid_lightmap_size(16));
    CHECK(valid_lightmap_size(4096));
    CHECK_FALSE(valid_lightmap_size(8));
    CHECK_FALSE(valid_lightmap_size(100));
    CHECK_FALSE(valid_lightmap_size(8192));
    CHECK_THROWS_AS(lightmap_layout(5, 100), std::invalid_argument);
    CHECK_THROWS_AS(lightmap_layout(0, 64), std::invalid_argument);
    CHECK_THROWS_AS(lightmap_layout(50, 16), std::invalid_argument);  // 8 columns of 2 texels
    CHECK(smallest_lightmap_size(1) == 16);
    CHECK(smallest_lightmap_size(16) == 16);  // 4 x 4 tiles of 4 texels, gutter 1, 2 inside
    CHECK(smallest_lightmap_size(17) == 32);
    CHECK(smallest_lightmap_size(5000000) == 0);
    const LightmapLayout big = lightmap_layout(27, 1024);
    CHECK(big.columns == 6);
    CHECK(big.tile == 170);
    CHECK(big.gutter == 2);
    CHECK(big.inner == 166);
    CHECK(big.tile_x(7) == 170);
    CHECK(big.tile_y(7) == 170);

    const Scene scene = shapes_scene();
    const std::vector<SplineField> fields = shapes_fields();
    const RadiosityView view(fields);
    const int size = 64;
    const LightmapLayout layout = lightmap_layout(view.size(), size);
    CHECK(layout.columns == 3);
    CHECK(layout.tile == 21);
    CHECK(layout.gutter == 2);
    CHECK(layout.inner == 17);
    const Image radiance = bake_lightmap(view, layout);
    REQUIRE(radiance.width == size);
    REQUIRE(radiance.height == size);
    for (int k = 0; k < view.size(); ++k) {
        const int x0 = layout.tile_x(k), y0 = layout.tile_y(k), g = layout.gutter;
        const int n = layout.inner;
        for (int r = 0; r < n; ++r)
            for (int a = 0; a < n; ++a) {
                const double u = (a + 0.5) / n, v = 1 - (r + 0.5) / n;
                const Rgb expected = (1 / Pi) * view.at(k, u, v);
                CHECK(relative_difference(radiance.at(x0 + g + a, y0 + g + r), expected) < 1e-12);
            }
        // The gutter repeats the edge texels.
        for (int t = 0; t < layout.tile; ++t)
            for (int e = 0; e < g; ++e) {
                const int c = std::clamp(t, g, g + n - 1);
                CHECK(radiance.at(x0 + e, y0 + t) == radiance.at(x0 + g, y0 + c));
                CHECK(radiance.at(x0 + layout.tile - 1 - e, y0 + t) ==
                      radiance.at(x0 + g + n - 1, y0 + c));
                CHECK(radiance.at(x0 + t, y0 + e) == radiance.at(x0 + c, y0 + g));
                CHECK(radiance.at(x0 + t, y0 + layout.tile - 1 - e) ==
                      radiance.at(x0 + c, y0 + g + n - 1));
            }
    }

    // In the GLB: the PNG, TEXCOORD_0 inside each tile, no COLOR_0, a textured unlit material.
    const double exposure = 1.5;
    const Lightmap lightmap = make_lightmap(view, size, exposure);
    const ExportMesh mesh = tessellate_for_export(scene, view);
    GlbOptions options;
    options.exposure = exposure;
    options.lightmap = &lightmap;
    const Glb glb = parse_glb(encode_glb(mesh, options));
    const Json& j = glb.json;
    const Json& material = j["materials"][0];
    CHECK(material["extensions"].has("KHR_materials_unlit"));
    CHECK(material["pbrMetallicRoughness"]["baseColorTexture"]["index"].integer() == 0);
    REQUIRE(j["textures"].size() == 1);
    CHECK(j["textures"][0]["source"].integer() == 0);
    const Json& sampler = j["samplers"][size_t(j["textures"][0]["sampler"].integer())];
    CHECK(sampler["wrapS"].integer() == 33071);
    CHECK(sampler["wrapT"].integer() == 33071);
    const Json& image = j["images"][0];
    CHECK(image["mimeType"].string == "image/png");
    const std::string png = view_bytes(glb, image["bufferView"].integer());
    CHECK(png == lightmap.png);
    REQUIRE(png.size() > 24);
    CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
    CHECK(be_u32(png, 8) == 13);
    CHECK(png.compare(12, 4, "IHDR") == 0);
    CHECK(be_u32(png, 16) == unsigned(size));
    CHECK(be_u32(png, 20) == unsigned(size));
    // The texels are the render's tone mapping of B / pi (stb_image decodes the PNG).
    int w = 0, h = 0, channels = 0;
    stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()),
                                            int(png.size()), &w, &h, &channels, 3);
    REQUIRE(pixels != nullptr);
    std::vector<unsigned char> texels(pixels, pixels + size_t(w) * size_t(h) * 3);
    stbi_image_free(pixels);
    REQUIRE(w == size);
    REQUIRE(h == size);
    const Image display = tone_map(radiance, exposure);
    for (int p = 0; p < size * size; ++p)
        for (int c = 0; c < 3; ++c)
            REQUIRE(long(texels[size_t(3 * p + c)]) ==
                    std::lround(255 * display.pixels[size_t(p)][c]));

    for (size_t i = 0; i < mesh.surfaces.size(); ++i) {
        const ExportSurface& s = mesh.surfaces[i];
        CAPTURE(s.name);
        const Json& node = j["nodes"][i];
        const Json& tile = node["extras"]["mbr_lightmap_tile"];
        CHECK(tile[0].integer() == layout.tile_x(int(i)));
        CHECK(tile[1].integer() == layout.tile_y(int(i)));
        CHECK(tile[2].integer() == layout.tile);
        const Json& p = j["meshes"][size_t(node["mesh"].integer())]["primitives"][0];
        CHECK_FALSE(p["attributes"].has("COLOR_0"));  // the texture alone: not its square
        const AccessorData uv = read_accessor(glb, p["attributes"]["TEXCOORD_0"].integer());
        REQUIRE(uv.width == 2);
        REQUIRE(uv.count == long(s.vertices.size()));
        // Inside the tile's inner texels (the gutter only filters in).
        const double x_lo = double(layout.tile_x(int(i)) + layout.gutter) / size;
        const double y_lo = double(layout.tile_y(int(i)) + layout.gutter) / size;
        const double span = double(layout.inner) / size, eps = 1e-6;
        for (long k = 0; k < uv.count; ++k) {
            const double s_ = uv.values[size_t(2 * k)], t_ = uv.values[size_t(2 * k + 1)];
            CHECK(s_ >= 0);
            CHECK(s_ <= 1);
            CHECK(t_ >= 0);
            CHECK(t_ <= 1);
            CHECK(s_ >= x_lo - eps);
            CHECK(s_ <= x_lo + span + eps);
            CHECK(t_ >= y_lo - eps);
            CHECK(t_ <= y_lo + span + eps);
            // u to the right, v upwards in the image.
            const Vec2 at = s.vertices[size_t(k)].uv;
            CHECK(s_ == Approx(x_lo + at.x * span).margin(1e-6));
            CHECK(t_ == Approx(y_lo + (1 - at.y) * span).margin(1e-6));
        }
    }
}

#ifdef MBR_TOOL

namespace {

const std::string cornell = std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene";
// Fast settings: a few shots without shadows, a shallow quadtree.
const std::vector<std::string> fast = {"--shots", "3", "--max-depth", "3", "--shadows", "none"};

mbr::test::ProgramRun run_mbr(std::vector<std::string> args, bool with_fast = true) {
    if (with_fast) args.insert(args.end(), fast.begin(), fast.end());
    return mbr::test::run_program(MBR_TOOL, args);
}

// The _RADIOSITY values of every node of a GLB file, node after node.
std::vector<double> glb_radiosity(const std::string& bytes) {
    const Glb glb = parse_glb(bytes);
    std::vector<double> all;
    for (const Json& node : glb.json["nodes"].array) {
        const Json& p = glb.json["meshes"][size_t(node["mesh"].integer())]["primitives"][0];
        const AccessorData d = read_accessor(glb, p["attributes"]["_RADIOSITY"].integer());
        all.insert(all.end(), d.values.begin(), d.values.end());
    }
    return all;
}

}  // namespace

TEST_CASE("export: mbr export writes .glb and .ply, refuses bad names, and loads solutions",
          "[export]") {
    namespace fs = std::filesystem;
    mbr::test::TempFolder dir;
    const mbr::test::ProgramRun glb = run_mbr(
        {"export", cornell, "-o", dir / "box.glb", "--save-solution", dir / "box.solution"});
    CAPTURE(glb);
    REQUIRE(glb.status == 0);
    CHECK(glb.out.find("wrote " + dir / "box.glb") != std::string::npos);
    CHECK(glb.out.find("16 surfaces") != std::string::npos);
    const std::string glb_bytes = mbr::test::read_bytes(dir / "box.glb");
    const Glb parsed = parse_glb(glb_bytes);
    CHECK(parsed.json["nodes"].size() == 16);
    CHECK(parsed.json["nodes"][0]["name"].string == "light");

    const mbr::test::ProgramRun ply =
        run_mbr({"export", cornell, "-o", dir / "BOX.PLY", "--quiet"});  // any case
    CAPTURE(ply);
    REQUIRE(ply.status == 0);
    CHECK(ply.out.empty());
    CHECK(mbr::test::read_bytes(dir / "BOX.PLY").rfind("ply\nformat binary_little_endian", 0) == 0);

    // The same colours from the saved solution as from the solve.
    const mbr::test::ProgramRun loaded = run_mbr(
        {"export", cornell, "-o", dir / "loaded.glb", "--load-solution", dir / "box.solution"});
    CAPTURE(loaded);
    REQUIRE(loaded.status == 0);
    const std::vector<double> solved = glb_radiosity(glb_bytes);
    const std::vector<double> reread = glb_radiosity(mbr::test::read_bytes(dir / "loaded.glb"));
    REQUIRE(solved.size() == reread.size());
    double worst = 0;
    for (size_t k = 0; k < solved.size(); ++k)
        worst = std::max(worst,
                         std::fabs(solved[k] - reread[k]) / std::max(std::fabs(solved[k]), 1e-12));
    CHECK(worst < 1e-6);

    // A solution saved by mbr render loads too, to the same colours.
    const mbr::test::ProgramRun render =
        run_mbr({"render", cornell, "-o", dir / "box.png", "--size", "8", "8", "--spp", "1",
                 "--save-solution", dir / "render.solution", "--quiet"});
    CAPTURE(render);
    REQUIRE(render.status == 0);
    const mbr::test::ProgramRun from_render =
        run_mbr({"export", cornell, "-o", dir / "r.glb", "--load-solution", dir / "render.solution",
                 "--quiet"});
    CAPTURE(from_render);
    REQUIRE(from_render.status == 0);
    CHECK(glb_radiosity(mbr::test::read_bytes(dir / "r.glb")) == solved);

    // Lightmaps.
    const mbr::test::ProgramRun lit =
        run_mbr({"export", cornell, "-o", dir / "lit.glb", "--load-solution", dir / "box.solution",
                 "--lightmaps", "256", "--quiet"});
    CAPTURE(lit);
    REQUIRE(lit.status == 0);
    CHECK(parse_glb(mbr::test::read_bytes(dir / "lit.glb")).json["images"].size() == 1);

    // Bad usage: status 2, one line, nothing written.
    const std::vector<std::vector<std::string>> bad = {
        {"export", cornell, "-o", dir / "box.obj"},                       // the extension
        {"export", cornell, "-o", dir / "noext"},                         // none
        {"export", cornell},                                              // no -o
        {"export", cornell, "-o", dir / "x.ply", "--lightmaps", "64"},    // PLY: no textures
        {"export", cornell, "-o", dir / "x.glb", "--lightmaps", "100"},   // not a power of 2
        {"export", cornell, "-o", dir / "x.glb", "--lightmaps", "8192"},  // too large
        {"export", cornell, "-o", dir / "x.glb", "--exposure", "0"},      // exposure
        {"export", cornell, "-o", dir / "x.glb", "--load-solution", dir / "box.solution",
         "--save-solution", dir / "y.solution"},
        {"export", cornell, "-o", dir / "missing folder/x.glb"},  // cannot be written
    };
    for (const std::vector<std::string>& args : bad) {
        const mbr::test::ProgramRun r = run_mbr(args);
        CAPTURE(args, r);
        CHECK(r.status == 2);
        CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    }
    CHECK_FALSE(fs::exists(dir / "x.glb"));
    CHECK_FALSE(fs::exists(dir / "x.ply"));
    const mbr::test::ProgramRun wrong = run_mbr({"export", cornell, "-o", dir / "box.obj"});
    CHECK(wrong.err.find(".glb") != std::string::npos);
    CHECK(wrong.err.find(".ply") != std::string::npos);

    // An output that is the scene itself (here through a link whose name ends in .glb) is
    // refused before any work, and the scene is untouched.
    const std::string copy = dir / "box.scene";
    fs::copy_file(cornell, copy);
    fs::create_symlink(copy, dir / "scene.glb");
    const std::string before = mbr::test::read_bytes(copy);
    const mbr::test::ProgramRun same = run_mbr({"export", copy, "-o", dir / "scene.glb"});
    CAPTURE(same);
    CHECK(same.status == 2);
    CHECK(mbr::test::read_bytes(copy) == before);

    // Help.
    const mbr::test::ProgramRun help = run_mbr({"export", "--help"}, false);
    CHECK(help.status == 0);
    CHECK(help.out.rfind("usage: mbr export SCENE -o OUT.glb|OUT.ply", 0) == 0);
    const mbr::test::ProgramRun main_help = run_mbr({"--help"}, false);
    CHECK(main_help.out.find("export SCENE -o OUT.glb|OUT.ply") != std::string::npos);
}

#endif  // MBR_TOOL
