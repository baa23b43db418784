// radiosity/solver/superposition.h - relighting by superposition (paper section 8: "superposition
// can be easily performed"). Equation (1) is linear in the emission E: the radiosity of a scene
// lit by several lights is the sum of the radiosities of the scene lit by each light alone, and
// a weighted sum of those is the radiosity of the scene with each light's emission multiplied by
// its weight. So each light group is solved once, and any combination of them is rendered
// without solving again (docs/solution-format.md, "Light groups"; mbr render --light-group).
//
// A light group is an emitting material: every surface of that material belongs to it. The
// material's name is the group's name (in OBJ files the name of usemtl), so no scene statement
// is needed. A group's solve is the solve of light_group_scene(): the scene with every other
// emitting material's emission switched off and every reflectance kept, so that the other lamps
// still reflect the group's light.
#pragma once

#include <string>
#include <vector>

#include "radiosity/scene/scene.h"
#include "radiosity/solver/solver.h"

namespace mbr {

/// A light group: an emitting material and the surfaces made of it.
struct LightGroup {
    std::string name;           // the material's name
    int material = -1;          // its index in Scene::materials
    std::vector<int> surfaces;  // the surfaces of that material, in scene order
};

/// The scene's light groups, in the order of its materials: every emitting material that at
/// least one surface uses (an emitting material no surface uses lights nothing and is none).
std::vector<LightGroup> light_groups(const Scene& scene);

/// The scene with groups[g]'s emission multiplied by weights[g] (finite, >= 0), channel by
/// channel; a weight of 1 leaves the material as it is (the same bits), 0 makes its emission the
/// constant black. Reflectance, surfaces, camera and settings are unchanged.
Scene weighted_scene(const Scene& scene, const std::vector<LightGroup>& groups,
                     const std::vector<double>& weights);

/// The scene lit by `group` alone: weighted_scene with weight 1 for it and 0 for every other
/// group. Its solution is the group's solution, and its fingerprint (solution_file.h) is the one
/// the group's solution file carries.
Scene light_group_scene(const Scene& scene, const std::vector<LightGroup>& groups, int group);

/// The weighted sum of solutions of one scene's light groups, sum_g weights[g] solutions[g]
/// (weights finite and >= 0): per surface, the radiosity fields and the unshot fields added
/// (SplineField::add refines the coarser to the finer level by eq. (17); a zero weight adds
/// nothing), the quadtree leaves the union of the trees of the solutions of positive weight (a
/// cell is split when one of them split it). Every other per-surface member of Solution is
/// copied from the first solution (the solutions are of one scene, so they agree; each surface
/// must hold the same FieldQuantity in all of them, an MBR_CHECK). The run
/// statistics are the weighted sums of the powers (emitted, unshot, ambient), the sums of the
/// counts (shots, seconds, kernel evaluations, rays), the largest peak memory, the coefficients of
/// the sum, converged when every solution of positive weight converged, and no per-shot rows.
/// Since each solution holds its group's emission times one, the sum holds each group's emission
/// times its weight: the solution of weighted_scene(scene, groups, weights), up to the solves'
/// tolerance. View it with that scene (radiosity_view(weighted_scene(...), sum)): a surface that
/// stores the irradiance H takes its emission E from the scene it is viewed with.
Solution combine(const std::vector<const Solution*>& solutions, const std::vector<double>& weights);

}  // namespace mbr
