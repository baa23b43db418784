// test/test_octree.cpp - the paper's octree (section 6, "Octree"): the three-step node-polygon
// test against exact clipping, and closest-hit / any-hit queries against brute force.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "math/check.h"
#include "octree/octree.h"
#include "test/clip_reference.h"

using namespace mbr;

namespace {

Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-3) return normalize(v);
    }
}

// k vertices on an ellipse (semi-axes radius, radius * aspect) in the plane through c with
// normal n, at stratified angles: convex and counter-clockwise about n.
std::vector<Vec3> ellipse_polygon(std::mt19937& rng, Vec3 c, Vec3 n, double radius, double aspect,
                                  int k) {
    std::uniform_real_distribution<double> u01(0, 1);
    Vec3 a = std::fabs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    Vec3 t1 = normalize(cross(a, n)), t2 = cross(n, t1);
    double theta0 = 2 * Pi * u01(rng);
    std::vector<Vec3> v;
    for (int i = 0; i < k; ++i) {
        double theta = theta0 + 2 * Pi * (i + 0.8 * u01(rng)) / k;
        v.push_back(c + radius * std::cos(theta) * t1 + radius * aspect * std::sin(theta) * t2);
    }
    return v;
}

Polygon make_polygon(std::vector<Vec3> v, int surface = 0) {
    std::vector<Vec2> uv;
    for (size_t i = 0; i < v.size(); ++i) uv.push_back({0.1 * i, 1 - 0.1 * i});
    return Polygon(std::move(v), std::move(uv), surface);
}

Box3 cube_at(Vec3 centre, double side) {
    Vec3 h{0.5 * side, 0.5 * side, 0.5 * side};
    return Box3{centre - h, centre + h};
}

// The exact reference for node-polygon intersection (test/clip_reference.h).
bool clip_reference_meets(const Box3& cube, const std::vector<Vec3>& polygon) {
    return polygon_meets_box(polygon, cube);
}

// Step 3 alone: the polygon's plane has cube corners on both sides (or on it).
bool plane_meets_cube(const Box3& cube, const Polygon& polygon) {
    bool above = false, below = false;
    for (int i = 0; i < 8; ++i) {
        Vec3 corner{(i & 1) ? cube.hi.x : cube.lo.x, (i & 2) ? cube.hi.y : cube.lo.y,
                    (i & 4) ? cube.hi.z : cube.lo.z};
        double s = polygon.plane().signed_distance(corner);
        above = above || s >= 0;
        below = below || s <= 0;
    }
    return above && below;
}

// Tallies of the three-step test against the reference.
struct NodeTestTally {
    long n_pairs = 0, n_true_meet = 0, n_true_apart = 0;
    long n_false_apart = 0;                    // must stay zero
    long n_over = 0;                           // reported meet, truly apart
    long n_plane_alone_over = 0;               // step 3 alone would report meet, truly apart
    long n_by_step[5] = {0, 0, 0, 0, 0};       // answers per NodeTestResult
    long n_over_by_step[5] = {0, 0, 0, 0, 0};  // over-reports per NodeTestResult
    void add(NodeTestResult r, bool truth, bool plane_meets) {
        int s = static_cast<int>(r);
        bool meets = r == NodeTestResult::meet_by_projection || r == NodeTestResult::meet_by_plane;
        ++n_pairs;
        ++n_by_step[s];
        (truth ? n_true_meet : n_true_apart) += 1;
        if (truth && !meets) ++n_false_apart;
        if (!truth && meets) {
            ++n_over;
            ++n_over_by_step[s];
        }
        if (!truth && plane_meets) ++n_plane_alone_over;
    }
    std::string summary() const {
        std::ostringstream os;
        int plane = static_cast<int>(NodeTestResult::meet_by_plane);
        os << n_pairs << " pairs (" << n_true_meet << " meet, " << n_true_apart
           << " apart by clipping); over-reported " << n_over << " = "
           << 100.0 * n_over / std::max(1L, n_true_apart) << "% of the truly apart pairs, "
           << 100.0 * n_over / std::max(1L, n_pairs) << "% of all; step 3 said meet "
           << n_by_step[plane] << " times, wrongly " << n_over_by_step[plane] << " ("
           << 100.0 * n_over_by_step[plane] / std::max(1L, n_by_step[plane]) << "%); decided by "
           << "bounds " << n_by_step[0] << ", projection meet " << n_by_step[1]
           << ", projection apart " << n_by_step[2] << ", plane apart " << n_by_step[3]
           << ". Step 3 alone would over-report " << n_plane_alone_over << " = "
           << 100.0 * n_plane_alone_over / std::max(1L, n_true_apart) << "% of the apart pairs";
        return os.str();
    }
};

// Checks one pair: never a false "apart", and over-reports only from step 3.
void check_pair(const Box3& cube, const Polygon& polygon, NodeTestTally& tally) {
    bool truth = clip_reference_meets(cube, polygon.vertices());
    NodeTestResult r = classify_node_polygon(cube, polygon);
    CAPTURE(cube, polygon, to_string(r), truth);
    if (truth) CHECK(node_meets_polygon(cube, polygon));
    if (!truth && node_meets_polygon(cube, polygon)) CHECK(r == NodeTestResult::meet_by_plane);
    tally.add(r, truth, plane_meets_cube(cube, polygon));
}

// A random scene in [0, 10]^3: convex polygons of 3-6 vertices (mostly triangles and quads),
// radii log-uniform in [0.05, 2], 15% long thin ones (aspect 0.02, radius up to 4). A flat scene
// puts them all in z = 0 at half the size (else they would overlap seven deep on average).
std::vector<Polygon> random_scene(std::mt19937& rng, int n, bool flat = false) {
    std::uniform_real_distribution<double> u01(0, 1), pos(0, 10);
    std::vector<Polygon> scene;
    for (int i = 0; i < n; ++i) {
        double w = u01(rng);
        int k = w < 0.45 ? 3 : (w < 0.9 ? 4 : 5 + static_cast<int>(2 * u01(rng)));
        bool thin = u01(rng) < 0.15;
        double radius = thin ? 0.5 + 3.5 * u01(rng) : 0.05 * std::pow(40.0, u01(rng));
        if (flat) radius *= 0.5;
        double aspect = thin ? 0.02 : 0.3 + 0.7 * u01(rng);
        Vec3 n = flat ? Vec3{0, 0, u01(rng) < 0.5 ? 1.0 : -1.0} : random_unit(rng);
        Vec3 c{pos(rng), pos(rng), flat ? 0.0 : pos(rng)};
        std::vector<Vec3> v = ellipse_polygon(rng, c, n, radius, aspect, k);
        if (flat)
            for (Vec3& p : v) p.z = 0;  // exactly flat
        scene.push_back(make_polygon(v, i % 17));
    }
    return scene;
}

// Brute force: every polygon, the smallest t, the lowest index among equal t.
std::optional<Hit> brute_closest(const std::vector<Polygon>& polygons, const Ray& ray) {
    std::optional<Hit> best;
    for (int i = 0; i < static_cast<int>(polygons.size()); ++i) {
        std::optional<double> t = polygons[i].intersect(ray);
        if (t && (!best || *t < best->t))
            best = Hit{i, polygons[i].surface(), polygons[i].uv_at(ray.at(*t)), *t};
    }
    return best;
}
bool brute_any(const std::vector<Polygon>& polygons, const Ray& ray) {
    for (const Polygon& p : polygons)
        if (p.intersect(ray)) return true;
    return false;
}

// Random rays for a scene in [0, 10]^3: origins in [-5, 15]^3 (many inside the root), a third
// aimed at a random point of a random polygon, a third between two points (shadow segments with
// t in [1e-6, 1 - 1e-6]), a third with random t ranges; directions not normalised.
Ray random_ray(std::mt19937& rng, const std::vector<Polygon>& scene, int kind) {
    std::uniform_real_distribution<double> u01(0, 1), pos(-5, 15);
    Vec3 o{pos(rng), pos(rng), pos(rng)};
    double scale = std::pow(10.0, 2 * u01(rng) - 1);
    switch (kind % 3) {
        case 0: {
            const Polygon& p =
                scene[std::uniform_int_distribution<int>(0, (int)scene.size() - 1)(rng)];
            Vec3 target;
            double w_sum = 0;
            for (Vec3 v : p.vertices()) {
                double w = u01(rng);
                target += w * v;
                w_sum += w;
            }
            target = target / w_sum;
            if (kind % 6 == 3) target = p.vertices()[0];  // through a vertex
            return Ray{o, scale * (target - o)};
        }
        case 1: {
            Vec3 b{pos(rng), pos(rng), pos(rng)};
            return Ray{o, b - o, 1e-6, 1 - 1e-6};
        }
        default: {
            double t0 = u01(rng) < 0.5 ? 0.0 : 20 * u01(rng) / scale;
            double t1 = t0 + (u01(rng) < 0.3 ? HUGE_VAL : 20 * u01(rng) / scale);
            return Ray{o, scale * random_unit(rng), t0, t1};
        }
    }
}

// Random rays with their brute-force answers, computed once and shared by several octrees.
struct RaySet {
    std::vector<Ray> rays;
    std::vector<std::optional<Hit>> closest;
    std::vector<bool> any;
};
RaySet brute_force_rays(const std::vector<Polygon>& scene, std::mt19937& rng, int n_rays) {
    RaySet set;
    for (int r = 0; r < n_rays; ++r) {
        Ray ray = random_ray(rng, scene, r);
        set.rays.push_back(ray);
        set.closest.push_back(brute_closest(scene, ray));
        set.any.push_back(brute_any(scene, ray));
    }
    return set;
}

// Compares the octree with the brute-force answers; returns the octree's stats.
RayStats check_against_brute_force(const Octree& octree, const RaySet& set, unsigned seed,
                                   long* n_hits = nullptr) {
    RayStats stats;
    for (size_t r = 0; r < set.rays.size(); ++r) {
        const Ray& ray = set.rays[r];
        const std::optional<Hit>& expected = set.closest[r];
        CAPTURE(seed, r, ray);
        std::optional<Hit> got = octree.closest_hit(ray, &stats);
        REQUIRE(got.has_value() == expected.has_value());
        if (got) {
            if (n_hits) ++*n_hits;
            CAPTURE(*got, *expected);
            // Same polygon, same t bit for bit (both come from the same Polygon::intersect), the
            // same surface and (u, v).
            CHECK(got->polygon == expected->polygon);
            CHECK(got->t == expected->t);
            CHECK(got->surface == expected->surface);
            CHECK(got->uv.x == expected->uv.x);
            CHECK(got->uv.y == expected->uv.y);
        }
        CHECK(octree.any_hit(ray, &stats) == set.any[r]);
    }
    return stats;
}

}  // namespace

TEST_CASE("octree: node test never misses a meeting on random polygons and cubes", "[octree]") {
    // Random cubes (side 0.1..3) and random convex polygons (radius 0.01..5, some thin) around
    // them: over-reporting is measured, a false "apart" fails.
    const unsigned seed = 31337;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    NodeTestTally tally;
    for (int trial = 0; trial < 20000; ++trial) {
        double side = std::pow(10.0, -1 + 1.5 * u01(rng));
        Box3 cube = cube_at({sym(rng), sym(rng), sym(rng)}, side);
        double radius = side * std::pow(10.0, -1 + 1.7 * u01(rng));
        double aspect = u01(rng) < 0.2 ? 0.03 : 0.2 + 0.8 * u01(rng);
        Vec3 c = cube.centre() + (0.6 * side + 0.6 * radius) * Vec3{sym(rng), sym(rng), sym(rng)};
        int k = 3 + trial % 6;
        Polygon p = make_polygon(ellipse_polygon(rng, c, random_unit(rng), radius, aspect, k));
        CAPTURE(seed, trial);
        check_pair(cube, p, tally);
    }
    CHECK(tally.n_false_apart == 0);
    // Exact for convex polygons (argument in octree.h); no pair here is within the 1e-12
    // rounding tolerance of touching, so not even a tolerance-sized over-report is expected.
    CHECK(tally.n_over == 0);
    CHECK(tally.n_true_meet > 2000);  // both answers well represented
    CHECK(tally.n_true_apart > 2000);
    WARN("node test, random polygons and cubes: " << tally.summary());
}

TEST_CASE("octree: node test on contained and touching configurations", "[octree]") {
    const unsigned seed = 555;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    NodeTestTally tally;
    // Dyadic cubes (corners multiples of 1/8, side 1/2..2) so that the touching constructions
    // below put vertices exactly on faces, edges and corners.
    auto dyadic_cube = [&]() {
        Vec3 lo{std::floor(16 * sym(rng)) / 8, std::floor(16 * sym(rng)) / 8,
                std::floor(16 * sym(rng)) / 8};
        double side = (4 << std::uniform_int_distribution<int>(0, 2)(rng)) / 8.0;
        return Box3{lo, lo + Vec3{side, side, side}};
    };
    for (int trial = 0; trial < 3000; ++trial) {
        Box3 cube = dyadic_cube();
        double side = cube.extent().x;
        int kind = trial % 7;
        CAPTURE(seed, trial, kind);
        Vec3 n = random_unit(rng);
        switch (kind) {
            case 0: {  // small polygon inside the cube: meet by projection
                Vec3 c = cube.centre() + 0.2 * side * Vec3{sym(rng), sym(rng), sym(rng)};
                Polygon p = make_polygon(ellipse_polygon(rng, c, n, 0.2 * side, 0.5, 4));
                check_pair(cube, p, tally);
                CHECK(classify_node_polygon(cube, p) == NodeTestResult::meet_by_projection);
                break;
            }
            case 1: {  // a huge polygon through the cube (the cube inside the polygon's slab)
                Vec3 c = cube.centre() + 0.4 * side * Vec3{sym(rng), sym(rng), sym(rng)};
                Polygon p = make_polygon(ellipse_polygon(rng, c, n, 50 * side, 1, 5));
                check_pair(cube, p, tally);
                CHECK(node_meets_polygon(cube, p));
                break;
            }
            case 2: {  // a huge polygon just missing the cube: its plane clears every corner
                Vec3 far = cube.centre() + (0.9 * side + 0.1 * u01(rng)) * n;
                Polygon p = make_polygon(ellipse_polygon(rng, far, n, 50 * side, 1, 5));
                check_pair(cube, p, tally);
                CHECK_FALSE(node_meets_polygon(cube, p));
                break;
            }
            case 3: {  // lying in a face plane (z = lo.z or hi.z), overlapping the face or not
                double z = u01(rng) < 0.5 ? cube.lo.z : cube.hi.z;
                Vec3 c{cube.centre().x + side * 1.5 * sym(rng),
                       cube.centre().y + side * 1.5 * sym(rng), z};
                std::vector<Vec3> v = ellipse_polygon(rng, c, {0, 0, 1}, side * u01(rng) + 0.05,
                                                      0.5 + 0.5 * u01(rng), 3 + trial % 4);
                for (Vec3& x : v) x.z = z;
                check_pair(cube, make_polygon(v), tally);
                break;
            }
            case 4: {  // one vertex exactly on a face (inside it), the rest outside
                std::vector<Vec3> v =
                    ellipse_polygon(rng, {0, 0, 0}, n, side * (0.2 + u01(rng)), 0.6, 3 + trial % 4);
                int axis = trial % 3;
                bool upper = u01(rng) < 0.5;
                // The extreme vertex towards the cube goes onto the face at a point of the face.
                int best = 0;
                for (int i = 1; i < (int)v.size(); ++i)
                    if (upper ? v[i][axis] < v[best][axis] : v[i][axis] > v[best][axis]) best = i;
                Vec3 on_face = cube.centre() + 0.45 * side * Vec3{sym(rng), sym(rng), sym(rng)};
                on_face[axis] = upper ? cube.hi[axis] : cube.lo[axis];
                Vec3 shift = on_face - v[best];
                for (Vec3& x : v) x += shift;
                v[best] = on_face;
                Polygon p = make_polygon(v);
                CHECK(clip_reference_meets(cube, p.vertices()));
                check_pair(cube, p, tally);
                break;
            }
            case 5: {  // an edge exactly in a face plane, the polygon outside: touching along it
                int axis = trial % 3, a = (axis + 1) % 3, b = (axis + 2) % 3;
                bool upper = u01(rng) < 0.5;
                double sgn = upper ? 1 : -1;
                Vec3 d;  // the edge direction, in the face plane
                double phi = 2 * Pi * u01(rng);
                d[a] = std::cos(phi);
                d[b] = std::sin(phi);
                Vec3 out;  // leaving the cube, and tilted
                out[axis] = sgn * (0.2 + u01(rng));
                out[a] = sym(rng);
                out[b] = sym(rng);
                out = normalize(out - dot(out, d) * d);
                Vec3 p0 = cube.centre() + 0.6 * side * Vec3{sym(rng), sym(rng), sym(rng)};
                p0[axis] = upper ? cube.hi[axis] : cube.lo[axis];
                double len = side * (0.1 + u01(rng)), w = side * (0.1 + u01(rng));
                std::vector<Vec3> v{p0, p0 + len * d, p0 + len * d + w * out, p0 + w * out};
                v[1][axis] = p0[axis];  // exactly in the face plane
                check_pair(cube, make_polygon(v), tally);
                break;
            }
            default: {  // through a corner of the cube, in a plane touching the cube only there:
                        // either a vertex at the corner or an edge passing through it (dyadic
                        // offsets keep both exact)
                Vec3 sigma{u01(rng) < 0.5 ? -1.0 : 1.0, u01(rng) < 0.5 ? -1.0 : 1.0,
                           u01(rng) < 0.5 ? -1.0 : 1.0};
                Vec3 corner;
                for (int k = 0; k < 3; ++k) corner[k] = sigma[k] > 0 ? cube.hi[k] : cube.lo[k];
                int r = trial % 3;  // a cyclic permutation of the axes
                auto perm = [&](Vec3 x) {
                    Vec3 y;
                    for (int k = 0; k < 3; ++k) y[(k + r) % 3] = sigma[(k + r) % 3] * x[k];
                    return y;
                };
                Vec3 a = perm({0.125, -0.125, 0}), w = perm({0.125, 0.125, -0.25});
                std::vector<Vec3> v = u01(rng) < 0.5
                                          ? std::vector<Vec3>{corner - a, corner + a, corner + w}
                                          : std::vector<Vec3>{corner, corner + a, corner + w};
                Polygon p = make_polygon(v);
                CHECK(clip_reference_meets(cube, p.vertices()));
                check_pair(cube, p, tally);
                // Moved away by 1/64 along the plane's normal sigma, it is truly apart, and step 3
                // (or an earlier one) must say so: the corner is then strictly on one side.
                Vec3 away = (1.0 / 64) * sigma;
                for (Vec3& x : v) x += away;
                Polygon q = make_polygon(v);
                check_pair(cube, q, tally);
                CHECK_FALSE(node_meets_polygon(cube, q));
                break;
            }
        }
    }
    CHECK(tally.n_false_apart == 0);
    CHECK(tally.n_over == 0);  // touching is meeting; the near misses are 1/64 away
    WARN("node test, contained and touching cases: " << tally.summary());
}

TEST_CASE("octree: node test over-reporting on an octree-like workload", "[octree]") {
    // What the build actually asks: the grid cubes of depths 2-4 over a random scene against
    // the polygons whose bounding boxes they overlap.
    const unsigned seed = 2718;
    std::mt19937 rng(seed);
    std::vector<Polygon> scene = random_scene(rng, 1000);
    NodeTestTally tally;
    long n_bbox_pairs = 0;
    for (int depth = 2; depth <= 4; ++depth) {
        int m = 1 << depth;
        double h = 10.0 / m;
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                for (int k = 0; k < m; ++k) {
                    Box3 cube{{i * h, j * h, k * h}, {(i + 1) * h, (j + 1) * h, (k + 1) * h}};
                    for (const Polygon& p : scene) {
                        if (!overlaps(cube, p.bounds())) continue;
                        ++n_bbox_pairs;
                        CAPTURE(seed, depth, i, j, k);
                        check_pair(cube, p, tally);
                    }
                }
    }
    CHECK(tally.n_false_apart == 0);
    CHECK(tally.n_over == 0);
    WARN(
        "node test, octree grid cubes of depth 2-4 vs a 1000-polygon scene (pairs with "
        "overlapping bounding boxes only): "
        << tally.summary());
}

TEST_CASE("octree: node test is exact where step 3 alone over-reports", "[octree]") {
    // The hard case for step 3: the polygon lies in a plane through the cube, next to the cube's
    // cross-section. The plane test alone says "meet" for every such pair; steps 1 and 2 must
    // catch the ones that are truly apart (see the argument in octree.h).
    const unsigned seed = 8128;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1), sym(-1, 1);
    Box3 cube{{0, 0, 0}, {1, 1, 1}};
    NodeTestTally tally;
    for (int trial = 0; trial < 30000; ++trial) {
        Vec3 n = random_unit(rng);
        Vec3 through{u01(rng), u01(rng), u01(rng)};  // the plane passes through the cube
        Vec3 a = std::fabs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        Vec3 t1 = normalize(cross(a, n)), t2 = cross(n, t1);
        double spread = std::pow(10.0, sym(rng));
        Vec3 c = through + spread * (sym(rng) * t1 + sym(rng) * t2);
        double aspect = u01(rng) < 0.3 ? 0.03 : 0.2 + 0.8 * u01(rng);
        Polygon p = make_polygon(
            ellipse_polygon(rng, c, n, spread * (0.05 + u01(rng)), aspect, 3 + trial % 5));
        CAPTURE(seed, trial);
        check_pair(cube, p, tally);
    }
    CHECK(tally.n_false_apart == 0);
    CHECK(tally.n_over == 0);
    CHECK(tally.n_plane_alone_over > 5000);  // the case is really exercised
    WARN("node test, polygons in planes through the cube: " << tally.summary());
}

TEST_CASE("octree: projections follow Warnock's classes", "[octree]") {
    Box3 cube{{0, 0, 0}, {1, 1, 1}};
    // A small triangle in the plane z = 5: its xy projection is inside the square, its yz and zx
    // projections are segments at z = 5, apart from the squares.
    Polygon small = make_polygon({{0.2, 0.2, 5}, {0.8, 0.2, 5}, {0.5, 0.8, 5}});
    CHECK(projection_relation(cube, small, 2) == ProjectionRelation::inside);
    CHECK(projection_relation(cube, small, 0) == ProjectionRelation::apart);
    CHECK(projection_relation(cube, small, 1) == ProjectionRelation::apart);
    CHECK(classify_node_polygon(cube, small) == NodeTestResult::apart_by_bounds);
    // A large tilted triangle surrounding the xy square without crossing it: undecided in xy.
    Polygon big = make_polygon({{-5, -5, 0}, {10, -5, 1}, {-5, 10, 2}});
    CHECK(projection_relation(cube, big, 2) == ProjectionRelation::undecided);
    // A triangle whose xy projection is beside the square: apart, although boxes overlap.
    Polygon beside = make_polygon({{1.2, -0.5, 0.5}, {3, 2, 0.5}, {1.2, 2, 0.6}});
    CHECK(projection_relation(cube, beside, 2) == ProjectionRelation::apart);
    // A diagonal sliver crossing the corner region of the square but missing it, boxes overlap:
    // x + y = 2.1 misses the unit square.
    Polygon sliver = make_polygon({{2.1, 0, 0.5}, {0, 2.1, 0.5}, {0, 2.1, 0.6}, {2.1, 0, 0.6}});
    CHECK(classify_node_polygon(cube, sliver) == NodeTestResult::apart_by_projection);
    // Touching the square at one point: x + y = 2 passes through the corner (1, 1).
    Polygon touch = make_polygon({{2, 0, 0.5}, {0, 2, 0.5}, {0, 2, 0.6}, {2, 0, 0.6}});
    CHECK(node_meets_polygon(cube, touch));
    CHECK(clip_reference_meets(cube, touch.vertices()));
    CHECK_THROWS_AS(projection_relation(cube, small, 3), CheckFailure);
}

TEST_CASE("octree: empty, single-polygon and flat scenes", "[octree]") {
    Ray ray{{-1, 0.5, 0.5}, {1, 0, 0}};
    Octree empty({});
    CHECK(empty.polygon_count() == 0);
    CHECK(empty.node_count() == 0);
    CHECK(empty.bounds().empty());
    RayStats stats;
    CHECK_FALSE(empty.closest_hit(ray, &stats));
    CHECK_FALSE(empty.any_hit(ray, &stats));
    CHECK(stats.n_nodes_visited == 0);

    Octree one({Polygon({{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}},
                        {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, 5)});
    CHECK(one.node_count() == 1);
    CHECK(one.depth() == 0);
    std::optional<Hit> hit = one.closest_hit(ray);
    REQUIRE(hit);
    CHECK(hit->polygon == 0);
    CHECK(hit->surface == 5);
    CHECK(hit->t == 1);
    CHECK(hit->uv.x == Approx(0.5).margin(1e-15));  // (y, z) = (0.5, 0.5): the quad's centre
    CHECK(hit->uv.y == Approx(0.5).margin(1e-15));
    CHECK(one.any_hit(ray));
    CHECK_FALSE(one.any_hit(Ray{ray.origin, ray.dir, 0, 0.999}));
    CHECK_FALSE(one.closest_hit(Ray{ray.origin, -1 * ray.dir}));
    // The root cube holds the polygon (flat in x) with a margin.
    Box3 b = one.bounds();
    CHECK(b.lo.x < 0);
    CHECK(b.hi.x > 0);
    CHECK(b.lo.y < 0);
    CHECK(b.hi.y > 1);

    // A flat scene (every polygon in z = 0): the root is still a cube; rays from both sides.
    const unsigned seed = 8;
    std::mt19937 rng(seed);
    Octree flat(random_scene(rng, 1200, true));
    Vec3 e = flat.bounds().extent();
    CHECK(e.x == Approx(e.z).epsilon(1e-15));  // hi - lo of a cube, up to rounding
    CHECK(flat.depth() > 0);
    WARN("flat scene: " << flat.polygon_count() << " polygons, " << flat.node_count()
                        << " nodes, depth " << flat.depth() << ", " << flat.reference_count()
                        << " references");
    long n_hits = 0;
    check_against_brute_force(flat, brute_force_rays(flat.polygons(), rng, 2000), seed, &n_hits);
    CHECK(n_hits > 200);
}

TEST_CASE("octree: closest_hit and any_hit equal brute force on random scenes", "[octree]") {
    const unsigned seed = 1001;
    std::mt19937 rng(seed);
    std::vector<Polygon> scene = random_scene(rng, 1500);
    // Add a 10 x 10 grid of quads sharing edges (a tessellated wall) and two exact duplicates,
    // so that rays through shared edges and ties in t occur.
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j)
            scene.push_back(make_polygon({{i * 1.0, j * 1.0, 5.5},
                                          {i + 1.0, j * 1.0, 5.5},
                                          {i + 1.0, j + 1.0, 5.5},
                                          {i * 1.0, j + 1.0, 5.5}},
                                         99));
    scene.push_back(scene[3]);
    scene.push_back(scene[10]);
    int n_polygons = static_cast<int>(scene.size());
    const int n_rays = 3000;
    const RaySet set = brute_force_rays(scene, rng, n_rays);

    for (Octree::Options options :
         {Octree::Options{}, Octree::Options{6, 4}, Octree::Options{0, 8}, Octree::Options{8, 1}}) {
        auto start = std::chrono::steady_clock::now();
        Octree octree(scene, options);
        double build_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        CAPTURE(seed, options.max_depth, options.max_polygons_per_leaf);
        CHECK(octree.polygon_count() == n_polygons);
        CHECK(octree.depth() <= options.max_depth);
        for (const Polygon& p : octree.polygons()) {  // the root encloses every polygon
            CHECK(p.bounds().lo.x > octree.bounds().lo.x);
            CHECK(p.bounds().hi.z < octree.bounds().hi.z);
        }
        long n_hits = 0;
        RayStats stats = check_against_brute_force(octree, set, seed, &n_hits);
        CHECK(n_hits > n_rays / 4);
        CHECK(stats.n_nodes_visited > 0);
        CHECK(stats.n_polygons_tested > 0);
        WARN("octree max_depth " << options.max_depth << ", max_polygons_per_leaf "
                                 << options.max_polygons_per_leaf << ": " << n_polygons
                                 << " polygons, " << octree.node_count() << " nodes, "
                                 << octree.leaf_count() << " leaves, depth " << octree.depth()
                                 << ", " << octree.reference_count() << " references, built in "
                                 << build_s << " s; per query (closest + any): "
                                 << double(stats.n_nodes_visited) / (2 * n_rays) << " nodes, "
                                 << double(stats.n_polygons_tested) / (2 * n_rays)
                                 << " polygon tests (brute force: " << n_polygons << ')');
    }

    // Rays through the shared edges and corners of the grid hit it (no cracks), from above.
    Octree octree(scene);
    for (int i = 0; i <= 20; ++i) {
        Vec3 target{0.5 * i, 0.5 * (i % 7) + 1, 5.5};
        Ray ray{target + Vec3{0.3, -0.2, 4.5}, Vec3{-0.3, 0.2, -4.5}};
        CAPTURE(i, ray);
        std::optional<Hit> hit = octree.closest_hit(ray);
        std::optional<Hit> expected = brute_closest(scene, ray);
        REQUIRE(expected);
        REQUIRE(hit);
        CHECK(hit->polygon == expected->polygon);
    }
}

TEST_CASE("octree: stats count work, and the tree beats brute force", "[octree]") {
    const unsigned seed = 4711;
    std::mt19937 rng(seed);
    std::vector<Polygon> scene = random_scene(rng, 1000);
    Octree octree(scene);
    RayStats closest, any;
    const int n_rays = 4000;
    std::vector<Ray> rays;
    for (int r = 0; r < n_rays; ++r) rays.push_back(random_ray(rng, scene, r));
    for (const Ray& ray : rays) {
        RayStats one;
        octree.closest_hit(ray, &one);
        // Counters add up: a second query with the same stats object doubles them.
        RayStats twice = one;
        octree.closest_hit(ray, &twice);
        CHECK(twice.n_nodes_visited == 2 * one.n_nodes_visited);
        CHECK(twice.n_polygons_tested == 2 * one.n_polygons_tested);
        // Each polygon at most once per ray (32-slot cache; duplicates only after eviction).
        CHECK(one.n_polygons_tested <= octree.polygon_count());
        closest += one;
        octree.any_hit(ray, &any);
    }
    CHECK(closest.n_nodes_visited > 0);
    CHECK(closest.n_polygons_tested > 0);
    CHECK(any.n_polygons_tested <= closest.n_polygons_tested);
    // A ray that misses the root cube visits nothing.
    RayStats miss;
    CHECK_FALSE(octree.closest_hit(Ray{{-100, -100, -100}, {-1, 0, 0}}, &miss));
    CHECK(miss.n_nodes_visited == 0);
    CHECK(miss.n_polygons_tested == 0);

    double nodes_c = double(closest.n_nodes_visited) / n_rays;
    double tests_c = double(closest.n_polygons_tested) / n_rays;
    double nodes_a = double(any.n_nodes_visited) / n_rays;
    double tests_a = double(any.n_polygons_tested) / n_rays;
    CHECK(tests_c < 0.1 * scene.size());  // the point of the octree
    // Time against brute force (reported, not checked: timing is not a test).
    auto time = [&](auto&& f) {
        auto start = std::chrono::steady_clock::now();
        long n = 0;
        for (const Ray& ray : rays) n += f(ray) ? 1 : 0;
        double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return std::make_pair(s, n);
    };
    auto oct = time([&](const Ray& r) { return octree.closest_hit(r).has_value(); });
    auto brute = time([&](const Ray& r) { return brute_closest(scene, r).has_value(); });
    CHECK(oct.second == brute.second);
    WARN("1000-polygon scene, " << octree.node_count() << " nodes, depth " << octree.depth()
                                << ": closest_hit visits " << nodes_c << " nodes and tests "
                                << tests_c << " polygons per ray; any_hit " << nodes_a << " and "
                                << tests_a << "; brute force tests 1000. Time for " << n_rays
                                << " rays: octree " << oct.first << " s, brute force "
                                << brute.first << " s");
}

TEST_CASE("octree: coplanar overlapping polygons do not blow up the build", "[octree]") {
    // Twelve copies of one large quad: no split can separate them, so the root stays a leaf
    // (instead of 4^10 nodes along the plane); the lowest index wins ties.
    std::vector<Polygon> scene;
    for (int i = 0; i < 12; ++i)
        scene.push_back(make_polygon({{0, 0, 0}, {8, 0, 0}, {8, 8, 0}, {0, 8, 0}}, i));
    scene.push_back(make_polygon({{1, 1, 1}, {1.1, 1, 1}, {1, 1.1, 1}}, 12));
    Octree octree(scene);
    CHECK(octree.node_count() < 100);
    std::optional<Hit> hit = octree.closest_hit(Ray{{4, 4, 3}, {0, 0, -1}});
    REQUIRE(hit);
    CHECK(hit->polygon == 0);
    CHECK(hit->t == 3);
}

TEST_CASE("octree: a cluster in one corner is subdivided", "[octree]") {
    // Forty tiny triangles in a 0.01 box at the origin and a quad 1 away: the first splits put
    // the whole cluster into one child, which must still be split (down to cubes of 0.001 at
    // depth 10) until the triangles separate.
    const unsigned seed = 12;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<Polygon> scene;
    for (int i = 0; i < 40; ++i) {
        Vec3 c{0.01 * u01(rng), 0.01 * u01(rng), 0.01 * u01(rng)};
        scene.push_back(make_polygon(ellipse_polygon(rng, c, random_unit(rng), 1e-4, 1, 3)));
    }
    scene.push_back(make_polygon({{0.9, 0.9, 1}, {1, 0.9, 1}, {1, 1, 1}, {0.9, 1, 1}}));
    Octree octree(scene);
    CAPTURE(seed, octree.node_count(), octree.depth());
    CHECK(octree.depth() >= 8);
    RayStats stats;
    long n_hits = 0;
    for (int i = 0; i < 40; ++i) {
        Vec3 target;
        for (Vec3 v : scene[i].vertices()) target += v / 3.0;
        Ray ray{target + Vec3{1, 2, 3}, -1 * Vec3{1, 2, 3}};
        std::optional<Hit> hit = octree.closest_hit(ray, &stats);
        std::optional<Hit> expected = brute_closest(scene, ray);
        REQUIRE(hit.has_value() == expected.has_value());
        if (hit) CHECK(hit->polygon == expected->polygon);
        n_hits += hit ? 1 : 0;
    }
    CHECK(n_hits == 40);
    CHECK(stats.n_polygons_tested < 40 * 10);  // not all forty per ray
}

TEST_CASE("octree: region queries see every node's grown cube", "[octree]") {
    // polygons_near and append_polygons_near walk the stored tree: a test that accepts
    // everything is asked once per node, and the leaves' lists add up to reference_count().
    // The cubes it is shown are the nodes' cubes grown by the margin: the root's first, each
    // other inside an earlier one at half its side. A polygon that meets the region (exact
    // clipping) is always returned.
    const unsigned seed = 515;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    const std::vector<Polygon> scene = random_scene(rng, 900);
    const Octree octree(scene, Octree::Options{8, 4});
    std::vector<Box3> cubes;
    std::vector<int> all;
    octree.append_polygons_near(
        [&](const Box3& c) {
            cubes.push_back(c);
            return true;
        },
        all);
    CHECK(static_cast<int>(cubes.size()) == octree.node_count());
    CHECK(static_cast<long>(all.size()) == octree.reference_count());
    CHECK(octree.polygons_near([](const Box3&) { return true; }).size() == scene.size());
    const double root_side = octree.bounds().extent().x;
    REQUIRE(!cubes.empty());
    const double margin = 0.5 * (cubes[0].extent().x - root_side);
    CHECK(margin > 0);
    CHECK(margin < 1e-6 * root_side);
    for (size_t i = 1; i < cubes.size(); ++i) {
        CAPTURE(i, cubes[i]);
        const double side = cubes[i].extent().x - 2 * margin;
        bool has_parent = false;
        for (size_t j = i; j-- > 0 && !has_parent;) {
            const double parent = cubes[j].extent().x - 2 * margin;
            has_parent = std::fabs(side - 0.5 * parent) <= 1e-9 * root_side &&
                         cubes[i].lo.x >= cubes[j].lo.x && cubes[i].hi.x <= cubes[j].hi.x &&
                         cubes[i].lo.y >= cubes[j].lo.y && cubes[i].hi.y <= cubes[j].hi.y &&
                         cubes[i].lo.z >= cubes[j].lo.z && cubes[i].hi.z <= cubes[j].hi.z;
        }
        CHECK(has_parent);
    }
    for (int r = 0; r < 200; ++r) {
        const Vec3 lo{10 * u01(rng), 10 * u01(rng), 10 * u01(rng)};
        const double s = 2 * u01(rng) * u01(rng);
        const Box3 region{lo, lo + Vec3{s, 0.5 * s, s}};
        const std::vector<int> near =
            octree.polygons_near([&](const Box3& c) { return overlaps(c, region); });
        CHECK(std::is_sorted(near.begin(), near.end()));
        for (int id = 0; id < static_cast<int>(scene.size()); ++id)
            if (clip_reference_meets(region, scene[id].vertices())) {
                CAPTURE(r, id);
                CHECK(std::binary_search(near.begin(), near.end(), id));
            }
    }
}

TEST_CASE("octree: concurrent queries agree with sequential ones", "[octree]") {
    const unsigned seed = 66;
    std::mt19937 rng(seed);
    std::vector<Polygon> scene = random_scene(rng, 1000);
    const Octree octree(scene);
    std::vector<Ray> rays;
    for (int r = 0; r < 2000; ++r) rays.push_back(random_ray(rng, scene, r));
    std::vector<double> sequential(rays.size()), parallel(rays.size());
    for (size_t r = 0; r < rays.size(); ++r) {
        std::optional<Hit> h = octree.closest_hit(rays[r]);
        sequential[r] = h ? h->t : -1;
    }
    std::vector<std::thread> threads;
    for (int k = 0; k < 4; ++k)
        threads.emplace_back([&, k] {
            for (size_t r = k; r < rays.size(); r += 4) {
                std::optional<Hit> h = octree.closest_hit(rays[r]);
                parallel[r] = h ? h->t : -1;
            }
        });
    for (std::thread& t : threads) t.join();
    CHECK(parallel == sequential);
}

TEST_CASE("octree: hits in a polygon's slack beyond its edges and corners are found", "[octree]") {
    // A leaf tests a polygon's box before its planes (Octree::ListEntry): the box must hold
    // every hit the bounding planes accept, which reach edge_slack() beyond each edge and
    // slack / sin(theta / 2) beyond a corner of angle theta. Rays aimed just inside that reach
    // (axis-aligned squares, whose edges are their box's faces; slivers with corners of 0.01 and
    // 0.0012 rad; polygons of size 1e-3 to 1e3, alone and in a crowd, from steep to grazing)
    // must find what Polygon::intersect finds.
    std::mt19937 rng(2718);
    std::uniform_real_distribution<double> u01(0, 1);
    int n_checked = 0, n_hits = 0;
    for (int trial = 0; trial < 60; ++trial) {
        const double size = std::pow(10.0, -3 + 6 * u01(rng));
        const Vec3 c{size * (u01(rng) - 0.5), size * (u01(rng) - 0.5), size * (u01(rng) - 0.5)};
        std::vector<Vec3> v;
        switch (trial % 3) {
            case 0:  // an axis-aligned square
                v = {c, c + Vec3{size, 0, 0}, c + Vec3{size, size, 0}, c + Vec3{0, size, 0}};
                break;
            case 1:
            case 2: {  // a sliver triangle, its sharpest corner at v[0]
                const double angle = trial % 3 == 1 ? 0.01 : 0.0012;
                const Vec3 n = random_unit(rng);
                const Vec3 a =
                    normalize(cross(std::fabs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, n));
                const Vec3 b = cross(n, a);
                v = {c, c + size * a, c + size * (std::cos(angle) * a + std::sin(angle) * b)};
                break;
            }
        }
        std::vector<Polygon> scene{make_polygon(v, 0)};
        if (trial % 2 == 1)  // in a crowd of others, so that the tree has leaves
            for (Polygon& p : random_scene(rng, 200)) scene.push_back(p);
        const Polygon& target = scene[0];
        const double slack = target.edge_slack();
        const Vec3 n = target.normal();
        // Points in the polygon's plane just inside the slack's reach: beyond each edge's middle
        // by 0.9 slack, and beyond each corner along its bisector by 0.9 slack / sin(theta / 2).
        std::vector<Vec3> aims;
        const int k = target.n_vertices();
        for (int i = 0; i < k; ++i) {
            const Vec3 p0 = v[size_t(i)], p1 = v[size_t((i + 1) % k)],
                       prev = v[size_t((i + k - 1) % k)];
            const Vec3 out = normalize(cross(p1 - p0, n));
            aims.push_back(0.5 * (p0 + p1) + 0.9 * slack * out);
            const Vec3 e_in = normalize(p0 - prev), e_out = normalize(p1 - p0);
            const Vec3 bisector = normalize(e_in - e_out);  // points away from the polygon
            const double sin_half = std::sqrt(std::max(0.0, 0.5 * (1 + dot(e_in, e_out))));
            aims.push_back(p0 + 0.9 * slack / sin_half * bisector);
        }
        Octree octree(scene);
        for (const Vec3& aim : aims)
            for (double steep : {1.0, 0.1, 1e-3}) {  // the cosine of the ray's angle to the normal
                const Vec3 side = normalize(cross(n, random_unit(rng)));
                const Vec3 dir = steep * n + std::sqrt(1 - steep * steep) * side;
                const Ray ray{aim + 2 * size * dir, -1.0 * dir};
                CAPTURE(trial, size, aim, steep, ray);
                const std::optional<Hit> expected = brute_closest(scene, ray);
                const std::optional<Hit> hit = octree.closest_hit(ray);
                REQUIRE(bool(hit) == bool(expected));
                if (hit) {
                    CHECK(hit->polygon == expected->polygon);
                    CHECK(hit->t == expected->t);
                    n_hits += expected->polygon == 0;
                }
                CHECK(octree.any_hit(ray) == brute_any(scene, ray));
                ++n_checked;
            }
    }
    // Most aims are accepted by the target's own test (rounding decides the others).
    CHECK(n_hits > n_checked / 2);
}

// ---- Segments between true surfaces: a polygon's thickness (polygon.h) -------------------------

TEST_CASE("octree: a hit within a polygon's thickness of a segment's end does not block",
          "[octree][thickness]") {
    // The unit square in z = 0 as a facet whose true surface stands up to 0.05 off its plane
    // (the rule's box: the square's box grown by its diameter, sqrt 2, on every side).
    Polygon facet = make_polygon({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
    const Polygon exact = facet;
    facet.set_thickness(0.05);
    CHECK(facet.thickness() == 0.05);
    CHECK(exact.thickness() == 0);
    auto segment = [](Vec3 a, Vec3 b) { return Ray{a, b - a, 1e-9, 1 - 1e-9}; };
    // From 0.02 above the plane, just beyond the edge y = 1 (a neighbour's true surface), into
    // the square and below: the plane is crossed at y = 0.997, inside.
    const Ray near_end = segment({0.5, 1.05, 0.02}, {0.5, 0.2, -0.3});
    REQUIRE(facet.intersect(near_end));
    CHECK(facet.within_thickness(near_end.origin));
    CHECK_FALSE(facet.intersect_segment(near_end));
    CHECK(exact.intersect_segment(near_end) == exact.intersect(near_end));  // zero: plain test
    // The same hit from the other end (the rule is symmetric in the ends).
    const Ray reversed = segment({0.5, 0.2, -0.3}, {0.5, 1.05, 0.02});
    REQUIRE(facet.intersect(reversed));
    CHECK_FALSE(facet.intersect_segment(reversed));
    // An end beyond the thickness (0.08 above the plane) blocks as before.
    const Ray high = segment({0.5, 1.05, 0.08}, {0.5, 0.2, -0.3});
    REQUIRE(facet.intersect(high));
    CHECK_FALSE(facet.within_thickness(high.origin));
    CHECK(facet.intersect_segment(high) == facet.intersect(high));
    // Ends within the thickness of the plane but outside the grown box (y = 3 and y = -2) block.
    const Ray far = segment({0.5, 3, 0.02}, {0.5, -2, -0.02});
    REQUIRE(facet.intersect(far));
    CHECK_FALSE(facet.within_thickness(far.origin));
    CHECK(facet.intersect_segment(far) == facet.intersect(far));
    // A ray with an infinite t_max has one end, at t_min (a ray leaving a surface).
    const Ray open{{0.5, 1.05, 0.02}, {0, -0.85, -0.32}, 0.05, HUGE_VAL};
    REQUIRE(facet.intersect(open));
    const std::array<Vec3, 2> ends = segment_ends(open);
    CHECK(ends[0].y == open.at(0.05).y);
    CHECK(ends[1].y == ends[0].y);
    CHECK_FALSE(facet.intersect_segment(open));
    // Not finite: never within.
    CHECK_FALSE(facet.within_thickness({HUGE_VAL, 0.5, 0}));
    CHECK_FALSE(facet.within_thickness({std::nan(""), 0.5, 0}));
    CHECK_THROWS_AS(facet.set_thickness(-1), CheckFailure);

    // The octree applies the rule only when asked (RayFilter::ends_on_surfaces): behind the facet
    // lies an exact polygon the segment also crosses, which then is the first hit.
    const Polygon behind =
        make_polygon({{0, 0, -0.2}, {1, 0, -0.2}, {1, 1, -0.2}, {0, 1, -0.2}}, 1);
    const Octree octree({facet, behind});
    const Ray down = segment({0.5, 1.05, 0.02}, {0.5, 0.2, -0.3});
    const RayFilter between{-1, -1, true};
    CHECK(octree.any_hit(down));
    CHECK(octree.any_hit(down, between));  // the exact polygon still blocks
    REQUIRE(octree.closest_hit(down));
    CHECK(octree.closest_hit(down)->polygon == 0);
    REQUIRE(octree.closest_hit(down, between));
    CHECK(octree.closest_hit(down, between)->polygon == 1);
    const Octree alone({facet});
    CHECK(alone.any_hit(down));
    CHECK_FALSE(alone.any_hit(down, between));
    CHECK_FALSE(alone.closest_hit(down, between));
}

TEST_CASE("octree: queries between true surfaces equal brute force over the rule",
          "[octree][thickness]") {
    // Random polygons with random thicknesses (half of them zero), rays of every kind; with
    // RayFilter::ends_on_surfaces the octree must answer as a loop over Polygon::intersect
    // with Polygon::hit_counts at the ray's ends.
    const unsigned seed = 2024;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<Polygon> scene = random_scene(rng, 800);
    for (Polygon& p : scene)
        if (u01(rng) < 0.5) p.set_thickness(0.3 * u01(rng) * p.diameter());
    const Octree octree(scene);
    const RayFilter between{-1, -1, true};
    long n_any = 0, n_discounted = 0;
    for (int r = 0; r < 3000; ++r) {
        const Ray ray = random_ray(rng, scene, r);
        // Half the segments start on a polygon's plane near it (a point of a curved surface).
        Ray s = ray;
        if (r % 2) {
            const Polygon& p = scene[size_t(r) % scene.size()];
            const Vec3 a = p.vertices()[0] + 0.3 * p.thickness() * p.normal();
            s = Ray{a, ray.origin - a, 1e-9, 1 - 1e-9};
        }
        const std::array<Vec3, 2> ends = segment_ends(s);
        std::optional<Hit> best;
        bool any = false, any_plain = false;
        for (int i = 0; i < static_cast<int>(scene.size()); ++i) {
            const std::optional<double> t = scene[i].intersect(s);
            if (!t) continue;
            any_plain = true;
            if (!scene[i].hit_counts(ends[0], ends[1])) continue;
            CHECK(scene[i].intersect_segment(s) == t);
            any = true;
            if (!best || *t < best->t) best = Hit{i, scene[i].surface(), {}, *t};
        }
        CAPTURE(seed, r, s);
        CHECK(octree.any_hit(s, between) == any);
        const std::optional<Hit> got = octree.closest_hit(s, between);
        REQUIRE(got.has_value() == best.has_value());
        if (got) {
            CHECK(got->polygon == best->polygon);
            CHECK(got->t == best->t);
        }
        n_any += any;
        n_discounted += any_plain && !any;
    }
    CHECK(n_any > 300);
    CHECK(n_discounted > 20);  // the rule did discount some segments' only hits
}
