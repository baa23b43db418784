// radiosity/scene/scene.h - the scene model as plain structs (DESIGN.md sections 1, 4, 5): materials
// with reflectance rho_i and emission E_i (eq. (1)), surfaces on [0,1]^2 (section 2), a camera,
// and the solver settings of the progressive loop (section 4) and the receiver pipeline
// (section 5). Reading and validating scene files is scene_io.h's work.
#pragma once

#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/geometry/texture.h"

namespace mbr {

/// A Lambertian material. Reflectance channels lie in [0,1); emission is the emitted radiosity
/// E of eq. (1) (power per area, pi times the emitted radiance), each channel >= 0.
struct Material {
    std::string name;
    Texture reflectance;  // rho(u,v), channels in [0, 1)
    Texture emission;     // E(u,v), channels >= 0
    /// True when some channel of the emission is positive somewhere.
    bool emits() const { return max_abs(emission.maximum()) > 0; }
};

/// One surface of the scene and the index of its material in Scene::materials.
struct SceneSurface {
    std::string name;
    Surface surface;
    int material = -1;
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

/// Options of the solver: the progressive loop (section 4) and one transfer (section 5).
struct SolverSettings {
    int order = 4;                         // B-spline order m (degree m - 1); the paper uses 4, 3
    int min_depth = 1;                     // oracle quadtree bounds; min = max = d is uniform
    int max_depth = 6;                     // (d = subdivisions below the root: leaves 2^-d wide)
    double oracle_tolerance = 1e-3;        // relative agreement of the two Gauss-Legendre rules
    double truncation_eps = 1e-6;          // relative cut-off of |DN x DN| (rhombus, Figure 3)
    double rhombus_radius = 0;             // in cells; 0: derived from truncation_eps
    std::string extrapolation = "linear";  // "linear" (23)-(25) or "higher" (26)-(27)
    int shadow_rays = 4;                   // rays per fulcrum per shooter patch, eq. (28)
    int max_shots = 100;                   // cap on progressive shots
    double convergence = 1e-3;             // stop when unshot power < this x emitted power
    bool self_transfer = false;            // may a concave curved surface light itself
    int tessellation = 16;                 // facets per parameter direction for ray casting
    std::string shadows = "exact";         // "exact" (visibility inside (21)), "paper"
                                           //   (fractions (28) and masking) or "none"
    double tolerance = 2e-3;               // accuracy relative to the scene's radiosity scale
    std::string unify = "projection";      // "projection" (every finest coefficient on the fine
                                           //   grid) or "paper" ((17) from selected fulcrums)
    bool ambient = true;                   // ambient correction of the unshot power at the end
    bool hidden = true;                    // hidden regions take their visible neighbours' values
    int shooter_level = 3;                 // a shooter's unshot field coarsened to at most this
                                           //   level (section 6's "lower resolution version")
    int contact_depth = 2;                 // receiver cells touching a planar shooter split to
                                           //   at least this level (0: off)
    std::string contact_oracle = "means";  // the oracle's test in cells touching a planar
                                           //   shooter: "means" (the paper's test) or
                                           //   "interpolation" (the polynomial through the m^2
                                           //   samples predicts the others: sees the d log d
                                           //   growth at a contact, costs more)
};

/// A whole scene. Surface i's material is materials[surfaces[i].material].
struct Scene {
    std::vector<Material> materials;
    std::vector<SceneSurface> surfaces;
    Camera camera;
    bool has_camera = false;
    SolverSettings settings;

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
};

}  // namespace mbr
