// radiosity/visibility/visible_parts.cpp - the exact visible part of a planar shooter (the geometry
// of radiosity/visibility/visible_parts.h; paper section 6, "Shadow"). The occluders of a pair
// and the shadow rays are in occlusion.cpp; the fractions (28) and the shadow subdivision of
// stage 7 in radiosity/transfer/shadows.cpp.
#include "radiosity/visibility/visible_parts.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "math/check.h"

namespace mbr {

// ---- The visible part of a planar shooter ------------------------------------------------

Vec2 ShooterPlane::at(double u, double v) const {
    return (1 - u) * (1 - v) * corner[0] + u * (1 - v) * corner[1] + u * v * corner[2] +
           (1 - u) * v * corner[3];
}

ShooterPlane make_shooter_plane(const Surface& quad) {
    MBR_CHECK(quad.kind() == Surface::Kind::PlanarQuad);
    const Vec3* c = quad.corners();
    ShooterPlane sp;
    sp.origin = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    // Newell's normal of the corners: the mean plane of a (slightly) non-planar quad. For four
    // corners it is the cross product of the diagonals, which, unlike the sum of cross(c_i,
    // c_{i+1}) over absolute positions (terms of order |c|^2 cancelling down to the area),
    // keeps its digits for a quad far smaller than its distance from the origin (measured: a
    // shooter of side 1e-8 at distance 1 got a normal off by radians).
    sp.normal = normalize(cross(c[2] - c[0], c[3] - c[1]));
    sp.e1 = normalize(c[1] - c[0] - dot(c[1] - c[0], sp.normal) * sp.normal);
    sp.e2 = cross(sp.normal, sp.e1);
    for (int i = 0; i < 4; ++i) sp.corner[i] = sp.to_plane(c[i]);
    sp.outline.assign(sp.corner, sp.corner + 4);
    // An exact parallelogram (the twist q0 - q1 + q2 - q3 vanishes to rounding): affine inverse.
    const Vec2 e = sp.corner[1] - sp.corner[0], f = sp.corner[3] - sp.corner[0];
    const Vec2 g = sp.corner[0] - sp.corner[1] + sp.corner[2] - sp.corner[3];
    const double det = cross(e, f);
    if (det != 0 && std::sqrt(dot(g, g)) <= 1e-14 * std::sqrt(std::fabs(det))) {
        sp.parallelogram = true;
        sp.inverse_row0 = Vec2{f.y, -f.x} * (1 / det);
        sp.inverse_row1 = Vec2{-e.y, e.x} * (1 / det);
    }
    if (signed_area(sp.outline) < 0) std::reverse(sp.outline.begin(), sp.outline.end());
    sp.size = std::sqrt(std::fabs(signed_area(sp.outline)));
    return sp;
}

std::optional<Plane> surface_plane(const Surface& surface) {
    if (surface.kind() == Surface::Kind::PlanarQuad) {
        const Vec3* c = surface.corners();
        // Newell's normal as the diagonals' cross product (see make_shooter_plane).
        const Vec3 n = normalize(cross(c[2] - c[0], c[3] - c[1]));
        const Vec3 o = 0.25 * (c[0] + c[1] + c[2] + c[3]);
        // Only a quad planar to rounding: the scene format accepts corners 0.25 % off their
        // mean plane, whose tangent planes then differ from it.
        double size = 0, off = 0;
        for (int i = 0; i < 4; ++i) {
            size = std::max(size, length(c[i] - c[(i + 2) % 4]));
            off = std::max(off, std::fabs(dot(n, c[i] - o)));
        }
        if (off > 1e-12 * size) return std::nullopt;
        return Plane{n, dot(n, o)};
    }
    if (surface.kind() == Surface::Kind::Disk) {
        const Vec3 n = surface.normal(0.5, 0.5);
        return Plane{n, dot(n, surface.point(0.5, 0.5))};
    }
    return std::nullopt;
}

std::vector<int> occluders_toward(const OcclusionContext& context, const ShooterPlane& plane,
                                  Vec3 p, size_t limit) {
    // The pyramid: a plane through p and each edge of the shooter's outline, and the shooter's
    // own plane (nothing beyond the shooter blocks a segment that ends on it).
    struct Side {
        Vec3 n;
        double d;
    };
    std::vector<Side> sides;
    const int nc = static_cast<int>(plane.outline.size());
    double scale = length(p);
    for (int i = 0; i < nc; ++i) {
        const Vec3 a = plane.to_space(plane.outline[i]),
                   b = plane.to_space(plane.outline[(i + 1) % nc]);
        scale = std::max(scale, length(a));
        Vec3 n = normalize(cross(b - a, p - a));
        if (dot(n, plane.to_space(plane.outline[(i + 2) % nc]) - a) > 0) n = -1.0 * n;
        sides.push_back({n, dot(n, a)});
    }
    sides.push_back({-1.0 * plane.normal, -dot(plane.normal, plane.origin)});
    // DESIGN: a polygon or box within 1e-9 of the coordinates' size of the pyramid is kept.
    const double tol = 1e-9 * scale;
    auto outside_box = [&](const Box3& box) {
        for (const Side& s : sides) {
            const Vec3 inner{s.n.x > 0 ? box.lo.x : box.hi.x, s.n.y > 0 ? box.lo.y : box.hi.y,
                             s.n.z > 0 ? box.lo.z : box.hi.z};
            if (dot(s.n, inner) - s.d > tol) return true;
        }
        return false;
    };
    const std::vector<Polygon>& polys = context.octree->polygons();
    // Whether a polygon meets the pyramid: not when all its vertices lie beyond one side (the
    // quick test); else when something of it is left after clipping it to every side.
    // DESIGN: the clip, not the quick test alone, decides: a polygon beside the pyramid that no
    // one side separates (beside one of its edges) casts no shadow at p, but counted as a caster
    // it could send p to rays (exact_limit) and kept its patches' rays. So the list is the same
    // whichever way it was found (the scan or the octree's walk below).
    std::vector<Vec3> part, next;
    auto meets = [&](int id) {
        const std::vector<Vec3>& v = polys[size_t(id)].vertices();
        for (const Side& s : sides) {
            bool all = true;
            for (const Vec3& x : v)
                if (dot(s.n, x) - s.d <= tol) {
                    all = false;
                    break;
                }
            if (all) return false;
        }
        part.assign(v.begin(), v.end());
        for (const Side& s : sides) {
            next.clear();
            const auto inside = [&](Vec3 x) { return -(dot(s.n, x) - s.d - tol); };
            clip_polygon(part, inside, next);
            part.swap(next);
            if (part.empty()) return false;
        }
        return true;
    };
    std::vector<int> out;
    // DESIGN: up to max_scanned_candidates the pair's candidates are tested one by one: the
    // octree's walk cost 11.5-22 us a point whatever the list (its nodes, a binary search of
    // the candidates for each polygon a leaf lists, the polygons listed by several leaves), the
    // loop 0.9 us at 32 candidates and 5.9 us at 1,024 (the classroom's first 4 shots, 608,000
    // points on one thread; docs/method.md, "The occluders toward a point, scanned").
    if (context.candidates.size() <= max_scanned_candidates) {
        for (int id : context.candidates)
            if (meets(id)) {
                out.push_back(id);
                if (out.size() > limit) break;  // more than `limit`: enough (see the header)
            }
        return out;
    }
    // The octree's leaves one at a time (a polygon listed by several leaves comes several
    // times): each listed candidate that meets the pyramid is kept, and the kept ones are made
    // unique whenever they outgrow twice the limit; more than `limit` distinct ones stop the
    // walk (the node test then refuses every further node).
    bool enough = false;
    auto compact = [&out] {
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    };
    std::vector<int> listed;
    auto keep_listed = [&] {  // the listed candidates that meet the pyramid
        for (int id : listed)
            if (std::binary_search(context.candidates.begin(), context.candidates.end(), id) &&
                meets(id))
                out.push_back(id);
        listed.clear();
    };
    context.octree->append_polygons_near(
        [&](const Box3& b) {
            if (enough) return false;
            keep_listed();
            if (limit != SIZE_MAX && out.size() > 2 * limit) {
                compact();
                enough = out.size() > limit;
                if (enough) return false;
            }
            return !outside_box(b);
        },
        listed);
    keep_listed();
    compact();
    return out;
}

namespace {

/// How many of the points lie in front of the view's horizon line and how many behind it;
/// points within BlockedView::front_tolerance of the line lie on it and count as neither.
struct HorizonSides {
    int front = 0, behind = 0;
};
HorizonSides horizon_sides(const BlockedView& view, const Vec2* points, size_t n) {
    HorizonSides sides;
    for (size_t i = 0; i < n; ++i) {
        const double v = view.front.value(points[i]);
        if (v > view.front_tolerance) ++sides.front;
        if (v < -view.front_tolerance) ++sides.behind;
    }
    return sides;
}

/// The top of the slab an occluder is cut to, seen from p at height h_p > 0 above the shooter's
/// plane. DESIGN: occluder points within 1e-7 h_p of p's height are cut off: they could only
/// block rays grazing the shooter's plane, and would project 1e7 times further out.
double slab_top(double h_p) {
    return h_p * (1 - 1e-7);
}

/// Appends the points where the edge a -> b (heights ha, hb above the shooter's plane) crosses
/// the slab 0 <= h <= h_max strictly inside the edge, in order along it (Sutherland-Hodgman
/// against two planes at once: the parameter range of the edge inside the slab).
void push_slab_crossings(Vec3 a, Vec3 b, double ha, double hb, double h_max,
                         std::vector<Vec3>& out) {
    double t0 = 0, t1 = 1;
    const double dh = hb - ha;
    if (dh != 0) {
        double ta = (0 - ha) / dh, tb = (h_max - ha) / dh;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    } else if (!(ha >= 0 && ha <= h_max)) {
        return;
    }
    if (t0 > t1) return;
    if (t0 > 0 && t0 < 1) out.push_back(a + t0 * (b - a));
    if (t1 < 1 && t1 > t0 && t1 > 0) out.push_back(a + t1 * (b - a));
}

/// The central projection from p (at height h_p above the shooter's plane) of a point x of the
/// slab onto the plane, x -> p + h_p / (h_p - h(x)) (x - p), in the plane's frame.
Vec2 project_from(const ShooterPlane& plane, Vec3 p, double h_p, Vec3 x) {
    const double h = dot(plane.normal, x - plane.origin);
    return plane.to_plane(p + (h_p / (h_p - h)) * (x - p));
}

/// A shadow clipped to the shooter's outline, or nothing when only a sliver is left.
/// DESIGN: a sliver at most 1e-10 of the shooter's size wide (or a speck 1e-7 of it across)
/// is dropped (is_sliver): an occluder touching the shooter along its outline (a neighbouring
/// face) leaves one of no area, whose nearly coincident vertices give edge lines pointing
/// anywhere (see blocked_view). Its width, not its area against the shooter's: seen from a
/// point close to a large shooter, a shadow small beside the shooter can hide most of what the
/// point sees.
ConvexPolygon clip_to_shooter(const ShooterPlane& plane, const ConvexPolygon& shadow) {
    ConvexPolygon clipped = intersect(shadow, plane.outline);
    if (is_sliver(clipped, 1e-10 * plane.size, 1e-7 * plane.size)) return {};
    return clipped;
}

/// The central projection from p (at height h_p > 0 above the shooter's plane) of the part of
/// an occluder strictly between the plane and p, x -> p + h_p / (h_p - h(x)) (x - p), clipped
/// to the shooter's outline, counter-clockwise; empty when it hides nothing.
ConvexPolygon project_occluder(const ShooterPlane& plane, Vec3 p, double h_p,
                               const std::vector<Vec3>& vs) {
    // Keep the part of the occluder strictly between the plane and p (0 <= h < h_p), then
    // project it from p.
    const int n = static_cast<int>(vs.size());
    const double h_max = slab_top(h_p);
    std::vector<Vec3> slab;
    slab.reserve(n + 4);
    for (int i = 0; i < n; ++i) {
        const Vec3 a = vs[i], b = vs[(i + 1) % n];
        const double ha = dot(plane.normal, a - plane.origin);
        const double hb = dot(plane.normal, b - plane.origin);
        if (ha >= 0 && ha <= h_max) slab.push_back(a);
        push_slab_crossings(a, b, ha, hb, h_max, slab);
    }
    if (slab.size() < 3) return {};
    ConvexPolygon shadow;
    shadow.reserve(slab.size());
    for (const Vec3& x : slab) shadow.push_back(project_from(plane, p, h_p, x));
    const double area = signed_area(shadow);
    if (area < 0) std::reverse(shadow.begin(), shadow.end());
    if (std::fabs(area) <= 0) return {};  // an occluder seen edge-on hides nothing
    return clip_to_shooter(plane, shadow);
}

/// The central projections from p (at height h_p above the shooter's plane) of the part of a
/// polytope between the plane and p: its corners in the slab (heights h), then its edges'
/// crossings of the slab's two planes, in order (as solid_shadow and shadow_covered cut them).
std::vector<Vec2> project_slab_part(const ShooterPlane& plane, Vec3 p, double h_p,
                                    const std::vector<Vec3>& points, const std::vector<double>& h,
                                    const std::vector<std::array<int, 2>>& edges) {
    const double h_max = slab_top(h_p);
    std::vector<Vec3> slab;
    slab.reserve(h.size() + 8);  // the corners in the slab and a few edges' crossings
    for (size_t k = 0; k < h.size(); ++k)
        if (h[k] >= 0 && h[k] <= h_max) slab.push_back(points[k]);
    for (const std::array<int, 2>& e : edges)
        push_slab_crossings(points[size_t(e[0])], points[size_t(e[1])], h[size_t(e[0])],
                            h[size_t(e[1])], h_max, slab);
    std::vector<Vec2> projected;
    projected.reserve(slab.size());
    for (const Vec3& x : slab) projected.push_back(project_from(plane, p, h_p, x));
    return projected;
}

/// Points and edges whose convex hull holds an occluder (a polygon's corners and sides, a box's
/// corners and edges).
struct Outline {
    std::vector<Vec3> points;
    std::vector<std::array<int, 2>> edges;
    void add_polygon(const std::vector<Vec3>& corners) {
        const int first = static_cast<int>(points.size()), n = static_cast<int>(corners.size());
        points.insert(points.end(), corners.begin(), corners.end());
        for (int k = 0; k < n; ++k) edges.push_back({first + k, first + (k + 1) % n});
    }
    void add_box(const Box3& b) {
        const int first = static_cast<int>(points.size());
        for (int c = 0; c < 8; ++c)
            points.push_back(
                {(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z});
        for (int c = 0; c < 8; ++c)
            for (int bit : {1, 2, 4})
                if (!(c & bit)) edges.push_back({first + c, first + (c | bit)});
    }
};

/// Whether every segment from p to a point of the shooter that meets the convex hull of the
/// outline ends in one of the `shadows` (convex, counter-clockwise): the hull's part between the
/// shooter's plane and p (its points in that slab and its edges' crossings of it), projected
/// from p and clipped to the shooter, lies in one shadow.
/// DESIGN: inside within 1e-9 of the shooter's size, as the shadows' own edges are rounded.
bool shadow_covered(const ShooterPlane& plane, Vec3 p, double h_p, const Outline& outline,
                    const std::vector<ConvexPolygon>& shadows) {
    std::vector<double> h(outline.points.size());
    for (size_t k = 0; k < h.size(); ++k)
        h[k] = dot(plane.normal, outline.points[k] - plane.origin);
    std::vector<Vec2> projected =
        project_slab_part(plane, p, h_p, outline.points, h, outline.edges);
    if (projected.empty()) return true;  // wholly outside the slab: it meets no segment
    ConvexPolygon hull = convex_hull(std::move(projected));
    if (hull.size() < 3) return false;  // (a point or a segment: not worth deciding)
    hull = intersect(hull, plane.outline);
    if (hull.empty()) return true;  // it hides none of the shooter
    const double slack = 1e-9 * plane.size;
    for (const ConvexPolygon& shadow : shadows)
        if (std::all_of(hull.begin(), hull.end(),
                        [&](Vec2 q) { return contains(shadow, q, slack); }))
            return true;
    return false;
}

/// Whether every corner lies behind the plane through p with normal n_p, or on it (within
/// `tol`): nothing there comes between p and a point in front of p.
bool behind_p(Vec3 p, Vec3 n_p, const std::vector<Vec3>& corners, double tol) {
    for (const Vec3& v : corners)
        if (dot(n_p, v - p) > tol) return false;
    return true;
}

}  // namespace

std::optional<ConvexPolygon> solid_shadow(const ShooterPlane& plane, Vec3 p, double h_p,
                                          const ConvexSolid& solid, bool openings_covered,
                                          SolidRefusal* why) {
    if (why) *why = SolidRefusal::none;
    // The rule of convex_solids.h holds when p lies outside K by more than 1e-6 of the longest
    // ray to the shooter: a ray entering K within 1e-7 h_p below p's height (where the faces
    // are cut off) would then have to run 1e7 times that margin before reaching the shooter.
    double reach = 0;
    for (const Vec2& c : plane.outline) reach = std::max(reach, length(plane.to_space(c) - p));
    double outside = -HUGE_VAL;
    for (const SolidOpening& o : solid.openings)
        outside = std::max(outside, o.plane.signed_distance(p));
    for (const Plane& face : solid.faces) outside = std::max(outside, face.signed_distance(p));
    if (!(outside > 1e-6 * reach)) {
        if (why) *why = SolidRefusal::inside;
        return std::nullopt;
    }
    const double h_max = slab_top(h_p);
    std::vector<double> h(solid.vertices.size());
    double lowest = HUGE_VAL, highest = -HUGE_VAL;
    for (size_t k = 0; k < h.size(); ++k) {
        h[k] = dot(plane.normal, solid.vertices[k] - plane.origin);
        lowest = std::min(lowest, h[k]);
        highest = std::max(highest, h[k]);
    }
    if (highest < 0 || lowest > h_max) return ConvexPolygon{};  // wholly outside the slab
    // An opening that p sees: a ray entering through it crosses no face when it ends on the
    // shooter inside K (K reaches the shooter's plane), unless that opening lies in the
    // shooter's plane itself (a block standing on its shooter), or when it leaves K through the
    // other opening towards a shooter that reaches in front of that opening's plane.
    const double tol = 1e-9 * (plane.size + solid.diameter);
    if (!openings_covered)
        for (const SolidOpening& seen : solid.openings) {
            if (!(seen.plane.signed_distance(p) > 0)) continue;
            bool passes = false;
            if (lowest <= tol)
                for (int k : seen.outline)
                    if (std::fabs(h[size_t(k)]) > tol) passes = true;
            for (const SolidOpening& other : solid.openings) {
                if (&other == &seen) continue;
                for (const Vec2& c : plane.outline)
                    if (other.plane.signed_distance(plane.to_space(c)) > tol) passes = true;
            }
            if (passes) {
                if (why) *why = SolidRefusal::opening;
                return std::nullopt;
            }
        }
    std::vector<Vec2> projected = project_slab_part(plane, p, h_p, solid.vertices, h, solid.edges);
    if (projected.size() < 3) return ConvexPolygon{};
    const ConvexPolygon hull = convex_hull(std::move(projected));
    if (hull.empty()) return hull;  // seen edge-on: it hides nothing
    return clip_to_shooter(plane, hull);
}

std::optional<ConvexPolygon> sheet_shadow(const ShooterPlane& plane, Vec3 p, double h_p,
                                          const ConvexSheet& sheet) {
    // Every corner strictly between the shooter's plane and p (in the slab), and p on the same
    // side of every face, by more than 1e-9 of the sizes (a face seen edge-on could fold the
    // projection).
    const double h_max = slab_top(h_p);
    for (const Vec3& v : sheet.vertices) {
        const double h = dot(plane.normal, v - plane.origin);
        if (!(h >= 0 && h <= h_max)) return std::nullopt;
    }
    const double tol = 1e-9 * (plane.size + sheet.diameter + h_p);
    int front = 0, behind = 0;
    for (const Plane& face : sheet.faces) {
        const double d = face.signed_distance(p);
        if (d > tol)
            ++front;
        else if (d < -tol)
            ++behind;
        else
            return std::nullopt;
    }
    if (front > 0 && behind > 0) return std::nullopt;
    // The projected boundary encloses the projection; it is the shadow when it is convex: its
    // area (the projected faces' areas, each once) equals its hull's.
    std::vector<Vec2> loop;
    loop.reserve(sheet.boundary.size());
    for (const Vec3& x : sheet.boundary) loop.push_back(project_from(plane, p, h_p, x));
    double area = 0;
    for (size_t k = 0; k < loop.size(); ++k) area += cross(loop[k], loop[(k + 1) % loop.size()]);
    area = 0.5 * std::fabs(area);
    ConvexPolygon hull = convex_hull(std::move(loop));
    if (hull.size() < 3) return ConvexPolygon{};  // seen edge-on: it hides nothing
    // DESIGN: within 1e-9 of the hull's area, as convex_union's test.
    if (std::fabs(signed_area(hull) - area) > 1e-9 * signed_area(hull)) return std::nullopt;
    return clip_to_shooter(plane, hull);
}

ShadowCasters casters_among(const OcclusionContext& context, const std::vector<int>& occluders,
                            int limit) {
    // A candidate that attach_solids did not leave loose belongs to one of the pair's solids,
    // which stands for all its faces.
    ShadowCasters out;
    for (int id : occluders) {
        const int s =
            context.solids && !std::binary_search(context.loose.begin(), context.loose.end(), id)
                ? context.solids->solid_of[size_t(id)]
                : -1;
        if (s < 0)
            out.loose.push_back(id);
        else if (std::find(out.solids.begin(), out.solids.end(), s) == out.solids.end())
            out.solids.push_back(s);
        if (out.count() > limit) break;
    }
    return out;
}

int casters_toward(const OcclusionContext& context, const ShooterPlane& plane, Vec3 p) {
    // As blocked_view counts them: the pair's own when they are few, else those toward p.
    const size_t loose = context.solids ? context.loose.size() : context.candidates.size();
    const int pair_casters = static_cast<int>(context.solid_ids.size() + loose);
    if (pair_casters <= exact_limit) return pair_casters;
    return casters_among(context, occluders_toward(context, plane, p), exact_limit).count();
}

BlockedView blocked_view(const ShooterPlane& plane, Vec3 p, Vec3 n_p,
                         const OcclusionContext* context, const Plane* receiver_plane) {
    BlockedView view;
    // The horizon: the shooter's points x with n_p . (x - p) > 0 are in front of p (or, for a
    // point of a planar receiver, in front of the receiver's plane: the same line each time).
    if (receiver_plane)
        view.front = HalfPlane{
            {dot(receiver_plane->normal, plane.e1), dot(receiver_plane->normal, plane.e2)},
            dot(receiver_plane->normal, plane.origin) - receiver_plane->offset};
    else
        view.front =
            HalfPlane{{dot(n_p, plane.e1), dot(n_p, plane.e2)}, dot(n_p, plane.origin - p)};
    // DESIGN: a corner within rounding of the horizon line lies on it: within 1e-12 of the
    // magnitudes its value is computed from (the shooter's size and the planes' distances from
    // the origin), some 1e4 times their rounding. A shooter sharing an edge with the receiver
    // (the walls of a box) has two corners on the line, and rounding put them in front or
    // behind by turns: the horizon then cut the cells along that edge or not, and their rules
    // (triangles or the tensor rule) differ by the quadrature's error, so that one scene in two
    // units differed by it. (Not a fraction of the shooter's size alone: a shooter 1e9 times
    // its distance from the receiver has its corners 1e-9 of its size in front.)
    const double distances = receiver_plane
                                 ? std::fabs(dot(receiver_plane->normal, plane.origin)) +
                                       std::fabs(receiver_plane->offset)
                                 : std::fabs(dot(n_p, plane.origin)) + std::fabs(dot(n_p, p));
    const double magnitude = plane.size + distances;
    view.front_tolerance = 1e-12 * magnitude;
    const HorizonSides corners = horizon_sides(view, plane.corner, 4);
    if (corners.front == 0) {
        view.behind_all = true;
        return view;
    }
    view.horizon_cuts = corners.behind > 0;

    const double h_p = dot(plane.normal, p - plane.origin);  // height of p above the plane
    if (!context || context->candidates.empty() || h_p <= 0) return view;
    const std::vector<Polygon>& polys = context->octree->polygons();
    // What casts a shadow at p: whole convex solids (one silhouette each), convex sheets (one
    // polygon each) and loose polygons.
    // DESIGN: exact_limit counts these casters, not polygons: a box standing in the way is one
    // shadow, not six (scene_scaling's room of 17 blocks, 102 faces, took one ray per
    // quadrature node at every receiving point when the faces were counted).
    // DESIGN: a caster within 1e-9 of the sizes of p's tangent plane, or behind it, hides
    // nothing from p (the pair's points see each other only in front): a face beside the
    // receiver in its plane, the stool's seat above the point under it.
    const double behind_tolerance = 1e-9 * (plane.size + length(p - plane.origin));
    std::vector<int> near_p;
    ShadowCasters near;  // near_p's casters
    const std::vector<int>* occluders = &context->candidates;
    const std::vector<int>* solid_ids = &context->solid_ids;
    const std::vector<int>* loose = context->solids ? &context->loose : &context->candidates;
    auto use_rays = [&]() {
        view.use_rays = true;
        view.shadows.clear();
        view.occluders = near_p.empty() ? context->candidates : std::move(near_p);
        return view;
    };
    // DESIGN: the pair's casters are counted by surface, as shadow_casters counts them (a cloth
    // of 1,152 triangles is one surface): per point the octree's list of the occluders toward p
    // cost more than projecting the pair's few casters (the room's floor shot with exact
    // visibility: 20 % of its time in occluders_toward and 8 % sorting its lists).
    const int pair_casters =
        static_cast<int>(solid_ids->size()) +
        (context->solids ? context->loose_surfaces : static_cast<int>(loose->size()));
    // Many for the pair (a big scene), or more than the limit at p from the pair's lists: only
    // the occluders that meet the pyramid from p to the shooter count for p, found with the
    // octree, by their solids as the pair's are (attach_solids: a solid of the pair's stands
    // for all its faces); more solids than the limit: rays instead of projection.
    auto toward_p = [&]() {
        near_p = occluders_toward(*context, plane, p);
        near = casters_among(*context, near_p, std::numeric_limits<int>::max());
        occluders = &near_p;
        solid_ids = &near.solids;
        loose = &near.loose;
        return static_cast<int>(solid_ids->size()) <= exact_limit;
    };
    if (pair_casters > exact_limit && !toward_p()) return use_rays();
    const bool may_narrow = occluders == &context->candidates &&
                            static_cast<int>(solid_ids->size() + loose->size()) > exact_limit;
    std::vector<std::vector<ConvexPolygon>> slots;
    for (int attempt = 0;; ++attempt) {
        // Each caster's shadows in a slot of its own, so that they enter the view in the casters'
        // order whatever is decided last (the solids', then the loose polygons' by polygon).
        const size_t n_solids = solid_ids->size();
        slots.assign(n_solids + loose->size(), {});
        auto add_shadow = [&slots](size_t slot, ConvexPolygon shadow) {
            if (!shadow.empty()) slots[slot].push_back(std::move(shadow));
        };
        // Every shadow in the slots so far (a solid refused for an opening has none yet).
        auto shadows_so_far = [&slots]() {
            std::vector<ConvexPolygon> all;
            for (const std::vector<ConvexPolygon>& slot : slots)
                all.insert(all.end(), slot.begin(), slot.end());
            return all;
        };
        auto add_faces = [&](size_t slot, const ConvexSolid& solid) {
            for (int id : solid.polygons)
                if (std::binary_search(occluders->begin(), occluders->end(), id))
                    add_shadow(slot, project_occluder(plane, p, h_p, polys[size_t(id)].vertices()));
        };
        // Each convex solid by its silhouette (convex_solids.h); where its rule does not hold at p,
        // by those of its faces that are occluders, unless only an opening refused it (decided
        // below, once the other casters' shadows are known).
        std::vector<size_t> seen_openings;  // slots of solids refused for an opening p sees
        int n_casters = 0;
        for (size_t k = 0; k < n_solids; ++k) {
            const ConvexSolid& solid = context->solids->solids[size_t((*solid_ids)[k])];
            if (behind_p(p, n_p, solid.vertices, behind_tolerance)) continue;
            ++n_casters;
            SolidRefusal why = SolidRefusal::none;
            if (std::optional<ConvexPolygon> shadow =
                    solid_shadow(plane, p, h_p, solid, false, &why))
                add_shadow(k, std::move(*shadow));
            else if (why == SolidRefusal::opening)
                seen_openings.push_back(k);
            else
                add_faces(k, solid);
        }
        // The loose polygons: a sheet's as one polygon (in the slot of its first), the
        // others one by one. Beyond exact_limit, the polygons of a surface whose bounding box's
        // shadow lies inside a solid's or a sheet's are dropped (a cloth lying on a table, seen
        // past the table), and so is a lone polygon whose shadow does.
        const ConvexSolids* groups = context->solids;
        std::vector<int> sheets_done, sheets_refused;
        std::vector<size_t> singles;  // slots of loose polygons projected one by one
        for (size_t k = 0; k < loose->size(); ++k) {
            const int id = (*loose)[k];
            const int sheet = groups ? groups->sheet_of[size_t(id)] : -1;
            if (sheet >= 0 && std::find(sheets_refused.begin(), sheets_refused.end(), sheet) ==
                                  sheets_refused.end()) {
                if (std::find(sheets_done.begin(), sheets_done.end(), sheet) != sheets_done.end())
                    continue;
                const ConvexSheet& sh = groups->sheets[size_t(sheet)];
                if (behind_p(p, n_p, sh.vertices, behind_tolerance)) {
                    sheets_done.push_back(sheet);
                    continue;
                }
                if (std::optional<ConvexPolygon> shadow = sheet_shadow(plane, p, h_p, sh)) {
                    sheets_done.push_back(sheet);
                    ++n_casters;
                    add_shadow(n_solids + k, std::move(*shadow));
                    continue;
                }
                sheets_refused.push_back(sheet);
            }
            if (behind_p(p, n_p, polys[size_t(id)].vertices(), behind_tolerance)) continue;
            singles.push_back(k);
        }
        if (n_casters + static_cast<int>(singles.size()) > exact_limit) {
            const std::vector<ConvexPolygon> cover = shadows_so_far();  // solids' and sheets'
            std::vector<size_t> kept;
            for (size_t a = 0; a < singles.size();) {
                // The run of loose polygons of one surface (the list is by polygon, and a surface's
                // polygons are consecutive in the octree's list).
                const int surface = polys[size_t((*loose)[singles[a]])].surface();
                size_t b = a;
                Box3 bounds;
                while (b < singles.size() &&
                       polys[size_t((*loose)[singles[b]])].surface() == surface)
                    bounds.extend(polys[size_t((*loose)[singles[b++]])].bounds());
                Outline hull_of;
                if (b - a == 1)
                    hull_of.add_polygon(polys[size_t((*loose)[singles[a]])].vertices());
                else
                    hull_of.add_box(bounds);
                if (!shadow_covered(plane, p, h_p, hull_of, cover))
                    for (size_t c = a; c < b; ++c) kept.push_back(singles[c]);
                a = b;
            }
            singles = std::move(kept);
        }
        n_casters += static_cast<int>(singles.size());
        if (n_casters > exact_limit) {
            if (attempt == 0 && may_narrow && toward_p()) continue;  // the pair's were too many
            return use_rays();
        }
        for (size_t k : singles)
            add_shadow(n_solids + k,
                       project_occluder(plane, p, h_p, polys[size_t((*loose)[k])].vertices()));
        // The solids refused for an opening: their silhouettes where every ray through each opening
        // p sees is blocked by another caster (its shadow holds the opening's: a table leg's top
        // under the table), else their faces.
        if (!seen_openings.empty()) {
            const std::vector<ConvexPolygon> cover = shadows_so_far();
            for (size_t k : seen_openings) {
                const ConvexSolid& solid = context->solids->solids[size_t((*solid_ids)[k])];
                bool covered = true;
                for (const SolidOpening& o : solid.openings) {
                    if (!(o.plane.signed_distance(p) > 0)) continue;
                    std::vector<Vec3> corners;
                    for (int v : o.outline) corners.push_back(solid.vertices[size_t(v)]);
                    Outline opening;
                    opening.add_polygon(corners);
                    covered = covered && shadow_covered(plane, p, h_p, opening, cover);
                }
                std::optional<ConvexPolygon> shadow;
                if (covered) shadow = solid_shadow(plane, p, h_p, solid, true);
                if (shadow)
                    add_shadow(k, std::move(*shadow));
                else
                    add_faces(k, solid);
            }
        }
        break;
    }
    for (std::vector<ConvexPolygon>& slot : slots)
        for (ConvexPolygon& shadow : slot) view.shadows.push_back(std::move(shadow));
    merge_shadows(view.shadows);
    // DESIGN: vertices within 1e-10 of the shooter's size of the line through their neighbours
    // are removed (changing a shadow's area by about 1e-10 of the shooter's). Clipping and the
    // hulls of merged faces leave such vertices where rounding decides, and an edge between
    // two nearly equal vertices has a line pointing anywhere, along which the shadow stage
    // would cut (subtract, classify).
    for (ConvexPolygon& shadow : view.shadows) remove_flat_vertices(shadow, 1e-10 * plane.size);
    return view;
}

void merge_shadows(std::vector<ConvexPolygon>& shadows) {
    // The faces of one solid cast overlapping shadows (a box's top and sides); every cell a
    // shadow edge cuts is integrated over convex pieces, and each overlapping shadow multiplies
    // the pieces. Two shadows whose union is convex (one inside the other, or overlapping or
    // touching so that no notch is left) become that
    // union, until no pair merges (the faces of a convex solid usually end as one polygon,
    // its silhouette's).
    // DESIGN: the convexity test's tolerance, 1e-9 of the hull's area, only absorbs rounding.
    std::vector<Rect> boxes;
    boxes.reserve(shadows.size());
    for (const ConvexPolygon& s : shadows) boxes.push_back(bounding_rect(s));
    for (bool merged = true; merged;) {
        merged = false;
        for (size_t i = 0; i < shadows.size(); ++i)
            for (size_t j = i + 1; j < shadows.size(); ++j) {
                // Shadows whose boxes do not even touch cannot have a convex union.
                const Rect& a = boxes[i];
                const Rect& b = boxes[j];
                if (a.x1 < b.x0 || b.x1 < a.x0 || a.y1 < b.y0 || b.y1 < a.y0) continue;
                // Overlapping, nested or only touching along an edge (two faces of one solid):
                // the hull is the union exactly when the union is convex.
                ConvexPolygon u = convex_union(shadows[i], shadows[j]);
                if (u.empty()) continue;
                shadows[i] = std::move(u);
                boxes[i] = bounding_rect(shadows[i]);
                shadows.erase(shadows.begin() + long(j));
                boxes.erase(boxes.begin() + long(j));
                merged = true;
                j = i;  // shadow i grew: check it against the others again
            }
    }
}

CellVisibility classify_cell(const ConvexPolygon& cell, const BlockedView& view, bool* shadowed) {
    if (shadowed) *shadowed = false;
    if (view.behind_all) return CellVisibility::hidden;
    bool cut = false;
    if (view.horizon_cuts) {
        const HorizonSides sides = horizon_sides(view, cell.data(), cell.size());
        if (sides.front == 0) return CellVisibility::hidden;
        cut = sides.behind > 0;
    }
    for (const ConvexPolygon& s : view.shadows) {
        const Overlap o = classify(cell, s);
        if (o == Overlap::inside) return CellVisibility::hidden;
        if (o == Overlap::partial) {
            cut = true;
            if (shadowed) *shadowed = true;
        }
    }
    return cut ? CellVisibility::cut : CellVisibility::clear;
}

std::vector<ConvexPolygon> visible_pieces(const ConvexPolygon& cell, const BlockedView& view) {
    std::vector<ConvexPolygon> pieces;
    ConvexPolygon first = view.horizon_cuts ? clip(cell, view.front) : cell;
    if (first.empty()) return pieces;
    pieces.push_back(std::move(first));
    // DESIGN: slivers below 1e-14 of the cell's area are dropped (they hold no measurable
    // energy and only cost quadrature points).
    const double min_area = 1e-14 * std::fabs(signed_area(cell));
    for (const ConvexPolygon& s : view.shadows) {
        if (classify(cell, s) == Overlap::disjoint) continue;
        std::vector<ConvexPolygon> next;
        for (const ConvexPolygon& piece : pieces) {
            std::vector<ConvexPolygon> rest = subtract(piece, s, min_area);
            for (ConvexPolygon& r : rest) next.push_back(std::move(r));
        }
        pieces = std::move(next);
        if (pieces.empty()) break;
    }
    // The pieces' fans (pieces_value) follow the geometry, not where clipping began nor which
    // near-repeated vertices rounding left (each would add a fan triangle of no area).
    for (ConvexPolygon& piece : pieces) {
        remove_flat_vertices(piece, 1e-9 * std::sqrt(std::fabs(signed_area(cell))));
        start_at_canonical_vertex(piece);
    }
    return pieces;
}

}  // namespace mbr
