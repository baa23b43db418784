// test/test_occlusion.cpp - the occluders of a pair and the octree queries under them (paper
// section 6, "Octree"; radiosity/visibility/occlusion.h): make_occlusion_context, segment_blocked,
// any_hit with a RayFilter and polygons_near against brute force.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "math/bspline.h"
#include "math/gauss_legendre.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/visibility/occlusion.h"
#include "radiosity/visibility/visible_parts.h"
#include "test/report.h"
#include "test/shadow_scenes.h"

using namespace mbr;
using namespace mbr::test;

// ---- The occluders of a pair and the octree queries under them ---------------------------------

namespace {

/// n random polygons in [0, 4]^3 (parallelograms and triangles in turn), each of a random
/// surface 0..5.
std::vector<Polygon> random_polygons(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> u(0, 4);
    std::uniform_int_distribution<int> surface(0, 5);
    std::vector<Polygon> polygons;
    for (int i = 0; i < n; ++i) {
        const Vec3 c{u(rng), u(rng), u(rng)};
        const int s = surface(rng);
        polygons.push_back(make_polygon(
            i % 2 ? random_parallelogram(rng, c, 0.6) : random_triangle(rng, c, 0.8), s));
    }
    return polygons;
}

/// n random parallelograms of the given size between the squares of occluded_squares, their
/// centres uniform over the unit square in x and y and over [z0, z1] in height.
void add_random_occluders(ShadowSetup& setup, std::mt19937& rng, int n, double z0, double z1,
                          double size) {
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < n; ++i) {
        const Vec3 c{u(rng), u(rng), z0 + (z1 - z0) * u(rng)};
        setup.occluders.push_back(random_parallelogram(rng, c, size));
    }
}

}  // namespace

TEST_CASE("shadow: any_hit with a RayFilter equals brute force over the unfiltered polygons",
          "[shadow][occlusion]") {
    // Random polygons of six surfaces, random rays with random [t_min, t_max]; for each filter the
    // octree's answer must be "some polygon of a surface not skipped is hit in range", which a
    // loop over all polygons with Polygon::intersect decides. Exact agreement: both use the same
    // ray-polygon test, and the octree's margins make it never miss a listed hit.
    const unsigned seed = 909;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 4);
    const std::vector<Polygon> scene = random_polygons(rng, 400);
    const Octree octree(scene, OctreeOptions{8, 4});
    const RayFilter filters[] = {RayFilter{}, RayFilter{0, -1}, RayFilter{-1, 3}, RayFilter{2, 4},
                                 RayFilter{5, 5}};
    long n_hits[5] = {0, 0, 0, 0, 0}, n_differ_by_filter = 0;
    for (int r = 0; r < 1500; ++r) {
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
        const double t0 = 0.25 * u(rng) / 4, t1 = 1 - 0.25 * u(rng) / 4;
        const Ray ray{a, b - a, t0, t1};
        bool previous = false;
        for (int f = 0; f < 5; ++f) {
            bool brute = false;
            for (const Polygon& p : scene)
                if (!filters[f].skips(p.surface()) && p.intersect(ray)) brute = true;
            CAPTURE(seed, r, f, ray);
            CHECK(octree.any_hit(ray, filters[f]) == brute);
            n_hits[f] += brute;
            if (f > 0 && brute != previous) ++n_differ_by_filter;
            previous = brute;
        }
        CHECK(octree.any_hit(ray) == octree.any_hit(ray, RayFilter{}));
    }
    // The filters matter: hits do occur, and differ between filters on some rays.
    CHECK(n_hits[0] > 300);
    CHECK(n_hits[3] < n_hits[0]);
    CHECK(n_differ_by_filter > 50);
}

TEST_CASE("shadow: polygons_near equals the leaves' lists brute-forced over node tests",
          "[shadow][occlusion]") {
    // polygons_near(test) must be the union of the lists of the leaves whose grown cube and whose
    // ancestors' grown cubes the test accepts. The tree is read back through polygons_near itself:
    // an accept-all test records every node's grown cube (leaves are the cubes containing no
    // smaller recorded cube), and "cube contains leaf L" returns exactly L's list. Then random box
    // queries are compared with the union over the leaves, and with exact clipping: a polygon
    // that truly meets the box is never missing (it meets the box in some leaf's cube).
    const unsigned seed = 4242;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 4);
    std::vector<Polygon> scene;
    for (int i = 0; i < 250; ++i) {
        const Vec3 c{u(rng), u(rng), u(rng)};
        scene.push_back(make_polygon(random_parallelogram(rng, c, 0.7), i % 3));
    }
    const Octree octree(scene, OctreeOptions{6, 4});
    std::vector<Box3> cubes;
    const std::vector<int> all = octree.polygons_near([&](const Box3& b) {
        cubes.push_back(b);
        return true;
    });
    CHECK(all.size() == scene.size());  // every polygon is listed by some leaf
    REQUIRE(static_cast<int>(cubes.size()) == octree.node_count());
    auto contains = [](const Box3& outer, const Box3& inner) {
        return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
               inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
    };
    auto side = [](const Box3& b) { return b.hi.x - b.lo.x; };
    struct Leaf {
        Box3 cube;
        std::vector<int> ancestors;  // indices into cubes
        std::vector<int> polygons;
    };
    std::vector<Leaf> leaves;
    for (size_t i = 0; i < cubes.size(); ++i) {
        bool leaf = true;
        std::vector<int> ancestors;
        for (size_t j = 0; j < cubes.size(); ++j) {
            if (j == i) continue;
            if (side(cubes[j]) < side(cubes[i]) && contains(cubes[i], cubes[j])) leaf = false;
            if (side(cubes[j]) > side(cubes[i]) && contains(cubes[j], cubes[i]))
                ancestors.push_back(int(j));
        }
        if (!leaf) continue;
        const Box3 cube = cubes[i];
        std::vector<int> list =
            octree.polygons_near([&](const Box3& b) { return contains(b, cube); });
        // A leaf lists only polygons the node test accepts for its grown cube (the build filters
        // each child's list with it).
        for (int id : list) CHECK(node_meets_polygon(cube, scene[id]));
        leaves.push_back({cube, ancestors, list});
    }
    CHECK(static_cast<int>(leaves.size()) == octree.leaf_count());

    long n_results = 0, n_over = 0;
    for (int q = 0; q < 200; ++q) {
        const Vec3 lo{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5};
        const double s = 0.1 + 0.4 * u(rng);
        const Box3 box{lo, lo + Vec3{s, 0.7 * s, 1.3 * s}};
        auto test = [&](const Box3& b) { return overlaps(b, box); };
        const std::vector<int> got = octree.polygons_near(test);
        std::set<int> expected;
        for (const Leaf& leaf : leaves) {
            bool accepted = test(leaf.cube);
            for (int a : leaf.ancestors) accepted = accepted && test(cubes[a]);
            if (accepted) expected.insert(leaf.polygons.begin(), leaf.polygons.end());
        }
        CAPTURE(seed, q, box);
        CHECK(got == std::vector<int>(expected.begin(), expected.end()));
        for (int id = 0; id < static_cast<int>(scene.size()); ++id) {
            const bool meets = polygon_meets_box(scene[id].vertices(), box);
            const bool listed = std::binary_search(got.begin(), got.end(), id);
            if (meets) CHECK(listed);
            n_over += listed && !meets;
        }
        n_results += static_cast<long>(got.size());
    }
    CHECK(n_results > 500);
    mbr::test::report() << "shadow polygons_near: " << octree.node_count() << " nodes, "
                        << leaves.size() << " leaves; 200 box queries returned " << n_results
                        << " polygons, " << n_over << " of them not meeting the box\n";
}

TEST_CASE("shadow: make_occlusion_context finds every polygon that meets the pair's hull",
          "[shadow][occlusion]") {
    // Random shooter and receiver quads (and, every fourth time, a cylinder patch as the
    // receiver: its hull points are its bounding box's corners) with random occluders around
    // them. Brute force: a polygon meets the convex hull of the two true surfaces iff no
    // separating axis exists (hull_polygon_gap); a curved surface's hull is taken from 6 x 6
    // of its points (the brute force is cubic in the points), which lie inside it, so a polygon
    // that meets the points' hull meets the true one. (Not the bounding box's corners:
    // make_occlusion_context may drop a polygon that meets their hull but has both true surfaces on
    // one side of its plane.) A polygon meeting it by more than 1e-7 (the library drops polygons
    // within 1e-9 x the coordinates of the hull's boundary) must be a candidate: no false negatives
    // ever. False positives (listed, but apart) only cost rays; they are counted. The two surfaces'
    // own polygons never are.
    const unsigned seed = 123;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    long n_meet = 0, n_apart = 0, n_false_positive = 0, n_ambiguous = 0;
    for (int config = 0; config < 120; ++config) {
        const Surface shooter =
            quad_surface(random_parallelogram(rng, {u(rng), u(rng), u(rng)}, 1));
        Surface receiver = quad_surface(random_parallelogram(rng, {u(rng), u(rng), u(rng)}, 1));
        if (config % 4 == 3) {
            const Vec3 base{u(rng), u(rng), u(rng)};
            const Vec3 axis = random_unit(rng);
            receiver = Surface::cylinder(base, axis, Vec3{1, 0, 0}, 0.3, 0.6, 0, 2);
        }
        std::vector<Polygon> polygons;
        polygons.push_back(make_polygon(quad_polygon(shooter), 0));
        for (const Facet& f : receiver.tessellate(4))
            polygons.push_back(make_polygon(f.vertices, 1));
        std::vector<std::vector<Vec3>> occluders;
        for (int i = 0; i < 25; ++i) {
            const Vec3 c{1.6 * u(rng) - 0.3, 1.6 * u(rng) - 0.3, 1.6 * u(rng) - 0.3};
            occluders.push_back(i % 2 ? random_parallelogram(rng, c, 0.4)
                                      : random_triangle(rng, c, 0.5));
            polygons.push_back(make_polygon(occluders.back(), 2 + i));
        }
        const int first_occluder = static_cast<int>(polygons.size()) - 25;
        const Octree octree(polygons, OctreeOptions{6, 4});
        const OcclusionContext ctx =
            make_occlusion_context(octree, shooter, 0, receiver, 1, config);
        CHECK(std::is_sorted(ctx.candidates.begin(), ctx.candidates.end()));
        std::vector<Vec3> pts = hull_points(shooter);
        if (receiver.is_planar()) {
            for (const Vec3& q : hull_points(receiver)) pts.push_back(q);
        } else {
            for (int i = 0; i <= 5; ++i)
                for (int j = 0; j <= 5; ++j) pts.push_back(receiver.point(i / 5.0, j / 5.0));
        }
        for (int id : ctx.candidates) CHECK(octree.polygons()[id].surface() >= 2);
        for (int i = 0; i < 25; ++i) {
            const int id = first_occluder + i;
            const double gap = hull_polygon_gap(pts, occluders[i]);
            const bool listed =
                std::binary_search(ctx.candidates.begin(), ctx.candidates.end(), id);
            CAPTURE(seed, config, i, gap);
            if (gap < -1e-7) {
                ++n_meet;
                CHECK(listed);
            } else if (gap > 1e-7) {
                ++n_apart;
                n_false_positive += listed;
            } else {
                ++n_ambiguous;
            }
        }
    }
    CHECK(n_meet > 300);
    CHECK(n_apart > 300);
    mbr::test::report() << "shadow make_occlusion_context: " << n_meet << " occluders meet the hull"
                        << " (all listed), " << n_apart << " are apart, of which "
                        << n_false_positive << " listed (false positives), " << n_ambiguous
                        << " within 1e-7 of touching\n";
}

TEST_CASE("shadow: segment_blocked equals brute force with few and with many candidates",
          "[shadow][occlusion]") {
    // segment_blocked loops over the candidates when there are at most 16, else asks the octree
    // with the pair's surfaces filtered out. Both must equal "some polygon other than the two
    // surfaces' crosses the open segment", for segments between points of the two surfaces.
    const unsigned seed = 5;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    int n_few = 0, n_many = 0;
    long n_blocked = 0, n_segments = 0;
    for (int config = 0; config < 12; ++config) {
        const int n_occluders = config % 2 ? 6 : 60;
        ShadowSetup setup = occluded_squares(0);
        setup.occluders.clear();
        add_random_occluders(setup, rng, n_occluders, 0.1, 0.9, n_occluders > 10 ? 0.15 : 0.3);
        const Pair pair(setup, config);
        const bool many = pair.context.candidates.size() > 16;
        (many ? n_many : n_few) += 1;
        for (int s = 0; s < 300; ++s) {
            const double ua = u(rng), va = u(rng), ub = u(rng), vb = u(rng);
            const Vec3 a = setup.shooter.point(ua, va), b = setup.receiver.point(ub, vb);
            const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
            bool brute = false;
            for (const Polygon& p : pair.octree.polygons())
                if (p.surface() >= 2 && p.intersect(ray)) brute = true;
            long n_rays = 0;
            CAPTURE(seed, config, s);
            CHECK(segment_blocked(pair.context, a, b, &n_rays) == brute);
            CHECK(n_rays == 1);
            n_blocked += brute;
            ++n_segments;
        }
    }
    CHECK(n_few > 0);
    CHECK(n_many > 0);
    CHECK(n_blocked > n_segments / 10);
    CHECK(n_blocked < n_segments);
}

TEST_CASE("shadow: any_hit with only_polygons counts the listed polygons alone",
          "[shadow][occlusion]") {
    // RayFilter::only_polygons: the octree's answer must be "some listed polygon of a surface not
    // skipped is hit in range", as a loop over the list decides; random lists of about a third
    // of the polygons, random rays.
    const unsigned seed = 1707;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 4);
    const std::vector<Polygon> scene = random_polygons(rng, 300);
    const Octree octree(scene, OctreeOptions{8, 4});
    long n_hits_all = 0, n_hits_listed = 0;
    for (int list = 0; list < 5; ++list) {
        std::vector<int> only;
        for (int i = 0; i < int(scene.size()); ++i)
            if (u(rng) < 4.0 / 3) only.push_back(i);
        RayFilter filter{list % 3, -1};
        filter.only_polygons = &only;
        for (int r = 0; r < 400; ++r) {
            const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
            const Ray ray{a, b - a, 0, 1};
            bool brute = false;
            for (int id : only)
                if (!filter.skips(scene[size_t(id)].surface()) && scene[size_t(id)].intersect(ray))
                    brute = true;
            CAPTURE(seed, list, r, ray);
            const int hit = octree.any_hit_polygon(ray, filter);
            CHECK((hit >= 0) == brute);
            if (hit >= 0) CHECK(std::binary_search(only.begin(), only.end(), hit));
            n_hits_listed += brute;
            n_hits_all += octree.any_hit(ray, RayFilter{list % 3, -1});
        }
    }
    // The list matters: some rays hit only polygons that are not listed.
    CHECK(n_hits_listed > 100);
    CHECK(n_hits_listed < n_hits_all);
}

TEST_CASE("shadow: segment_misses_boxes never misses a box the segment enters",
          "[shadow][occlusion]") {
    // Random boxes and segments: a segment that has a point (of 200 along it) inside a box never
    // misses; one that misses every box has no point inside any. Segments along a box's face
    // and through its corner meet it; one just beside it misses.
    const unsigned seed = 44;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    long n_meet = 0, n_miss = 0;
    for (int k = 0; k < 2000; ++k) {
        std::vector<Box3> boxes;
        for (int b = 0; b < 3; ++b) {
            const Vec3 lo{u(rng), u(rng), u(rng)};
            boxes.push_back(Box3{lo, lo + Vec3{0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng)}});
        }
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
        bool inside = false;
        for (int i = 0; i <= 200 && !inside; ++i) {
            const Vec3 x = a + (i / 200.0) * (b - a);
            for (const Box3& box : boxes)
                inside = inside || (x.x >= box.lo.x && x.x <= box.hi.x && x.y >= box.lo.y &&
                                    x.y <= box.hi.y && x.z >= box.lo.z && x.z <= box.hi.z);
        }
        const bool misses = segment_misses_boxes(a, b, boxes);
        CAPTURE(seed, k);
        if (inside) CHECK_FALSE(misses);
        (misses ? n_miss : n_meet) += 1;
    }
    CHECK(n_meet > 200);
    CHECK(n_miss > 200);
    const std::vector<Box3> unit{Box3{{0, 0, 0}, {1, 1, 1}}};
    CHECK_FALSE(segment_misses_boxes({-1, 0.5, 1}, {2, 0.5, 1}, unit));  // along the top face
    CHECK_FALSE(segment_misses_boxes({-1, -1, -1}, {0, 0, 0}, unit));    // ends at a corner
    CHECK(segment_misses_boxes({-1, 0.5, 1.001}, {2, 0.5, 1.001}, unit));
    CHECK(segment_misses_boxes({2, 2, 2}, {3, 3, 3}, unit));
    // Grown for segments: a polygon's hit within its edge slack (1e-10 of its diameter) beyond
    // its box lies inside the grown box; a segment 1e-8 away still misses it.
    const std::vector<Box3> grown{grown_for_segments(unit[0])};
    CHECK(segment_misses_boxes({-1, 0.5, 1 + 1e-10}, {2, 0.5, 1 + 1e-10}, unit));
    CHECK_FALSE(segment_misses_boxes({-1, 0.5, 1 + 1e-10}, {2, 0.5, 1 + 1e-10}, grown));
    CHECK(segment_misses_boxes({-1, 0.5, 1 + 1e-8}, {2, 0.5, 1 + 1e-8}, grown));
}

TEST_CASE("shadow: a shaft separates only polygons that no segment to its patch meets",
          "[shadow][occlusion]") {
    // Shaft (occlusion.h): the pyramid from p to a planar quadrilateral patch. A polygon it
    // separates (every vertex outside one plane) must meet none of the segments from p to the
    // patch: checked on 64 segments to random points of the patch (bilinear, so inside it) for
    // random triangles and parallelograms around the shaft; separated polygons also have boxes
    // the shaft may or may not meet, but a polygon a segment hits is never separated and its
    // box always meets the shaft.
    const unsigned seed = 31;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    long n_separated = 0, n_hit = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vec3 p{u(rng), u(rng), 0};
        const Vec3 q[4] = {{0.2 * u(rng), 0.2 * u(rng), 1},
                           {0.8 + 0.2 * u(rng), 0.2 * u(rng), 1},
                           {0.8 + 0.2 * u(rng), 0.8 + 0.2 * u(rng), 1},
                           {0.2 * u(rng), 0.8 + 0.2 * u(rng), 1}};
        const Shaft shaft(p, q);
        for (int k = 0; k < 20; ++k) {
            const Vec3 c{2 * u(rng) - 0.5, 2 * u(rng) - 0.5, 0.1 + 0.8 * u(rng)};
            const Polygon poly = make_polygon(
                k % 2 ? random_parallelogram(rng, c, 0.3) : random_triangle(rng, c, 0.4), 2);
            bool hit = false;
            for (int r = 0; r < 64 && !hit; ++r) {
                const double a = u(rng), b = u(rng);
                const Vec3 x = (1 - a) * (1 - b) * q[0] + a * (1 - b) * q[1] + a * b * q[2] +
                               (1 - a) * b * q[3];
                hit = bool(poly.intersect(Ray{p, x - p, 1e-9, 1 - 1e-9}));
            }
            const bool separated = shaft.separates(poly.vertices());
            CAPTURE(seed, trial, k);
            if (hit) {
                CHECK_FALSE(separated);
                CHECK(shaft.meets(poly.bounds()));
            }
            n_separated += separated;
            n_hit += hit;
        }
    }
    // Both kinds occur.
    CHECK(n_separated > 1000);
    CHECK(n_hit > 200);
}

TEST_CASE("shadow: a polygon lying on the receiver blocks no segment, few candidates or many",
          "[shadow][occlusion]") {
    // make_occlusion_context leaves out a polygon lying on a planar receiver (a rug on the
    // floor, 1e-5 above it). The loop over few candidates never tests it; with many, the
    // octree finds it on segments that leave the receiver under it, and segment_blocked must
    // skip it there too (RayFilter::only_polygons): the answer is brute force over the
    // candidates alone, on both paths.
    const unsigned seed = 12;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    for (const int n_occluders : {4, 40}) {
        ShadowSetup setup = occluded_squares(0);
        setup.occluders.clear();
        setup.occluders.push_back(square_at(0.5, 0.5, 1e-5, 0.3));  // the rug
        add_random_occluders(setup, rng, n_occluders, 0.2, 0.8, 0.1);
        const Pair pair(setup, 1);
        const std::vector<int>& candidates = pair.context.candidates;
        REQUIRE_FALSE(std::binary_search(candidates.begin(), candidates.end(), 2));  // the rug
        CHECK((candidates.size() > 16) == (n_occluders > 16));
        long n_blocked = 0;
        for (int s = 0; s < 300; ++s) {
            const Vec3 a = setup.shooter.point(u(rng), u(rng));
            const Vec3 b = setup.receiver.point(0.3 + 0.4 * u(rng), 0.3 + 0.4 * u(rng));  // under the rug
            const Ray ray{a, b - a, 1e-9, 1 - 1e-9};
            bool brute = false;
            for (int id : candidates)
                if (pair.octree.polygons()[size_t(id)].intersect(ray)) brute = true;
            CAPTURE(seed, n_occluders, s);
            CHECK(segment_blocked(pair.context, a, b, nullptr) == brute);
            n_blocked += brute;
        }
        CHECK(n_blocked < 300);  // the rug would block all of them
    }
}

// ---- Curved neighbours: segments leave true surfaces, not facets -------------------------------

namespace {

/// A point of the radius-1 sphere about the origin (pole +z) at polar angle theta, azimuth phi
/// (degrees).
Vec3 on_sphere(double theta, double phi) {
    const double t = theta * Pi / 180, f = phi * Pi / 180;
    return {std::sin(t) * std::cos(f), std::sin(t) * std::sin(f), std::cos(t)};
}

Scene parse(const std::string& text) {
    std::istringstream in(text);
    return parse_scene(in, "test.scene");
}

}  // namespace

TEST_CASE("shadow: the facets of a curved neighbour do not block segments from its true surface",
          "[shadow][occlusion][thickness]") {
    // Inside a sphere nothing occludes anything. Cap (0-30 deg), band A (30-60), band B (60-90):
    // the plane of a facet of A in its last row cuts the sphere in a circle through the facet's
    // corners, and the points of B just below the shared circle inside it stand on the far side
    // of that plane, so a chord from them to the cap crossed the facet: false occlusion (measured
    // before the rule: most of these segments were blocked).
    const Scene scene = parse(
        "material m reflectance 0.5 0.5 0.5\n"
        "sphere cap m 0 0 0  0 0 1  1 0 0  1  0 30  0 360 inward\n"
        "sphere A m 0 0 0  0 0 1  1 0 0  1  30 60  0 360 inward\n"
        "sphere B m 0 0 0  0 0 1  1 0 0  1  60 90  0 360 inward\n");
    const Octree octree = build_octree(scene);
    for (const Polygon& p : octree.polygons()) REQUIRE(p.thickness() > 0);
    const OcclusionContext ctx = make_occlusion_context(octree, scene.surfaces[0].surface, 0,
                                                        scene.surfaces[2].surface, 2, 0);
    const unsigned seed = 31;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    int n_facet_hits = 0, n_blocked = 0;
    const int n = 2000;
    for (int s = 0; s < n; ++s) {
        // p on B within 1.5 deg of the shared circle, q anywhere on the cap's outer half.
        const Vec3 p = on_sphere(60 + 1.5 * u01(rng), 360 * u01(rng));
        const Vec3 q = on_sphere(15 + 15 * u01(rng), 360 * u01(rng));
        const Ray ray{p, q - p, 1e-9, 1 - 1e-9};
        bool facet_hit = false;
        for (const Polygon& poly : octree.polygons())
            if (poly.surface() == 1 && poly.intersect(ray)) facet_hit = true;
        long n_rays = 0;
        CAPTURE(seed, s, p, q);
        const bool blocked = segment_blocked(ctx, p, q, &n_rays);
        CHECK_FALSE(blocked);
        n_facet_hits += facet_hit;
        n_blocked += blocked;
    }
    CHECK(n_facet_hits > n / 10);  // the facets are crossed: the rule is what keeps them clear
    CHECK(n_blocked == 0);
}

TEST_CASE("shadow: a curved occluder still blocks, resting on the receiver or not",
          "[shadow][occlusion][thickness]") {
    // A closed curved occluder is crossed twice; discounting the facets near a segment's end
    // leaves the far crossing. A ball resting on a floor and a cylinder standing on it, a square
    // lamp above: segments from floor points under them (up to the contact) to the lamp are
    // blocked, those that pass beside them are not.
    const Scene scene = parse(
        "material m reflectance 0.5 0.5 0.5\n"
        "rectangle floor m  -2 0 -2   0 0 4   4 0 0\n"
        "rectangle lamp m  -0.2 3 -0.2   0.4 0 0   0 0 0.4\n"
        "sphere ball m  0 0.5 0   0 1 0   1 0 0   0.5   0 180   0 360\n"
        "cylinder post m  1.2 0 0   0 1 0   1 0 0   0.3 1   0 360\n");
    const Octree octree = build_octree(scene);
    const OcclusionContext ctx = make_occlusion_context(octree, scene.surfaces[1].surface, 1,
                                                        scene.surfaces[0].surface, 0, 0);
    REQUIRE_FALSE(ctx.clear());
    const Vec3 light{0, 3, 0};
    long n_rays = 0;
    // Under the ball: the contact point's neighbourhood, within the bottom facets' thickness.
    for (double x : {0.0, 0.004, 0.02, 0.1, 0.3}) {
        CAPTURE(x);
        CHECK(segment_blocked(ctx, {x, 0, 0}, light, &n_rays));
        CHECK(segment_blocked(ctx, {x, 0, 0}, light + Vec3{0.15, 0, 0.1}, &n_rays));
    }
    // Inside the post (a tube, radius 0.3 about x = 1.2: these segments to the lamp leave
    // through its far wall below its top), and outside it beyond the thickness of its facets
    // (0.05 and 0.2 from the wall; the segments cross the whole tube below its top).
    const Vec3 base{1.2, 0, 0};
    for (double dx : {0.05, 0.1, 0.35, 0.5}) {
        CAPTURE(dx);
        CHECK(segment_blocked(ctx, base + Vec3{dx, 0, 0}, light, &n_rays));
    }
    // Beside both, and on the floor's far corner: clear.
    CHECK_FALSE(segment_blocked(ctx, {0.85, 0, 0}, light, &n_rays));
    CHECK_FALSE(segment_blocked(ctx, {-1.5, 0, -1.5}, light, &n_rays));
    CHECK_FALSE(segment_blocked(ctx, {0.6, 0, -1.5}, light, &n_rays));
}
