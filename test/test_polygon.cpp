// test/test_polygon.cpp - the planar convex polygon of octree/polygon.h: its bounding planes
// (paper section 6, "Octree", Figure 6), the bounding-plane ray-polygon test against an
// independent in-plane reference, and the (u, v) interpolation of hit points.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/check.h"
#include "octree/polygon.h"

using namespace mbr;

namespace {

/// A random convex polygon together with the exact description it was made from: centre c, an
/// orthonormal right-handed frame (t1, t2, n) and the 2D vertices in that frame.
struct TestPolygon {
    Polygon polygon;
    Vec3 c, t1, t2, n;
    std::vector<Vec2> local;
};

Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-3) return normalize(v);
    }
}

// (t1, t2, n) right-handed and orthonormal.
void frame_of(Vec3 n, Vec3& t1, Vec3& t2) {
    Vec3 a = std::fabs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    t1 = normalize(cross(a, n));
    t2 = cross(n, t1);
}

// k vertices on an ellipse with semi-axes radius and radius * aspect, at stratified angles
// (so neighbours are at least 0.2 * 2 pi / k apart): convex and counter-clockwise about n.
TestPolygon random_polygon(std::mt19937& rng, Vec3 c, double radius, double aspect, int k) {
    std::uniform_real_distribution<double> u01(0, 1);
    Vec3 n = random_unit(rng), t1, t2;
    frame_of(n, t1, t2);
    double theta0 = 2 * Pi * u01(rng);
    std::vector<Vec2> local;
    std::vector<Vec3> vertices;
    std::vector<Vec2> uv;
    for (int i = 0; i < k; ++i) {
        double theta = theta0 + 2 * Pi * (i + 0.8 * u01(rng)) / k;
        Vec2 q{radius * std::cos(theta), radius * aspect * std::sin(theta)};
        local.push_back(q);
        vertices.push_back(c + q.x * t1 + q.y * t2);
        uv.push_back({u01(rng), u01(rng)});
    }
    return TestPolygon{Polygon(vertices, uv, 7), c, t1, t2, n, local};
}

// Reference inside test, independent of the bounding planes: the smallest signed distance of the
// 2D point q from the edge lines of the counter-clockwise 2D polygon (positive inside).
double inside_margin(const std::vector<Vec2>& poly, Vec2 q) {
    double m = HUGE_VAL;
    int n = static_cast<int>(poly.size());
    for (int i = 0; i < n; ++i) {
        Vec2 e = poly[(i + 1) % n] - poly[i];
        m = std::min(m, cross(e, q - poly[i]) / std::sqrt(dot(e, e)));
    }
    return m;
}

Vec2 bilerp(const std::vector<Vec2>& c, double s, double t) {
    return (1 - s) * (1 - t) * c[0] + s * (1 - t) * c[1] + s * t * c[2] + (1 - s) * t * c[3];
}
Vec3 bilerp(const std::vector<Vec3>& c, double s, double t) {
    return (1 - s) * (1 - t) * c[0] + s * (1 - t) * c[1] + s * t * c[2] + (1 - s) * t * c[3];
}

/// The (u, v) of a quad's four corners: the unit square's, or random in [-1, 1]^2.
std::vector<Vec2> corner_uv(std::mt19937& rng, bool random) {
    if (!random) return {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    std::uniform_real_distribution<double> sym(-1, 1);
    std::vector<Vec2> uv;
    for (int k = 0; k < 4; ++k) uv.push_back({sym(rng), sym(rng)});
    return uv;
}

std::vector<Vec2> no_uv(int n) {
    return std::vector<Vec2>(n);
}

}  // namespace

TEST_CASE("polygon: normal, area and bounds of a unit square", "[polygon]") {
    std::vector<Vec3> ccw{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    Polygon p(ccw, no_uv(4), 3);
    CHECK(p.normal() == Vec3{0, 0, 1});
    CHECK(p.area() == Approx(1.0).epsilon(1e-15));  // exact up to one rounding
    CHECK(p.surface() == 3);
    CHECK(p.n_vertices() == 4);
    CHECK(p.bounds().lo == Vec3{0, 0, 0});
    CHECK(p.bounds().hi == Vec3{1, 1, 0});
    CHECK(p.diameter() == Approx(std::sqrt(2.0)).epsilon(1e-15));
    CHECK(p.planarity_error() == 0);
    // Clockwise seen from +z means the front faces -z.
    std::vector<Vec3> cw(ccw.rbegin(), ccw.rend());
    CHECK(Polygon(cw, no_uv(4), 0).normal() == Vec3{0, 0, -1});
    // Bounding plane of the bottom edge: y = 0 with outward normal -y (Figure 6).
    const Plane& b0 = p.bounding_planes()[0];
    CHECK(b0.normal == Vec3{0, -1, 0});
    CHECK(b0.offset == 0);
}

TEST_CASE("polygon: bounding planes contain their edge and the normal and point outward",
          "[polygon]") {
    const unsigned seed = 20240611;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-10, 10), size(-3, 1);
    std::uniform_int_distribution<int> k_dist(3, 9);
    for (int trial = 0; trial < 500; ++trial) {
        double radius = std::pow(10.0, size(rng)), aspect = std::pow(10.0, size(rng) - 1);
        TestPolygon tp = random_polygon(rng, {u(rng), u(rng), u(rng)}, radius,
                                        std::min(aspect, 1.0), k_dist(rng));
        const Polygon& p = tp.polygon;
        CAPTURE(seed, trial, p);
        // The Newell normal equals the generator's frame normal up to the rounding of the
        // coordinates (1e-16 x 10 at most, 1e-14 allowed) over the polygon's width 2 area / diam.
        CHECK(length(p.normal() - tp.n) < 1e-14 * 10 / (2 * p.area() / p.diameter()));
        // Rounding of coordinates up to 10 on polygons as small as 1e-3: 1e-12 absolute.
        const double tol = 1e-12 * (1 + 10 / p.diameter()) * p.diameter();
        int n = p.n_vertices();
        for (int i = 0; i < n; ++i) {
            const Plane& b = p.bounding_planes()[i];
            Vec3 edge = p.vertices()[(i + 1) % n] - p.vertices()[i];
            CHECK(std::fabs(length(b.normal) - 1) < 1e-14);
            CHECK(std::fabs(dot(b.normal, p.normal())) < 1e-9);           // contains the normal
            CHECK(std::fabs(dot(b.normal, edge)) < 1e-9 * length(edge));  // contains the edge
            CHECK(std::fabs(b.signed_distance(p.vertices()[i])) < tol);
            CHECK(std::fabs(b.signed_distance(p.vertices()[(i + 1) % n])) < tol);
            for (int j = 0; j < n; ++j)
                if (j != i && j != (i + 1) % n) CHECK(b.signed_distance(p.vertices()[j]) < tol);
            // Outward: the centroid of the vertices is strictly inside.
            Vec3 centroid;
            for (Vec3 v : p.vertices()) centroid += v;
            CHECK(b.signed_distance(centroid / n) < 0);
        }
    }
}

TEST_CASE("polygon: constructor rejects degenerate, non-planar and non-convex input", "[polygon]") {
    auto make = [](std::vector<Vec3> v) {
        return Polygon(v, no_uv(static_cast<int>(v.size())), 0);
    };
    CHECK_NOTHROW(make({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
    // Too few vertices, (u,v) count mismatch.
    CHECK_THROWS_AS(make({{0, 0, 0}, {1, 0, 0}}), CheckFailure);
    CHECK_THROWS_AS(Polygon({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, no_uv(2), 0), CheckFailure);
    // Not finite, repeated vertex, collinear, all coincident.
    CHECK_THROWS_AS(make({{0, 0, 0}, {NAN, 0, 0}, {0, 1, 0}}), CheckFailure);
    CHECK_THROWS_AS(make({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}}), CheckFailure);
    CHECK_THROWS_AS(make({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}), CheckFailure);
    CHECK_THROWS_AS(make({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}), CheckFailure);
    // Non-planar quad (one corner lifted by 1% of the size), non-convex dart.
    CHECK_THROWS_AS(make({{0, 0, 0}, {1, 0, 0}, {1, 1, 0.01}, {0, 1, 0}}), CheckFailure);
    CHECK_THROWS_AS(make({{0, 0, 0}, {2, 1, 0}, {0, 2, 0}, {1, 1, 0}}), CheckFailure);
    // A pentagram: every turn is to the left, but it winds twice.
    std::vector<Vec3> star;
    for (int i = 0; i < 5; ++i) {
        double a = 2 * Pi * (2 * i % 5) / 5;
        star.push_back({std::cos(a), std::sin(a), 0});
    }
    CHECK_THROWS_AS(make(star), CheckFailure);
    // Collinear vertices along an edge are fine (convex, with a straight angle).
    CHECK_NOTHROW(make({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}}));
}

TEST_CASE("polygon: ray test agrees with an independent in-plane reference", "[polygon]") {
    // Reference: the hit point from the generator's exact frame, then the 2D signed distance to
    // the edge lines of the generator's 2D vertices. Both tests decide the sign of the same
    // quantity, so they may differ only within rounding of the boundary (plus the 1e-10 x
    // diameter slack of the closed test): points within band = 1e-8 x diameter of the boundary
    // accept either answer (and are counted), everything else must agree.
    const unsigned seed = 77;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1), size(-2, 1);
    std::uniform_int_distribution<int> k_dist(3, 8), kind_dist(0, 5);
    long n_rays = 0, n_hits = 0, n_band = 0, n_forced = 0;
    for (int trial = 0; trial < 400; ++trial) {
        double radius = std::pow(10.0, size(rng));
        double aspect = u01(rng) < 0.2 ? 0.02 : 0.3 + 0.7 * u01(rng);  // some long thin ones
        Vec3 c{5 * sym(rng), 5 * sym(rng), 5 * sym(rng)};
        TestPolygon tp = random_polygon(rng, c, radius, aspect, k_dist(rng));
        const Polygon& p = tp.polygon;
        const double diam = p.diameter(), band = 1e-8 * diam;
        const int n = p.n_vertices();
        for (int r = 0; r < 40; ++r) {
            // A target point of the plane, in 2D, chosen by kind.
            int kind = kind_dist(rng);
            int i = std::uniform_int_distribution<int>(0, n - 1)(rng);
            Vec2 a = tp.local[i], b = tp.local[(i + 1) % n];
            Vec2 e = b - a, out = (1 / std::sqrt(dot(e, e))) * Vec2{e.y, -e.x};
            Vec2 target;
            bool must_hit = false;
            switch (kind) {
                case 0:  // anywhere around the polygon
                case 1:
                    target = 1.5 * radius * Vec2{sym(rng), sym(rng)};
                    break;
                case 2:
                    target = a;
                    must_hit = true;
                    break;  // through a vertex
                case 3:     // through an edge point
                    target = a + u01(rng) * e;
                    must_hit = true;
                    break;
                case 4:  // grazing an edge, 1e-6 of the diameter inside or outside
                    target = a + u01(rng) * e + (sym(rng) < 0 ? -1e-6 : 1e-6) * diam * out;
                    break;
                default:  // grazing a vertex
                    target = a + 1e-6 * diam * Vec2{sym(rng), sym(rng)};
                    break;
            }
            Vec3 target3 = tp.c + target.x * tp.t1 + target.y * tp.t2;
            // Origins on either side at 0.5..5 diameters; every fifth ray nearly parallel to the
            // plane (a normal component of 0.5e-3 to 1e-3 of the direction).
            Vec3 dir = random_unit(rng);
            if (r % 5 == 4) {
                double cosine = (sym(rng) < 0 ? -1e-3 : 1e-3) * (0.5 + 0.5 * u01(rng));
                dir = normalize(dir - dot(dir, tp.n) * tp.n + cosine * tp.n);
            }
            if (dot(dir, tp.n) == 0) continue;
            double dist = (0.5 + 4.5 * u01(rng)) * diam;
            double scale = std::pow(10.0, 2 * sym(rng));  // dir need not be unit
            Ray ray{target3 - dist * dir, scale * dir, 0, HUGE_VAL};
            CAPTURE(seed, trial, r, kind, p, ray);

            // Reference hit point and margin from the generator's exact description.
            double t_ref = dot(tp.n, tp.c - ray.origin) / dot(tp.n, ray.dir);
            Vec3 q3 = ray.at(t_ref) - tp.c;
            double margin = inside_margin(tp.local, {dot(q3, tp.t1), dot(q3, tp.t2)});
            std::optional<double> t = p.intersect(ray);
            ++n_rays;
            if (t) {
                ++n_hits;
                // t agrees to 1e-9 relative: both are one division of O(1e-16)-accurate dot
                // products; the nearly parallel rays lose three digits to the 1e-3 cosine.
                CHECK(*t == Approx(t_ref).epsilon(1e-9));
            }
            if (must_hit) {
                ++n_forced;
                CHECK(t.has_value());  // closed polygon: vertices and edges are hit
            } else if (std::fabs(margin) <= band) {
                ++n_band;
            } else {
                CHECK(t.has_value() == (margin > 0));
            }
        }
    }
    CHECK(n_hits > n_rays / 4);  // the rays are not trivially all misses
    WARN("polygon ray test: " << n_rays << " rays, " << n_hits << " hits, " << n_forced
                              << " through vertices or edges (all hit), " << n_band
                              << " within 1e-8 x diameter of the boundary (either answer)");
}

TEST_CASE("polygon: parallel rays, t range and both faces", "[polygon]") {
    Polygon p({{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}}, no_uv(4), 0);
    // Parallel to the plane (dir.z exactly 0): a miss, also when the ray lies in the plane.
    CHECK_FALSE(p.intersect(Ray{{-1, 1, 0}, {1, 0, 0}}));
    CHECK_FALSE(p.intersect(Ray{{-1, 1, 1}, {1, 0, 0}}));
    CHECK_FALSE(p.intersect(Ray{{1, 1, 1}, {0, 0, 0}}));  // zero direction
    // From the front and from the back.
    Ray down{{1, 1, 3}, {0, 0, -1}}, up{{1, 1, -3}, {0, 0, 2}};
    REQUIRE(p.intersect(down));
    CHECK(*p.intersect(down) == 2);
    REQUIRE(p.intersect(up));
    CHECK(*p.intersect(up) == 2);  // t in units of dir: dir has length 2
    // The t range is closed at both ends; the ray is a ray, not a line.
    CHECK(p.intersect(Ray{{1, 1, 3}, {0, 0, -1}, 2, 2}));
    CHECK_FALSE(p.intersect(Ray{{1, 1, 3}, {0, 0, -1}, 0, std::nextafter(2.0, 0.0)}));
    CHECK_FALSE(p.intersect(Ray{{1, 1, 3}, {0, 0, -1}, std::nextafter(2.0, 3.0)}));
    CHECK_FALSE(p.intersect(Ray{{1, 1, 3}, {0, 0, 1}}));
    CHECK(p.intersect(Ray{{1, 1, 3}, {0, 0, 1}, -HUGE_VAL}));
    // A ray starting on the polygon hits at t = 0 (hence shadow rays start at t_min > 0).
    CHECK(p.intersect(Ray{{1, 1, 1}, {0, 0, 1}}) == 0.0);
    // Exactly on a corner and on an edge: inside (closed polygon).
    CHECK(p.intersect(Ray{{2, 2, 3}, {0, 0, -1}}));
    CHECK(p.intersect(Ray{{0, 1, 3}, {0, 0, -1}}));
    CHECK_FALSE(p.intersect(Ray{{2 + 1e-6, 1, 3}, {0, 0, -1}}));
}

TEST_CASE("polygon: neighbours sharing an edge leave no crack", "[polygon]") {
    // Rays through points of a shared edge, computed by interpolation (so off the exact edge by
    // rounding), must hit at least one of the two polygons: the closed test's slack covers it.
    const unsigned seed = 4242;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    long n_rays = 0;
    for (int trial = 0; trial < 300; ++trial) {
        TestPolygon tp = random_polygon(rng, {10 * sym(rng), 10 * sym(rng), 10 * sym(rng)},
                                        std::pow(10.0, 2 * sym(rng)), 0.2 + 0.8 * u01(rng), 4);
        const std::vector<Vec3>& v = tp.polygon.vertices();
        // Split the quad along the diagonal v0 v2, and also fan it around an inner point.
        Polygon t1({v[0], v[1], v[2]}, no_uv(3), 0), t2({v[0], v[2], v[3]}, no_uv(3), 0);
        for (int r = 0; r < 30; ++r) {
            Vec3 target = v[0] + u01(rng) * (v[2] - v[0]);
            Vec3 dir = random_unit(rng);
            if (std::fabs(dot(dir, tp.n)) < 1e-2) continue;
            Ray ray{target - 3 * tp.polygon.diameter() * dir, dir};
            CAPTURE(seed, trial, r, ray, t1, t2);
            CHECK((t1.intersect(ray) || t2.intersect(ray)));
            ++n_rays;
        }
    }
    CHECK(n_rays > 5000);
}

TEST_CASE("polygon: uv_at is barycentric on triangles and exact on linear (u,v)", "[polygon]") {
    // For a linear (u,v) = A x + b, barycentric (triangles) and mean-value coordinates (more
    // vertices) both have linear precision, so uv_at returns the linear function exactly up to
    // rounding (1e-9: condition numbers of thin polygons times O(1e-16)).
    const unsigned seed = 99;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    for (int trial = 0; trial < 300; ++trial) {
        int k = trial % 2 == 0 ? 3 : 5 + trial % 4;
        TestPolygon tp = random_polygon(rng, {sym(rng), sym(rng), sym(rng)}, 0.5 + u01(rng),
                                        0.1 + 0.9 * u01(rng), k);
        Vec3 au = random_unit(rng), av = random_unit(rng);
        double bu = sym(rng), bv = sym(rng);
        auto uv_of = [&](Vec3 x) { return Vec2{dot(au, x) + bu, dot(av, x) + bv}; };
        std::vector<Vec2> uv;
        for (Vec3 x : tp.polygon.vertices()) uv.push_back(uv_of(x));
        Polygon p(tp.polygon.vertices(), uv, 1);
        CAPTURE(seed, trial, p);
        for (int i = 0; i < k; ++i) {  // vertices reproduce their (u,v)
            Vec2 w = p.uv_at(p.vertices()[i]);
            CHECK(std::fabs(w.x - uv[i].x) < 1e-9);
            CHECK(std::fabs(w.y - uv[i].y) < 1e-9);
        }
        for (int r = 0; r < 20; ++r) {
            // A random interior point (a convex combination of the vertices), and an edge point.
            Vec3 x;
            double w_sum = 0;
            for (Vec3 v : p.vertices()) {
                double w = u01(rng);
                x += w * v;
                w_sum += w;
            }
            x = x / w_sum;
            int i = r % k;
            Vec3 on_edge =
                p.vertices()[i] + u01(rng) * (p.vertices()[(i + 1) % k] - p.vertices()[i]);
            for (Vec3 y : {x, on_edge}) {
                CAPTURE(y);
                Vec2 w = p.uv_at(y), expected = uv_of(y);
                CHECK(std::fabs(w.x - expected.x) < 1e-9);
                CHECK(std::fabs(w.y - expected.y) < 1e-9);
            }
        }
    }
}

TEST_CASE("polygon: uv_at inverts the bilinear map of a quadrilateral", "[polygon]") {
    // Planar convex quads (not parallelograms): the point at bilinear parameters (s,t) gets the
    // bilinear interpolation of the corner (u,v) at (s,t). The closed-form root plus Newton
    // polishing is accurate to rounding; 1e-9 allows for the map's conditioning near thin corners.
    const unsigned seed = 1234;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    for (int trial = 0; trial < 400; ++trial) {
        double aspect = trial % 4 == 0 ? 1.0 : 0.1 + 0.9 * u01(rng);
        TestPolygon tp = random_polygon(rng, {3 * sym(rng), 3 * sym(rng), 3 * sym(rng)},
                                        std::pow(10.0, sym(rng)), aspect, 4);
        const std::vector<Vec2> uv = corner_uv(rng, trial % 2 == 1);
        Polygon p(tp.polygon.vertices(), uv, 2);
        CAPTURE(seed, trial, p);
        for (int r = 0; r < 25; ++r) {
            double s = u01(rng), t = u01(rng);
            if (r == 0) s = 0, t = 0;
            if (r == 1) s = 1, t = 0.5;  // on an edge
            if (r == 2) s = 1, t = 1;
            Vec3 x = bilerp(p.vertices(), s, t);
            CAPTURE(s, t, x);
            Vec2 w = p.uv_at(x), expected = bilerp(uv, s, t);
            CHECK(std::fabs(w.x - expected.x) < 1e-9);
            CHECK(std::fabs(w.y - expected.y) < 1e-9);
        }
    }
    // A parallelogram (k2 = 0 in the quadratic) and an axis-aligned rectangle.
    Polygon rect({{0, 0, 0}, {4, 0, 0}, {4, 2, 0}, {0, 2, 0}}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, 0);
    Vec2 w = rect.uv_at({1, 1.5, 0});
    CHECK(w.x == Approx(0.25).margin(1e-15));
    CHECK(w.y == Approx(0.75).margin(1e-15));
    Polygon para({{0, 0, 0}, {4, 0, 0}, {5, 2, 0}, {1, 2, 0}}, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, 0);
    w = para.uv_at({3, 1, 0});
    CHECK(w.x == Approx(0.625).margin(1e-15));
    CHECK(w.y == Approx(0.5).margin(1e-15));
}

TEST_CASE("polygon: uv_at on parallelograms, by their affine inverse, agrees with the bilinear one",
          "[polygon]") {
    // Parallelograms (the twist q0 - q1 + q2 - q3 zero to rounding) take the affine inverse in
    // space; quads twisted by as little as 1e-9 of their size take inverse_bilinear. Both must
    // give the bilinear blend of the corners' (u, v) at the point's (s, t), also for points off
    // the plane (projected along the normal) and slightly outside (extrapolated).
    const unsigned seed = 4321;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    int n_checked = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vec3 origin{100 * sym(rng), 100 * sym(rng), 100 * sym(rng)};
        const double scale = std::pow(10.0, 3 * sym(rng));
        Vec3 e = scale * random_unit(rng), f = scale * (0.1 + u01(rng)) * random_unit(rng);
        const Vec3 n = normalize(cross(e, f));
        if (!(length(cross(e, f)) > 0.05 * scale * length(f))) continue;  // nearly degenerate
        // trial % 3 == 2: the fourth corner moved in the plane by 1e-9 of the size (a twist).
        const Vec3 twist = trial % 3 == 2 ? 1e-9 * scale * normalize(cross(n, e)) : Vec3{0, 0, 0};
        const std::vector<Vec3> v{origin, origin + e, origin + e + f + twist, origin + f};
        const std::vector<Vec2> uv = corner_uv(rng, trial % 2 == 1);
        Polygon p(v, uv, 0);
        CAPTURE(seed, trial, p);
        for (int r = 0; r < 20; ++r) {
            const double s = -0.05 + 1.1 * u01(rng), t = -0.05 + 1.1 * u01(rng);
            const Vec3 x = bilerp(v, s, t) + (r % 2 ? 0.01 * scale * sym(rng) : 0.0) * n;
            const Vec2 w = p.uv_at(x), expected = bilerp(uv, s, t);
            CAPTURE(s, t, x, w, expected);
            CHECK(std::fabs(w.x - expected.x) < 1e-9);
            CHECK(std::fabs(w.y - expected.y) < 1e-9);
            ++n_checked;
        }
    }
    CHECK(n_checked > 4000);
}
