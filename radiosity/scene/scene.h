// radiosity/scene/scene.h - the scene model as plain structs (DESIGN.md sections 1, 4, 5):
// materials with reflectance rho_i and emission E_i (eq. (1)), surfaces on [0,1]^2 (section 2), a
// camera, and the solver settings of its `set` lines (settings.h). Reading and validating scene
// files is scene_io.h's work.
#pragma once

#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/geometry/texture.h"
#include "radiosity/scene/settings.h"

namespace mbr {

/// The largest emission channel E of eq. (1) that the readers accept, from the scene format's
/// `emission` and from MTL's Ke alike (E = pi Ke): far beyond any light's, yet small enough that
/// the solver's sums of E x area (areas up to max_coordinate^2) and their squares stay finite.
constexpr double max_emission = 1e30;

/// A Lambertian material. Reflectance channels lie in [0,1); emission is the emitted radiosity
/// E of eq. (1) (power per area, pi times the emitted radiance), each channel in
/// [0, max_emission].
struct Material {
    std::string name;
    Texture reflectance;  // rho(u,v), channels in [0, 1)
    Texture emission;     // E(u,v), channels >= 0
    /// Surfaces of this material are two-sided: each gets a twin facing the other way
    /// (add_back_sides, light_sides.h), so that it emits and reflects on both sides.
    bool two_sided = false;
    /// True when some channel of the emission is positive somewhere.
    bool emits() const { return max_abs(emission.maximum()) > 0; }
};

/// One surface of the scene, the index of its material in Scene::materials and where its
/// statement is (Scene::where): the readers set source and line; a surface made in code has -1
/// and 0.
struct SceneSurface {
    std::string name;
    Surface surface;
    int material = -1;
    int source = -1;  // index into Scene::sources: the file of its statement
    int line = 0;     // the statement's line there (1-based)
    /// The B-spline order m of this surface's fields, 2..8 (its statement's `order M`), or 0:
    /// the scene's order (`set order`, `--order`; SolverSettings::order). "On different
    /// surfaces in an environment, different B-spline bases can be used" (paper section 3).
    int order = 0;
};

/// Something the readers accepted but the user should hear of (a repeated surface they
/// dropped, say). A load keeps one warning per kind: the first instance's place and message,
/// and how many instances there were (Scene::warn). The programs print them once after loading,
/// each as "warning: " + text().
struct SceneWarning {
    std::string kind;     // a short fixed phrase naming the kind ("duplicate surface")
    std::string file;     // the first instance's file ("" when none)
    int line = 0;         // and its line (0: the file as a whole)
    std::string message;  // the first instance, in the input's terms
    long count = 1;       // instances of this kind in the load

    /// "FILE:LINE: MESSAGE", with " (and N more like it)" when count > 1.
    std::string text() const;
};

/// How the readers treat faults in imported files: OBJ, its MTL libraries and the textures
/// they name (docs/scene-format.md, "A forgiving import"). By default a fault is repaired where
/// the file's intent is clear (a value clamped into range, a degenerate face dropped, a missing
/// texture replaced by its material's colour, a stray statement skipped), each kind with one
/// warning in Scene::warnings; strict refuses the first fault with an InputError at its line.
/// mbr's own scene format is always read strictly.
struct ImportOptions {
    bool strict = false;
    /// Triangles that make a planar quad with a neighbour of the same material and name become
    /// that one quad (docs/scene-format.md, "Triangle pairs"); false keeps every triangle as
    /// three quads, as written (`--keep-triangles`).
    bool join_triangles = true;
};

/// A pinhole camera. A right-handed frame: the image's right is (look_at - eye) x up.
struct Camera {
    Vec3 eye{0, 0, 1};        // centre of projection
    Vec3 look_at{0, 0, 0};    // a point on the optical axis
    Vec3 up{0, 1, 0};         // projects to the image's upward direction
    double fov_degrees = 45;  // vertical field of view, in (0, 180)
    int width = 512;          // image size in pixels
    int height = 512;         // (the aspect ratio is width / height)
};

/// A whole scene. Surface i's material is materials[surfaces[i].material].
struct Scene {
    std::vector<Material> materials;
    std::vector<SceneSurface> surfaces;
    Camera camera;
    bool has_camera = false;
    SolverSettings settings;  // the scene's `set` lines (radiosity/scene/settings.h)
    /// Every file the readers opened for this scene, in the order read, as the paths opened:
    /// the scene or OBJ file itself (when loaded from a file), includes, OBJ files, MTL
    /// libraries and texture images (each image once, however many materials name it).
    std::vector<std::string> input_files;
    /// The files that surface statements came from (SceneSurface::source), each once: the
    /// scene file, includes and OBJ files, as the readers named them (a parsed stream by its
    /// name).
    std::vector<std::string> sources;
    /// What the readers accepted with a warning, one per kind, in the order first met.
    std::vector<SceneWarning> warnings;

    /// Index of the material called `name`, or -1.
    int find_material(const std::string& name) const;
    /// Index of the first surface called `name`, or -1.
    int find_surface(const std::string& name) const;
    /// The material of surface i.
    const Material& material_of(int surface) const;
    /// Indices of the surfaces whose material emits.
    std::vector<int> emitters() const;
    /// Sum of the surfaces' areas.
    double total_area() const;
    /// Total emitted power per channel: sum over emitters of mean(E) x area (exact for constant
    /// emission; for textured emission it ignores the correlation of E with A(u,v)).
    Rgb emitted_power() const;
    /// A box containing every surface (empty when there are none).
    Box3 bounds() const;
    /// "FILE:LINE" of surface i's statement, or its name in quotes when it was made in code.
    std::string where(int surface) const;
    /// Records a warning: a new kind is appended; a kind already recorded keeps its first
    /// instance and adds w.count to its count.
    void warn(const SceneWarning& w);
};

/// The order m of surface i's fields: its own `order M`, else `global_order` (the solver's,
/// SolverOptions::receiver.m, which `set order` and `--order` give).
int surface_order(const Scene& scene, int surface, int global_order);
/// The same with the scene's `set order` (SolverSettings::order) as the global order.
int surface_order(const Scene& scene, int surface);

/// Removes the surfaces whose entry of `drop` (one per surface) is non-zero; the others keep
/// their order.
void remove_surfaces(Scene& scene, const std::vector<char>& drop);

}  // namespace mbr
