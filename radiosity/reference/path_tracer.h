// radiosity/reference/path_tracer.h - an independent Monte Carlo estimate of the radiosity of eq.
// (1) at chosen surface points, to check the solver on any scene. It solves the same equation over
// the same scene and octree, diffuse and one-sided as the paper's surfaces (section 2):
//   B(p) = E(p) + rho(p) int_{hemisphere at p} L_in(p, w) cos(theta) dw,
//   L_in(p, w) = B(x) / pi at the first surface point x hit in direction w if x's front faces p,
//   else 0 (a back face absorbs),
// by path tracing with next-event estimation (light sampled on the emitters by area) and
// cosine-weighted bounces combined by multiple importance sampling, and Russian roulette. It shares
// nothing with the solver but the scene, the surfaces' maps and the octree's ray queries.
#pragma once

#include <cstdint>
#include <vector>

#include "octree/octree.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// Options of estimate_radiosity.
struct PathTracerOptions {
    long paths = 4096;                    // paths per point
    std::uint64_t seed = 1;               // with the point and path index, seeds each path
    int min_bounces_before_roulette = 3;  // bounces always followed before Russian roulette
    int paths_per_block = 1024;           // paths of one parallel work item (speed only)
    int threads = 0;                      // OpenMP threads; 0: OpenMP's default
    bool multiple_importance = true;      // weigh light sampling against bounces that hit an
                                          //   emitter (false: pure next-event estimation)
};

/// The estimate at one point: the mean over the paths and its standard error (the sample
/// standard deviation over sqrt(paths)), per channel.
struct RadiosityEstimate {
    Rgb mean;
    Rgb standard_error;
};

/// Estimates B at each point (surface, u, v; other fields of SurfaceLocation are not used) by
/// options.paths independent paths per point. Each path is one sample of
///   E(p) + rho(p) [D(p) + rho(x_1) [D(x_1) + rho(x_2) [D(x_2) + ...]]],
/// where x_1, x_2, ... are found by cosine-weighted bounces (the path ends on a miss, a back
/// face or a black surface) and D(x), the irradiance / pi from the emitters alone, is sampled
/// twice per vertex: by one point y on an emitter chosen in proportion to its power, uniform in
/// (u, v) and weighted by the area factor A(u, v), with a shadow ray (next-event estimation),
/// and by the emission E(x_{i+1}) the bounce from x_i finds. With multiple_importance the two
/// are combined by the power heuristic (Veach and Guibas 1995); without it the bounce's
/// emission is dropped and D is next-event estimation alone.
/// Deviation: multiple importance is the default. Next-event estimation alone has infinite
/// variance wherever an emitter meets a receiving surface (1 / r^2 of the light sample near the
/// common edge): on the emitting cube of test_path_tracer (64000 paths) it reads 20 % low near
/// a corner with a standard error that claims 6 %, and elsewhere its standard errors are 4 to
/// 26 times those of the power heuristic, whose samples are all bounded.
/// After options.min_bounces_before_roulette bounces a path goes on with probability
/// q = min(1, max channel of its weight) and the weight is divided by q.
/// Self-hits: a ray ignores hits nearer than 1e-7 of the scene's diagonal to its origin (and to
/// its end, for shadow rays). Vertices lie on the true surfaces, rays meet their facets: on a
/// surface its facets miss (curved kinds, non-planar quads) rays leave from, and shadow rays
/// aim at, the point moved along the normal by twice its chord error (see path_tracer.cpp);
/// the estimate then carries an error of the order of that chord error (0.2-0.6 % on closed
/// curved enclosures at tessellation 16, 0.1 % at 64). A start point within 1e-4 of the
/// diagonal of its surface's edge is moved inward to that distance.
/// Paths are independent of scheduling: each draws from its own counter-based generator seeded
/// by (seed, point index, path index), and sums are formed in a fixed order, so the results are
/// bitwise the same for any number of threads. `octree` must be build_octree(scene) (or built
/// over scene_polygons(scene, ...)): its polygons' surface ids index scene.surfaces.
std::vector<RadiosityEstimate> estimate_radiosity(const Scene& scene, const Octree& octree,
                                                  const std::vector<SurfaceLocation>& points,
                                                  const PathTracerOptions& options = {});

}  // namespace mbr
