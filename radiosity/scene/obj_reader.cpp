// radiosity/scene/obj_reader.cpp - OBJ + MTL import (obj_reader.h): OBJ statements line by line,
// each face to planar quads (faces_to_quads.h), MTL materials to reflectance and emission.
#include "radiosity/scene/obj_reader.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <unordered_set>

#include "math/check.h"
#include "radiosity/scene/duplicate_faces.h"
#include "radiosity/scene/faces_to_quads.h"

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
    Rgb kd{0.5, 0.5, 0.5}, ke{0, 0, 0};
    bool has_kd = false;
    std::string map_kd, map_ke;
    Line map_kd_line, map_ke_line;
};

class ObjReader {
public:
    ObjReader(std::string name, LoadState& state) : name_(std::move(name)), state_(state) {
        group_ = fs::path(name_).stem().string();
        if (group_.empty()) group_ = "obj";
        scene_.sources = {name_};  // every surface's statement is in this file
    }

    Scene read(std::istream& in) {
        LineReader reader(in, name_);
        Line line;
        while (reader.next(line)) statement(line);
        if (scene_.surfaces.empty()) throw InputError(name_, 0, "the OBJ file has no faces");
        name_surfaces();
        scene_.input_files = state_.files();
        return std::move(scene_);
    }

private:
    void statement(const Line& line) {
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
        } else if (key == "vt" || key == "vp") {
            if (line.size() < 2 || line.size() > 4)
                line.fail("'" + key + "' needs 1 to 3 numbers, found " +
                          std::to_string(line.size() - 1));
            for (size_t i = 1; i < line.size(); ++i) parse_double(line, line[i], key);
            if (key == "vt") ++n_vt_;
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
            for (size_t i = 1; i < line.size(); ++i) mtllib(line, resolve(name_, line[i]));
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
            p.push_back(v_[size_t(index(line, parts[0], long(v_.size()), "vertex", "vertices"))]);
            if (parts.size() >= 2 && !parts[1].empty())
                index(line, parts[1], n_vt_, "texture vertex", "texture vertices");
            if (parts.size() == 3) index(line, parts[2], n_vn_, "normal", "normals");
        }
        if (material_ < 0) material_ = default_material();
        for (const Quad& q : face_to_quads(line, p)) {
            SceneSurface s;
            s.name = group_;
            s.surface = Surface::planar_quad(q[0], q[1], q[2], q[3]);
            s.material = material_;
            s.source = 0;
            s.line = line.number;
            scene_.surfaces.push_back(std::move(s));
        }
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

    /// A group that yields one surface gives it its own name; the surfaces of a group that
    /// yields several are NAME.0, NAME.1, ... in file order, skipping every number whose name is
    /// already taken (by a group of that name, say `a.0` next to a group `a` of two faces), so
    /// that every name is unique.
    void name_surfaces() {
        std::unordered_map<std::string, int> count, next;
        for (const SceneSurface& s : scene_.surfaces) ++count[s.name];
        std::unordered_set<std::string> taken;
        for (const auto& [name, n] : count)
            if (n == 1) taken.insert(name);
        for (SceneSurface& s : scene_.surfaces) {
            if (count[s.name] == 1) continue;
            int& k = next[s.name];
            std::string numbered;
            do numbered = s.name + "." + std::to_string(k++);
            while (!taken.insert(numbered).second);
            s.name = std::move(numbered);
        }
    }

    void mtllib(const Line& at, const std::string& path) {
        state_.charge(at);
        std::ifstream in;
        open_named(at, "material library", path, in);
        state_.record(path);
        LineReader reader(in, path);
        Line line;
        MtlEntry entry;
        bool open = false;
        while (reader.next(line)) {
            const std::string& key = line[0];
            if (key == "newmtl") {
                if (open) finish_material(entry, path);
                if (line.size() != 2) line.fail("'newmtl' needs one material name");
                entry = MtlEntry();
                entry.name = line[1];
                entry.newmtl_line = line;
                open = true;
                continue;
            }
            if (!open) line.fail(in_quotes(key) + " before any 'newmtl'");
            mtl_statement(line, entry, path);
        }
        if (open) finish_material(entry, path);
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

    static void mtl_statement(const Line& line, MtlEntry& e, const std::string&) {
        const std::string& key = line[0];
        if (key == "Kd") {
            Rgb kd = mtl_colour(line);
            for (int i = 0; i < 3; ++i)
                if (!(kd[i] >= 0 && kd[i] < 1))
                    line.fail("Kd " + fmt(kd[i]) +
                              " is outside [0, 1): a reflectance of 1 or more makes the "
                              "radiosity iteration diverge (scale the colour below 1)");
            e.kd = kd;
            e.has_kd = true;
        } else if (key == "Ke") {
            Rgb ke = mtl_colour(line);
            for (int i = 0; i < 3; ++i) {
                if (ke[i] < 0) line.fail("Ke " + fmt(ke[i]) + " is negative");
                // The scene format's limit on the emission E = pi Ke (scene.h).
                if (Pi * ke[i] > max_emission)
                    line.fail("Ke " + fmt(ke[i]) + " exceeds the limit " + fmt(max_emission / Pi) +
                              " (the emission E = pi Ke is at most " + fmt(max_emission) + ")");
            }
            e.ke = ke;
        } else if (key == "map_Kd" || key == "map_Ke") {
            // Options (-s, -o, -bm, ...) come first; the file name is the last token.
            if (line.size() < 2) line.fail(in_quotes(key) + " needs a file name");
            (key == "map_Kd" ? e.map_kd : e.map_ke) = line[line.size() - 1];
            (key == "map_Kd" ? e.map_kd_line : e.map_ke_line) = line;
        } else if (key == "Ka" || key == "Ks" || key == "Tf") {
            if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz")) return;
            mtl_colour(line);
        } else if (key == "Ns" || key == "Ni" || key == "Tr" || key == "illum" ||
                   key == "sharpness" || key == "Pr" || key == "Pm" || key == "Ps" || key == "Pc" ||
                   key == "Pcr" || key == "aniso" || key == "anisor") {
            if (line.size() != 2)
                line.fail(in_quotes(key) + " needs one number, found " +
                          std::to_string(line.size() - 1));
            parse_double(line, line[1], key);
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

    Texture mtl_texture(const Line& line, const std::string& file, Rgb scale) {
        return state_.image(line, resolve(line.file, file)).scaled(scale);
    }

    void finish_material(const MtlEntry& e, const std::string&) {
        if (material_index_.count(e.name))
            e.newmtl_line.fail("duplicate material " + in_quotes(e.name));
        Material m;
        m.name = e.name;
        if (!e.map_kd.empty()) {
            Rgb scale = e.has_kd ? e.kd : Rgb{0.9, 0.9, 0.9};
            m.reflectance = mtl_texture(e.map_kd_line, e.map_kd, scale);
        } else {
            m.reflectance = Texture::constant(e.kd);
        }
        // MTL's Ke is emitted radiance (as in the common Cornell box files); E = pi L.
        if (!e.map_ke.empty()) {
            bool any = max_abs(e.ke) > 0;
            m.emission = mtl_texture(e.map_ke_line, e.map_ke, Pi * (any ? e.ke : Rgb{1, 1, 1}));
        } else {
            m.emission = Texture::constant(Pi * e.ke);
        }
        material_index_[e.name] = int(scene_.materials.size());
        scene_.materials.push_back(std::move(m));
    }

    std::string name_;
    LoadState& state_;
    Scene scene_;
    std::vector<Vec3> v_;
    long long n_vt_ = 0, n_vn_ = 0;
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
Scene parse_obj(std::istream& in, const std::string& name) {
    LoadState state;
    Scene scene = read_obj(in, name, state);
    drop_duplicate_surfaces(scene);
    return scene;
}

Scene load_obj(const std::string& path) {
    std::ifstream in;
    open_top(path, in);
    LoadState state;
    state.record(path);
    Scene scene = read_obj(in, path, state);
    drop_duplicate_surfaces(scene);
    return scene;
}

}  // namespace mbr
