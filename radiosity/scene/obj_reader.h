// radiosity/scene/obj_reader.h - Wavefront OBJ + MTL import (docs/scene-format.md, "OBJ import"):
// vertices and faces to the planar quads of paper section 2, Kd and Ke to the reflectance rho
// and emission E of eq. (1). Every bad input becomes one InputError naming the file and line.
#pragma once

#include <algorithm>
#include <array>
#include <iosfwd>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "radiosity/scene/line_reader.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// Imports a Wavefront OBJ file and the MTL libraries it names (docs/scene-format.md, "OBJ
/// import"): Kd -> reflectance, Ke (emitted radiance) -> emission E = pi Ke, every face ->
/// one or more planar quads. A face that repeats another (same corners, same front side) is
/// dropped with a warning in Scene::warnings, or refused when its material differs
/// (duplicate_faces.h). The scene has no camera and default settings. Throws InputError.
/// Faults in the OBJ, its MTL libraries and their textures are repaired with warnings, or
/// refused when options.strict (ImportOptions, scene.h).
Scene load_obj(const std::string& path, const ImportOptions& options = {});

/// Parses OBJ text from a stream; `name` is used in messages and to resolve `mtllib` paths.
Scene parse_obj(std::istream& in, const std::string& name, const ImportOptions& options = {});

/// True when `path` names an OBJ file: its extension is .obj in any case (.OBJ, .Obj).
bool is_obj_path(const std::string& path);

namespace detail {

/// The material of OBJ faces before any `usemtl`; a scene that imports several OBJ files
/// shares one.
constexpr const char* obj_default_material = "obj_default";

/// What the readers of one top-level load share: the count of files opened, which bounds
/// exponential include trees, the files opened so far, and the texture images decoded so far.
class LoadState {
public:
    explicit LoadState(const ImportOptions& options = {}) : options_(options) {}
    /// How faults in imported files are treated.
    const ImportOptions& options() const { return options_; }

    /// Counts one more file read on behalf of `line` (at most 1000 per load).
    void charge(const Line& line);

    /// Records that the file at `path` was opened (Scene::input_files), once however often.
    void record(const std::string& path) {
        if (std::find(files_.begin(), files_.end(), path) == files_.end()) files_.push_back(path);
    }

    /// The files recorded so far, in the order opened.
    const std::vector<std::string>& files() const { return files_; }

    /// The image file at `path` (resolved), unscaled. Each file is read and decoded once per
    /// load, however many materials name it (a big image costs its memory once, not once per
    /// material); later requests share its texels and are not charged as files read.
    Texture image(const Line& line, const std::string& path);

private:
    ImportOptions options_;
    int n_files_ = 0;
    std::vector<std::string> files_;                     // paths opened, in order
    std::unordered_map<std::string, Texture> textures_;  // canonical path -> decoded image
};

/// Names the surfaces of an import uniquely: a group (an OBJ group, an MGF object) that yields
/// one surface gives it its own name; the surfaces of a group that yields several are NAME.0,
/// NAME.1, ... in file order, skipping every number whose name is already taken (by a group of
/// that name, say `a.0` next to a group `a` of two faces).
void number_surface_names(Scene& scene);

/// What the OBJ and MGF readers share: the load's state, the scene being read, and the
/// forgiving import's warnings and faults (ImportOptions).
class ImportReader {
protected:
    explicit ImportReader(LoadState& state) : state_(state) {}

    bool strict() const { return state_.options().strict; }
    /// A repaired fault's record: one warning of `kind` (Scene::warn keeps the first instance
    /// and counts the rest).
    void warn(const std::string& kind, const std::string& file, int line,
              const std::string& message);
    /// A fault met at `line`: refused (InputError) when the import is strict, else a warning of
    /// `kind` saying `message` and what the import does instead (`then`).
    void fault(const Line& line, const std::string& kind, const std::string& message,
               const std::string& then);
    /// The scene read, its surfaces named uniquely (number_surface_names) and the files opened
    /// recorded (Scene::input_files).
    Scene finish();
    /// Called with each face's corners (in the face's turn) and the number of quads
    /// face_to_quads made of it, added from surface `first` on: a triangle's three quads are
    /// recorded, so that finish() may join it with a neighbour of the same material and name
    /// into one quad (pair_triangles, faces_to_quads.h).
    void record_face(size_t first, const std::vector<Vec3>& corners, size_t n_quads);

    LoadState& state_;
    Scene scene_;

private:
    /// Joins the recorded triangles in pairs (docs/scene-format.md, "Triangle pairs"): the
    /// first triangle's first quad becomes the pair's quad, the pair's other five go.
    void join_triangle_pairs();

    std::vector<std::pair<size_t, std::array<Vec3, 3>>> triangles_;  // (first surface, corners)
};

/// Reads OBJ text named `name` as part of the load `state` (parse_obj with a shared state),
/// without the check for repeated faces, which the caller runs once on the whole scene.
Scene read_obj(std::istream& in, const std::string& name, LoadState& state);

}  // namespace detail

}  // namespace mbr
