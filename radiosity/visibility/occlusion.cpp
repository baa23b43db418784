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

CosineFrame::CosineFrame(Vec3 normal) : nz(normal) {
    const Vec3 helper = std::fabs(nz.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    nx = normalize(cross(helper, nz));
    ny = cross(nz, nx);
}

Vec3 CosineFrame::direction(double a, double b) const {
    const double phi = 2 * Pi * a, sin_theta = std::sqrt(b);
    const double cos_theta = std::sqrt(std::max(0.0, 1 - b));
    return (sin_theta * std::cos(phi)) * nx + (sin_theta * std::sin(phi)) * ny + cos_theta * nz;
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

/// A ball {x : |x - centre| <= radius}.
struct Ball {
    Vec3 centre;
    double radius = 0;
};

/// Balls that together hold the true surface `surface_id` of a curved surface, whose facets are
/// chords of it: its polygons in the octree grouped by where their (u, v) centroids fall on an
/// 8 x 8 grid over [0, 1]^2, a ball around each group's vertices grown by the largest thickness
/// plus 0.3 diameter of its polygons. (The true surface stands within its facet's thickness of
/// the facet's plane, and its boundary arcs bulge beyond the chords by at most tan(30 deg) / 2
/// = 0.29 of a chord across 120 degrees, the coarsest a tessellation makes: at least 3 facets
/// along an angle, which spans at most 360 degrees.)
std::vector<Ball> surface_balls(const Octree& octree, const Surface& surface, int surface_id) {
    constexpr int grid = 8;
    Box3 around = surface.bounds();
    const Vec3 grow = 1e-6 * length(around.extent()) * Vec3{1, 1, 1};
    around = Box3{around.lo - grow, around.hi + grow};
    const std::vector<int> near =
        octree.polygons_near([&](const Box3& cube) { return overlaps(cube, around); });
    std::vector<Box3> boxes(grid * grid);
    std::vector<double> margins(grid * grid, 0.0);
    std::vector<int> members;  // polygon ids by group, for the radii
    std::vector<int> group_of;
    for (int id : near) {
        const Polygon& poly = octree.polygons()[id];
        if (poly.surface() != surface_id) continue;
        Vec2 c;
        for (const Vec2& q : poly.uv()) c = c + (1.0 / poly.n_vertices()) * q;
        const int gi = std::clamp(int(c.x * grid), 0, grid - 1),
                  gj = std::clamp(int(c.y * grid), 0, grid - 1);
        const int g = gj * grid + gi;
        for (const Vec3& v : poly.vertices()) boxes[g].extend(v);
        margins[g] = std::max(margins[g], poly.thickness() + 0.3 * poly.diameter());
        members.push_back(id);
        group_of.push_back(g);
    }
    std::vector<Ball> balls(grid * grid);
    for (int g = 0; g < grid * grid; ++g) balls[g].centre = boxes[g].centre();
    for (size_t k = 0; k < members.size(); ++k) {
        Ball& b = balls[group_of[k]];
        for (const Vec3& v : octree.polygons()[members[k]].vertices())
            b.radius = std::max(b.radius, length(v - b.centre));
    }
    std::vector<Ball> out;
    for (int g = 0; g < grid * grid; ++g)
        if (!boxes[g].empty()) out.push_back({balls[g].centre, balls[g].radius + margins[g]});
    return out;
}

/// The balls of surface_balls for a pair with a curved member (both surfaces' balls), empty for
/// two planar surfaces or when either has no polygons (then there is no test).
std::vector<Ball> pair_balls(const Octree& octree, const Surface& shooter, int shooter_surface,
                             const Surface& receiver, int receiver_surface) {
    if (shooter.is_planar() && receiver.is_planar()) return {};
    std::vector<Ball> balls = surface_balls(octree, shooter, shooter_surface);
    const std::vector<Ball> more = surface_balls(octree, receiver, receiver_surface);
    if (balls.empty() || more.empty()) return {};
    balls.insert(balls.end(), more.begin(), more.end());
    return balls;
}

/// True when every ball lies strictly (by more than tol) on one side of the plane.
bool balls_on_one_side(const std::vector<Ball>& balls, const Plane& pl, double tol) {
    bool pos = false, neg = false;
    for (const Ball& b : balls) {
        const double s = pl.signed_distance(b.centre);
        if (s + b.radius > -tol) pos = true;
        if (s - b.radius < tol) neg = true;
        if (pos && neg) return false;
    }
    return true;
}

}  // namespace

OcclusionContext pair_context(const Octree& octree, int shooter_surface, int receiver_surface,
                              std::uint64_t shot) {
    OcclusionContext ctx;
    ctx.octree = &octree;
    ctx.shooter_surface = shooter_surface;
    ctx.receiver_surface = receiver_surface;
    ctx.seed = hash_seed(std::uint64_t(shooter_surface), std::uint64_t(receiver_surface), shot);
    return ctx;
}

OcclusionContext make_occlusion_context(const Octree& octree, const Surface& shooter,
                                        int shooter_surface, const Surface& receiver,
                                        int receiver_surface, std::uint64_t shot) {
    OcclusionContext ctx = pair_context(octree, shooter_surface, receiver_surface, shot);

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
    // DESIGN: a curved surface's hull points are its bounding box's corners (a sphere patch's
    // are the whole sphere's), through which nearly every plane passes: the facets of its other
    // pieces all became candidates (4600 of 5120 for two of 20 pieces of a sphere), and every
    // cell of every receiving point went through them. Balls that hold the true surfaces
    // (surface_balls) decide again for the polygons the hull keeps: one whose plane has every
    // ball strictly on one side cannot come between the two.
    const std::vector<Ball> balls =
        pair_balls(octree, shooter, shooter_surface, receiver, receiver_surface);
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
        if (!balls.empty() && balls_on_one_side(balls, pl, tol)) continue;
        ctx.candidates.push_back(id);
    }
    group_surface_boxes(ctx);
    return ctx;
}

void group_surface_boxes(OcclusionContext& context) {
    context.surface_boxes.clear();
    context.surface_box_counts.clear();
    std::vector<int> surfaces;  // surface of each box
    const std::vector<Polygon>& polys = context.octree->polygons();
    for (int id : context.candidates) {
        const Polygon& poly = polys[size_t(id)];
        const auto it = std::find(surfaces.begin(), surfaces.end(), poly.surface());
        if (it == surfaces.end()) {
            surfaces.push_back(poly.surface());
            context.surface_boxes.push_back(poly.bounds());
            context.surface_box_counts.push_back(1);
        } else {
            const size_t k = size_t(it - surfaces.begin());
            context.surface_boxes[k].extend(poly.bounds());
            ++context.surface_box_counts[k];
        }
    }
    context.segment_boxes.clear();
    for (const Box3& box : context.surface_boxes)
        context.segment_boxes.push_back(grown_for_segments(box));
}

int shadow_casters(const OcclusionContext& context) {
    if (!context.solids) return static_cast<int>(context.surface_boxes.size());
    return static_cast<int>(context.solid_ids.size()) + context.loose_surfaces;
}

namespace {

/// Whether one of the recent blockers (none when `recent` is null) blocks the ray; the one
/// found becomes the most recent.
bool blocked_by_recent(RecentBlockers* recent, const std::vector<Polygon>& polys, const Ray& ray) {
    if (!recent) return false;
    for (int id : recent->ids)
        if (id >= 0 && polys[size_t(id)].intersect_segment(ray)) {
            recent->note(id);
            return true;
        }
    return false;
}

}  // namespace

Shaft::Shaft(Vec3 p, const Vec3 (&q)[4]) {
    const Vec3 centre = 0.25 * (q[0] + q[1] + q[2] + q[3]);
    double scale = length(p);
    for (const Vec3& c : q) scale = std::max(scale, length(c));
    tol = 1e-9 * std::max(scale, 1.0);
    for (int j = 0; j < 5; ++j) {
        Vec3 n = j < 4 ? cross(q[j] - p, q[(j + 1) % 4] - p) : cross(q[1] - q[0], q[3] - q[0]);
        const Vec3 inside = j < 4 ? centre : p;  // a point the half-space keeps
        const Vec3 on = j < 4 ? p : q[0];
        const double len = length(n);
        if (!(len > 0)) {
            oriented = false;
            return;
        }
        n = (1 / len) * n;
        if (dot(n, inside - on) > 0) n = -1.0 * n;  // inside: dot(n, x) <= offset
        normal[j] = n;
        offset[j] = dot(n, on);
    }
}

bool Shaft::meets(const Box3& box) const {
    if (!oriented) return true;
    for (int j = 0; j < 5; ++j) {
        const Vec3& n = normal[j];
        const Vec3 nearest{n.x > 0 ? box.lo.x : box.hi.x, n.y > 0 ? box.lo.y : box.hi.y,
                           n.z > 0 ? box.lo.z : box.hi.z};
        if (dot(n, nearest) - offset[j] > tol) return false;
    }
    return true;
}

bool Shaft::separates(const std::vector<Vec3>& points) const {
    if (!oriented) return false;
    for (int j = 0; j < 5; ++j) {
        bool all_outside = true;
        for (const Vec3& x : points)
            if (!(dot(normal[j], x) - offset[j] > tol)) {
                all_outside = false;
                break;
            }
        if (all_outside) return true;
    }
    return false;
}

Box3 grown_for_segments(const Box3& box) {
    double size = length(box.extent());
    for (const Vec3& c : {box.lo, box.hi})
        size = std::max({size, std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    const Vec3 grow{1e-9 * size, 1e-9 * size, 1e-9 * size};
    return Box3{box.lo - grow, box.hi + grow};
}

bool segment_misses_boxes(Vec3 a, Vec3 b, const std::vector<Box3>& boxes) {
    const double origin[3] = {a.x, a.y, a.z}, dir[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
    double inverse[3];
    for (int k = 0; k < 3; ++k) inverse[k] = dir[k] != 0 ? 1 / dir[k] : 0;
    for (const Box3& box : boxes) {
        const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
        double t0 = 0, t1 = 1;
        bool meets = true;
        for (int k = 0; k < 3 && meets; ++k) {
            if (dir[k] == 0) {
                meets = origin[k] >= lo[k] && origin[k] <= hi[k];
                continue;
            }
            double u = (lo[k] - origin[k]) * inverse[k], v = (hi[k] - origin[k]) * inverse[k];
            if (u > v) std::swap(u, v);
            t0 = std::max(t0, u);
            t1 = std::min(t1, v);
            meets = t0 <= t1;
        }
        if (meets) return false;
    }
    return true;
}

/// At most this many boxes of occluding surfaces are tested before a segment goes to the octree.
constexpr size_t max_box_tests = 16;

bool segment_blocked(const OcclusionContext& context, Vec3 a, Vec3 b, long* n_rays,
                     RecentBlockers* recent) {
    if (context.candidates.empty()) return false;
    if (n_rays) ++*n_rays;
    // DESIGN: the open segment, t in [1e-9, 1 - 1e-9]: the end points lie on the two surfaces,
    // which never block their own transfer anyway (their polygons are skipped). The ends lie on
    // true surfaces, so a curved neighbour's facets near them do not block (Polygon::hit_counts).
    const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
    const std::vector<Polygon>& polys = context.octree->polygons();
    // Polygons that blocked this point's rays before were found under the same rules (the
    // octree's test is Polygon::intersect_segment's on a packed copy): a hit among them is one.
    if (blocked_by_recent(recent, polys, ray)) return true;
    // DESIGN: a segment that misses the box of every occluding surface is clear without the
    // octree's walk (the room's paper shadows: 12.0 M of the 13.5 M segments the octree found
    // clear missed them all). Only for pairs with few such surfaces (max_box_tests): the
    // classroom's pairs have thousands.
    const std::vector<Box3>& boxes = context.segment_boxes;
    if (!boxes.empty() && boxes.size() <= max_box_tests && segment_misses_boxes(a, b, boxes))
        return false;
    int blocker = -1;
    if (context.candidates.size() <= 16) {
        for (int id : context.candidates)
            if (polys[id].intersect_segment(ray)) {
                blocker = id;
                break;
            }
    } else {
        // DESIGN: only the candidates block, as in the loop above and in the lists of
        // occluders_toward (a polygon lying on the receiver is none: make_occlusion_context).
        RayFilter filter{context.shooter_surface, context.receiver_surface, true};
        filter.only_polygons = &context.candidates;
        blocker = context.octree->any_hit_polygon(ray, filter);
    }
    if (blocker >= 0 && recent) recent->note(blocker);
    return blocker >= 0;
}

bool segment_blocked(const OcclusionContext& context, const std::vector<int>& occluders, Vec3 a,
                     Vec3 b, long* n_rays, size_t max_listed, RecentBlockers* recent) {
    if (occluders.empty()) return false;
    // DESIGN: up to 32 occluders are tested one by one; beyond, the octree is faster.
    if (occluders.size() > max_listed) return segment_blocked(context, a, b, n_rays, recent);
    if (n_rays) ++*n_rays;
    const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
    const std::vector<Polygon>& polys = context.octree->polygons();
    // The recent blockers first: a hit among them is a hit (the same test); the list holds
    // every polygon that can meet the segment, so a miss there leaves the answer to the list.
    if (blocked_by_recent(recent, polys, ray)) return true;
    for (int id : occluders)
        if (polys[id].intersect_segment(ray)) {
            if (recent) recent->note(id);
            return true;
        }
    return false;
}

}  // namespace mbr
