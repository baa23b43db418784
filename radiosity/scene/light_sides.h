// radiosity/scene/light_sides.h - which side a light shines from (docs/scene-format.md, "Light
// sides"). Surfaces are one-sided (eq. (1): a surface emits and reflects on its front), so an
// imported face wound the wrong way shines into the ceiling it hangs below, and a lamp meant to
// shine both ways needs its back made. Both are fixed here, once the scene is read.
#pragma once

#include <vector>

#include "radiosity/scene/scene.h"

namespace mbr {

/// Gives every surface made of one of `materials` (indices into Scene::materials) a twin
/// facing the other way (Surface::reversed), named NAME.back (NAME.back2, ... when taken), with
/// the same material and statement, appended after the scene's surfaces; marks the materials
/// two_sided.
void add_back_sides(Scene& scene, const std::vector<int>& materials);

/// The materials marked two_sided (Material::two_sided), for add_back_sides.
std::vector<int> two_sided_materials(const Scene& scene);

/// An emitter whose front sees nothing it can light while its back does.
struct BackFacingLight {
    int surface = -1;
    double front_distance = 0;  // median distance to what the front rays hit (inf: nothing)
    double back_distance = 0;   // and the back rays
};

/// The emitters among `candidates` that face the wrong way. From five points of each (its
/// centre and the centres of its quarters) a ray leaves along the normal and one against it; a
/// ray *lights* something when it hits a surface at least a tenth of the emitter's size away
/// (nearer, it lies against that surface: a lamp facing the ceiling it hangs below). A light
/// faces the wrong way when none of its front rays lights anything and at least four of its
/// back rays do. Rays are closest-hit queries of the scene's octree (build_octree).
std::vector<BackFacingLight> find_back_facing_lights(const Scene& scene,
                                                     const std::vector<int>& candidates);

/// The forgiving import's repair of back-facing lights (ImportOptions): every emitter read
/// from an OBJ or MGF file (is_import_path) that find_back_facing_lights names, with a constant
/// emission and reflectance (a texture would be mirrored), is turned around (Surface::reversed),
/// with one warning of kind "light turned around" for the load. Strict, the lights stay as they are
/// and the warning says so ("light faces away").
void face_lights_to_the_open_side(Scene& scene, const ImportOptions& options);

/// What every load does once all its surfaces are in (a scene with its includes and imports, or
/// an OBJ or MGF file on its own): repeated faces dropped (drop_duplicate_surfaces,
/// duplicate_faces.h), imported lights that face away turned round
/// (face_lights_to_the_open_side), and two-sided materials given their backs (add_back_sides).
void repair_loaded_scene(Scene& scene, const ImportOptions& options);

}  // namespace mbr
