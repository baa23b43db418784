// radiosity/visibility/occlusion.h - the occluders of one shooter -> receiver pair and the
// shadow rays between them (paper section 6, "Octree": a pair that no polygon can come between
// casts no rays; "Shadow": the rays of eq. (28)), with the reproducible seeds of those rays.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "math/vec3.h"
#include "octree/octree.h"
#include "radiosity/geometry/surface.h"

namespace mbr {

struct ConvexSolids;

/// The occluders of one shooter -> receiver pair: the polygons (of an octree over the scene)
/// that meet the convex hull of the two surfaces, other than the two surfaces' own.
struct OcclusionContext {
    const Octree* octree = nullptr;
    int shooter_surface = -1;  // surface ids as the octree's polygons carry them
    int receiver_surface = -1;
    std::vector<int> candidates;  // polygon indices, increasing
    /// The candidates' bounds, one box per surface they belong to (a shaft that misses every
    /// box is clear, and so is a segment that misses them grown: compute_fraction,
    /// segment_blocked).
    std::vector<Box3> surface_boxes;
    std::vector<int> surface_box_counts;  // how many candidates each of those boxes holds
    std::vector<Box3> segment_boxes;      // each of those boxes grown_for_segments
    std::uint64_t seed = 0;  // of every ray of the transfer: the pair and the shot number
    /// The scene's convex solids (convex_solids.h; null: the candidates are loose polygons).
    /// With them the candidates are split (attach_solids) into whole solids, solid_ids
    /// (indices into solids->solids), and the loose polygons (increasing).
    const ConvexSolids* solids = nullptr;
    std::vector<int> solid_ids;
    std::vector<int> loose;
    int loose_surfaces = 0;  // the surfaces of the loose polygons (attach_solids)
    /// True when nothing can come between the two surfaces.
    bool clear() const { return candidates.empty(); }
};

/// The points whose convex hull holds a surface: the corners of a planar quad, else the eight
/// corners of its bounding box.
std::vector<Vec3> hull_points(const Surface& surface);

/// The context of a pair with no candidates yet: its octree, surface ids and seed (`shot`
/// enters the seed).
OcclusionContext pair_context(const Octree& octree, int shooter_surface, int receiver_surface,
                              std::uint64_t shot);

/// Fills context.surface_boxes (with surface_box_counts and segment_boxes) from its candidates.
void group_surface_boxes(OcclusionContext& context);

/// What casts the pair's shadows as exact visibility projects them: its whole convex solids
/// (one silhouette each: attach_solids) and the surfaces of its loose polygons; without solids,
/// the surfaces of its candidates (surface_boxes).
int shadow_casters(const OcclusionContext& context);

/// A box of polygons grown by 1e-9 of its coordinates' magnitude and size: more than a
/// polygon's hits reach beyond its vertices' box (its edge slack, 1e-10 of its diameter).
Box3 grown_for_segments(const Box3& box);
/// Whether the segment a -> b misses every (closed) box. With the grown_for_segments boxes of
/// some polygons, a segment that misses them all meets none of those polygons.
bool segment_misses_boxes(Vec3 a, Vec3 b, const std::vector<Box3>& boxes);

/// The shaft from p to a planar patch with corners q[0..3] (in order around it): the convex hull
/// of p and the patch, which holds every segment from p to the patch, as the four planes through
/// p and an edge and the patch's own plane (nothing beyond the shooter blocks). DESIGN: a box or
/// a polygon within 1e-9 of the coordinates' size of a plane counts as meeting it (more than a
/// polygon's edge slack); a shaft too thin to orient meets everything.
struct Shaft {
    Vec3 normal[5];
    double offset[5] = {0, 0, 0, 0, 0};
    double tol = 0;
    bool oriented = true;
    Shaft(Vec3 p, const Vec3 (&q)[4]);
    /// Whether the box may meet the shaft (no plane has it wholly outside).
    bool meets(const Box3& box) const;
    /// Whether every one of the points lies outside one plane of the shaft: a polygon with these
    /// vertices meets no segment from p to the patch.
    bool separates(const std::vector<Vec3>& points) const;
};

/// The occluders between two surfaces, found with the octree (nodes and polygons outside the
/// convex hull of both surfaces' hull_points are skipped). `shot` enters the seed.
OcclusionContext make_occlusion_context(const Octree& octree, const Surface& shooter,
                                        int shooter_surface, const Surface& receiver,
                                        int receiver_surface, std::uint64_t shot);

/// Up to this many occluders a segment is tested against the list one by one; beyond, the
/// octree is faster (segment_blocked with a list, occluders_toward's limit).
constexpr size_t max_listed_occluders = 32;

/// Exact visibility projects at most this many occluders for one receiving point: a pair with
/// more candidates keeps those that meet the point's pyramid to the shooter (occluders_toward);
/// still more, and visibility is one ray per quadrature node (BlockedView::use_rays).
constexpr int exact_limit = 24;

/// The occluders that blocked the last few segments of one receiving point (a shadow cache, as
/// Haines and Greenberg's light buffer keeps the last occluder): tested first, since nearby
/// rays are mostly blocked by the same polygon. Answers never depend on it.
struct RecentBlockers {
    std::array<int, 4> ids{{-1, -1, -1, -1}};  // most recent first
    /// Makes `id` the most recent.
    void note(int id) {
        int k = 0;
        while (k < 3 && ids[size_t(k)] != id) ++k;
        for (; k > 0; --k) ids[size_t(k)] = ids[size_t(k - 1)];
        ids[0] = id;
    }
};

/// True when an occluder of the context blocks the open segment a -> b (any-hit: a loop over
/// the candidates when they are few, else their boxes and the octree, counting the candidates
/// only; the answer is the same). Counts the ray in *n_rays. With `recent`, its polygons are
/// tested first and the blocker found is noted there.
bool segment_blocked(const OcclusionContext& context, Vec3 a, Vec3 b, long* n_rays,
                     RecentBlockers* recent = nullptr);
/// The same against a subset of the candidates known to hold every polygon that can meet the
/// segment (occluders_toward); an empty subset casts no ray. Beyond `max_listed` occluders the
/// segment goes to the octree instead.
bool segment_blocked(const OcclusionContext& context, const std::vector<int>& occluders, Vec3 a,
                     Vec3 b, long* n_rays, size_t max_listed = max_listed_occluders,
                     RecentBlockers* recent = nullptr);
/// Up to this many occluders a ray of exact visibility is tested one by one: its list holds only
/// the polygons that meet its cell's shaft, where the octree costs several times more per ray
/// (measured inside a sphere of 20 pieces: 4 us against 0.5 us).
constexpr size_t max_shaft_occluders = 256;

/// A reproducible 64-bit hash of a few integers (splitmix64 steps), for seeding rays.
std::uint64_t hash_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0, std::uint64_t d = 0);
/// A uniform double in [0, 1) from a counter (the hash of `key` and `index`).
double uniform01(std::uint64_t key, std::uint64_t index);

/// An orthonormal frame around a unit normal, for directions distributed by cos(theta) / pi
/// over the hemisphere in front (the rays of find_hidden and of the ambient gather).
struct CosineFrame {
    Vec3 nx, ny, nz;
    explicit CosineFrame(Vec3 normal);
    /// The direction of the unit-square point (a, b): phi = 2 pi a, sin^2(theta) = b.
    Vec3 direction(double a, double b) const;
};

}  // namespace mbr
