// radiosity/solver/ambient_gather.h - the ambient correction gathered (beyond the paper): at the
// end of a solve, the power still unshot, U, and everything it becomes after further bounces are
// gathered by rays at the m x m Gauss-Legendre points of every cell of one level of every
// surface, so that the light the progressive loop did not send lands where it falls, shadows and
// distances included, instead of as a constant per surface (Cohen et al. 1988's ambient term).
// What each surface gains is the L2 projection of its gathered samples at that level
// (docs/method.md, "Ambient correction, gathered").
#pragma once

#include <cstdint>
#include <vector>

#include "octree/octree.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/scene/scene.h"
#include "radiosity/visibility/hidden_regions.h"

namespace mbr {

/// What gather_ambient is given for every surface (in scene order), by reference: the solver's
/// own fields, not a copy of them.
struct AmbientSources {
    const std::vector<SplineField>& unshot;  // U_j, radiosity still unshot (empty or 0: none)
    const std::vector<int>& order;           // each surface's order m
    const std::vector<bool>& irradiance;     // the surface's field holds H (B = E + rho H)
    const std::vector<HiddenMask>& hidden;   // per surface (may be empty: nothing hidden)
};

/// What the gather adds: per surface the field to add to its solution (empty when nothing
/// arrives; H for an irradiance field, B otherwise), the power it adds (sum of channels, by the
/// Gauss rule of the samples), the rays cast and the Jacobi iterations taken.
struct AmbientGather {
    std::vector<SplineField> added;
    double power = 0;
    long rays = 0;
    int iterations = 0;
};

/// The most Jacobi iterations of the gather and their stopping rule: the change of the added
/// power below this share of it.
constexpr int ambient_max_iterations = 100;
constexpr double ambient_iteration_tolerance = 1e-4;

/// The most rays of one gather, all points together (2^24: 192 MiB of kept hits). DESIGN:
/// 256 rays a point at level 1 cost cube.mgf's 196 surfaces 3.1 M rays and 1.3 s on 2 threads;
/// a scene of 9,804 surfaces would need 160 M, so past the cap every point takes fewer (there
/// 26), at least 16.
constexpr double ambient_max_rays = 16777216;
constexpr int ambient_min_rays = 16;

/// Rays per point of a gather asked for `rays` a point over `samples` points: `rays`, or fewer
/// (at least ambient_min_rays, never more than asked) so that all of them stay within
/// ambient_max_rays.
int gather_rays_per_point(int rays, double samples);

/// The memory the gather holds: per sample (4^level m_i^2 of each surface of order m_i) its
/// kept hits (an int and two floats a ray), six colours and a weight.
double ambient_gather_bytes(const std::vector<int>& order, int level, int rays);

/// The finest level the gather takes.
constexpr int max_ambient_level = 4;

/// The memory the final gather holds besides the gather's, at most: per sample of every
/// surface it could refine (at its final_gather_level, when finer than `level`) its kept hits
/// (the two passes share them) and its values.
double final_gather_bytes(const Scene& scene, const std::vector<int>& order, int level, int rays);

/// The gather. At each of the m x m Gauss-Legendre points p of every level-`level` cell of every
/// surface with a reflectance (a hidden point at its substitute),
/// gather_rays_per_point(rays, points) cosine-distributed directions (a Hammersley set
/// shifted per point: stratified, reproducible, independent of the thread count) find the
/// first surface in front; the ray's hit (j, u, v) is kept, a back face or nothing counts 0.
/// The gathered irradiance is the mean over the rays of what leaves the hit (eq. (1) with the
/// cos / pi weights of the directions):
///   H(p) = mean [U_j(u, v) + R_j(u, v)],
///   R_i = l2_projection_of_samples of rho(p) H(p) over i's points (solver.h),
/// solved by Jacobi iteration from R = 0 (U's first bounce, then each further bounce), until
/// the added power changes by less than ambient_iteration_tolerance of itself. The samples
/// projected are rho H (H itself for an irradiance field). `octree` is build_octree(scene).
///
/// The final gather (beyond the gather above, when final_threshold > 0): a surface whose
/// gathered radiosity rho H reaches final_threshold somewhere, and whose cells at `level` are
/// wider than 1 / final_gather_cells of the scene's bounding-box diagonal, gathers once more
/// at the m x m Gauss points of every cell of its final_gather_level, a quarter of the rays
/// a point (final_gather_ray_share), one bounce from what the converged gather makes every surface
/// send (U_j + R_j): the ambient light of a large surface then follows the shadows of what stands
/// near it (a block a third of a unit from a wall ten units wide) instead of one field over half
/// the wall. Its points keep their hits and gather a second time through them, from what the
/// refined surfaces send after the first pass; then the surfaces it did not refine take one
/// more step of the iteration through their own kept hits, from what every surface sends now
/// (the last bounce): a small surface beside a large one sees the large one's ambient light
/// at the large one's final level (a luminaire's housing under a ceiling).
AmbientGather gather_ambient(const Scene& scene, const Octree& octree,
                             const AmbientSources& sources, int rays, int level = 0,
                             std::uint64_t seed = 1, double final_threshold = 0);

/// The final gather (DESIGN, measured on cube.mgf and the Cornell box: docs/method.md, "The
/// final gather"): its cells are no wider than 1 / final_gather_cells of the scene's diagonal
/// (up to max_ambient_level); its points take 1 / final_gather_ray_share of the gather's rays
/// (at least ambient_min_rays: the projection averages m^2 points a cell); the solver asks it
/// of the surfaces whose gathered radiosity reaches final_gather_share absolute tolerances.
constexpr double final_gather_cells = 16;
constexpr int final_gather_ray_share = 4;
constexpr double final_gather_share = 10;

/// The level at which the final gather takes `surface`: the first from `level` at which its
/// cells (its longer diagonal / 2^level) are no wider than diagonal / final_gather_cells, at
/// most max_ambient_level.
int final_gather_level(const Surface& surface, double diagonal, int level);

}  // namespace mbr
