// test/test_projection.cpp - stages 5 and 6 of one transfer (paper section 5, "Selection of Dual
// Basis Functions", Figure 2, and "Projection", eq. (19), Figure 3; radiosity/transfer/
// projection.h), on states built by hand, with stage 8 to read the result:
// - polynomials of degree < m per variable lie in every spline space, so projection returns them
//   up to the truncation of the dual (bounded here by an independent integral of the dropped
//   tail of |p DN DN|);
// - a random level-L spline is returned coefficient for coefficient;
// - project() is compared with an independent sum over exactly the cells that meet the rhombus;
// - select_fulcrums against hand-listed sets.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "math/bspline.h"
#include "math/dual_basis.h"
#include "math/gauss_legendre.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"
#include "test/report.h"
#include "test/transfer_helpers.h"

using namespace mbr;
using namespace mbr::test;

// ---- Projection: polynomials and spline-space functions -------------------------------------

namespace {

/// Projects the polynomial p on a depth-3 tree (uniform, or mixed: two cells at depth 4 and
/// the ring beyond the cells next to the domain left at level 0, so that stage 6 fits and
/// resamples leaves coarser than the fulcrum and stage 8 refines coarse coefficients by (17))
/// with the rhombus of eps; returns the largest error on [0,1]^2 and writes the bound.
double polynomial_error(const Poly& p, bool mixed, double eps, double* bound) {
    const int m = p.m;
    const DualTable dn(m);
    ReceiverState state = make_state(m, dn.rhombus_radius(eps));
    if (mixed)
        build_mixed_domain(state.forest, 3);
    else
        split_domain_uniform(state.forest, 3);
    build_ring(state, mixed ? 0 : 3);
    fill_samples(state, p);
    const SplineField field = select_project_unify(state, dn);
    CHECK(field.level() == (mixed ? 4 : 3));
    if (mixed) CHECK(state.stats.n_refined > 0);
    std::vector<double> abs_a(p.a.size());
    for (size_t i = 0; i < p.a.size(); ++i) abs_a[i] = std::fabs(p.a[i]);
    *bound = field_error_bound(state, dn, abs_a);
    const double error = max_field_error(field, p);
    mbr::test::report() << "receiver polynomial m=" << m << (mixed ? " mixed  " : " uniform")
                        << " eps=" << eps << ": rhombus " << state.rhombus_radius
                        << " cells, max error " << error << ", bound " << *bound << ", fulcrums "
                        << state.fulcrums.size() << ", refined by (17) " << state.stats.n_refined
                        << "\n";
    return error;
}

}  // namespace

TEST_CASE("receiver: projection reproduces polynomials of degree < m up to truncation",
          "[receiver][projection]") {
    // Random p of degree m - 1 in each variable, extended exactly outside the domain, with the
    // default eps = 1e-7. The only error is the truncation of the dual: the bound is the
    // dropped tail of |p DN DN| (projection_error_bound). p grows like |x|^(2m-2) while DN DN
    // decays geometrically, so for m = 4, 5 the error is far above eps itself (measured 9e-5
    // and 1.8e-3 at this depth, against bounds 8e-3 and 0.4; m = 2, 3: 7e-7, 5e-7).
    std::mt19937 rng(42);
    const double eps = ReceiverOptions{}.truncation_eps;
    for (int m = 2; m <= 5; ++m)
        for (bool mixed : {false, true}) {
            CAPTURE(m, mixed);
            const Poly p = random_poly(m, rng);
            double bound = 0;
            const double error = polynomial_error(p, mixed, eps, &bound);
            CAPTURE(error, bound);
            CHECK(error <= bound);
        }
}

TEST_CASE("receiver: polynomial reproduction error is truncation alone", "[receiver][projection]") {
    // A much smaller eps (1e-11: rhombus radii 19-51 cells instead of 12-33) must shrink the
    // error by orders of magnitude (measured factors 360-6700); anything left by the fit, the
    // resampling, the quadrature or (17) would not shrink. Uniform trees only, to keep it fast.
    std::mt19937 rng(43);
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const Poly p = random_poly(m, rng);
        double bound_default = 0, bound_small = 0;
        const double e_default = polynomial_error(p, false, 1e-7, &bound_default);
        const double e_small = polynomial_error(p, false, 1e-11, &bound_small);
        CAPTURE(e_default, e_small, bound_small);
        CHECK(e_small <= bound_small);
        CHECK(e_small <= 0.01 * e_default);
    }
}

TEST_CASE("receiver: projecting a function of the spline space returns its coefficients",
          "[receiver][projection]") {
    // f = sum c_kl N_m(4s - k) N_m(4t - l) with random c in [-1,1] over the whole forest
    // (domain and ring), sampled at every leaf's Gauss-Legendre nodes; every leaf is at level
    // >= 2, so f is one polynomial per leaf and the quadrature of f DN DN is exact. Uniform
    // depth 2 (result at level 2) and depth 2 with cells at depth 3 (result at level 3, the
    // coefficients of f refined by (17)). The error of each coefficient is the dropped tail of
    // |f DN DN| <= max|c| times the tail of |DN DN| outside the rhombus.
    std::mt19937 rng(44);
    std::uniform_real_distribution<double> u(-1, 1);
    const double eps = ReceiverOptions{}.truncation_eps;
    for (int m = 2; m <= 5; ++m)
        for (bool mixed : {false, true}) {
            CAPTURE(m, mixed);
            const DualTable dn(m);
            ReceiverState state = make_state(m, dn.rhombus_radius(eps));
            if (mixed)
                build_mixed_domain(state.forest, 2);
            else
                split_domain_uniform(state.forest, 2);
            build_ring(state, 2);
            const int L = 2, K = state.forest.extent();
            const int first = -K * (1 << L) - (m - 1), count = (2 * K + 1) * (1 << L) + m - 1;
            CoefficientGrid grid(L, first, first, count, count);
            for (double& c : grid.a) c = u(rng);
            fill_samples(state, [&](double s, double t) { return evaluate(m, grid, s, t); });
            const SplineField field = select_project_unify(state, dn);
            const int j = mixed ? 3 : 2;
            REQUIRE(field.level() == j);
            const CoefficientGrid expect = j == L ? grid : refine(m, grid);
            std::vector<double> one(size_t(m) * m, 0.0);
            one[0] = 1;  // the data bound is the constant max|c| = 1
            const double bound = projection_error_bound(dn, state.rhombus_radius, 1, 0, one, m);
            double worst = 0;
            const int t0 = first_touching_index(m), tn = touching_count(m, j);
            for (int k = t0; k < t0 + tn; ++k)
                for (int l = t0; l < t0 + tn; ++l) {
                    REQUIRE(expect.contains(k, l));
                    worst = std::max(worst, std::fabs(field.coefficient(k, l).r - expect(k, l)));
                }
            CAPTURE(worst, bound);
            CHECK(worst <= bound);
            mbr::test::report() << "receiver spline space m=" << m
                                << (mixed ? " mixed  " : " uniform") << ": max coefficient error "
                                << worst << ", bound " << bound << "\n";
        }
}

// ---- The rhombus (section 5 "Projection", Figure 3) -----------------------------------------

TEST_CASE("receiver: the rhombus holds every point where |DN DN| exceeds eps, and little more",
          "[receiver][projection]") {
    for (int m = 2; m <= 5; ++m)
        for (double eps : {1e-4, 1e-7, 1e-10}) {
            CAPTURE(m, eps);
            const DualTable dn(m);
            ReceiverOptions options;
            options.m = m;
            options.truncation_eps = eps;
            const double r = rhombus_radius_cells(options, dn);
            CHECK(r == dn.rhombus_radius(eps));
            options.rhombus_radius = 7.25;  // an explicit radius wins
            CHECK(rhombus_radius_cells(options, dn) == 7.25);
            const double threshold = eps * dn.max_abs() * dn.max_abs();
            auto DD = [&](double x, double y) {
                return std::fabs(dn(0.5 * m + x) * dn(0.5 * m + y));
            };
            // Outside: on the lines |x| + |y| = r + d for d in (0, 3], 257 points along one
            // quadrant of each (DN is symmetric).
            double outside = 0, inside = 0;
            for (double d : {1e-9, 0.01, 0.5, 1.0, 3.0})
                for (int q = 0; q <= 64 * 4; ++q) {
                    const double x = (r + d) * q / (64.0 * 4);
                    outside = std::max(outside, DD(x, r + d - x));
                }
            // Not much more: one cell inside the rhombus's edge some point exceeds eps.
            for (int q = 0; q <= 64 * 4; ++q) {
                const double x = (r - 1) * q / (64.0 * 4);
                inside = std::max(inside, DD(x, r - 1 - x));
            }
            CAPTURE(r, outside / threshold, inside / threshold);
            CHECK(outside <= threshold);
            CHECK(inside > threshold);
        }
}

namespace {

/// int over [a, b] (in x = 2^L s - k units, inside one knot interval of DN or finer) of DN_m(x)
/// by an (m + 2)-point rule: exact for the degree m - 1 piece.
double dn_integral(const DualTable& dn, double a, double b) {
    static thread_local std::vector<GaussLegendre> rules(12);
    const int n = dn.order() + 2;
    if (rules[n].n() != n) rules[n] = gauss_legendre(n);
    return integrate_1d([&](double x) { return dn(x); }, a, b, rules[n]);
}

/// Reference for project() when every leaf carries one constant value v (the red sample):
/// sum over leaves of v times the integral of 4^L DN DN over the leaf's cells at scale
/// min(leaf, fulcrum) that meet the closed rhombus |s - cx| + |t - cy| <= R (1-norm distance
/// from the cell to the centre at most R): written without the tree walk, the root window or the
/// strip-and-window loop of project().
Rgb project_brute_force(const ReceiverState& state, const DualTable& dn, const Fulcrum& f) {
    const int m = state.options.m;
    const double scale = std::ldexp(1.0, f.level);
    const Vec2 c = f.position(m);
    const double R = state.rhombus_radius / scale;
    Rgb sum;
    for (int index : state.forest.leaves()) {
        const Forest::Node& node = state.forest.node(index);
        const Rgb v = state.samples[size_t(node.samples) * m * m];
        const Rect r = node.cell.rect();
        const int n_sub = node.cell.level < f.level ? 1 << (f.level - node.cell.level) : 1;
        const double h = r.width() / n_sub;
        for (int p = 0; p < n_sub; ++p)
            for (int q = 0; q < n_sub; ++q) {
                const double x0 = r.x0 + p * h, y0 = r.y0 + q * h;
                const double dx = std::max({0.0, x0 - c.x, c.x - (x0 + h)});
                const double dy = std::max({0.0, y0 - c.y, c.y - (y0 + h)});
                if (dx + dy > R) continue;
                const double ix = dn_integral(dn, x0 * scale - f.k, (x0 + h) * scale - f.k);
                const double iy = dn_integral(dn, y0 * scale - f.l, (y0 + h) * scale - f.l);
                sum += (ix * iy) * v;  // 4^L ds dt = dx dy
            }
    }
    return sum;
}

}  // namespace

TEST_CASE("receiver: project visits exactly the leaf cells that meet the rhombus",
          "[receiver][projection]") {
    // A mixed tree (depth 2, two cells at depth 3, the far ring at level 0) whose leaves carry
    // random constants: project() must equal the sum over exactly the cells meeting the
    // rhombus. Radii 6.3 and 9.7 cells (not dyadic, so no cell touches the rhombus exactly;
    // DN DN is still ~1e-2 of its peak on the edge of the smaller one, so a cell taken or
    // dropped wrongly changes the value by far more than rounding). The fulcrums are the
    // selected ones plus some of level 1..4 around the domain, coarser and finer than leaves.
    std::mt19937 rng(45);
    std::uniform_real_distribution<double> value(0.5, 1.5);
    for (int m : {3, 4})
        for (double radius : {6.3, 9.7}) {
            CAPTURE(m, radius);
            const DualTable dn(m);
            ReceiverState state = make_state(m, radius);
            build_mixed_domain(state.forest, 2);
            build_ring(state, 0);
            // One random constant per leaf (all m x m samples equal: the fit is exact).
            state.samples.clear();
            int block = 0;
            for (int index : state.forest.leaves()) {
                state.forest.node(index).samples = block++;
                const double v = value(rng);
                for (int i = 0; i < m * m; ++i) state.samples.push_back({v, v, v});
            }
            std::vector<Fulcrum> fulcrums = select_fulcrums(state.forest, m);
            std::uniform_int_distribution<int> level(1, 4);
            for (int i = 0; i < 12; ++i) {
                const int L = level(rng);
                std::uniform_int_distribution<int> k(-m - 2, (1 << L) + 1);
                fulcrums.push_back({L, k(rng), k(rng)});
            }
            double worst = 0;
            for (const Fulcrum& f : fulcrums) {
                CAPTURE(f.level, f.k, f.l);
                const double got = project(state, dn, f).r;
                const double expect = project_brute_force(state, dn, f).r;
                worst = std::max(worst, std::fabs(got - expect));
                // Both sum the same exact cell integrals (m points against m + 2): rounding of
                // a few hundred O(1) terms.
                CHECK(got == Approx(expect).epsilon(1e-12).margin(1e-13));
            }
            mbr::test::report() << "receiver rhombus walk m=" << m << " R=" << radius << ": "
                                << fulcrums.size() << " fulcrums, max difference " << worst << "\n";
        }
}

// ---- Fulcrum selection (Figure 2) -----------------------------------------------------------

namespace {

/// The small mixed tree of the fulcrum test: the domain split once, its quadrant (0,0) split
/// again; the ring of eight unit roots split once, and the five level-1 ring cells that touch a
/// level-2 domain leaf split again (an expanded cell next to the domain has the boundary leaf's
/// size, expand_domain's rule, corners included).
Forest fulcrum_tree() {
    Forest forest(0);
    const int q = forest.split(forest.domain_root());
    forest.split(q);  // quadrant (0,0): cells (2,0,0), (2,1,0), (2,0,1), (2,1,1)
    forest.grow(1);
    for (int J = -1; J <= 1; ++J)
        for (int I = -1; I <= 1; ++I)
            if (I != 0 || J != 0) forest.split(forest.root(I, J));
    for (const DyadicCell c : {DyadicCell{1, -1, -1}, DyadicCell{1, -1, 0}, DyadicCell{1, -1, 1},
                               DyadicCell{1, 0, -1}, DyadicCell{1, 1, -1}}) {
        const int index = forest.find(c);
        REQUIRE(forest.node(index).cell == c);
        forest.split(index);
    }
    return forest;
}

/// A fulcrum as (level, position in units of `unit`), e.g. unit 1/8 for centres.
struct Spot {
    int level, x, y;
    bool operator<(const Spot& o) const {
        return level != o.level ? level < o.level : (x != o.x ? x < o.x : y < o.y);
    }
    bool operator==(const Spot& o) const { return level == o.level && x == o.x && y == o.y; }
};

std::set<Spot> spots(const std::vector<Fulcrum>& fulcrums, int m, double unit) {
    std::set<Spot> out;
    for (const Fulcrum& f : fulcrums) {
        const Vec2 p = f.position(m);
        const double x = p.x / unit, y = p.y / unit;
        REQUIRE(x == std::round(x));
        REQUIRE(y == std::round(y));
        out.insert({f.level, int(x), int(y)});
    }
    return out;
}

/// The paper's rule read literally (section 5, "Selection of Dual Basis Functions"): the centres
/// (odd m) or corners (even m) of the domain leaves, and of the expanded leaves adjoining the
/// domain (sharing an edge or a corner with it), each at its leaf's scale.
std::set<Spot> paper_rule(const Forest& forest, int m, double unit) {
    std::set<Spot> out;
    for (int index : forest.leaves()) {
        const DyadicCell c = forest.node(index).cell;
        if (!c.in_domain() && !touching(c.rect(), Rect{0, 1, 0, 1})) continue;
        const Rect r = c.rect();
        std::vector<Vec2> points;
        if (m % 2 == 1)
            points.push_back(r.centre());
        else
            points = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x0, r.y1}, {r.x1, r.y1}};
        for (const Vec2& p : points)
            out.insert({c.level, int(std::lround(p.x / unit)), int(std::lround(p.y / unit))});
    }
    return out;
}

}  // namespace

TEST_CASE("receiver: fulcrums for m = 3 on a hand-built tree equal the hand-listed set",
          "[receiver][projection]") {
    // Centres (units of 1/8) of: the domain's level-2 leaves (2,0,0) (2,1,0) (2,0,1) (2,1,1) and
    // level-1 leaves (1,1,0) (1,0,1) (1,1,1); the level-2 ring leaves adjoining the domain,
    // (2,-1,j) for j = -1..3 and (2,i,-1) for i = 0..3; the level-1 ring leaves adjoining it,
    // (1,-1,2) (1,2,-1) (1,2,0) (1,2,1) (1,2,2) (1,0,2) (1,1,2). The other expanded leaves have
    // centres whose N_3 (support: the cell and one on each side) misses the domain.
    const std::set<Spot> expect{// domain, level 2
                                {2, 1, 1},
                                {2, 3, 1},
                                {2, 1, 3},
                                {2, 3, 3},
                                // domain, level 1
                                {1, 6, 2},
                                {1, 2, 6},
                                {1, 6, 6},
                                // ring, level 2
                                {2, -1, -1},
                                {2, -1, 1},
                                {2, -1, 3},
                                {2, -1, 5},
                                {2, -1, 7},
                                {2, 1, -1},
                                {2, 3, -1},
                                {2, 5, -1},
                                {2, 7, -1},
                                // ring, level 1
                                {1, -2, 10},
                                {1, 10, -2},
                                {1, 10, 2},
                                {1, 10, 6},
                                {1, 10, 10},
                                {1, 2, 10},
                                {1, 6, 10}};
    REQUIRE(expect.size() == 23);
    const Forest forest = fulcrum_tree();
    const std::vector<Fulcrum> fulcrums = select_fulcrums(forest, 3);
    CHECK(fulcrums.size() == 23);  // no duplicates
    CHECK(spots(fulcrums, 3, 0.125) == expect);
    CHECK(paper_rule(forest, 3, 0.125) == expect);  // odd m: the code's rule is the paper's
    // Index convention: centre (i + 1/2) 2^-L is fulcrum k = i - (m - 1)/2.
    CHECK(std::count(fulcrums.begin(), fulcrums.end(), Fulcrum{2, -2, 1}) == 1);  // cell (2,-1,2)
    CHECK(std::count(fulcrums.begin(), fulcrums.end(), Fulcrum{1, 0, 0}) == 1);   // cell (1,1,1)
}

TEST_CASE("receiver: fulcrums for m = 4 on a hand-built tree equal the hand-listed set",
          "[receiver][projection]") {
    // Corners (units of 1/4) of the same tree. Level 2: the corners of the four level-2 domain
    // leaves, {0,1,2}^2, and of the level-2 ring leaves adjoining the domain: x in {-1,0} with
    // y in -1..4, and y in {-1,0} with x in -1..4. Level 1: the corners of the three level-1
    // domain leaves, {0,2,4}^2 without (0,0), and of the level-1 ring leaves adjoining the
    // domain: x in {4,6} with y in -2..6, y in {4,6} with x in -2..2.
    std::set<Spot> expect;
    for (int x = 0; x <= 2; ++x)
        for (int y = 0; y <= 2; ++y) expect.insert({2, x, y});
    for (int a : {-1, 0})
        for (int b = -1; b <= 4; ++b) {
            expect.insert({2, a, b});
            expect.insert({2, b, a});
        }
    const std::set<Spot> paper_level2 = expect;
    REQUIRE(paper_level2.size() == 24);
    // Level 1, written out: 19 points.
    const Spot level1[] = {
        {1, 2, 0},  {1, 4, 0},  {1, 0, 2}, {1, 2, 2},  {1, 4, 2}, {1, 0, 4},
        {1, 2, 4},  {1, 4, 4},  // the domain leaves' corners
        {1, 4, -2}, {1, 6, -2}, {1, 6, 0}, {1, 6, 2},  {1, 6, 4}, {1, 6, 6},
        {1, 4, 6},  {1, 2, 6},  {1, 0, 6}, {1, -2, 6}, {1, -2, 4}};  // the adjoining ring leaves'
    for (const Spot& s : level1) expect.insert(s);
    REQUIRE(expect.size() == 43);
    const Forest forest = fulcrum_tree();
    CHECK(paper_rule(forest, 4, 0.25) == expect);

    // select_fulcrums takes, besides, the corners of non-adjoining expanded leaves whose basis
    // function still reaches into the domain: N_4 spans four cells, so a level-1 corner one
    // level-1 cell outside the domain qualifies. Here the level-1 leaves (1,-2,j) and (1,i,-2)
    // beyond the level-2 ring add five level-1 fulcrums the paper's wording leaves out (their
    // coefficients are projected but never needed: every coefficient they could feed by (17)
    // sits where the leaves are of level 2). They change no value, only cost (the
    // unification projects missing coefficients on demand, with the same result).
    const Spot extras[] = {{1, -2, -2}, {1, -2, 0}, {1, -2, 2}, {1, 0, -2}, {1, 2, -2}};
    std::set<Spot> expect_code = expect;
    for (const Spot& s : extras) expect_code.insert(s);
    const std::vector<Fulcrum> fulcrums = select_fulcrums(forest, 4);
    CHECK(fulcrums.size() == 48);
    CHECK(spots(fulcrums, 4, 0.25) == expect_code);

    // Coincident pairs: a corner shared by leaves of two sizes carries a fulcrum of each scale.
    std::set<std::pair<int, int>> level1_at, level2_at, both;
    for (const Spot& s : expect_code) (s.level == 1 ? level1_at : level2_at).insert({s.x, s.y});
    for (const auto& p : level1_at)
        if (level2_at.count(p)) both.insert(p);
    const std::set<std::pair<int, int>> expect_pairs{{0, 2}, {0, 4}, {2, 0}, {4, 0}, {2, 2}};
    CHECK(both == expect_pairs);
    // Index convention: corner c 2^-L is fulcrum k = c - m/2; the pair at (1/2, 1/2).
    CHECK(std::count(fulcrums.begin(), fulcrums.end(), Fulcrum{2, 0, 0}) == 1);
    CHECK(std::count(fulcrums.begin(), fulcrums.end(), Fulcrum{1, -1, -1}) == 1);
    // Every selected basis function touches the open domain.
    for (const Fulcrum& f : fulcrums) {
        const int n = 1 << f.level;
        CHECK((f.k < n && f.k + 4 > 0 && f.l < n && f.l + 4 > 0));
    }
}

TEST_CASE("receiver: the extra fulcrums of select_fulcrums change no coefficient",
          "[receiver][projection]") {
    // Unification with the paper's set of fulcrums (the extras left out) gives the same field,
    // bit for bit: a coefficient is the same number whether stored in stage 6 or projected on
    // demand in stage 8.
    const int m = 4;
    const DualTable dn(m);
    ReceiverState state = make_state(m, 6.3);
    state.forest = fulcrum_tree();
    build_ring(state, 0);
    std::mt19937 rng(46);
    const Poly p = random_poly(m, rng);
    fill_samples(state, p);
    const SplineField with_extras = select_project_unify(state, dn);
    const std::set<Spot> paper = paper_rule(state.forest, m, 1.0 / 64);
    std::vector<Fulcrum> kept;
    for (const Fulcrum& f : state.fulcrums)
        if (paper.count(*spots({f}, m, 1.0 / 64).begin())) kept.push_back(f);
    CHECK(kept.size() < state.fulcrums.size());
    state.fulcrums = kept;
    state.coefficients.clear();
    project_in_rhombi(state, dn);
    const SplineField without = unify_scales(state, dn);
    REQUIRE(without.level() == with_extras.level());
    const int first = first_touching_index(m), n = touching_count(m, without.level());
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l)
            CHECK(without.coefficient(k, l) == with_extras.coefficient(k, l));
}
