// test/test_convex2d.cpp - convex polygons of the plane (math/convex2d.h), the geometry under the
// exact visibility of the shadow stage: clip, intersect, subtract and classify against polygons
// and areas computed by hand, random polygons against the identities that tie the four together,
// the inverse bilinear map by round trips, and the collapsed Gauss rule on the triangle against
// the closed form int_T x^a y^b = a! b! / (a + b + 2)!.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/convex2d.h"
#include "test/report.h"

using namespace mbr;

namespace {

const ConvexPolygon unit_square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};

ConvexPolygon rect(double x0, double y0, double x1, double y1) {
    return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

/// True when every vertex of `expected` is a vertex of `got` (within tol) and the counts agree:
/// the same polygon up to the starting vertex.
bool same_vertices(const ConvexPolygon& got, const ConvexPolygon& expected, double tol = 1e-15) {
    if (got.size() != expected.size()) return false;
    for (Vec2 e : expected) {
        bool found = false;
        for (Vec2 g : got)
            found = found || (std::fabs(g.x - e.x) <= tol && std::fabs(g.y - e.y) <= tol);
        if (!found) return false;
    }
    return true;
}

/// Consecutive vertices that coincide exactly (a zero-length edge).
int repeated_vertices(const ConvexPolygon& p) {
    int n = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        const Vec2 a = p[i], b = p[(i + 1) % p.size()];
        if (a.x == b.x && a.y == b.y) ++n;
    }
    return n;
}

/// Convex and counter-clockwise: no right turn beyond rounding.
bool is_convex_ccw(const ConvexPolygon& p, double tol) {
    if (p.size() < 3 || !(signed_area(p) > 0)) return false;
    for (size_t i = 0; i < p.size(); ++i) {
        const Vec2 a = p[i], b = p[(i + 1) % p.size()], c = p[(i + 2) % p.size()];
        if (cross(b - a, c - b) < -tol) return false;
    }
    return true;
}

/// k vertices on an ellipse at sorted random angles: convex, counter-clockwise.
ConvexPolygon random_convex(std::mt19937& rng, int k, double scale) {
    std::uniform_real_distribution<double> u(0, 1);
    const Vec2 c{scale * (u(rng) - 0.5), scale * (u(rng) - 0.5)};
    const double ra = 0.2 + u(rng), rb = 0.2 + u(rng), phi = 2 * Pi * u(rng);
    std::vector<double> angles;
    for (int i = 0; i < k; ++i) angles.push_back(2 * Pi * u(rng));
    std::sort(angles.begin(), angles.end());
    ConvexPolygon p;
    for (double a : angles) {
        const double x = ra * std::cos(a), y = rb * std::sin(a);
        p.push_back({c.x + x * std::cos(phi) - y * std::sin(phi),
                     c.y + x * std::sin(phi) + y * std::cos(phi)});
    }
    return p;
}

double length2(Vec2 a) {
    return std::hypot(a.x, a.y);
}

double area(const ConvexPolygon& p) {
    return p.empty() ? 0.0 : signed_area(p);
}

double factorial(int n) {
    double f = 1;
    for (int i = 2; i <= n; ++i) f *= i;
    return f;
}

}  // namespace

TEST_CASE("convex2d: clip by a half-plane against hand-computed polygons", "[convex2d]") {
    // x >= 1/4: the rectangle [1/4, 1] x [0, 1].
    ConvexPolygon c = clip(unit_square, HalfPlane{{1, 0}, -0.25});
    CHECK(same_vertices(c, rect(0.25, 0, 1, 1)));
    CHECK(signed_area(c) == Approx(0.75).epsilon(1e-15));
    // x + y <= 1/2: the corner triangle, area 1/8; a pentagon when the cut is x + y <= 3/2.
    c = clip(unit_square, HalfPlane{{-1, -1}, 0.5});
    CHECK(same_vertices(c, {{0, 0}, {0.5, 0}, {0, 0.5}}));
    CHECK(signed_area(c) == Approx(0.125).epsilon(1e-15));
    c = clip(unit_square, HalfPlane{{-1, -1}, 1.5});
    CHECK(same_vertices(c, {{0, 0}, {1, 0}, {1, 0.5}, {0.5, 1}, {0, 1}}));
    CHECK(signed_area(c) == Approx(0.875).epsilon(1e-15));
    // Wholly outside: empty; wholly inside: unchanged.
    CHECK(clip(unit_square, HalfPlane{{1, 0}, -2}).empty());
    c = clip(unit_square, HalfPlane{{1, 0}, 1});
    CHECK(same_vertices(c, unit_square, 0));
    // left_of(a, b) is the inside of a counter-clockwise edge a -> b.
    const HalfPlane h = left_of({0, 0}, {1, 0});
    CHECK(h.value({0.3, 0.5}) > 0);
    CHECK(h.value({0.3, -0.5}) < 0);
    CHECK(h.value({7, 0}) == 0);
    // Fewer than three vertices: empty.
    CHECK(clip(ConvexPolygon{{0, 0}, {1, 0}}, HalfPlane{{1, 0}, 1}).empty());
}

TEST_CASE("convex2d: clip by a line through vertices repeats no vertex and leaves no sliver",
          "[convex2d]") {
    // A vertex ON the line (value 0) followed by one outside must not add a crossing point (it
    // would repeat the vertex: a zero-length edge). Found by this test, since fixed:
    // - unit square, x + y >= 1 (the line through (1,0) and (0,1)): the triangle
    //   (1,0) (1,1) (0,1) (it was (1,0) (1,0) (1,1) (0,1) (0,1));
    // - unit square, x <= 0 (the line through its left edge): empty (it was (0,0) (0,0) (0,1)
    //   (0,1) of area 0);
    // - unit square, x + y <= 0 (touching the vertex (0,0) only): empty (it was (0,0) x 3).
    // Repeated vertices break classify and subtract (the zero-length-edge test below).
    const ConvexPolygon half = clip(unit_square, HalfPlane{{1, 1}, -1});
    CAPTURE(half);
    CHECK(signed_area(half) == Approx(0.5).epsilon(1e-15));
    CHECK(repeated_vertices(half) == 0);
    CHECK(same_vertices(half, {{1, 0}, {1, 1}, {0, 1}}));
    const ConvexPolygon edge = clip(unit_square, HalfPlane{{-1, 0}, 0});
    CAPTURE(edge);
    CHECK(edge.empty());
    const ConvexPolygon vertex = clip(unit_square, HalfPlane{{-1, -1}, 0});
    CAPTURE(vertex);
    CHECK(vertex.empty());
}

TEST_CASE("convex2d: clip measures a crossing from the end nearer the line", "[convex2d]") {
    // A shadow's vertex can lie 1e9 times further out than the shooter it is clipped to. The
    // crossing of the edge from (1e9, 1) back to (0, 1) with x = 1 is (1, 1): measured from
    // the far end, it carried that end's rounding (about 1e-7); from the near end it is exact
    // to rounding of the shooter's own size.
    const ConvexPolygon far_triangle{{0, 0}, {1e9, 1}, {0, 1}};
    const ConvexPolygon kept = clip(far_triangle, HalfPlane{{-1, 0}, 1});  // x <= 1
    CAPTURE(kept);
    REQUIRE(kept.size() == 4);
    int on_line = 0;
    for (Vec2 q : kept)
        if (q.x > 0.5) {
            ++on_line;
            CHECK(std::fabs(q.x - 1) <= 1e-15);
        }
    CHECK(on_line == 2);
    CHECK(signed_area(kept) == Approx(1 - 0.5e-9).epsilon(1e-14));
}

TEST_CASE("convex2d: remove_flat_vertices drops repeated and collinear vertices only",
          "[convex2d]") {
    // The unit square with a vertex repeated to rounding, one on an edge to 1e-12 and one
    // truly out of line by 1e-3: one of the repeated pair and the one on the edge go, the
    // third stays.
    ConvexPolygon p{{0, 0}, {0.5, -1e-12}, {1, 0}, {1, 1e-14}, {1, 1}, {0.5, 1.001}, {0, 1}};
    remove_flat_vertices(p, 1e-9);
    CAPTURE(p);
    CHECK(same_vertices(p, {{0, 0}, {1, 0}, {1, 1}, {0.5, 1.001}, {0, 1}}, 1e-14));
    // A triangle stays a triangle, however flat.
    ConvexPolygon flat{{0, 0}, {1, 0}, {0.5, 1e-15}};
    remove_flat_vertices(flat, 1e-9);
    CHECK(flat.size() == 3);
}

TEST_CASE("convex2d: is_sliver tells thin strips and specks from small full polygons",
          "[convex2d]") {
    // A strip 1 long and 1e-12 wide, and a triangle 1e-9 across, are slivers at width 1e-10
    // and extent 1e-7; a square 1e-6 across is not, however small beside anything else.
    CHECK(is_sliver({{0, 0}, {1, 0}, {1, 1e-12}, {0, 1e-12}}, 1e-10, 1e-7));
    CHECK(is_sliver({{0, 0}, {1e-9, 0}, {0, 1e-9}}, 1e-10, 1e-7));
    CHECK_FALSE(is_sliver(rect(0.3, 0.3, 0.3 + 1e-6, 0.3 + 1e-6), 1e-10, 1e-7));
    CHECK_FALSE(is_sliver({{0, 0}, {1, 0}, {1, 1e-9}, {0, 1e-9}}, 1e-10, 1e-7));
    CHECK(is_sliver({{0, 0}, {1, 0}}, 1e-10, 1e-7));
}

TEST_CASE("convex2d: start_at_canonical_vertex gives the same list whatever the first vertex",
          "[convex2d]") {
    // A fan of triangles from the first vertex must follow the polygon, not where a clip
    // started its list: every rotation of a hexagon, and the hexagon after a decimal change of
    // units and back (its coordinates then differ by rounding), start at the same vertex.
    const ConvexPolygon hexagon{{2, 0}, {3, 1}, {3, 2.5}, {2, 3}, {0.5, 2}, {0.5, 0.7}};
    ConvexPolygon canonical = hexagon;
    start_at_canonical_vertex(canonical);
    for (size_t r = 0; r < hexagon.size(); ++r) {
        ConvexPolygon p = hexagon;
        std::rotate(p.begin(), p.begin() + long(r), p.end());
        for (Vec2& q : p) q = 1e3 * (1e-3 * q);
        start_at_canonical_vertex(p);
        CAPTURE(r, p);
        REQUIRE(p.size() == hexagon.size());
        for (size_t i = 0; i < p.size(); ++i) {
            CHECK(p[i].x == Approx(canonical[i].x).epsilon(1e-15));
            CHECK(p[i].y == Approx(canonical[i].y).epsilon(1e-15));
        }
    }
    // Axis-aligned sides do not tie: the square starts at (0, 0) however it is listed.
    ConvexPolygon square{{1, 1}, {0, 1}, {0, 0}, {1, 0}};
    start_at_canonical_vertex(square);
    CHECK(square[0].x == 0);
    CHECK(square[0].y == 0);
}

TEST_CASE("convex2d: intersect against hand-computed polygons", "[convex2d]") {
    // Overlapping squares: [1, 2]^2.
    ConvexPolygon i = intersect(rect(0, 0, 2, 2), rect(1, 1, 3, 3));
    CHECK(same_vertices(i, rect(1, 1, 2, 2)));
    CHECK(signed_area(i) == Approx(1).epsilon(1e-15));
    // A triangle over the square: the square's part below x + y = 3/2 ... as a triangle x, y >= 0,
    // x + y <= 3/2 meets the unit square in the pentagon of area 7/8.
    i = intersect(ConvexPolygon{{0, 0}, {1.5, 0}, {0, 1.5}}, unit_square);
    CHECK(signed_area(i) == Approx(0.875).epsilon(1e-15));
    // A diamond inscribed in the square: itself, area 1/2 (from either side).
    const ConvexPolygon diamond{{0.5, 0}, {1, 0.5}, {0.5, 1}, {0, 0.5}};
    CHECK(signed_area(intersect(diamond, unit_square)) == Approx(0.5).epsilon(1e-15));
    CHECK(signed_area(intersect(unit_square, diamond)) == Approx(0.5).epsilon(1e-15));
    // Contained: the inner polygon.
    i = intersect(rect(0.25, 0.25, 0.75, 0.5), unit_square);
    CHECK(same_vertices(i, rect(0.25, 0.25, 0.75, 0.5)));
    // Disjoint, touching along an edge, touching at a corner: empty.
    CHECK(intersect(unit_square, rect(2, 0, 3, 1)).empty());
    CHECK(intersect(unit_square, rect(1, 0, 2, 1)).empty());
    CHECK(intersect(unit_square, rect(1, 1, 2, 2)).empty());
    // A rotated square of side 1 about the centre of the unit square, by 45 degrees: the regular
    // octagon of area 2 (sqrt 2 - 1) = 0.828427...
    const double r = std::sqrt(0.5);
    const ConvexPolygon rotated{{0.5, 0.5 - r}, {0.5 + r, 0.5}, {0.5, 0.5 + r}, {0.5 - r, 0.5}};
    i = intersect(unit_square, rotated);
    CHECK(i.size() == 8);
    CHECK(signed_area(i) == Approx(2 * (std::sqrt(2.0) - 1)).epsilon(1e-14));
}

TEST_CASE("convex2d: intersections have no repeated vertices", "[convex2d]") {
    // The clip case above seen through intersect: a vertex of `a` lying exactly on an edge line
    // of `b` followed by a vertex outside it. Input: a = (0.5,0) (0.8,-0.5) (1.2,0.6)
    // (0.3,0.7), b = the unit square; expected: the hexagon (0.5,0) (0.981818,0) (1,0.05)
    // (1,0.622222) (0.3,0.7) ... without repeats (before the fix, (0.5,0) came twice).
    const ConvexPolygon a{{0.5, 0}, {0.8, -0.5}, {1.2, 0.6}, {0.3, 0.7}};
    const ConvexPolygon i = intersect(a, unit_square);
    CAPTURE(i);
    CHECK(signed_area(i) == Approx(0.39232323).epsilon(1e-7));
    CHECK(repeated_vertices(i) == 0);
}

TEST_CASE("convex2d: subtract and classify survive a zero-length edge", "[convex2d]") {
    // An edge of b of zero length would give left_of(b[i], b[i]) = the zero half-plane (value 0
    // everywhere): classify took it for a separating axis and answered disjoint, subtract kept
    // all of `rest` as a piece. Such polygons came out of intersect (test above), which is how
    // blocked_view makes its shadows (radiosity/visibility/visible_parts.cpp). Input: s =
    // intersect(a, unit square) with a as above. Expected: classify(s, square) = inside,
    // classify(square, s) = partial, subtract(square, s) of total area 1 - 0.392323 = 0.607677
    // (before the fix: disjoint, disjoint, and 1.60768).
    const ConvexPolygon a{{0.5, 0}, {0.8, -0.5}, {1.2, 0.6}, {0.3, 0.7}};
    const ConvexPolygon s = intersect(a, unit_square);
    CAPTURE(s);
    REQUIRE(signed_area(s) == Approx(0.39232323).epsilon(1e-7));
    CHECK(classify(s, unit_square) == Overlap::inside);
    CHECK(classify(unit_square, s) == Overlap::partial);
    double total = 0;
    for (const ConvexPolygon& piece : subtract(unit_square, s)) total += signed_area(piece);
    CHECK(total == Approx(1 - signed_area(s)).epsilon(1e-12));
}

TEST_CASE("convex2d: subtract against hand-computed pieces", "[convex2d]") {
    // [0,3]^2 minus [1,2]^2: a frame of area 8 in four pieces (one per edge of b met).
    std::vector<ConvexPolygon> pieces = subtract(rect(0, 0, 3, 3), rect(1, 1, 2, 2));
    double total = 0;
    for (const ConvexPolygon& p : pieces) total += signed_area(p);
    CHECK(pieces.size() == 4);
    CHECK(total == Approx(8).epsilon(1e-15));
    // The first piece is the part below b's first edge line y = 1: [0,3] x [0,1].
    REQUIRE(!pieces.empty());
    CHECK(same_vertices(pieces[0], rect(0, 0, 3, 1)));
    // Unit square minus a rectangle covering its right part: one piece, [0, 1/2] x [0, 1].
    pieces = subtract(unit_square, rect(0.5, -1, 2, 2));
    REQUIRE(pieces.size() == 1);
    CHECK(same_vertices(pieces[0], rect(0, 0, 0.5, 1)));
    // Disjoint: a itself. Contained in b: nothing.
    pieces = subtract(unit_square, rect(2, 2, 3, 3));
    REQUIRE(pieces.size() == 1);
    CHECK(signed_area(pieces[0]) == Approx(1).epsilon(1e-15));
    CHECK(subtract(rect(0.2, 0.2, 0.4, 0.4), unit_square).empty());
    // b with fewer than three vertices removes nothing.
    CHECK(subtract(unit_square, ConvexPolygon{{0, 0}, {1, 1}}).size() == 1);
    // min_area drops slivers: the square minus [0, 1] x [1e-6, 1] leaves a 1e-6 strip.
    CHECK(subtract(unit_square, rect(-1, 1e-6, 2, 2)).size() == 1);
    CHECK(subtract(unit_square, rect(-1, 1e-6, 2, 2), 1e-5).empty());
}

TEST_CASE("convex2d: subtract pieces are disjoint and with the intersection tile the polygon",
          "[convex2d]") {
    // Random convex polygons (3 to 9 vertices on ellipses) overlapping in every way. The pieces
    // must be convex, inside a, outside b, pairwise disjoint, and their areas plus the
    // intersection's must add up to a's. Every area is a sum of O(10) products of O(1)
    // coordinates clipped a few times: rounding of 1e-13 relative to a's area is generous.
    const unsigned seed = 2024;
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> k(3, 9);
    int n_partial = 0, n_pieces = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const ConvexPolygon a = random_convex(rng, k(rng), 2.0),
                            b = random_convex(rng, k(rng), 2.0);
        CAPTURE(seed, trial, a, b);
        const double area_a = signed_area(a), tol = 1e-13 * area_a;
        const std::vector<ConvexPolygon> pieces = subtract(a, b);
        const double area_i = area(intersect(a, b));
        double sum = area_i;
        for (size_t p = 0; p < pieces.size(); ++p) {
            CHECK(is_convex_ccw(pieces[p], 1e-12));
            sum += signed_area(pieces[p]);
            CHECK(area(intersect(pieces[p], a)) == Approx(signed_area(pieces[p])).margin(tol));
            CHECK(area(intersect(pieces[p], b)) <= tol);
            for (size_t q = p + 1; q < pieces.size(); ++q)
                CHECK(area(intersect(pieces[p], pieces[q])) <= tol);
        }
        CHECK(sum == Approx(area_a).margin(tol));
        if (area_i > 0 && !pieces.empty()) ++n_partial;
        n_pieces += static_cast<int>(pieces.size());
    }
    CHECK(n_partial > 100);  // the overlaps of interest do occur
    mbr::test::report() << "convex2d subtract: " << n_partial << " of 400 pairs overlap partly, "
                        << n_pieces << " pieces\n";
}

TEST_CASE("convex2d: classify against hand-computed configurations", "[convex2d]") {
    CHECK(classify(unit_square, rect(2, 0, 3, 1)) == Overlap::disjoint);
    CHECK(classify(unit_square, rect(1, 0, 2, 1)) == Overlap::disjoint);  // touching an edge
    CHECK(classify(unit_square, rect(1, 1, 2, 2)) == Overlap::disjoint);  // touching a corner
    // Separated only along the triangle's slanted edge (no axis-parallel gap).
    CHECK(classify(ConvexPolygon{{0, 0}, {1, 0}, {0, 1}}, rect(0.6, 0.6, 1.6, 1.6)) ==
          Overlap::disjoint);
    CHECK(classify(rect(0.25, 0.25, 0.75, 0.75), unit_square) == Overlap::inside);
    CHECK(classify(rect(0, 0, 0.5, 0.5), unit_square) == Overlap::inside);  // inside, edges shared
    CHECK(classify(unit_square, unit_square) == Overlap::inside);
    CHECK(classify(rect(0.5, 0.5, 1.5, 1.5), unit_square) == Overlap::partial);
    CHECK(classify(unit_square, rect(0.25, 0.25, 0.75, 0.75)) == Overlap::partial);  // b inside a
    CHECK(classify(ConvexPolygon{{0, 0}, {1, 0}}, unit_square) == Overlap::disjoint);
}

TEST_CASE("convex2d: classify agrees with the area of the intersection on random polygons",
          "[convex2d]") {
    // disjoint <=> no common area; inside <=> the intersection is all of a; partial otherwise.
    // Random ellipse polygons touch with probability zero, so the areas decide cleanly (1e-12
    // relative separates rounding from a true overlap).
    const unsigned seed = 77;
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> k(3, 8);
    int counts[3] = {0, 0, 0};
    for (int trial = 0; trial < 600; ++trial) {
        const ConvexPolygon b = random_convex(rng, k(rng), 2.0);
        // Every third a is shrunk about a point of b, so that "inside" occurs often.
        ConvexPolygon a = random_convex(rng, k(rng), 2.0);
        if (trial % 3 == 0) {
            const Vec2 a0 = a[0], target = b[0] + 0.3 * (b[1] - b[0]) + 0.3 * (b[2] - b[0]);
            for (Vec2& v : a) v = target + 0.15 * (v - a0);
        }
        CAPTURE(seed, trial, a, b);
        const double area_a = signed_area(a), area_i = area(intersect(a, b));
        const Overlap o = classify(a, b);
        ++counts[static_cast<int>(o)];
        if (o == Overlap::disjoint) CHECK(area_i <= 1e-12 * area_a);
        if (o == Overlap::inside) CHECK(area_i == Approx(area_a).epsilon(1e-12));
        if (o == Overlap::partial) {
            CHECK(area_i > 1e-12 * area_a);
            CHECK(area_i < (1 - 1e-12) * area_a);
        }
        // contains() agrees at the vertices: all of a's vertices in b when a is inside b.
        if (o == Overlap::inside)
            for (Vec2 v : a) CHECK(contains(b, v));
    }
    CHECK(counts[0] > 50);
    CHECK(counts[1] > 50);
    CHECK(counts[2] > 50);
    mbr::test::report() << "convex2d classify: disjoint " << counts[0] << ", inside " << counts[1]
                        << ", partial " << counts[2] << "\n";
}

TEST_CASE("convex2d: contains is the closed polygon", "[convex2d]") {
    const ConvexPolygon tri{{0, 0}, {2, 0}, {0, 2}};
    CHECK(contains(tri, {0.5, 0.5}));
    CHECK(contains(tri, {0, 0}));    // a vertex
    CHECK(contains(tri, {1, 1}));    // on the slanted edge (exact in binary)
    CHECK(contains(tri, {0, 1.3}));  // on the left edge
    CHECK_FALSE(contains(tri, {1.0000001, 1}));
    CHECK_FALSE(contains(tri, {-1e-12, 0.5}));
    CHECK_FALSE(contains(tri, {0.5, -1e-12}));
    CHECK_FALSE(contains(tri, {3, 3}));
    CHECK_FALSE(contains(ConvexPolygon{{0, 0}, {1, 0}}, {0.5, 0}));  // not a polygon
    // Random points against the sign of the barycentric coordinates of a random triangle.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 2);
    const ConvexPolygon t{{0.1, -0.2}, {1.3, 0.4}, {0.2, 1.1}};
    for (int i = 0; i < 1000; ++i) {
        const Vec2 x{u(rng), u(rng)};
        const double d = cross(t[1] - t[0], t[2] - t[0]);
        const double l1 = cross(x - t[0], t[2] - t[0]) / d, l2 = cross(t[1] - t[0], x - t[0]) / d;
        const bool inside = l1 >= 0 && l2 >= 0 && l1 + l2 <= 1;
        CAPTURE(x);
        CHECK(contains(t, x) == inside);
    }
}

TEST_CASE("convex2d: inverse_bilinear undoes the bilinear map of convex quads", "[convex2d]") {
    // P(s,t) = (1-s)(1-t) q0 + s(1-t) q1 + s t q2 + (1-s) t q3 on random convex quads (four
    // points on an ellipse, sorted), on parallelograms (k2 = 0: the linear branch) and on
    // trapezoids (one pair of sides parallel). Round trip of (s, t) in [0,1]^2: the closed form
    // plus two Newton steps is exact to rounding; 1e-12 allows for quads of aspect ~10.
    const unsigned seed = 31;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    auto map = [](const ConvexPolygon& q, double s, double t) {
        return (1 - s) * (1 - t) * q[0] + s * (1 - t) * q[1] + s * t * q[2] + (1 - s) * t * q[3];
    };
    double worst = 0, worst_outside = 0;
    int n_general = 0;  // random quads kept
    for (int trial = 0; trial < 450; ++trial) {
        ConvexPolygon q;
        const int kind = trial % 3;
        if (kind == 0) {
            q = random_convex(rng, 4, 1.0);
            // Reject near-triangles (a short edge or a flat corner): there the map folds just
            // outside [0,1]^2 and no inverse exists to compare with.
            bool thin = false;
            double longest = 0;
            for (int i = 0; i < 4; ++i) longest = std::max(longest, length2(q[(i + 1) % 4] - q[i]));
            for (int i = 0; i < 4; ++i) {
                const Vec2 a = q[i], b = q[(i + 1) % 4], c = q[(i + 2) % 4];
                const double sin_angle = cross(b - a, c - b) / (length2(b - a) * length2(c - b));
                thin = thin || sin_angle < 0.2 || length2(b - a) < 0.3 * longest;
            }
            if (thin) continue;
            ++n_general;
        } else if (kind == 1) {  // parallelogram
            const Vec2 o{u(rng), u(rng)}, e{0.5 + u(rng), 0.3 * u(rng)},
                f{0.3 * u(rng) - 0.15, 0.5 + u(rng)};
            q = {o, o + e, o + e + f, o + f};
        } else {  // trapezoid: bottom and top parallel
            const double w0 = 0.5 + u(rng), w1 = 0.2 + u(rng), shift = u(rng) - 0.5,
                         h = 0.3 + u(rng);
            q = {{0, 0}, {w0, 0}, {shift + w1, h}, {shift, h}};
        }
        for (int i = 0; i < 10; ++i) {
            const double s = u(rng), t = u(rng);
            const Vec2 x = map(q, s, t);
            const Vec2 st = inverse_bilinear(q[0], q[1], q[2], q[3], x);
            CAPTURE(seed, trial, kind, q, s, t, st);
            worst = std::max({worst, std::fabs(st.x - s), std::fabs(st.y - t)});
            CHECK(std::fabs(st.x - s) <= 1e-12);
            CHECK(std::fabs(st.y - t) <= 1e-12);
            // Slightly outside (s, t in [-0.05, 1.05]): the extrapolating root, still a round trip
            // while the map stays one-to-one there.
            const double so = -0.05 + 1.1 * u(rng), to = -0.05 + 1.1 * u(rng);
            const Vec2 sto = inverse_bilinear(q[0], q[1], q[2], q[3], map(q, so, to));
            worst_outside = std::max({worst_outside, std::fabs(sto.x - so), std::fabs(sto.y - to)});
            CHECK(std::fabs(sto.x - so) <= 1e-10);
            CHECK(std::fabs(sto.y - to) <= 1e-10);
        }
    }
    CHECK(n_general > 20);
    // The corners themselves, and the unit square (identity).
    const ConvexPolygon q{{0, 0}, {2, 0.2}, {1.7, 1.4}, {-0.3, 0.9}};
    const Vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
        const Vec2 st = inverse_bilinear(q[0], q[1], q[2], q[3], q[i]);
        CHECK(st.x == Approx(corners[i].x).margin(1e-14));
        CHECK(st.y == Approx(corners[i].y).margin(1e-14));
    }
    const Vec2 id = inverse_bilinear({0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.3, 0.8});
    CHECK(id.x == Approx(0.3).margin(1e-15));
    CHECK(id.y == Approx(0.8).margin(1e-15));
    mbr::test::report() << "convex2d inverse_bilinear: worst round-trip error " << worst
                        << " inside, " << worst_outside << " slightly outside\n";
}

namespace {

/// Checks a rule on the triangle (0,0) (1,0) (0,1): positive weights summing to its area 1/2,
/// points in the closed triangle, every monomial x^a y^b of total degree <= `degree` integrated
/// to 1e-13 relative (int x^a y^b = a! b! / (a + b + 2)!), and x^(degree + 2) missed: the check
/// that the test can fail.
void check_triangle_rule(const TriangleRule& rule, int degree) {
    REQUIRE(rule.weights.size() == rule.points.size());
    double w_sum = 0;
    for (size_t q = 0; q < rule.points.size(); ++q) {
        const Vec2 x = rule.points[q];
        CHECK(rule.weights[q] > 0);
        CHECK(x.x >= 0);
        CHECK(x.y >= 0);
        CHECK(x.x + x.y <= 1);
        w_sum += rule.weights[q];
    }
    CHECK(w_sum == Approx(0.5).epsilon(1e-14));
    auto integrate = [&](int a, int b) {
        double sum = 0;
        for (size_t q = 0; q < rule.points.size(); ++q)
            sum += rule.weights[q] * std::pow(rule.points[q].x, a) * std::pow(rule.points[q].y, b);
        return sum;
    };
    for (int deg = 0; deg <= degree; ++deg)
        for (int a = 0; a <= deg; ++a) {
            const int b = deg - a;
            CAPTURE(degree, a, b);
            CHECK(integrate(a, b) ==
                  Approx(factorial(a) * factorial(b) / factorial(a + b + 2)).epsilon(1e-13));
        }
    const double beyond = factorial(degree + 2) / factorial(degree + 4);
    CAPTURE(degree);
    CHECK(std::fabs(integrate(degree + 2, 0) - beyond) > 1e-10 * beyond);
}

}  // namespace

TEST_CASE("convex2d: triangle_rule integrates monomials of degree 2n - 2 exactly", "[convex2d]") {
    // The collapsed (Duffy) n x n rule is exact for total degree <= 2n - 2; at degree 2n, beyond
    // its reach in the collapsed variable, it misses.
    for (int n = 1; n <= 8; ++n) {
        const TriangleRule rule = triangle_rule(n);
        REQUIRE(rule.points.size() == size_t(n) * n);
        check_triangle_rule(rule, 2 * n - 2);
    }
}

TEST_CASE("convex2d: the symmetric triangle rules integrate monomials of their degree exactly",
          "[convex2d]") {
    // Strang-Fix / Dunavant rules of degree 2, 4 and 6 (3, 6 and 12 points, inside the triangle;
    // their constants carry 15 digits); triangle_rule_of_degree_2n_minus_2 takes them for
    // n = 2, 3, 4 and the collapsed rule beyond.
    const int points[] = {0, 0, 3, 0, 6, 0, 12};
    for (int degree : {2, 4, 6}) {
        const TriangleRule rule = symmetric_triangle_rule(degree);
        REQUIRE(rule.points.size() == size_t(points[degree]));
        CHECK(triangle_rule_of_degree_2n_minus_2(degree / 2 + 1).points.size() ==
              rule.points.size());
        for (const Vec2& x : rule.points) CHECK((x.x > 0 && x.y > 0 && x.x + x.y < 1));
        check_triangle_rule(rule, degree);
    }
    CHECK(triangle_rule_of_degree_2n_minus_2(1).points.size() == 1);
    CHECK(triangle_rule_of_degree_2n_minus_2(5).points.size() == 25);
    CHECK_THROWS(symmetric_triangle_rule(3));
}

TEST_CASE(
    "convex2d: narrowest_width is a square's side, a strip's width, a triangle's least height",
    "[convex2d]") {
    CHECK(narrowest_width(unit_square) == Approx(1));
    const ConvexPolygon strip{{0, 0}, {1.4, 0}, {1.4, 0.08}, {0, 0.08}};
    CHECK(narrowest_width(strip) == Approx(0.08));
    // Clockwise, the same.
    CHECK(narrowest_width(ConvexPolygon(strip.rbegin(), strip.rend())) == Approx(0.08));
    // A strip turned by 30 degrees keeps its width.
    ConvexPolygon turned;
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    for (const Vec2& p : strip) turned.push_back({c * p.x - s * p.y, s * p.x + c * p.y});
    CHECK(narrowest_width(turned) == Approx(0.08));
    // The triangle (0,0), (4,0), (0,3): its heights are 3, 4 and 12/5.
    CHECK(narrowest_width({{0, 0}, {4, 0}, {0, 3}}) == Approx(2.4));
}
