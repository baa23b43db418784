// radiosity/visibility/occlusion.cpp - the occluders of a pair, shadow rays and their seeds
// (paper section 6, "Octree" and "Shadow"; the queries of radiosity/visibility/occlusion.h).
#include "radiosity/visibility/occlusion.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "radiosity/visibility/visible_parts.h"

namespace mbr {

// ---- Seeds -------------------------------------------------------------------------------

namespace {
std::uint64_t splitmix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}
}  // namespace

std::uint64_t hash_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
    return splitmix(splitmix(splitmix(splitmix(a) ^ b) ^ c) ^ d);
}

double uniform01(std::uint64_t key, std::uint64_t index) {
    return double(hash_seed(key, index) >> 11) * 0x1.0p-53;
}

// ---- Occluders of a pair -----------------------------------------------------------------

std::vector<Vec3> hull_points(const Surface& surface) {
    if (surface.kind() == Surface::Kind::PlanarQuad) {
        const Vec3* c = surface.corners();
        return {c[0], c[1], c[2], c[3]};
    }
    const Box3 b = surface.bounds();
    std::vector<Vec3> out;
    for (int i = 0; i < 8; ++i)
        out.push_back(
            {(i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z});
    return out;
}

namespace {

/// An outward plane n . x <= d of a convex hull.
struct HullPlane {
    Vec3 n;
    double d;
};

/// The supporting planes of the convex hull of a few points: every plane through three of them
/// with all the others on its inner side (a flat hull gets its plane in both orientations).
/// Brute force, for the 8 to 16 points of two surfaces.
std::vector<HullPlane> hull_planes(const std::vector<Vec3>& pts, double tol) {
    std::vector<HullPlane> planes;
    const int n = static_cast<int>(pts.size());
    for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b)
            for (int c = b + 1; c < n; ++c) {
                Vec3 normal = cross(pts[b] - pts[a], pts[c] - pts[a]);
                const double len = length(normal);
                if (len <= tol * tol) continue;  // (nearly) collinear
                normal = normal / len;
                for (double sign : {1.0, -1.0}) {
                    const Vec3 nn = sign * normal;
                    const double d = dot(nn, pts[a]);
                    bool supporting = true;
                    for (const Vec3& q : pts)
                        if (dot(nn, q) - d > tol) {
                            supporting = false;
                            break;
                        }
                    if (supporting) planes.push_back({nn, d});
                }
            }
    return planes;
}

}  // namespace

OcclusionContext make_occlusion_context(const Octree& octree, const Surface& shooter,
                                        int shooter_surface, const Surface& receiver,
                                        int receiver_surface, std::uint64_t shot) {
    OcclusionContext ctx;
    ctx.octree = &octree;
    ctx.shooter_surface = shooter_surface;
    ctx.receiver_surface = receiver_surface;
    ctx.seed = hash_seed(std::uint64_t(shooter_surface), std::uint64_t(receiver_surface), shot);

    std::vector<Vec3> pts = hull_points(shooter);
    for (const Vec3& q : hull_points(receiver)) pts.push_back(q);
    Box3 hull_box;
    double scale = 0;
    for (const Vec3& q : pts) {
        hull_box.extend(q);
        scale = std::max({scale, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
    }
    scale = std::max(scale, length(hull_box.extent()));
    // DESIGN: 1e-9 of the coordinates: points that far off a hull plane count as on it, and a
    // polygon that only touches the hull's boundary cannot block a segment inside it.
    const double tol = 1e-9 * scale;
    const std::vector<HullPlane> planes = hull_planes(pts, tol);

    auto box_outside = [&](const Box3& box) {
        if (!overlaps(box, hull_box)) return true;
        for (const HullPlane& h : planes) {
            // The corner furthest inside: all eight corners outside when even it is.
            const Vec3 inner{h.n.x > 0 ? box.lo.x : box.hi.x, h.n.y > 0 ? box.lo.y : box.hi.y,
                             h.n.z > 0 ? box.lo.z : box.hi.z};
            if (dot(h.n, inner) - h.d > tol) return true;
        }
        return false;
    };
    // DESIGN: a polygon lying on a planar receiver (every vertex in front of its plane by at
    // most 1e-3 of the receiver's size: a light hung a hair below the ceiling, a rug on the
    // floor) is no occluder of that receiver. It can only block rays that leave the receiver
    // within 1e-3 of grazing, whose kernel (3) carries a cosine below 1e-3, except under its
    // footprint, which sees nothing anyway (hidden regions, radiosity/visibility/hidden_regions.h).
    // Kept, its shadow seen from a receiving point is a sliver along the horizon whose shape
    // rounding decides: the kind of shadow that made edgefill's divided differences (22) thousands
    // of times too steep (IncrementIntegrator::take_shadows_apart).
    const std::optional<Plane> receiver_plane = surface_plane(receiver);
    const double lying = 1e-3 * length(receiver.bounds().extent());
    auto lies_on_receiver = [&](const Polygon& poly) {
        if (!receiver_plane) return false;
        for (const Vec3& v : poly.vertices()) {
            const double h = dot(receiver_plane->normal, v) - receiver_plane->offset;
            if (h < -tol || h > lying) return false;
        }
        return true;
    };
    const std::vector<int> near =
        octree.polygons_near([&](const Box3& cube) { return !box_outside(cube); });
    for (int id : near) {
        const Polygon& poly = octree.polygons()[id];
        if (poly.surface() == shooter_surface || poly.surface() == receiver_surface) continue;
        if (box_outside(poly.bounds())) continue;
        if (lies_on_receiver(poly)) continue;
        bool outside = false;
        for (const HullPlane& h : planes) {
            bool all_out = true;
            for (const Vec3& v : poly.vertices())
                if (dot(h.n, v) - h.d < -tol) {
                    all_out = false;
                    break;
                }
            if (all_out) {
                outside = true;
                break;
            }
        }
        if (outside) continue;
        // The polygon's own plane may separate: every hull point strictly on one side.
        const Plane& pl = poly.plane();
        bool pos = false, neg = false;
        for (const Vec3& q : pts) {
            const double s = pl.signed_distance(q);
            if (s > tol) pos = true;
            if (s < -tol) neg = true;
        }
        if (pos != neg) continue;  // one side only (or touching): the hull's inside is clear
        ctx.candidates.push_back(id);
    }
    return ctx;
}

bool segment_blocked(const OcclusionContext& context, Vec3 a, Vec3 b, long* n_rays) {
    if (context.candidates.empty()) return false;
    if (n_rays) ++*n_rays;
    // DESIGN: the open segment, t in [1e-9, 1 - 1e-9]: the end points lie on the two surfaces,
    // which never block their own transfer anyway (their polygons are skipped).
    const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
    if (context.candidates.size() <= 16) {
        const std::vector<Polygon>& polys = context.octree->polygons();
        for (int id : context.candidates)
            if (polys[id].intersect(ray)) return true;
        return false;
    }
    return context.octree->any_hit(ray,
                                   RayFilter{context.shooter_surface, context.receiver_surface});
}

bool segment_blocked(const OcclusionContext& context, const std::vector<int>& occluders, Vec3 a,
                     Vec3 b, long* n_rays) {
    if (occluders.empty()) return false;
    // DESIGN: up to 32 occluders are tested one by one; beyond, the octree is faster.
    if (occluders.size() > max_listed_occluders) return segment_blocked(context, a, b, n_rays);
    if (n_rays) ++*n_rays;
    const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
    const std::vector<Polygon>& polys = context.octree->polygons();
    for (int id : occluders)
        if (polys[id].intersect(ray)) return true;
    return false;
}

}  // namespace mbr
