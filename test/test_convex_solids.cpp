// test/test_convex_solids.cpp - convex solids among a scene's polygons and their silhouettes
// (radiosity/visibility/convex_solids.h, solid_shadow in visible_parts.h): which face sets are
// solids, and that a solid's silhouette is the union of its faces' shadows wherever its rule
// holds (against the faces projected one by one and merged, as blocked_view did before).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "radiosity/visibility/convex_solids.h"
#include "radiosity/visibility/occlusion.h"
#include "radiosity/visibility/visible_parts.h"
#include "test/report.h"

using namespace mbr;

namespace {

std::vector<Vec2> no_uv(size_t n) {
    return std::vector<Vec2>(n, Vec2{0, 0});
}

/// The faces of the box [lo, hi] (outward, counter-clockwise from outside), bottom (y = lo.y)
/// last, each its own surface from `first_surface`.
std::vector<Polygon> box_faces(Vec3 lo, Vec3 hi, int first_surface, bool with_bottom) {
    const Vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z},
                       {lo.x, lo.y, hi.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z},
                       {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
    const int faces[6][4] = {{4, 7, 6, 5},   // top (+y)
                             {0, 4, 5, 1},   // -z
                             {1, 5, 6, 2},   // +x
                             {2, 6, 7, 3},   // +z
                             {3, 7, 4, 0},   // -x
                             {0, 1, 2, 3}};  // bottom (-y)
    std::vector<Polygon> out;
    for (int f = 0; f < (with_bottom ? 6 : 5); ++f) {
        std::vector<Vec3> v;
        for (int k : faces[f]) v.push_back(c[k]);
        out.emplace_back(v, no_uv(4), first_surface + f);
    }
    return out;
}

/// The shadows of the faces one by one, merged (the face-by-face path of blocked_view).
std::vector<ConvexPolygon> face_shadows(const ShooterPlane& plane, Vec3 p,
                                        const std::vector<Polygon>& faces) {
    OcclusionContext ctx;
    Octree octree(faces);
    ctx.octree = &octree;
    ctx.shooter_surface = ctx.receiver_surface = -1;
    for (int i = 0; i < int(faces.size()); ++i) ctx.candidates.push_back(i);
    return blocked_view(plane, p, -1.0 * plane.normal, &ctx).shadows;  // p faces the shooter
}

/// The area of the union of convex polygons: each minus the ones before it, in pieces.
double union_area(const std::vector<ConvexPolygon>& shadows) {
    double a = 0;
    for (size_t s = 0; s < shadows.size(); ++s) {
        std::vector<ConvexPolygon> parts{shadows[s]};
        for (size_t t = 0; t < s; ++t) {
            std::vector<ConvexPolygon> next;
            for (const ConvexPolygon& part : parts)
                for (ConvexPolygon& rest : subtract(part, shadows[t])) next.push_back(rest);
            parts = std::move(next);
        }
        for (const ConvexPolygon& part : parts) a += signed_area(part);
    }
    return a;
}

}  // namespace

TEST_CASE("convex solids: which sets of faces bound a convex solid", "[shadow][convex_solids]") {
    SECTION("a box without its bottom: one open solid, its missing face the bottom") {
        const std::vector<Polygon> faces = box_faces({0, 0, 0}, {1, 2, 3}, 0, false);
        const ConvexSolids s = find_convex_solids(faces);
        REQUIRE(s.solids.size() == 1);
        const ConvexSolid& solid = s.solids[0];
        CHECK(solid.open());
        CHECK(solid.polygons == std::vector<int>{0, 1, 2, 3, 4});
        CHECK(solid.vertices.size() == 8);
        CHECK(solid.edges.size() == 12);
        REQUIRE(solid.openings.size() == 1);
        CHECK(solid.openings[0].outline.size() == 4);
        CHECK(solid.openings[0].plane.normal.y == Approx(-1));
        CHECK(solid.openings[0].plane.offset == Approx(0).margin(1e-12));
        CHECK(std::count(s.solid_of.begin(), s.solid_of.end(), 0) == 5);
    }
    SECTION("a closed box") {
        const ConvexSolids s = find_convex_solids(box_faces({0, 0, 0}, {1, 1, 1}, 0, true));
        REQUIRE(s.solids.size() == 1);
        CHECK_FALSE(s.solids[0].open());
        CHECK(s.solids[0].faces.size() == 6);
    }
    SECTION("two boxes apart and a loose quad") {
        std::vector<Polygon> faces = box_faces({0, 0, 0}, {1, 1, 1}, 0, true);
        for (Polygon& p : box_faces({3, 0, 0}, {4, 1, 1}, 6, false)) faces.push_back(p);
        faces.emplace_back(std::vector<Vec3>{{0, 5, 0}, {1, 5, 0}, {1, 5, 1}, {0, 5, 1}},
                           no_uv(4), 11);
        const ConvexSolids s = find_convex_solids(faces);
        REQUIRE(s.solids.size() == 2);
        CHECK(s.solid_of[3] == 0);
        CHECK(s.solid_of[7] == 1);
        CHECK(s.solid_of[11] == -1);
    }
    SECTION("a block meshed with the floor it stands on: the block alone (a concave edge at its "
            "foot)") {
        // The floor as four quads around the block's footprint, sharing the footprint's edges
        // with the block's sides.
        std::vector<Polygon> faces = box_faces({1, 0, 1}, {2, 1, 2}, 0, false);
        const Vec3 o[4] = {{0, 0, 0}, {3, 0, 0}, {3, 0, 3}, {0, 0, 3}};  // the floor's corners
        const Vec3 f[4] = {{1, 0, 1}, {2, 0, 1}, {2, 0, 2}, {1, 0, 2}};  // the footprint's
        for (int k = 0; k < 4; ++k)  // counter-clockwise seen from above (+y)
            faces.emplace_back(std::vector<Vec3>{o[k], f[k], f[(k + 1) % 4], o[(k + 1) % 4]},
                               no_uv(4), 10 + k);
        for (Polygon& p : faces) {  // the floor quads must face up
            if (p.surface() >= 10 && p.normal().y < 0) {
                std::vector<Vec3> v = p.vertices();
                std::reverse(v.begin(), v.end());
                p = Polygon(v, no_uv(4), p.surface());
            }
        }
        const ConvexSolids s = find_convex_solids(faces);
        REQUIRE(s.solids.size() == 1);
        CHECK(s.solids[0].polygons == std::vector<int>{0, 1, 2, 3, 4});
        CHECK(s.solids[0].open());
    }
    SECTION("a box with a T-junction: one side split in two, its neighbours not") {
        std::vector<Polygon> faces = box_faces({0, 0, 0}, {2, 1, 1}, 0, true);
        // Face 1 (z = 0, corners (0,0,0) (0,1,0) (2,1,0) (2,0,0)) as two quads split at x = 1.
        faces.erase(faces.begin() + 1);
        faces.emplace_back(std::vector<Vec3>{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}},
                           no_uv(4), 6);
        faces.emplace_back(std::vector<Vec3>{{1, 0, 0}, {1, 1, 0}, {2, 1, 0}, {2, 0, 0}},
                           no_uv(4), 7);
        const ConvexSolids s = find_convex_solids(faces);
        REQUIRE(s.solids.size() == 1);
        CHECK(s.solids[0].polygons.size() == 7);
        CHECK_FALSE(s.solids[0].open());
    }
    SECTION("an open tube: a solid with two openings, top and bottom") {
        std::vector<Polygon> tube = box_faces({0, 0, 0}, {1, 2, 1}, 0, false);
        tube.erase(tube.begin());  // top and bottom missing
        const ConvexSolids s = find_convex_solids(tube);
        REQUIRE(s.solids.size() == 1);
        REQUIRE(s.solids[0].openings.size() == 2);
        CHECK(s.solids[0].openings[0].outline.size() == 4);
        CHECK(s.solids[0].openings[1].outline.size() == 4);
        const double y0 = s.solids[0].openings[0].plane.normal.y;
        const double y1 = s.solids[0].openings[1].plane.normal.y;
        CHECK(std::fabs(y0) == Approx(1));
        CHECK(y0 * y1 == Approx(-1));  // one looks up, the other down
        CHECK(s.sheets.empty());
    }
    SECTION("not solids: faces looking inward, two faces only, three missing faces, an L") {
        std::vector<Polygon> inward;
        for (const Polygon& p : box_faces({0, 0, 0}, {1, 1, 1}, 0, true)) {
            std::vector<Vec3> v = p.vertices();
            std::reverse(v.begin(), v.end());
            inward.emplace_back(v, no_uv(4), p.surface());
        }
        CHECK(find_convex_solids(inward).solids.empty());
        std::vector<Polygon> two = box_faces({0, 0, 0}, {1, 1, 1}, 0, false);
        two.erase(two.begin() + 2, two.end());
        CHECK(find_convex_solids(two).solids.empty());
        std::vector<Polygon> three = box_faces({0, 0, 0}, {1, 1, 1}, 0, false);
        three.erase(three.begin(), three.begin() + 2);  // top, bottom and one side missing
        CHECK(find_convex_solids(three).solids.empty());
        // Two boxes glued along an edge of their tops: connected, not convex.
        std::vector<Polygon> l = box_faces({0, 0, 0}, {1, 1, 1}, 0, false);
        std::vector<Polygon> other = box_faces({1, 0, 0}, {2, 2, 1}, 5, false);
        l.insert(l.end(), other.begin(), other.end());
        for (const ConvexSolid& solid : find_convex_solids(l).solids)
            CHECK(solid.polygons.size() == 5);  // each box alone, never the two together
    }
}

TEST_CASE("convex solids: a solid's silhouette is the union of its faces' shadows",
          "[shadow][convex_solids]") {
    // A block standing on the floor (no bottom) and a floating closed box, seen from random
    // points in front of three shooters: the floor the block stands on (its missing face in the
    // shooter's plane), a wall beside it and the ceiling (points below the block's top cut it).
    const std::vector<Polygon> block = box_faces({2, 0, 2}, {3, 1.5, 3.2}, 0, false);
    const std::vector<Polygon> floating = box_faces({1, 1, 1}, {1.6, 1.4, 1.5}, 0, true);
    const Surface shooters[] = {
        Surface::planar_quad({0, 0, 0}, {0, 0, 5}, {5, 0, 5}, {5, 0, 0}),  // floor, facing up
        Surface::planar_quad({5, 0, 0}, {5, 0, 5}, {5, 3, 5}, {5, 3, 0}),  // wall x = 5
        Surface::planar_quad({0, 3, 0}, {5, 3, 0}, {5, 3, 5}, {0, 3, 5}),  // ceiling, down
    };
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.05, 4.95), v(0.02, 2.95);
    int compared = 0, refused = 0;
    for (const std::vector<Polygon>* faces : {&block, &floating}) {
        const ConvexSolids solids = find_convex_solids(*faces);
        REQUIRE(solids.solids.size() == 1);
        for (const Surface& shooter : shooters) {
            const ShooterPlane plane = make_shooter_plane(shooter);
            for (int k = 0; k < 300; ++k) {
                const Vec3 p{u(rng), v(rng), u(rng)};
                const double h_p = dot(plane.normal, p - plane.origin);
                if (h_p <= 0) continue;
                const std::optional<ConvexPolygon> silhouette =
                    solid_shadow(plane, p, h_p, solids.solids[0]);
                if (!silhouette) {
                    ++refused;
                    continue;
                }
                ++compared;
                const std::vector<ConvexPolygon> merged = face_shadows(plane, p, *faces);
                INFO("p = " << p << ", shooter normal " << plane.normal);
                const double scale = plane.size * plane.size;
                CHECK(signed_area(*silhouette) == Approx(union_area(merged)).margin(1e-9 * scale));
                // Where the faces' shadows merged into one polygon, it is the silhouette.
                if (merged.size() == 1)
                    for (const Vec2& q : *silhouette) {
                        bool near = contains(merged[0], q);
                        for (const Vec2& r : merged[0])
                            near = near || std::hypot(q.x - r.x, q.y - r.y) <= 1e-9 * plane.size;
                        CHECK(near);
                    }
            }
        }
    }
    mbr::test::report() << "convex solids: silhouette against the faces' shadows at " << compared
                        << " points, the rule refused at " << refused << "\n";
    CHECK(compared > 1000);
    CHECK(refused < compared / 10);
}

TEST_CASE("convex solids: no silhouette where the rule fails", "[shadow][convex_solids]") {
    const ShooterPlane plane = make_shooter_plane(
        Surface::planar_quad({0, 3, 0}, {5, 3, 0}, {5, 3, 5}, {0, 3, 5}));  // ceiling, down
    SECTION("a point on (or inside) the solid") {
        const ConvexSolids s = find_convex_solids(box_faces({2, 0, 2}, {3, 1.5, 3}, 0, true));
        REQUIRE(s.solids.size() == 1);
        for (const Vec3 p : {Vec3{2.5, 1.5, 2.5}, Vec3{2.5, 1, 2.5}, Vec3{3, 1, 2.5}})
            CHECK_FALSE(solid_shadow(plane, p, dot(plane.normal, p - plane.origin), s.solids[0]));
    }
    SECTION("a missing face seen from below, on a solid that reaches the shooter") {
        // A box hanging from the ceiling, open at its bottom: from below a ray through the
        // opening to the ceiling inside the box crosses no face.
        const ConvexSolids s = find_convex_solids(box_faces({2, 2, 2}, {3, 3, 3}, 0, false));
        REQUIRE(s.solids.size() == 1);
        const Vec3 p{2.5, 0.5, 2.5};
        CHECK_FALSE(solid_shadow(plane, p, dot(plane.normal, p - plane.origin), s.solids[0]));
    }
    SECTION("a solid wholly behind the shooter or above the point hides nothing") {
        const ConvexSolids s = find_convex_solids(box_faces({2, 3.5, 2}, {3, 4, 3}, 0, true));
        const Vec3 p{2.5, 1, 2.5};
        const std::optional<ConvexPolygon> shadow =
            solid_shadow(plane, p, dot(plane.normal, p - plane.origin), s.solids[0]);
        REQUIRE(shadow);
        CHECK(shadow->empty());
    }
}

TEST_CASE("convex solids: a pair's candidates split into whole solids and loose polygons",
          "[shadow][convex_solids]") {
    std::vector<Polygon> faces = box_faces({2, 0, 2}, {3, 1, 3}, 10, false);  // surfaces 10-14
    for (Polygon& p : box_faces({0, 0, 0}, {1, 1, 1}, 20, true)) faces.push_back(p);
    faces.emplace_back(std::vector<Vec3>{{0, 5, 0}, {1, 5, 0}, {1, 5, 1}, {0, 5, 1}}, no_uv(4),
                       30);
    const Octree octree(faces);
    const ConvexSolids solids = find_convex_solids(faces);
    REQUIRE(solids.solids.size() == 2);
    OcclusionContext ctx;
    ctx.octree = &octree;
    ctx.shooter_surface = 21;  // a face of the second box: that solid casts no shadow
    ctx.receiver_surface = 99;
    ctx.candidates = {1, 3, 6, 8, 11};
    attach_solids(ctx, solids);
    CHECK(ctx.solids == &solids);
    CHECK(ctx.solid_ids == std::vector<int>{0});
    CHECK(ctx.loose == std::vector<int>{11});
    CHECK(ctx.loose_surfaces == 1);
    CHECK(shadow_casters(ctx) == 2);
}

TEST_CASE("convex solids: many faces but few solids are projected and not ray-cast",
          "[shadow][convex_solids]") {
    // Eight closed boxes (48 faces, more than exact_limit) between a ceiling shooter and a floor
    // receiver: exact visibility counts its shadow casters by solids (8), so every receiving
    // point projects silhouettes instead of casting one ray per quadrature node (use_rays). The
    // shadows must say what rays say: a shooter point lies in a shadow exactly when the segment
    // from the receiving point to it is blocked.
    const std::vector<Vec3> ceiling{{0, 3, 0}, {5, 3, 0}, {5, 3, 5}, {0, 3, 5}};
    const std::vector<Vec3> floor{{0, 0, 0}, {0, 0, 5}, {5, 0, 5}, {5, 0, 0}};
    const Surface shooter = Surface::planar_quad(ceiling[0], ceiling[1], ceiling[2], ceiling[3]);
    const Surface receiver = Surface::planar_quad(floor[0], floor[1], floor[2], floor[3]);
    std::vector<Polygon> polygons;
    polygons.emplace_back(ceiling, no_uv(4), 0);
    polygons.emplace_back(floor, no_uv(4), 1);
    for (int b = 0; b < 8; ++b) {
        const double x = 0.3 + 0.6 * b, z = b % 2 == 0 ? 1.5 : 3.0;
        for (Polygon& f : box_faces({x, 1.0, z}, {x + 0.35, 1.6, z + 0.5}, 2 + 6 * b, true))
            polygons.push_back(f);
    }
    const Octree octree(polygons);
    const ConvexSolids solids = find_convex_solids(polygons);
    REQUIRE(solids.solids.size() == 8);
    OcclusionContext ctx = make_occlusion_context(octree, shooter, 0, receiver, 1, 0);
    attach_solids(ctx, solids);
    REQUIRE(static_cast<int>(ctx.candidates.size()) > exact_limit);
    REQUIRE(ctx.solid_ids.size() + ctx.loose.size() <= size_t(exact_limit));
    const ShooterPlane plane = make_shooter_plane(shooter);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.01, 4.99), w(0, 1);
    int shadowed = 0, lit = 0;
    for (int k = 0; k < 40; ++k) {
        const Vec3 p{u(rng), 0, u(rng)};
        const BlockedView view = blocked_view(plane, p, {0, 1, 0}, &ctx);
        CHECK_FALSE(view.use_rays);
        CHECK(view.shadows.size() <= 8);
        for (int j = 0; j < 50; ++j) {
            const Vec3 x = shooter.point(w(rng), w(rng));
            const Vec2 q{dot(x - plane.origin, plane.e1), dot(x - plane.origin, plane.e2)};
            bool in_shadow = false;
            for (const ConvexPolygon& s : view.shadows) in_shadow = in_shadow || contains(s, q);
            const Ray segment{p, x - p, 1e-9, 1 - 1e-9};
            CAPTURE(p, x);
            CHECK(in_shadow == octree.any_hit(segment));
            ++(in_shadow ? shadowed : lit);
        }
    }
    CHECK(shadowed > 100);
    CHECK(lit > 100);
}

TEST_CASE("convex solids: a whole tessellated sphere is one solid, its silhouette its facets'",
          "[shadow][convex_solids]") {
    // A whole sphere's facets bound one convex polyhedron (max_solid_faces is 1024): one shadow
    // caster instead of hundreds of loose facets. At 16 and 24 facets a turn (256 and 576
    // faces, both over the cap of 64 before), centred at the origin with its pole along y,
    // where the corners at the seam and the poles need not agree to the bit (sin(2 pi) and
    // sin(pi) are 1e-16, not 0); it fails with the old cap. Its silhouette
    // from points under a ceiling shooter against the facets themselves: a point of the
    // shooter's plane lies in the silhouette exactly when the segment to it meets a facet,
    // checked on a 60 x 60 grid (away from the silhouette's outline by 1e-9 of the shooter's size).
    const Surface shooter =
        Surface::planar_quad({-2.5, 3, -2.5}, {2.5, 3, -2.5}, {2.5, 3, 2.5}, {-2.5, 3, 2.5});
    const ShooterPlane plane = make_shooter_plane(shooter);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-2, 2), v(-1.2, -0.7);
    auto outline_distance = [](const ConvexPolygon& poly, Vec2 q) {
        double d = HUGE_VAL;
        for (size_t k = 0; k < poly.size(); ++k) {
            const Vec2 a = poly[k], b = poly[(k + 1) % poly.size()];
            const Vec2 ab{b.x - a.x, b.y - a.y}, aq{q.x - a.x, q.y - a.y};
            const double t =
                std::clamp((ab.x * aq.x + ab.y * aq.y) / (ab.x * ab.x + ab.y * ab.y), 0.0, 1.0);
            d = std::min(d, std::hypot(aq.x - t * ab.x, aq.y - t * ab.y));
        }
        return d;
    };
    for (const int resolution : {16, 24}) {
        const Surface sphere =
            Surface::sphere({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, 0.61, 0, Pi, 0, 2 * Pi, false);
        std::vector<Polygon> facets;
        for (const Facet& f : sphere.tessellate(resolution))
            facets.emplace_back(f.vertices, f.uv, 0);
        CAPTURE(resolution, facets.size());
        REQUIRE(facets.size() == size_t(resolution * resolution));
        const ConvexSolids solids = find_convex_solids(facets);
        REQUIRE(solids.solids.size() == 1);
        CHECK(solids.solids[0].polygons.size() == facets.size());
        CHECK_FALSE(solids.solids[0].open());
        int inside = 0, outside = 0;
        for (int k = 0; k < 3; ++k) {
            const Vec3 p{u(rng), v(rng), u(rng)};
            const double h_p = dot(plane.normal, p - plane.origin);
            REQUIRE(h_p > 0);
            const std::optional<ConvexPolygon> silhouette =
                solid_shadow(plane, p, h_p, solids.solids[0]);
            REQUIRE(silhouette);
            REQUIRE(!silhouette->empty());
            Rect box{HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL};
            for (const Vec2& q : plane.outline) {
                box.x0 = std::min(box.x0, q.x);
                box.x1 = std::max(box.x1, q.x);
                box.y0 = std::min(box.y0, q.y);
                box.y1 = std::max(box.y1, q.y);
            }
            for (int i = 0; i < 60; ++i)
                for (int j = 0; j < 60; ++j) {
                    const Vec2 q{box.x0 + (i + 0.5) / 60 * (box.x1 - box.x0),
                                 box.y0 + (j + 0.5) / 60 * (box.y1 - box.y0)};
                    if (outline_distance(*silhouette, q) <= 1e-9 * plane.size) continue;
                    const Vec3 x = plane.to_space(q);
                    const Ray ray{p, x - p, 1e-9, 1 - 1e-9};
                    bool blocked = false;
                    for (const Polygon& f : facets)
                        if (f.intersect_segment(ray)) {
                            blocked = true;
                            break;
                        }
                    CAPTURE(p, q);
                    CHECK(contains(*silhouette, q) == blocked);
                    (blocked ? inside : outside) += 1;
                }
        }
        CHECK(inside > 100);  // the silhouette covers part of the grid, not all of it
        CHECK(outside > 100);
    }
}

namespace {

/// An open tube of `sides` faces around the vertical axis through (x, z), from y0 to y1, faces
/// outward, all of surface `surface`.
std::vector<Polygon> tube_faces(double x, double z, double r, double y0, double y1, int sides,
                                int surface) {
    std::vector<Polygon> out;
    const double pi = std::acos(-1.0);
    for (int k = 0; k < sides; ++k) {
        const double a = 2 * pi * k / sides, b = 2 * pi * ((k + 1) % sides) / sides;
        const Vec3 p{x + r * std::cos(a), 0, z + r * std::sin(a)};
        const Vec3 q{x + r * std::cos(b), 0, z + r * std::sin(b)};
        // Counter-clockwise from outside: (p, y0), (p, y1), (q, y1), (q, y0).
        out.emplace_back(
            std::vector<Vec3>{{p.x, y0, p.z}, {p.x, y1, p.z}, {q.x, y1, q.z}, {q.x, y0, q.z}},
            no_uv(4), surface);
    }
    return out;
}

/// A fan of triangles around (x, y, z) in the plane y, facing up.
std::vector<Polygon> disk_fan(double x, double y, double z, double r, int sectors, int surface) {
    std::vector<Polygon> out;
    const double pi = std::acos(-1.0);
    for (int k = 0; k < sectors; ++k) {
        const double a = 2 * pi * k / sectors, b = 2 * pi * ((k + 1) % sectors) / sectors;
        out.emplace_back(std::vector<Vec3>{{x, y, z},
                                           {x + r * std::cos(b), y, z + r * std::sin(b)},
                                           {x + r * std::cos(a), y, z + r * std::sin(a)}},
                         no_uv(3), surface);
    }
    return out;
}

/// A bilinear patch over [x0, x1] x [z0, z1] at height y, its (x1, z1) corner lifted by `lift`,
/// as n x n cells of two triangles each, facing up.
std::vector<Polygon> twisted_grid(double x0, double x1, double z0, double z1, double y, double lift,
                                  int n, int surface) {
    auto at = [&](int i, int j) {
        const double s = double(i) / n, t = double(j) / n;
        return Vec3{x0 + s * (x1 - x0), y + s * t * lift, z0 + t * (z1 - z0)};
    };
    std::vector<Polygon> out;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            // Up-facing: counter-clockwise seen from +y, (x, z) -> (x, z+1) -> (x+1, z+1).
            out.emplace_back(std::vector<Vec3>{at(i, j), at(i, j + 1), at(i + 1, j + 1)}, no_uv(3),
                             surface);
            out.emplace_back(std::vector<Vec3>{at(i, j), at(i + 1, j + 1), at(i + 1, j)}, no_uv(3),
                             surface);
        }
    return out;
}

}  // namespace

TEST_CASE("convex solids: sheets are the disks of one surface's faces", "[shadow][convex_solids]") {
    SECTION("a flat fan and a twisted grid: sheets, with their boundary loops") {
        std::vector<Polygon> faces = disk_fan(0, 1, 0, 0.5, 12, 0);
        for (Polygon& p : twisted_grid(2, 3, 0, 1, 1, 0.01, 4, 1)) faces.push_back(p);
        const ConvexSolids s = find_convex_solids(faces);
        CHECK(s.solids.empty());
        REQUIRE(s.sheets.size() == 2);
        CHECK(s.sheets[0].polygons.size() == 12);
        CHECK(s.sheets[0].boundary.size() == 12);
        CHECK(s.sheets[0].vertices.size() == 13);
        CHECK(s.sheets[1].polygons.size() == 32);
        CHECK(s.sheets[1].boundary.size() == 16);
        CHECK(s.sheet_of[0] == 0);
        CHECK(s.sheet_of[12] == 1);
    }
    SECTION("not sheets: a ring (two boundary loops), a face repeated, faces turned both ways") {
        std::vector<Polygon> ring;
        for (const Polygon& p : tube_faces(0, 0, 1, 0, 1, 8, 0)) ring.push_back(p);  // a band
        std::vector<Polygon> twice = disk_fan(0, 0, 0, 1, 6, 0);
        twice.push_back(twice[0]);
        std::vector<Polygon> flipped = disk_fan(0, 0, 0, 1, 6, 0);
        std::vector<Vec3> v = flipped[2].vertices();
        std::reverse(v.begin(), v.end());
        flipped[2] = Polygon(v, no_uv(3), 0);
        for (const std::vector<Polygon>* faces : {&twice, &flipped})
            CHECK(find_convex_solids(*faces).sheets.empty());
        const ConvexSolids band = find_convex_solids(ring);
        CHECK(band.sheets.empty());
        CHECK(band.solids.size() == 1);  // the band is an open tube instead
    }
}

TEST_CASE("convex solids: tubes, sheets and covered openings shadow exactly what their faces block",
          "[shadow][convex_solids]") {
    // A table (a closed box) on four legs that are open tubes standing on the floor, their tops
    // under the table; a cloth (a twisted grid of 72 triangles) lying on the table; a stool seat
    // (a fan of 12 triangles) on a tube leg; a pipe, open at its top, through which the floor
    // shows from above. More polygons than exact_limit, few casters: the legs' silhouettes hold
    // where the table covers their tops, the pipe's only where nothing looks into it, the seat
    // and the cloth are one shadow each or dropped inside the table's. At random receiving
    // points, whether a segment to a random point of the shooter is blocked by some polygon
    // (brute force) must agree with the view's shadows, away from their edges.
    std::vector<Polygon> polys;
    polys.emplace_back(std::vector<Vec3>{{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}}, no_uv(4), 0);
    polys.emplace_back(std::vector<Vec3>{{0, 3, 0}, {4, 3, 0}, {4, 3, 4}, {0, 3, 4}}, no_uv(4), 1);
    polys.emplace_back(std::vector<Vec3>{{4, 0, 0}, {4, 0, 4}, {4, 3, 4}, {4, 3, 0}}, no_uv(4), 2);
    const size_t first_occluder = polys.size();
    for (Polygon& p : box_faces({1, 0.7, 1}, {2.6, 0.75, 2.2}, 10, true)) polys.push_back(p);
    int leg = 20;
    for (const Vec3 c :
         {Vec3{1.1, 0, 1.1}, Vec3{2.5, 0, 1.1}, Vec3{1.1, 0, 2.1}, Vec3{2.5, 0, 2.1}})
        for (Polygon& p : tube_faces(c.x, c.z, 0.04, 0, 0.7, 8, leg++)) polys.push_back(p);
    for (Polygon& p : twisted_grid(1.3, 2.3, 1.3, 2.0, 0.751, 0.002, 6, 30)) polys.push_back(p);
    for (Polygon& p : disk_fan(3.2, 0.45, 3.0, 0.2, 12, 31)) polys.push_back(p);
    for (Polygon& p : tube_faces(3.2, 3.0, 0.03, 0, 0.45, 8, 32)) polys.push_back(p);
    // A pipe open at the top: from above, the floor inside it shows through.
    for (Polygon& p : tube_faces(3.3, 0.8, 0.3, 0, 1.0, 8, 33)) polys.push_back(p);
    const Octree octree(polys);
    const ConvexSolids solids = find_convex_solids(octree.polygons());
    CHECK(solids.solids.size() == 7);  // the table, five legs and the pipe
    CHECK(solids.sheets.size() == 2);  // the cloth and the seat
    const Surface floor = Surface::planar_quad({0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0});
    const Surface ceiling = Surface::planar_quad({0, 3, 0}, {4, 3, 0}, {4, 3, 4}, {0, 3, 4});
    const Surface wall = Surface::planar_quad({4, 0, 0}, {4, 0, 4}, {4, 3, 4}, {4, 3, 0});
    struct Pair {
        const Surface *shooter, *receiver;
        int s, r;
    };
    const Pair pairs[] = {{&floor, &ceiling, 0, 1},
                          {&ceiling, &floor, 1, 0},
                          {&wall, &ceiling, 2, 1},
                          {&wall, &floor, 2, 0},
                          {&floor, &wall, 0, 2}};
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.01, 0.99);
    long compared = 0, disagree = 0, views = 0, by_rays = 0;
    for (const Pair& pair : pairs) {
        OcclusionContext ctx =
            make_occlusion_context(octree, *pair.shooter, pair.s, *pair.receiver, pair.r, 0);
        attach_solids(ctx, solids);
        const ShooterPlane plane = make_shooter_plane(*pair.shooter);
        for (int k = 0; k < 60; ++k) {
            const SurfacePoint p = pair.receiver->evaluate(u(rng), u(rng));
            const BlockedView view = blocked_view(plane, p.position, p.normal, &ctx);
            ++views;
            if (view.use_rays) {
                ++by_rays;
                continue;
            }
            for (int j = 0; j < 200; ++j) {
                const SurfacePoint y = pair.shooter->evaluate(u(rng), u(rng));
                if (dot(p.normal, y.position - p.position) <= 0) continue;  // behind p
                const Vec2 q = plane.to_plane(y.position);
                bool in_shadow = false, near_edge = false;
                for (const ConvexPolygon& shadow : view.shadows) {
                    in_shadow = in_shadow || contains(shadow, q);
                    for (size_t e = 0; e < shadow.size(); ++e) {
                        const Vec2 a = shadow[e], b = shadow[(e + 1) % shadow.size()];
                        const Vec2 d = b - a;
                        const double t = std::clamp(dot(q - a, d) / dot(d, d), 0.0, 1.0);
                        const Vec2 w = q - (a + t * d);
                        near_edge = near_edge || std::sqrt(dot(w, w)) < 1e-6;
                    }
                }
                if (near_edge) continue;
                const Ray ray{p.position, y.position - p.position, 1e-9, 1 - 1e-9};
                bool blocked = false;
                for (size_t o = first_occluder; o < polys.size() && !blocked; ++o)
                    blocked = polys[o].intersect_segment(ray).has_value();
                ++compared;
                if (blocked != in_shadow) {
                    ++disagree;
                    CAPTURE(pair.s, pair.r, p.position, y.position, blocked, in_shadow);
                    CHECK(blocked == in_shadow);
                }
            }
        }
    }
    mbr::test::report() << "tubes, sheets and covered openings: " << compared
                        << " segments compared at " << views - by_rays << " of " << views
                        << " points (the others by rays), " << disagree << " disagree\n";
    CHECK(disagree == 0);
    CHECK(compared > 20000);
    CHECK(by_rays < views / 10);
}
