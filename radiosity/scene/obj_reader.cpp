// radiosity/scene/obj_reader.cpp - OBJ + MTL import (obj_reader.h): OBJ statements line by line,
// each face to planar quads (faces_to_quads.h), MTL materials to reflectance and emission.
#include "radiosity/scene/obj_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <memory>
#include <unordered_set>

#include "math/check.h"
#include "radiosity/scene/faces_to_quads.h"
#include "radiosity/scene/light_sides.h"

namespace mbr {

namespace fs = std::filesystem;
using namespace detail;

namespace {

constexpr int max_files_read = 1000;    // every `include`, `obj`, `mtllib` and texture
constexpr int max_face_vertices = 256;  // ear clipping (faces_to_quads.cpp) is cubic in this

/// A material being read from an MTL file, turned into a Material at its end.
struct MtlEntry {
    std::string name;
    Line newmtl_line;
    Rgb kd{0.5, 0.5, 0.5}, ke{0, 0, 0}, ks{0, 0, 0}, tf{0, 0, 0};
    bool has_kd = false;
    int illum = -1;  // -1: none given
    std::string map_kd, map_ke;
    Line map_kd_line, map_ke_line;
};

/// The largest reflectance a forgiving import clamps a Kd of 1 or more to: below 1, as the
/// radiosity iteration needs (a reflectance of 1 never converges), and close to what was meant.
constexpr double max_clamped_reflectance = 0.99;

/// A texture vertex or vertex that its statement could not define (forgiving import).
constexpr double unusable = std::numeric_limits<double>::quiet_NaN();

/// True when the first coordinate marks an unusable vertex.
bool is_unusable(double x) {
    return std::isnan(x);
}

/// Texture coordinates (u, v) of points in a face's plane: the affine map that best fits the
/// face's vertices (least squares over them; exact for a triangle, and for any face whose
/// coordinates are affine in its plane, such as a parallelogram's), used for the quads that
/// face_to_quads makes from a face with `vt`.
class FaceCoordinates {
public:
    FaceCoordinates(const std::vector<Vec3>& p, const std::vector<std::array<double, 2>>& uv)
        : p_(p), uv_(uv) {
        // The plane's frame: origin p0, e1 along the longest edge from p0, e2 in the plane.
        Vec3 n;  // Newell's normal
        for (size_t i = 0; i < p.size(); ++i) n += cross(p[i], p[(i + 1) % p.size()]);
        origin_ = p[0];
        size_t far = 1;
        for (size_t i = 1; i < p.size(); ++i)
            if (length(p[i] - origin_) > length(p[far] - origin_)) far = i;
        e1_ = normalize(p[far] - origin_);
        e2_ = normalize(cross(normalize(n), e1_));
        // Normal equations of the fit uv = a x + b y + c, solved by Cramer's rule.
        double m[3][3] = {}, r[2][3] = {};
        for (size_t k = 0; k < p.size(); ++k) {
            const double x[3] = {dot(p[k] - origin_, e1_), dot(p[k] - origin_, e2_), 1};
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) m[i][j] += x[i] * x[j];
                for (int c = 0; c < 2; ++c) r[c][i] += x[i] * uv[k][size_t(c)];
            }
        }
        const auto det = [](const double a[3][3]) {
            return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                   a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                   a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        };
        const double d = det(m);
        for (int c = 0; c < 2; ++c)
            for (int i = 0; i < 3; ++i) {
                double mi[3][3];
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b) mi[a][b] = b == i ? r[c][a] : m[a][b];
                coefficient_[c][i] = d != 0 ? det(mi) / d : 0;
            }
    }

    /// The coordinates at q: a vertex of the face keeps its own `vt`; any other point of the
    /// plane gets the fitted affine map's.
    std::array<double, 2> at(Vec3 q) const {
        for (size_t k = 0; k < p_.size(); ++k)
            if (p_[k] == q) return uv_[k];
        const double x = dot(q - origin_, e1_), y = dot(q - origin_, e2_);
        return {coefficient_[0][0] * x + coefficient_[0][1] * y + coefficient_[0][2],
                coefficient_[1][0] * x + coefficient_[1][1] * y + coefficient_[1][2]};
    }

private:
    std::vector<Vec3> p_;
    std::vector<std::array<double, 2>> uv_;
    Vec3 origin_, e1_, e2_;
    double coefficient_[2][3] = {};
};

/// The candidates for a file an OBJ or MTL file names: as written, relative to the naming
/// file's folder; then, for a forgiving import, with '\' read as '/', as its base name in that
/// folder, and as the base name spelt in another case (exporters write absolute or Windows
/// paths, or folders of the machine they ran on). The first that exists as a regular file, or
/// "" when none does.
std::string locate(const std::string& from, const std::string& file) {
    std::vector<std::string> candidates{resolve(from, file)};
    std::string slashed = file;
    std::replace(slashed.begin(), slashed.end(), '\\', '/');
    candidates.push_back(resolve(from, slashed));
    const fs::path folder = fs::path(from).parent_path();
    const std::string base = fs::path(slashed).filename().string();
    if (base.empty()) return "";
    candidates.push_back((folder / base).string());
    for (const std::string& c : candidates)
        if (file_problem(c).empty()) return c;
    // The base name in another case, among the folder's files.
    std::error_code ec;
    const auto lower = [](std::string t) {
        for (char& c : t) c = char(std::tolower(static_cast<unsigned char>(c)));
        return t;
    };
    const std::string wanted = lower(base);
    fs::directory_iterator it(folder.empty() ? fs::path(".") : folder, ec), end;
    for (int n = 0; !ec && it != end && n < 100000; it.increment(ec), ++n)
        if (lower(it->path().filename().string()) == wanted) {
            const std::string found = (folder / it->path().filename()).string();
            if (file_problem(found).empty()) return found;
        }
    return "";
}

class ObjReader : ImportReader {
public:
    ObjReader(std::string name, LoadState& state) : ImportReader(state), name_(std::move(name)) {
        group_ = fs::path(name_).stem().string();
        if (group_.empty()) group_ = "obj";
        scene_.sources = {name_};  // every surface's statement is in this file
    }

    Scene read(std::istream& in) {
        LineReader reader(in, name_);
        Line line;
        while (reader.next(line)) statement(line);
        if (scene_.surfaces.empty()) {
            std::string why = "the OBJ file has no faces";
            for (const SceneWarning& w : scene_.warnings)
                if (w.kind == "face dropped")
                    why += " that can be used (" + counted(w.count, "face was", "faces were") +
                           " dropped: the first at line " + std::to_string(w.line) + ", " +
                           w.message + ")";
            throw InputError(name_, 0, why);
        }
        return finish();
    }

private:
    /// One OBJ statement. A forgiving import repairs what its statement could not do: an
    /// unusable vertex keeps its place in the numbering (faces that use it are dropped), a face
    /// that cannot be made is dropped, an unknown material gives the default one, and any other
    /// statement that fails is skipped.
    void statement(const Line& line) {
        try {
            obj_statement(line);
        } catch (const InputError& e) {
            if (strict()) throw;
            const std::string& key = line[0];
            const std::string at = e.message();
            if (key == "v") {
                v_.push_back({unusable, 0, 0});
                warn("unusable vertex", e.file(), e.line(),
                     at + "; faces that use this vertex are dropped");
            } else if (key == "vt") {
                vt_.push_back({unusable, 0});
                warn("unusable texture vertex", e.file(), e.line(),
                     at + "; faces that use it show their texture without coordinates");
            } else if (key == "vn") {
                ++n_vn_;
                warn("statement skipped", e.file(), e.line(), at + "; the statement is skipped");
            } else if (key == "f") {
                warn("face dropped", e.file(), e.line(), at + "; the face is dropped");
            } else if (key == "usemtl") {
                material_ = default_material();
                warn("unknown material", e.file(), e.line(),
                     at + "; the faces that follow get the default material (grey 0.5)");
            } else {
                warn("statement skipped", e.file(), e.line(), at + "; the statement is skipped");
            }
        }
    }

    void obj_statement(const Line& line) {
        const std::string& key = line[0];
        if (key == "v") {
            if (line.size() != 4 && line.size() != 5 && line.size() != 7)
                line.fail("'v' needs 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b), found " +
                          std::to_string(line.size() - 1));
            Vec3 p;
            for (int i = 0; i < 3; ++i)
                p[i] = parse_double(line, line[1 + i], std::string("vertex ") + "xyz"[i]);
            for (size_t i = 4; i < line.size(); ++i) parse_double(line, line[i], "vertex w/colour");
            check_point(line, p, "vertex");
            v_.push_back(p);
        } else if (key == "vt") {
            if (line.size() < 2 || line.size() > 4)
                line.fail("'vt' needs 1 to 3 numbers, found " + std::to_string(line.size() - 1));
            std::array<double, 2> uv{0, 0};
            for (size_t i = 1; i < line.size(); ++i) {
                const double x = parse_double(line, line[i], key);
                if (i <= 2) uv[i - 1] = x;
            }
            for (double x : uv)
                if (std::abs(x) > max_coordinate)
                    line.fail("texture coordinate " + fmt(x) + " exceeds the limit " +
                              fmt(max_coordinate));
            vt_.push_back(uv);
        } else if (key == "vp") {
            if (line.size() < 2 || line.size() > 4)
                line.fail("'vp' needs 1 to 3 numbers, found " + std::to_string(line.size() - 1));
            for (size_t i = 1; i < line.size(); ++i) parse_double(line, line[i], key);
        } else if (key == "vn") {
            if (line.size() != 4)
                line.fail("'vn' needs 3 numbers, found " + std::to_string(line.size() - 1));
            for (size_t i = 1; i < 4; ++i) parse_double(line, line[i], "vn");
            ++n_vn_;
        } else if (key == "f") {
            face(line);
        } else if (key == "o" || key == "g") {
            // `g` may list several groups; the first names the surfaces. No name: the default.
            group_ = line.size() >= 2 ? line[1] : fs::path(name_).stem().string();
        } else if (key == "usemtl") {
            if (line.size() != 2) line.fail("'usemtl' needs one material name");
            auto it = material_index_.find(line[1]);
            if (it == material_index_.end())
                line.fail("unknown material " + in_quotes(line[1]) +
                          " (no 'mtllib' before this line defines it)");
            material_ = it->second;
        } else if (key == "mtllib") {
            if (line.size() < 2) line.fail("'mtllib' needs a file name");
            for (size_t i = 1; i < line.size(); ++i) mtllib(line, line[i]);
        } else if (key == "s") {
            if (line.size() != 2) line.fail("'s' needs one value (a group number or 'off')");
            if (line[1] != "off" && line[1] != "on")
                parse_integer(line, line[1], "smoothing group", 0, 1LL << 40);
        } else if (key == "l" || key == "p") {
            if (line.size() < 2) line.fail("'" + key + "' needs vertex indices");
        } else if (key == "mg" || key == "lod" || key == "bevel" || key == "c_interp" ||
                   key == "d_interp" || key == "shadow_obj" || key == "trace_obj" ||
                   key == "usemap" || key == "maplib") {
            // Display and grouping attributes that do not matter for radiosity.
        } else if (key == "cstype" || key == "deg" || key == "bmat" || key == "step" ||
                   key == "curv" || key == "curv2" || key == "surf" || key == "parm" ||
                   key == "trim" || key == "hole" || key == "scrv" || key == "sp" || key == "end" ||
                   key == "con") {
            line.fail("free-form geometry (" + in_quotes(key) + ") is not supported");
        } else {
            line.fail("unknown OBJ statement " + in_quotes(key));
        }
    }

    /// One index of a face vertex: 1-based, or negative counting back from the last defined.
    long long index(const Line& line, const std::string& text, long long count,
                    const std::string& what, const std::string& what_plural) {
        long long i = parse_integer(line, text, what + " index", -(1LL << 40), 1LL << 40);
        if (i == 0) line.fail(what + " index 0 is not allowed (OBJ indices start at 1)");
        long long k = i > 0 ? i - 1 : count + i;
        if (k < 0 || k >= count)
            line.fail(what + " index " + std::to_string(i) + " is out of range (" +
                      counted(long(count), what, what_plural) + " defined so far)");
        return k;
    }

    void face(const Line& line) {
        if (line.size() < 4)
            line.fail("'f' needs at least 3 vertices, found " + std::to_string(line.size() - 1));
        if (line.size() - 1 > size_t(max_face_vertices))
            line.fail("face has " + std::to_string(line.size() - 1) + " vertices; at most " +
                      std::to_string(max_face_vertices) + " are accepted");
        std::vector<Vec3> p;
        std::vector<std::array<double, 2>> uv;
        bool all_uv = true;
        for (size_t t = 1; t < line.size(); ++t) {
            // v, v/vt, v//vn or v/vt/vn.
            const std::string& ref = line[t];
            std::vector<std::string> parts(1);
            for (char c : ref) {
                if (c == '/')
                    parts.emplace_back();
                else
                    parts.back() += c;
            }
            if (parts.size() > 3 || parts[0].empty() || (parts.size() == 2 && parts[1].empty()) ||
                (parts.size() == 3 && parts[2].empty()))
                line.fail("malformed face vertex " + in_quotes(ref) +
                          " (expected v, v/vt, v//vn or v/vt/vn)");
            const long long k = index(line, parts[0], long(v_.size()), "vertex", "vertices");
            if (is_unusable(v_[size_t(k)][0]))
                line.fail("the face uses vertex " + parts[0] + ", which its line could not define");
            p.push_back(v_[size_t(k)]);
            if (parts.size() >= 2 && !parts[1].empty()) {
                const auto& c = vt_[size_t(
                    index(line, parts[1], long(vt_.size()), "texture vertex", "texture vertices"))];
                if (is_unusable(c[0])) all_uv = false;
                uv.push_back(c);
            } else {
                all_uv = false;
            }
            if (parts.size() == 3) index(line, parts[2], n_vn_, "normal", "normals");
        }
        if (material_ < 0) material_ = default_material();
        const std::vector<Quad> quads = face_to_quads(line, p);
        // Texture coordinates matter only for a textured material: its quads get copies of it
        // seen through their corners' coordinates (Texture::mapped).
        const Material& base = scene_.materials[size_t(material_)];
        const bool textured = !base.reflectance.is_constant() || !base.emission.is_constant();
        const FaceCoordinates* coordinates = nullptr;
        std::unique_ptr<FaceCoordinates> fit;
        if (all_uv && textured) {
            fit = std::make_unique<FaceCoordinates>(p, uv);
            coordinates = fit.get();
        }
        record_face(scene_.surfaces.size(), p, quads.size());
        for (size_t k = 0; k < quads.size(); ++k) {
            const Quad& q = quads[k];
            SceneSurface s;
            s.name = group_;
            s.surface = Surface::planar_quad(q[0], q[1], q[2], q[3]);
            s.material = coordinates ? mapped_material(*coordinates, q, line, k) : material_;
            s.source = 0;
            s.line = line.number;
            scene_.surfaces.push_back(std::move(s));
        }
    }

    /// A copy of the current material for one quad of a face with texture coordinates, named
    /// MATERIAL@LINE.K (docs/scene-format.md, "OBJ import"): its textures are seen through the
    /// coordinates at the quad's corners.
    int mapped_material(const FaceCoordinates& coordinates, const Quad& q, const Line& line,
                        size_t k) {
        Texture::CornerCoordinates corners;
        for (size_t c = 0; c < 4; ++c) corners[c] = coordinates.at(q[c]);
        Material m = scene_.materials[size_t(material_)];
        m.name += "@" + std::to_string(line.number) + "." + std::to_string(k);
        m.reflectance = m.reflectance.mapped(corners);
        m.emission = m.emission.mapped(corners);
        scene_.materials.push_back(std::move(m));
        return int(scene_.materials.size()) - 1;
    }

    int default_material() {
        int m = scene_.find_material(obj_default_material);
        if (m >= 0) return m;
        Material mat;
        mat.name = obj_default_material;
        mat.reflectance = Texture::constant({0.5, 0.5, 0.5});
        scene_.materials.push_back(mat);
        return int(scene_.materials.size()) - 1;
    }

    /// `mtllib FILE`: the library beside the OBJ file, or (forgiving) wherever locate() finds
    /// it, with a warning; one that cannot be found is skipped with a warning.
    void mtllib(const Line& at, const std::string& file) {
        std::string path = resolve(name_, file);
        if (!strict() && !file_problem(path).empty()) {
            const std::string found = locate(name_, file);
            if (found.empty()) {
                warn("material library not found", at.file, at.number,
                     "material library " + in_quotes(path) + ": " + file_problem(path) +
                         "; faces that use its materials get the default material (grey 0.5)");
                return;
            }
            warn("material library found elsewhere", at.file, at.number,
                 "material library " + in_quotes(path) + " is not there; " + in_quotes(found) +
                     " is read instead");
            path = found;
        }
        state_.charge(at);
        std::ifstream in;
        open_named(at, "material library", path, in);
        state_.record(path);
        LineReader reader(in, path);
        Line line;
        MtlEntry entry;
        bool open = false;
        while (reader.next(line)) {
            try {
                const std::string& key = line[0];
                if (key == "newmtl") {
                    if (open) finish_material(entry);
                    open = false;
                    if (line.size() != 2) line.fail("'newmtl' needs one material name");
                    entry = MtlEntry();
                    entry.name = line[1];
                    entry.newmtl_line = line;
                    open = true;
                    continue;
                }
                if (!open) line.fail(in_quotes(key) + " before any 'newmtl'");
                mtl_statement(line, entry);
            } catch (const InputError& e) {
                if (strict()) throw;
                warn("statement skipped", e.file(), e.line(),
                     e.message() + "; the statement is skipped");
            }
        }
        if (open) finish_material(entry);
    }

    /// "Kd r g b" or "Kd r" (grey); spectral and CIE XYZ forms are refused.
    static Rgb mtl_colour(const Line& line) {
        if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz"))
            line.fail(in_quotes(line[0]) + " " + line[1] +
                      " colours are not supported; give r g b");
        if (line.size() != 2 && line.size() != 4)
            line.fail(in_quotes(line[0]) + " needs 1 or 3 numbers (r g b), found " +
                      std::to_string(line.size() - 1));
        Rgb c;
        for (int i = 0; i < 3; ++i)
            c[i] = parse_double(line, line[line.size() == 2 ? 1 : 1 + i], line[0]);
        return c;
    }

    void mtl_statement(const Line& line, MtlEntry& e) {
        const std::string& key = line[0];
        if (key == "Kd") {
            Rgb kd = mtl_colour(line);
            // One fault per statement, named by its first channel out of range.
            for (int i = 0; i < 3; ++i)
                if (!(kd[i] >= 0 && kd[i] < 1)) {
                    fault(line, "value clamped",
                          "Kd " + fmt(kd[i]) +
                              " is outside [0, 1): a reflectance of 1 or more makes the "
                              "radiosity iteration diverge (scale the colour below 1)",
                          "every channel is clamped to [0, " + fmt(max_clamped_reflectance) + "]");
                    for (int k = 0; k < 3; ++k)
                        kd[k] = std::clamp(kd[k], 0.0, max_clamped_reflectance);
                    break;
                }
            e.kd = kd;
            e.has_kd = true;
        } else if (key == "Ke") {
            Rgb ke = mtl_colour(line);
            const double limit = max_emission / Pi;  // the scene format's limit of E = pi Ke
            for (int i = 0; i < 3; ++i)
                if (ke[i] < 0 || ke[i] > limit) {
                    fault(line, "value clamped",
                          ke[i] < 0 ? "Ke " + fmt(ke[i]) + " is negative"
                                    : "Ke " + fmt(ke[i]) + " exceeds the limit " + fmt(limit) +
                                          " (the emission E = pi Ke is at most " +
                                          fmt(max_emission) + ")",
                          "every channel is clamped to [0, " + fmt(limit) + "]");
                    for (int k = 0; k < 3; ++k) ke[k] = std::clamp(ke[k], 0.0, limit);
                    break;
                }
            e.ke = ke;
        } else if (key == "map_Kd" || key == "map_Ke") {
            // Options (-s, -o, -bm, ...) come first; the file name is the last token.
            if (line.size() < 2) line.fail(in_quotes(key) + " needs a file name");
            (key == "map_Kd" ? e.map_kd : e.map_ke) = line[line.size() - 1];
            (key == "map_Kd" ? e.map_kd_line : e.map_ke_line) = line;
        } else if (key == "Ks" || key == "Tf") {
            if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz")) return;
            const Rgb c = mtl_colour(line);
            (key == "Ks" ? e.ks : e.tf) = c;
        } else if (key == "Ka") {
            if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz")) return;
            mtl_colour(line);
        } else if (key == "Ns" || key == "Ni" || key == "Tr" || key == "illum" ||
                   key == "sharpness" || key == "Pr" || key == "Pm" || key == "Ps" || key == "Pc" ||
                   key == "Pcr" || key == "aniso" || key == "anisor") {
            if (line.size() != 2)
                line.fail(in_quotes(key) + " needs one number, found " +
                          std::to_string(line.size() - 1));
            const double x = parse_double(line, line[1], key);
            if (key == "illum") e.illum = (x >= 0 && x <= 10) ? int(x) : -1;
        } else if (key == "d") {
            size_t i = (line.size() == 3 && line[1] == "-halo") ? 2 : 1;
            if (line.size() != i + 1) line.fail("'d' needs one number");
            parse_double(line, line[i], key);
        } else if (key.compare(0, 4, "map_") == 0 || key == "bump" || key == "disp" ||
                   key == "decal" || key == "refl" || key == "norm") {
            if (line.size() < 2) line.fail(in_quotes(key) + " needs a file name");
        } else {
            line.fail("unknown MTL statement " + in_quotes(key));
        }
    }

    /// The image `file` named on `line`, scaled, or (forgiving) found elsewhere by locate(),
    /// or replaced by the constant `replacement` when it cannot be read.
    Texture mtl_texture(const Line& line, const std::string& file, Rgb scale, Rgb replacement) {
        std::string path = resolve(line.file, file);
        if (strict()) return state_.image(line, path).scaled(scale);
        if (!file_problem(path).empty()) {
            const std::string found = locate(line.file, file);
            if (!found.empty()) {
                warn("texture found elsewhere", line.file, line.number,
                     "texture " + in_quotes(path) + " is not there; " + in_quotes(found) +
                         " is read instead");
                path = found;
            }
        }
        try {
            return state_.image(line, path).scaled(scale);
        } catch (const InputError& e) {
            warn("texture replaced", e.file(), e.line(),
                 e.message() + "; the material's colour " + colour_text(replacement) +
                     " is used instead");
            return Texture::constant(replacement);
        }
    }

    static std::string colour_text(Rgb c) {
        return fmt_approx(c.r) + " " + fmt_approx(c.g) + " " + fmt_approx(c.b);
    }

    /// The material an MTL entry describes (docs/scene-format.md, "OBJ import"): Kd (or map_Kd
    /// scaled by Kd; a black or missing Kd beside a map_Kd is read as exporters mean it, the
    /// texture alone giving the colour, scaled by 0.9) is the reflectance; Ke (or map_Ke) is
    /// the emitted radiance, E = pi Ke. A specular or transmitting material (Ks, Tf) without a
    /// diffuse colour is treated as diffuse with the specular colour as its albedo; one with
    /// both keeps the diffuse part. Either is reported.
    void finish_material(const MtlEntry& e) {
        if (material_index_.count(e.name)) {
            if (strict()) e.newmtl_line.fail("duplicate material " + in_quotes(e.name));
            warn("duplicate material", e.newmtl_line.file, e.newmtl_line.number,
                 "duplicate material " + in_quotes(e.name) +
                     "; the first definition is kept and this one is skipped");
            return;
        }
        Material m;
        m.name = e.name;
        const bool black_kd = e.has_kd && max_abs(e.kd) == 0;
        const Rgb specular{std::max(e.ks.r, e.tf.r), std::max(e.ks.g, e.tf.g),
                           std::max(e.ks.b, e.tf.b)};
        const std::string illum =
            e.illum >= 0 ? ", illum " + std::to_string(e.illum) : std::string();
        if (!e.map_kd.empty()) {
            Rgb scale = e.has_kd && !black_kd ? e.kd : Rgb{0.9, 0.9, 0.9};
            m.reflectance = mtl_texture(e.map_kd_line, e.map_kd, scale,
                                        e.has_kd && !black_kd ? e.kd : Rgb{0.5, 0.5, 0.5});
        } else if ((black_kd || !e.has_kd) && max_abs(specular) > 0) {
            Rgb albedo;
            for (int i = 0; i < 3; ++i) albedo[i] = std::min(specular[i], max_clamped_reflectance);
            m.reflectance = Texture::constant(albedo);
            warn("specular material", e.newmtl_line.file, e.newmtl_line.number,
                 "material " + in_quotes(e.name) + " is specular or transparent (" +
                     (max_abs(e.ks) > 0 ? "Ks " + colour_text(e.ks) : std::string()) +
                     (max_abs(e.ks) > 0 && max_abs(e.tf) > 0 ? ", " : "") +
                     (max_abs(e.tf) > 0 ? "Tf " + colour_text(e.tf) : std::string()) + illum +
                     "); mbr reflects diffusely only: treated as diffuse, albedo " +
                     colour_text(albedo));
        } else {
            m.reflectance = Texture::constant(e.kd);
            if (max_abs(e.ks) > 0)
                warn("specular part dropped", e.newmtl_line.file, e.newmtl_line.number,
                     "material " + in_quotes(e.name) + " has a specular part (Ks " +
                         colour_text(e.ks) + illum + ") beside Kd " + colour_text(e.kd) +
                         "; mbr reflects diffusely only and keeps Kd");
        }
        // MTL's Ke is emitted radiance (as in the common Cornell box files); E = pi L.
        if (!e.map_ke.empty()) {
            bool any = max_abs(e.ke) > 0;
            const Rgb scale = Pi * (any ? e.ke : Rgb{1, 1, 1});
            m.emission = mtl_texture(e.map_ke_line, e.map_ke, scale, scale);
        } else {
            m.emission = Texture::constant(Pi * e.ke);
        }
        material_index_[e.name] = int(scene_.materials.size());
        scene_.materials.push_back(std::move(m));
    }

    std::string name_;
    std::vector<Vec3> v_;                    // x is NaN for an unusable vertex
    std::vector<std::array<double, 2>> vt_;  // u is NaN for an unusable one
    long long n_vn_ = 0;
    std::unordered_map<std::string, int> material_index_;
    int material_ = -1;
    std::string group_;
};

}  // namespace

namespace detail {

// ---------------------------------------------------------------------------------------------
// === Files shared by one load

void LoadState::charge(const Line& line) {
    if (++n_files_ > max_files_read)
        line.fail("more than " + std::to_string(max_files_read) +
                  " files are read by this scene (includes, OBJ, MTL, textures)");
}

void ImportReader::warn(const std::string& kind, const std::string& file, int line,
                        const std::string& message) {
    SceneWarning w;
    w.kind = kind;
    w.file = file;
    w.line = line;
    w.message = message;
    scene_.warn(w);
}

void ImportReader::fault(const Line& line, const std::string& kind, const std::string& message,
                         const std::string& then) {
    if (strict()) line.fail(message);
    warn(kind, line.file, line.number, message + "; " + then);
}

void ImportReader::record_face(size_t first, const std::vector<Vec3>& corners, size_t n_quads) {
    if (corners.size() == 3 && n_quads == 3)
        triangles_.push_back({first, {corners[0], corners[1], corners[2]}});
}

void ImportReader::join_triangle_pairs() {
    if (triangles_.empty() || !state_.options().join_triangles) return;
    // Groups: one per (material, name) of the triangles' first quads. A textured material's
    // triangles stay apart (each quad shows its image over its own (u, v) square, or through
    // its own copy of the material), each in a group of its own.
    std::map<std::pair<int, std::string>, int> groups;
    std::vector<Triangle> triangles;
    for (const auto& [first, corners] : triangles_) {
        const SceneSurface& s = scene_.surfaces[first];
        const Material& m = scene_.materials[size_t(s.material)];
        const bool textured = !m.reflectance.is_constant() || !m.emission.is_constant();
        const int group =
            textured ? -1 - int(triangles.size())
                     : groups.emplace(std::make_pair(s.material, s.name), int(groups.size()))
                           .first->second;
        triangles.push_back({corners, group});
    }
    const TrianglePairs pairs = pair_triangles(triangles);
    std::vector<char> drop(scene_.surfaces.size(), 0);
    for (size_t t = 0; t < triangles_.size(); ++t) {
        const int u = pairs.partner[t];
        if (u < 0 || size_t(u) < t) continue;
        const size_t first = triangles_[t].first, other = triangles_[size_t(u)].first;
        const Quad& q = pairs.quad[t];
        scene_.surfaces[first].surface = Surface::planar_quad(q[0], q[1], q[2], q[3]);
        drop[first + 1] = drop[first + 2] = 1;
        drop[other] = drop[other + 1] = drop[other + 2] = 1;
    }
    remove_surfaces(scene_, drop);
    triangles_.clear();
}

Scene ImportReader::finish() {
    join_triangle_pairs();
    number_surface_names(scene_);
    scene_.input_files = state_.files();
    return std::move(scene_);
}

void number_surface_names(Scene& scene) {
    std::unordered_map<std::string, int> count, next;
    for (const SceneSurface& s : scene.surfaces) ++count[s.name];
    std::unordered_set<std::string> taken;
    for (const auto& [name, n] : count)
        if (n == 1) taken.insert(name);
    for (SceneSurface& s : scene.surfaces) {
        if (count[s.name] == 1) continue;
        int& k = next[s.name];
        std::string numbered;
        do numbered = s.name + "." + std::to_string(k++);
        while (!taken.insert(numbered).second);
        s.name = std::move(numbered);
    }
}

Texture LoadState::image(const Line& line, const std::string& path) {
    const std::string key = canonical_name(path);
    auto cached = textures_.find(key);
    if (cached != textures_.end()) return cached->second;
    charge(line);
    std::string problem = file_problem(path);
    if (!problem.empty()) line.fail("texture " + in_quotes(path) + ": " + problem);
    record(path);
    Texture texture;
    try {
        texture = Texture::image(path);
    } catch (const InputError& e) {
        line.fail("texture " + in_quotes(path) + ": " + e.message());
    }
    textures_.emplace(key, texture);
    return texture;
}

Scene read_obj(std::istream& in, const std::string& name, LoadState& state) {
    return ObjReader(name, state).read(in);
}

}  // namespace detail

// An OBJ file read on its own is checked for repeated faces here; imported into a scene, by the
// scene reader, with the scene's other surfaces.
Scene parse_obj(std::istream& in, const std::string& name, const ImportOptions& options) {
    LoadState state(options);
    Scene scene = read_obj(in, name, state);
    repair_loaded_scene(scene, options);
    return scene;
}

Scene load_obj(const std::string& path, const ImportOptions& options) {
    std::ifstream in;
    open_top(path, in);
    LoadState state(options);
    state.record(path);
    Scene scene = read_obj(in, path, state);
    repair_loaded_scene(scene, options);
    return scene;
}

bool is_obj_path(const std::string& path) {
    return lowercase_extension(path) == ".obj";
}

}  // namespace mbr
