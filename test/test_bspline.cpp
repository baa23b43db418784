// test/test_bspline.cpp - cardinal B-splines N_m, the two-scale relation (14), refinement (17)
// and dyadic evaluation (18) of paper section 3 (math/bspline.h).
//
// Independent references: the truncated-power formula for N_m (in long double), Gauss-Legendre
// integrals on the unit knot intervals (exact for polynomials), and direct sums
// sum_k a_k N_m(2^j s - k) written out here rather than through evaluate().
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/bspline.h"
#include "math/gauss_legendre.h"

using namespace mbr;

namespace {

/// N_m(x) = 1/(m-1)! sum_{i=0}^{m} (-1)^i binom(m, i) (x - i)_+^{m-1}, in long double; an
/// independent formula (no recursion shared with the library). For m = 1, (x - i)_+^0 is the
/// indicator of x >= i.
double truncated_power_bspline(int m, double x_in) {
    const long double x = x_in;
    if (!(x >= 0 && x < m)) return 0;
    long double sum = 0, binom = 1, fact = 1;
    for (int k = 2; k < m; ++k) fact *= k;
    for (int i = 0; i <= m; ++i) {
        const long double d = x - i;
        if (d >= 0)
            sum += ((i % 2) ? -binom : binom) * std::pow(d, static_cast<long double>(m - 1));
        binom = binom * (m - i) / (i + 1);
    }
    return static_cast<double>(sum / fact);
}

/// sum_k a_k N_m(2^level s - k), the definition (15) summed term by term.
double direct_sum(int m, const CoefficientRow& row, double s) {
    double sum = 0;
    for (int k = row.first; k <= row.last(); ++k)
        sum += row.a[k - row.first] * bspline(m, std::ldexp(s, row.level) - k);
    return sum;
}

double direct_sum(int m, const CoefficientGrid& g, double s, double t) {
    double sum = 0;
    for (int k = g.first_k; k < g.first_k + g.n_k; ++k)
        for (int l = g.first_l; l < g.first_l + g.n_l; ++l)
            sum += g(k, l) * bspline(m, std::ldexp(s, g.level) - k) *
                   bspline(m, std::ldexp(t, g.level) - l);
    return sum;
}

CoefficientRow random_row(std::mt19937& rng, int level, int first, int n) {
    std::uniform_real_distribution<double> coef(-1, 1);
    CoefficientRow row;
    row.level = level;
    row.first = first;
    for (int i = 0; i < n; ++i) row.a.push_back(coef(rng));
    return row;
}

}  // namespace

TEST_CASE("bspline: integer translates sum to one", "[bspline]") {
    const unsigned seed = 101;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-20, 20);
    for (int m = 1; m <= 5; ++m)
        for (int trial = 0; trial < 200; ++trial) {
            const double x = u(rng);
            CAPTURE(m, x);
            double sum = 0;
            for (int k = static_cast<int>(std::floor(x)) - m - 1; k <= std::floor(x) + 1; ++k)
                sum += bspline(m, x - k);
            // Exact in theory; m non-negative terms summing to 1, each rounded: a few ulps.
            CHECK(sum == Approx(1.0).epsilon(0).margin(1e-14));
        }
}

TEST_CASE("bspline: non-negative, symmetric about m/2, zero outside its support", "[bspline]") {
    const unsigned seed = 102;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m) {
        std::uniform_real_distribution<double> u(-1.0, m + 1.0);
        for (int trial = 0; trial < 300; ++trial) {
            const double x = u(rng);
            CAPTURE(m, x);
            const double v = bspline(m, x);
            CHECK(v >= 0);
            if (x < 0 || x >= m) CHECK(v == 0);
            // N_m(x) = N_m(m - x); for m = 1 only away from the knots (N_1 is [0, 1)-indicator).
            // The two evaluations round differently: values are <= 1, so 1e-15 absolute.
            if (m > 1 || (x != 0 && x != 1)) CHECK(bspline(m, m - x) == Approx(v).margin(1e-15));
        }
        CHECK(bspline(m, m) == 0);
        CHECK(bspline(m, -1e-300) == 0);
        CHECK(bspline(m, std::nextafter(double(m), 0.0)) >= 0);
    }
}

TEST_CASE("bspline: integral of N_m is one", "[bspline]") {
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        // N_m is a polynomial of degree m - 1 on each unit interval: m-point Gauss-Legendre is
        // exact there (degree <= 2m - 1), so only rounding is left.
        const GaussLegendre rule = gauss_legendre(m);
        double integral = 0;
        for (int i = 0; i < m; ++i)
            integral += integrate_1d([&](double x) { return bspline(m, x); }, i, i + 1.0, rule);
        CHECK(integral == Approx(1.0).epsilon(0).margin(1e-14));
    }
}

TEST_CASE("bspline: agrees with the truncated-power formula", "[bspline]") {
    const unsigned seed = 103;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 6; ++m) {
        std::uniform_real_distribution<double> u(0.0, double(m));
        for (int trial = 0; trial < 300; ++trial) {
            const double x = u(rng);
            CAPTURE(m, x);
            // The truncated-power sum cancels terms up to m^{m-1}/(m-1)! (26 for m = 5, 54 for
            // m = 6) in long double (eps 1.1e-19): reference error < 1e-16. Cox-de Boor is stable
            // (convex combinations): a few ulps of values <= 1. So 1e-15 absolute.
            CHECK(bspline(m, x) == Approx(truncated_power_bspline(m, x)).margin(1e-15));
        }
    }
}

TEST_CASE("bspline: known values N_m(k) and omega_{m,k}", "[bspline]") {
    // N_2(1) = 1; N_3(1) = N_3(2) = 1/2, N_3(3/2) = 3/4; N_4: 1/6, 2/3, 1/6; N_5: 1/24, 11/24.
    CHECK(bspline(2, 1.0) == 1.0);
    CHECK(bspline(3, 1.5) == Approx(0.75).epsilon(1e-15));
    const std::vector<std::vector<double>> omega_expected = {
        {1, 0},
        {0, 1, 0},
        {0, 0.5, 0.5, 0},
        {0, 1.0 / 6, 4.0 / 6, 1.0 / 6, 0},
        {0, 1.0 / 24, 11.0 / 24, 11.0 / 24, 1.0 / 24, 0}};
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        const std::vector<double> omega = integer_values(m);
        REQUIRE(omega.size() == size_t(m + 1));
        double sum = 0;
        for (int k = 0; k <= m; ++k) {
            CAPTURE(k);
            CHECK(omega[k] == Approx(omega_expected[m - 1][k]).margin(1e-15));  // rounding only
            sum += omega[k];
        }
        CHECK(sum == Approx(1.0).margin(1e-15));
    }
}

TEST_CASE("bspline: bspline_values agrees with bspline", "[bspline]") {
    const unsigned seed = 104;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-50, 50);
    for (int m = 1; m <= 5; ++m)
        for (int trial = 0; trial < 300; ++trial) {
            // Integers too: the hot-loop form must agree on knots, where floor() decides.
            const double x = (trial % 10 == 0) ? std::round(u(rng)) : u(rng);
            CAPTURE(m, x);
            double values[8];
            const int first = bspline_values(m, x, values);
            CHECK(first == static_cast<int>(std::floor(x)) - m + 1);
            for (int i = 0; i < m; ++i) {
                CAPTURE(i);
                // Same recursion on the same t = x - floor(x) but different argument x - k in
                // bspline(): identical up to the rounding of x - k. 1e-15 absolute.
                CHECK(values[i] == Approx(bspline(m, x - (first + i))).margin(1e-15));
            }
            // Every translate outside the m returned ones vanishes at x.
            CHECK(bspline(m, x - (first - 1)) == 0);
            CHECK(bspline(m, x - (first + m)) == 0);
        }
}

TEST_CASE("bspline: derivatives agree with finite differences", "[bspline]") {
    const unsigned seed = 105;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    const double h = 1e-4;
    for (int m = 2; m <= 5; ++m) {
        std::uniform_real_distribution<double> u(-0.5, m + 0.5);
        for (int r = 1; r <= m - 1; ++r)
            for (int trial = 0; trial < 100; ++trial) {
                const double x = u(rng);
                // Stay 2h away from the knots so x +- h lies in one polynomial piece (the r-th
                // derivative is discontinuous at knots for r = m - 1).
                if (std::fabs(x - std::round(x)) < 2 * h) continue;
                CAPTURE(m, r, x);
                const double fd =
                    (bspline_derivative(m, r - 1, x + h) - bspline_derivative(m, r - 1, x - h)) /
                    (2 * h);
                // Central difference of a polynomial piece: error h^2/6 max|N_m^{(r+2)}| with
                // |N_m^{(q)}| <= 2^q, so <= 1e-8 * 128 / 6 ~ 2e-7; rounding 2^r eps / h ~ 4e-11.
                CHECK(bspline_derivative(m, r, x) == Approx(fd).margin(3e-7));
            }
    }
}

TEST_CASE("bspline: N_m' = N_{m-1}(x) - N_{m-1}(x - 1)", "[bspline]") {
    const unsigned seed = 106;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 2; m <= 5; ++m) {
        std::uniform_real_distribution<double> u(-1.0, m + 1.0);
        for (int trial = 0; trial < 200; ++trial) {
            const double x = u(rng);
            CAPTURE(m, x);
            CHECK(bspline_derivative(m, 1, x) ==
                  Approx(bspline(m - 1, x) - bspline(m - 1, x - 1)).margin(1e-15));
            CHECK(bspline_derivative(m, 0, x) == bspline(m, x));
        }
        // The derivative of a compactly supported function integrates to zero; exact per piece.
        const GaussLegendre rule = gauss_legendre(m);
        for (int r = 1; r <= m - 1; ++r) {
            double integral = 0;
            for (int i = 0; i < m; ++i)
                integral += integrate_1d([&](double x) { return bspline_derivative(m, r, x); }, i,
                                         i + 1.0, rule);
            CAPTURE(m, r);
            CHECK(integral == Approx(0.0).margin(1e-13));  // terms up to 2^r, rounding only
        }
    }
}

TEST_CASE("bspline: two-scale relation (14)", "[bspline]") {
    const unsigned seed = 107;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        const std::vector<double> p = two_scale_mask(m);
        REQUIRE(p.size() == size_t(m + 1));
        // p_{m,k} = 2^{1-m} binom(m, k): symmetric, sums to 2, even and odd parts sum to 1 each
        // (which is what makes refinement preserve the partition of unity).
        double sum_even = 0, sum_odd = 0;
        for (int k = 0; k <= m; ++k) {
            CHECK(p[k] == p[m - k]);
            CHECK(p[k] > 0);
            (k % 2 ? sum_odd : sum_even) += p[k];
        }
        CHECK(sum_even == Approx(1.0).margin(1e-15));
        CHECK(sum_odd == Approx(1.0).margin(1e-15));
        std::uniform_real_distribution<double> u(-1.0, m + 1.0);
        for (int trial = 0; trial < 200; ++trial) {
            const double x = u(rng);
            CAPTURE(x);
            double sum = 0;
            for (int k = 0; k <= m; ++k) sum += p[k] * bspline(m, 2 * x - k);
            // A positive combination of values <= 1 with weights summing to 2: a few ulps.
            CHECK(bspline(m, x) == Approx(sum).margin(1e-15));
        }
    }
}

TEST_CASE("bspline: refinement (17) then evaluation equals direct evaluation", "[bspline]") {
    const unsigned seed = 108;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> first_dist(-6, 6), size_dist(1, 9);
    for (int m = 1; m <= 5; ++m)
        for (int trial = 0; trial < 20; ++trial) {
            const int level = trial % 4;
            const CoefficientRow coarse = random_row(rng, level, first_dist(rng), size_dist(rng));
            CAPTURE(m, coarse);
            // Refine three times; every stage must describe the same function everywhere on
            // the real line (refine keeps every fine coefficient the coarse row feeds).
            CoefficientRow fine = coarse;
            for (int step = 1; step <= 3; ++step) {
                fine = refine(m, fine);
                CAPTURE(step);
                REQUIRE(fine.level == coarse.level + step);
                const double lo = std::ldexp(coarse.first - 1.0, -coarse.level);
                const double hi = std::ldexp(coarse.last() + m + 1.0, -coarse.level);
                std::uniform_real_distribution<double> s_dist(lo, hi);
                for (int q = 0; q < 40; ++q) {
                    const double s = s_dist(rng);
                    CAPTURE(s);
                    // |a| <= 1 and the weights are a partition of unity at every level: the
                    // values are <= 1 in size and each refinement adds a few ulps. 1e-14.
                    CHECK(evaluate(m, fine, s) == Approx(direct_sum(m, coarse, s)).margin(1e-14));
                }
            }
            // Exact size of (17)'s output: 2 n + m - 1 coefficients from n, starting at 2 first.
            const CoefficientRow once = refine(m, coarse);
            CHECK(once.first == 2 * coarse.first);
            CHECK(once.a.size() == 2 * coarse.a.size() + m - 1);
        }
}

TEST_CASE("bspline: refinement (17) of a single coefficient is the mask", "[bspline]") {
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        CoefficientRow unit;
        unit.level = 2;
        unit.first = 3;
        unit.a = {1.0};
        const CoefficientRow fine = refine(m, unit);
        const std::vector<double> p = two_scale_mask(m);
        REQUIRE(fine.a.size() == p.size());
        CHECK(fine.first == 6);
        CHECK(fine.level == 3);
        for (size_t i = 0; i < p.size(); ++i) CHECK(fine.a[i] == p[i]);
    }
}

TEST_CASE("bspline: touching layout covers exactly the basis functions meeting the unit interval",
          "[bspline]") {
    for (int m = 1; m <= 5; ++m)
        for (int level = 0; level <= 4; ++level) {
            CAPTURE(m, level);
            const CoefficientRow row = touching_row(m, level, 2.5);
            CHECK(row.first == first_touching_index(m));
            CHECK(row.first == -(m - 1));
            CHECK(int(row.a.size()) == touching_count(m, level));
            CHECK(row.last() == (1 << level) - 1);
            CHECK(row.at(row.first - 1) == 0);
            CHECK(row.at(row.last() + 1) == 0);
            CHECK(row.at(row.first) == 2.5);
            // Support of N_m(2^level s - k) is [k, k + m] 2^-level: it meets the open (0, 1)
            // exactly for -(m-1) <= k <= 2^level - 1.
            const double scale = std::ldexp(1.0, level);
            for (int k = row.first - 2; k <= row.last() + 2; ++k) {
                const bool meets = (k + m) / scale > 0 && k / scale < 1;
                CHECK(meets == (k >= row.first && k <= row.last()));
            }
            // A constant row reproduces the constant on [0, 1] (partition of unity).
            for (double s : {0.0, 0.1, 0.5, 0.77, 1.0 - 1e-12})
                CHECK(evaluate(m, row, s) == Approx(2.5).margin(1e-14));
            const CoefficientGrid grid = touching_grid(m, level, -1.5);
            CHECK(grid.n_k == touching_count(m, level));
            CHECK(grid.n_l == grid.n_k);
            CHECK(grid.first_k == row.first);
            CHECK(evaluate(m, grid, 0.3, 0.9) == Approx(-1.5).margin(1e-14));
        }
}

TEST_CASE("bspline: refine_touching keeps the function on the unit interval", "[bspline]") {
    const unsigned seed = 109;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> coef(-1, 1), s_dist(0, 1);
    for (int m = 1; m <= 5; ++m)
        for (int level = 0; level <= 4; ++level) {
            CoefficientRow row = touching_row(m, level);
            for (double& a : row.a) a = coef(rng);
            CAPTURE(m, level, row);
            const CoefficientRow fine = refine_touching(m, row);
            CHECK(fine.level == level + 1);
            CHECK(fine.first == first_touching_index(m));
            CHECK(int(fine.a.size()) == touching_count(m, level + 1));
            for (int q = 0; q < 50; ++q) {
                const double s = q == 0 ? 0.0 : s_dist(rng);
                CAPTURE(s);
                CHECK(evaluate(m, fine, s) == Approx(direct_sum(m, row, s)).margin(1e-14));
            }
        }
}

TEST_CASE("bspline: 2D refinement (17) then evaluation equals direct evaluation", "[bspline]") {
    const unsigned seed = 110;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> coef(-1, 1), s_dist(0, 1);
    for (int m = 1; m <= 5; ++m)
        for (int level = 0; level <= 3; ++level) {
            CAPTURE(m, level);
            // A general grid (not the touching layout): offset and rectangular.
            CoefficientGrid g(level, -m + 1 + level, -1, 3 + level, 2 + 2 * level);
            for (double& a : g.a) a = coef(rng);
            const CoefficientGrid fine = refine(m, g);
            CHECK(fine.level == level + 1);
            CHECK(fine.first_k == 2 * g.first_k);
            CHECK(fine.first_l == 2 * g.first_l);
            CHECK(fine.n_k == 2 * g.n_k + m - 1);
            CHECK(fine.n_l == 2 * g.n_l + m - 1);
            const CoefficientGrid fine2 = refine(m, fine);
            // The touching layout on [0, 1]^2.
            CoefficientGrid t = touching_grid(m, level);
            for (double& a : t.a) a = coef(rng);
            const CoefficientGrid t_fine = refine_touching(m, t);
            CHECK(t_fine.level == level + 1);
            CHECK(t_fine.n_k == touching_count(m, level + 1));
            for (int q = 0; q < 40; ++q) {
                const double s = s_dist(rng), u = s_dist(rng);
                CAPTURE(s, u);
                // Values bounded by max|a| = 1 (tensor partition of unity); a few ulps per
                // refinement step and per axis. 1e-14.
                const double direct = direct_sum(m, g, s, u);
                CHECK(evaluate(m, g, s, u) == Approx(direct).margin(1e-14));
                CHECK(evaluate(m, fine, s, u) == Approx(direct).margin(1e-14));
                CHECK(evaluate(m, fine2, s, u) == Approx(direct).margin(1e-14));
                CHECK(evaluate(m, t_fine, s, u) == Approx(direct_sum(m, t, s, u)).margin(1e-14));
            }
        }
}

TEST_CASE("bspline: 2D refinement of a separable grid is the product of 1D refinements",
          "[bspline]") {
    const unsigned seed = 111;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        const CoefficientRow rs = random_row(rng, 1, -2, 5), rt = random_row(rng, 1, 0, 4);
        CoefficientGrid g(1, rs.first, rt.first, 5, 4);
        for (int k = rs.first; k <= rs.last(); ++k)
            for (int l = rt.first; l <= rt.last(); ++l) g(k, l) = rs.at(k) * rt.at(l);
        const CoefficientGrid fine = refine(m, g);
        const CoefficientRow fs = refine(m, rs), ft = refine(m, rt);
        REQUIRE(fine.n_k == int(fs.a.size()));
        REQUIRE(fine.n_l == int(ft.a.size()));
        for (int k = fs.first; k <= fs.last(); ++k)
            for (int l = ft.first; l <= ft.last(); ++l)
                CHECK(fine(k, l) == Approx(fs.at(k) * ft.at(l)).margin(1e-15));  // rounding
    }
}

TEST_CASE("bspline: dyadic evaluation (18) equals direct evaluation", "[bspline]") {
    const unsigned seed = 112;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> first_dist(-5, 5), size_dist(1, 8);
    for (int m = 1; m <= 5; ++m)
        for (int trial = 0; trial < 12; ++trial) {
            const CoefficientRow row = random_row(rng, trial % 3, first_dist(rng), size_dist(rng));
            for (int j1 = row.level; j1 <= row.level + 3; ++j1) {
                CAPTURE(m, row, j1);
                int first_i = 0;
                const std::vector<double> values = dyadic_values(m, row, j1, &first_i);
                REQUIRE(!values.empty());
                for (size_t idx = 0; idx < values.size(); ++idx) {
                    const int i = first_i + int(idx);
                    CAPTURE(i);
                    // Both sides are sums of <= m products with |a| <= 1 and weights forming a
                    // partition of unity, after <= 3 refinements: a few ulps. 1e-14.
                    CHECK(values[idx] ==
                          Approx(direct_sum(m, row, std::ldexp(i, -j1))).margin(1e-14));
                }
                // Every dyadic point where f can be non-zero is included: just outside, f = 0.
                CHECK(direct_sum(m, row, std::ldexp(first_i - 1, -j1)) == 0);
                CHECK(direct_sum(m, row, std::ldexp(first_i + int(values.size()), -j1)) == 0);
            }
        }
}
