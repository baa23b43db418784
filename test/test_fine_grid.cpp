// test/test_fine_grid.cpp - stages 6 and 8 at once on the finest grid (beyond the paper,
// ReceiverOptions::unify_by_projection, the scenes' default; radiosity/transfer/fine_grid.h):
// project_fine_grid reproduces polynomials of degree < m up to the truncation of the dual (where
// its coefficients see only the domain's samples), and agrees with project_in_rhombi +
// unify_scales (section 5, eq. (19), Figure 3, eq. (17)) when both see the same values.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/dual_basis.h"
#include "radiosity/transfer/transfer.h"
#include "test/report.h"
#include "test/transfer_helpers.h"

using namespace mbr;
using namespace mbr::test;

namespace {

/// Edge profiles of f (values and derivatives along the normal coordinate, three channels f,
/// -2f, f/2 as fill_samples makes them) at nine nodes per edge, and linear extrapolation without
/// clamping, so that extrapolate() continues f's edges by (23)-(25) as it stands.
template <class F, class Fs, class Ft>
void fill_edges(ReceiverState& state, F&& f, Fs&& f_s, Ft&& f_t) {
    state.options.extrapolation = Extrapolation::Linear;
    state.options.clamp_factor = 1e6;
    state.options.clamp_values = false;
    for (int e = 0; e < 4; ++e) {
        EdgeProfile& p = state.edges[e];
        p = EdgeProfile{};
        p.h_min = 1.0 / 8;
        for (int i = 0; i <= 8; ++i) {
            const double sigma = i / 8.0;
            const double s = e == 0 || e == 2 ? sigma : (e == 1 ? 1.0 : 0.0);
            const double t = e == 1 || e == 3 ? sigma : (e == 2 ? 1.0 : 0.0);
            const double v = f(s, t), d = e == 0 || e == 2 ? f_t(s, t) : f_s(s, t);
            p.sigma.push_back(sigma);
            p.value.push_back({v, -2 * v, 0.5 * v});
            p.derivative.push_back({d, -2 * d, 0.5 * d});
        }
    }
}

/// The coefficient indices k at level J whose cells in project_fine_grid's window (fine_grid.cpp:
/// floor(k + m/2 - r) - 1 .. ceil(k + m/2 + r)) all lie in [0,1]^2, as [k_lo, k_hi].
void interior_indices(int m, int J, double r, int& k_lo, int& k_hi) {
    k_lo = static_cast<int>(std::ceil(r - 0.5 * m)) + 1;
    while (std::floor(k_lo + 0.5 * m - r) - 1 < 0) ++k_lo;
    k_hi = (1 << J) - 1;
    while (std::ceil(k_hi + 0.5 * m + r) > (1 << J) - 1) --k_hi;
}

}  // namespace

TEST_CASE("fine_grid: project_fine_grid reproduces polynomials of degree < m up to truncation",
          "[fine_grid]") {
    // Inside [s0, s1]^2 every coefficient of the field sees only domain cells, whose samples are
    // the polynomial's: the Gauss-Legendre rule is exact on each cell for p DN DN (degree
    // 2m - 2 per variable), so the error is the part of the projection (19) that the window
    // drops. The window is the square |x|, |y| <= r widened to whole cells, which holds the
    // rhombus |x| + |y| <= r: what it drops lies beyond the rhombus, so the bound of the
    // rhombus projection (projection_error_bound: truncation, table error, rounding) holds.
    std::mt19937 rng(7);
    const int J = 6;
    for (int m = 3; m <= 4; ++m) {
        const DualTable dn(m);
        const double r = dn.rhombus_radius(1e-4);
        int k_lo, k_hi;
        interior_indices(m, J, r, k_lo, k_hi);
        // Points x = 2^J s whose m coefficients k in (x - m, x] are all interior.
        const double h = std::ldexp(1.0, -J);
        const double s0 = (k_lo + m - 1) * h, s1 = (k_hi + 1) * h;
        CAPTURE(m, r, k_lo, k_hi);
        REQUIRE(s0 < s1);
        double c = 0;  // the interior fulcrums' largest distance from 1/2 in either coordinate
        for (int k = k_lo; k <= k_hi; ++k) c = std::max(c, std::fabs((k + 0.5 * m) * h - 0.5));
        for (int trial = 0; trial < 3; ++trial) {
            const Poly p = random_poly(m, rng);
            ReceiverState state = make_state(m, r);
            split_domain_uniform(state.forest, J);
            fill_samples(state, p);
            const double d = 1e-6;  // edge derivatives by central differences: any will do,
                                    //   the boundary coefficients are not checked
            fill_edges(
                state, p, [&](double s, double t) { return (p(s + d, t) - p(s - d, t)) / (2 * d); },
                [&](double s, double t) { return (p(s, t + d) - p(s, t - d)) / (2 * d); });
            state.max_sample = 1;
            state.fulcrums = select_fulcrums(state.forest, m);
            const SplineField field = project_fine_grid(state, dn);
            CHECK(field.level() == J);
            std::vector<double> abs_a(p.a.size());
            for (size_t i = 0; i < p.a.size(); ++i) abs_a[i] = std::fabs(p.a[i]);
            const double bound = projection_error_bound(dn, r, h, c, abs_a, m);
            double worst = 0;
            const int n = 17;
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    const double s = s0 + (s1 - s0) * a / n, t = s0 + (s1 - s0) * b / n;
                    const Rgb v = field.evaluate(s, t);
                    worst = std::max(worst, std::fabs(v.r - p(s, t)));
                    CHECK(v.g == Approx(-2 * v.r).margin(1e-12));
                    CHECK(v.b == Approx(0.5 * v.r).margin(1e-12));
                }
            CAPTURE(worst, bound);
            CHECK(worst <= bound);
            mbr::test::report() << "fine_grid polynomial m=" << m << ": rhombus " << r
                                << " cells, interior [" << s0 << ", " << s1 << "), max error "
                                << worst << ", bound " << bound << "\n";
        }
    }
}

TEST_CASE("fine_grid: project_fine_grid agrees with project_in_rhombi and unify_scales",
          "[fine_grid]") {
    // Both see the same values: the domain's samples of a smooth increment g, and outside the
    // linear extrapolation (23)-(25) at the level-J nodes (the rhombus path on a ring of level-J
    // cells sampled by extrapolate, as expand_domain samples it). Per cell both take the same
    // m x m Gauss-Legendre sum with DN from the same table; they differ only in the cells they
    // sum: project() those that meet the rhombus |x| + |y| <= r, project_fine_grid the square
    // window that holds it. The extra cells lie beyond the rhombus, so the difference is at most
    // M times the tail of |DN DN| beyond it, M the largest value there: projection_error_bound
    // for the constant M (its midpoint sums of the tail carry a factor 1.1; the Gauss sums of
    // |DN DN| on whole cells may exceed the integral where DN changes sign inside a cell, for
    // which the tolerance doubles it).
    const int J = 4;
    for (int m = 3; m <= 4; ++m) {
        const DualTable dn(m);
        const double r = dn.rhombus_radius(1e-4);
        auto g = [](double s, double t) { return 1 + 0.5 * std::sin(2 * s + 1) * std::cos(3 * t); };
        auto g_s = [](double s, double t) { return std::cos(2 * s + 1) * std::cos(3 * t); };
        auto g_t = [](double s, double t) { return -1.5 * std::sin(2 * s + 1) * std::sin(3 * t); };
        ReceiverState fine = make_state(m, r);
        split_domain_uniform(fine.forest, J);
        fill_samples(fine, g);
        fill_edges(fine, g, g_s, g_t);

        // The rhombus path: the same state with a ring of level-J cells sampled by extrapolation.
        ReceiverState rhombi = fine;
        build_ring(rhombi, J);
        fill_samples(rhombi, g);
        const GaussLegendre rule = gauss_legendre(m);
        double M = 0;  // the largest |value| either path uses, any channel
        for (int index : rhombi.forest.leaves()) {
            const Forest::Node& node = rhombi.forest.node(index);
            const Rect c = node.cell.rect();
            for (int a = 0; a < m; ++a)
                for (int b = 0; b < m; ++b) {
                    const double s = c.x0 + 0.5 * (rule.x[a] + 1) * c.width();
                    const double t = c.y0 + 0.5 * (rule.x[b] + 1) * c.height();
                    Rgb& v = rhombi.samples[size_t(node.samples) * m * m + a * m + b];
                    if (!node.cell.in_domain()) v = extrapolate(rhombi, s, t);
                    M = std::max(M, max_abs(v));
                }
        }
        const SplineField a = select_project_unify(rhombi, dn);
        fine.fulcrums = select_fulcrums(fine.forest, m);
        const SplineField b = project_fine_grid(fine, dn);
        REQUIRE(a.level() == J);
        REQUIRE(b.level() == J);
        // The ring reaches every cell of the fine grid's windows (the rhombus path needs no more:
        // its cells meet rhombi of radius r around fulcrums half a support outside).
        std::vector<double> abs_a(size_t(m) * m, 0.0);
        abs_a[0] = M;
        const double tolerance =
            2 * projection_error_bound(dn, r, std::ldexp(1.0, -J), 0, abs_a, m);
        const int first = first_touching_index(m), n = touching_count(m, J);
        double worst = 0;
        for (int k = first; k < first + n; ++k)
            for (int l = first; l < first + n; ++l)
                worst = std::max(worst, max_abs(a.coefficient(k, l) - b.coefficient(k, l)));
        CAPTURE(m, r, M, worst, tolerance);
        CHECK(worst <= tolerance);
        mbr::test::report() << "fine_grid vs rhombi m=" << m << ": rhombus " << r
                            << " cells, largest difference " << worst << ", tolerance " << tolerance
                            << "\n";
    }
}
