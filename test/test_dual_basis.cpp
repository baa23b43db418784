// test/test_dual_basis.cpp - the Gram sequence, mu_{m;0,l} by the appendix's growing inverses,
// DN_m and its table, and the truncation radii (paper section 3 eq. (13), Figure 1, section 5
// "Projection", Figure 3, appendix eqs. (30)-(32), Table 3; math/dual_basis.h).
//
// Independent references: Gauss-Legendre integrals on unit intervals (exact: every integrand
// here is a polynomial of degree <= 2m - 2 between integer knots); the closed form for m = 2;
// the decay rate from the roots of the Gram symbol (Euler-Frobenius polynomial); dense sampling
// of the table for the radii.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/bspline.h"
#include "math/dual_basis.h"
#include "math/gauss_legendre.h"
#include "test/report.h"

using namespace mbr;

namespace {

/// int f over [a, b] (a, b integers) by m-point Gauss-Legendre on each unit interval: exact for
/// piecewise polynomials of degree <= 2m - 1 with integer knots.
template <class F>
double integrate_pieces(F&& f, int a, int b, const GaussLegendre& rule) {
    double sum = 0;
    for (int i = a; i < b; ++i) sum += integrate_1d(f, double(i), double(i + 1), rule);
    return sum;
}

/// mu_{m;0,l} far beyond any table (l = 0..150), the reference for truncation errors.
std::vector<double> long_mu(int m) {
    return dual_coefficients(m, 150, 1e-17).mu;
}

/// Root of the Gram symbol sum_n gamma_|n| z^n in (-1, 0) closest to -1 (the Euler-Frobenius
/// polynomial has only simple negative roots), by a scan and bisection.
double dominant_root(const std::vector<double>& gamma) {
    const int m = static_cast<int>(gamma.size());
    auto symbol = [&](double z) {
        double s = gamma[0];
        for (int n = 1; n < m; ++n) s += gamma[n] * (std::pow(z, n) + std::pow(z, -n));
        return s;
    };
    const int steps = 20000;
    double z_prev = -1 + 1e-9, f_prev = symbol(z_prev);
    for (int i = 1; i <= steps; ++i) {
        const double z = -1 + 1e-9 + i * (1 - 2e-9) / steps;
        const double f = symbol(z);
        if ((f > 0) != (f_prev > 0)) {
            double a = z_prev, b = z;
            for (int it = 0; it < 200; ++it) {
                const double c = 0.5 * (a + b);
                if ((symbol(c) > 0) == (symbol(a) > 0))
                    a = c;
                else
                    b = c;
            }
            return 0.5 * (a + b);
        }
        z_prev = z;
        f_prev = f;
    }
    return 0;
}

}  // namespace

TEST_CASE("dual: Gram sequence equals <N_m, N_m(. - n)> by quadrature", "[dual]") {
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        const std::vector<double> gamma = gram_sequence(m);
        REQUIRE(gamma.size() == size_t(m));
        const GaussLegendre rule = gauss_legendre(m);
        double total = 0;
        for (int n = 0; n <= m; ++n) {
            CAPTURE(n);
            const double q = integrate_pieces(
                [&](double x) { return bspline(m, x) * bspline(m, x - n); }, 0, m + n, rule);
            const double g = n < m ? gamma[n] : 0.0;  // gamma_n = 0 for |n| >= m
            CHECK(g == Approx(q).margin(1e-15));      // both exact up to rounding of values < 1
            total += (n == 0 ? 1 : 2) * g;
        }
        // sum_n gamma_n = <N_m, sum_n N_m(. - n)> = int N_m = 1.
        CHECK(total == Approx(1.0).margin(1e-15));
    }
}

TEST_CASE("dual: mu for m = 3 equals the paper's Table 3 at six decimals", "[dual][paper]") {
    constexpr double paper_mu3[19] = {2.842171,  -1.321729, 0.573326,  -0.247042, 0.106378,
                                      -0.045804, 0.019722,  -0.008492, 0.003656,  -0.001574,
                                      0.000678,  -0.000292, 0.000126,  -0.000054, 0.000023,
                                      -0.000010, 0.000004,  -0.000002, 0.000001};
    // The appendix's procedure with the paper's N = 18 (and a tolerance far below the printed
    // precision), and the table's long central row: both must round to the printed values.
    const DualCoefficients dc = dual_coefficients(3, 18, 1e-10);
    const DualTable table(3);
    REQUIRE(dc.mu.size() == 19);
    CHECK(dc.last_change < 1e-10);
    CHECK(dc.n_matrices == dc.final_half_width - 18 + 1);
    for (int l = 0; l <= 18; ++l) {
        CAPTURE(l, dc.mu[l], paper_mu3[l]);
        // Printed to six decimals: rounding the computed value must give the printed digits.
        CHECK(std::round(dc.mu[l] * 1e6) == Approx(paper_mu3[l] * 1e6).margin(1e-6));
        CHECK(std::round(table.mu()[l] * 1e6) == Approx(paper_mu3[l] * 1e6).margin(1e-6));
        // And within half a unit of the last printed place.
        CHECK(std::fabs(dc.mu[l] - paper_mu3[l]) <= 5e-7);
    }
}

TEST_CASE("dual: growing inverses converge to the bi-infinite central row", "[dual]") {
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const std::vector<double> mu_long = long_mu(m);
        for (int N : {4, 10, 18, 30})
            for (double eps : {1e-6, 1e-10, 1e-14}) {
                CAPTURE(N, eps);
                const DualCoefficients dc = dual_coefficients(m, N, eps);
                REQUIRE(dc.mu.size() == size_t(N + 1));
                CHECK(dc.m == m);
                CHECK(dc.final_half_width >= N + 1);
                CHECK(dc.n_matrices == dc.final_half_width - N + 1);
                CHECK(dc.last_change < eps);
                for (int l = 0; l <= N; ++l) {
                    CAPTURE(l);
                    // Successive sections differ by a factor |lambda|^2 < 0.37 per step, so the
                    // distance to the limit is below change / (1 - 0.37) < 2 eps; plus rounding.
                    CHECK(dc.mu[l] == Approx(mu_long[l]).margin(2 * eps + 1e-15));
                }
            }
    }
}

TEST_CASE("dual: m = 2 has the closed form mu_l = sqrt(3) (sqrt(3) - 2)^|l|", "[dual]") {
    // For the tridiagonal Gram matrix [1/6, 2/3, 1/6], the bi-infinite inverse is
    // z^|l| / sqrt(a^2 - 4 b^2) with z = sqrt(3) - 2.
    const DualTable table(2);
    const double z = std::sqrt(3.0) - 2;
    for (size_t l = 0; l < table.mu().size(); ++l) {
        CAPTURE(l);
        // Relative accuracy of the solve ~1e-16 near the centre, absolute ~1e-16 in the tail.
        CHECK(table.mu()[l] ==
              Approx(std::sqrt(3.0) * std::pow(z, double(l))).epsilon(1e-13).margin(1e-16));
    }
}

TEST_CASE("dual: mu_l decays at the rate of the Gram symbol's dominant root", "[dual]") {
    // mu_l ~ C lambda^|l| where lambda is the root of the Euler-Frobenius polynomial in (-1, 0)
    // nearest -1; DESIGN.md quotes 0.535 per cell for m = 4.
    const double expected_lambda[] = {
        0, 0, std::sqrt(3.0) - 2, -0.4305753471, -0.5352804308, -0.6079973892};
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const double lambda = dominant_root(gram_sequence(m));
        CHECK(lambda == Approx(expected_lambda[m]).margin(1e-9));  // printed to 10 decimals
        const DualTable table(m);
        const std::vector<double>& mu = table.mu();
        // At l = 20 the next root contributes (lambda_2 / lambda)^20 < (0.33)^20 ~ 3e-10, and
        // mu_20 >= 1e-5 carries a relative rounding error ~1e-11: 1e-8 is safe.
        CHECK(mu[21] / mu[20] == Approx(lambda).margin(1e-8));
        // Alternating signs throughout the table.
        for (size_t l = 1; l < mu.size(); ++l) CHECK(mu[l] * mu[l - 1] < 0);
    }
}

TEST_CASE("dual: DualTable agrees with the direct sum (32) within error_bound()", "[dual]") {
    const unsigned seed = 301;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 2; m <= 5; ++m)
        for (double tail_eps : {1e-16, 1e-10, 1e-6}) {
            CAPTURE(m, tail_eps);
            const DualTable table(m, tail_eps);
            const std::vector<double> mu_long = long_mu(m);
            CHECK(table.order() == m);
            CHECK(table.fulcrum() == 0.5 * m);
            CHECK(table.error_bound() >= 0);
            CHECK(table.error_bound() <= 2 * tail_eps * mu_long[0]);
            const double H = table.half_width();
            std::uniform_real_distribution<double> u(table.fulcrum() - H - 1,
                                                     table.fulcrum() + H + 1);
            double worst = 0;
            for (int trial = 0; trial < 400; ++trial) {
                const double x = (trial < 40) ? std::round(u(rng)) : u(rng);  // knots too
                CAPTURE(x);
                const double reference = dual_basis(m, mu_long, x);
                const double diff = std::fabs(table(x) - reference);
                worst = std::max(worst, diff);
                // error_bound() covers the dropped mu_l; the two evaluations (power-basis pieces
                // vs. Cox-de Boor sums of up to m terms of size <= mu_0) add a few ulps of
                // mu_0 < 3: 4e-15.
                CHECK(diff <= table.error_bound() + 4e-15);
            }
            // Beyond the table, DN_m is below the error bound too (and the table returns 0).
            for (double dx : {H + 0.25, H + 3.5}) {
                CHECK(table(table.fulcrum() + dx) == 0);
                CHECK(table(table.fulcrum() - dx) == 0);
                CHECK(std::fabs(dual_basis(m, mu_long, table.fulcrum() + dx)) <=
                      table.error_bound() + 1e-16);
            }
            mbr::test::report() << "dual: m = " << m << ", tail_eps = " << tail_eps << ": "
                                << table.mu().size() - 1 << " coefficients, half width " << H
                                << ", error_bound " << table.error_bound() << ", worst table error "
                                << worst << '\n';
        }
}

TEST_CASE("dual: DN_m is symmetric about m/2 and largest there", "[dual]") {
    const unsigned seed = 302;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const DualTable table(m);
        const double c = table.fulcrum();
        // The maximum is at the fulcrum: DN_3(1.5) = 1.8012, DN_4(2) = 2.2795 (Figure 1).
        CHECK(table.max_abs() == Approx(std::fabs(table(c))).epsilon(1e-15));
        CHECK(table(c) > 0);
        std::uniform_real_distribution<double> u(0, table.half_width() + 1);
        for (int trial = 0; trial < 300; ++trial) {
            const double x = u(rng);
            CAPTURE(x);
            // The two sides are different pieces, each rounded on its own: a few ulps of max.
            CHECK(table(c + x) == Approx(table(c - x)).margin(2e-15));
            CHECK(std::fabs(table(c + x)) <= table.max_abs() * (1 + 1e-15));
        }
    }
    CHECK(DualTable(3).max_abs() == Approx(1.8011958233).margin(1e-10));
    CHECK(DualTable(4).max_abs() == Approx(2.2794744243).margin(1e-10));
}

TEST_CASE("dual: biorthogonality <N_m(. - k), DN_m(. - l)> = delta_kl", "[dual]") {
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const DualTable table(m);
        const GaussLegendre rule = gauss_legendre(m);
        double worst = 0;
        // <N_m(. - k), DN_m> over the support [k, k + m] of N_m(. - k): a polynomial of degree
        // 2m - 2 on each unit interval, so m-point Gauss-Legendre is exact.
        const int K = static_cast<int>(table.half_width()) + m;
        for (int k = -K; k <= K; ++k) {
            CAPTURE(k);
            const double ip = integrate_pieces(
                [&](double x) { return bspline(m, x - k) * table(x); }, k, k + m, rule);
            worst = std::max(worst, std::fabs(ip - (k == 0 ? 1.0 : 0.0)));
            // Error: the table's dropped mu (error_bound, weighted by int N_m = 1) plus rounding
            // of m^2 products of size <= 3: 4e-15.
            CHECK(ip == Approx(k == 0 ? 1.0 : 0.0).margin(table.error_bound() + 4e-15));
        }
        mbr::test::report() << "dual: m = " << m << ", worst biorthogonality error " << worst
                            << '\n';
    }
}

TEST_CASE("dual: biorthogonality of the paper's N = 18 truncation is limited by its tail",
          "[dual]") {
    // With mu_l kept for |l| <= 18 only, <N_m(. - k), DN> = sum_{|l| <= 18} mu_l gamma_{k-l}; for
    // |k| <= 18 - (m-1) every needed term is present, beyond that the missing ones are bounded
    // by sum_{|l| > 18} |mu_l| gamma_{k-l} <= max_{|l| > 18} |mu_l| (the gamma sum to 1).
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const std::vector<double> mu18 = dual_coefficients(m, 18, 1e-13).mu;
        const std::vector<double> mu_long = long_mu(m);
        const double tail = std::fabs(mu_long[19]);
        const GaussLegendre rule = gauss_legendre(m);
        for (int k = -22; k <= 22; ++k) {
            CAPTURE(k);
            const double ip = integrate_pieces(
                [&](double x) { return bspline(m, x - k) * dual_basis(m, mu18, x); }, k, k + m,
                rule);
            const double expected = k == 0 ? 1.0 : 0.0;
            // mu18 agrees with the limit within 2e-13 (previous test's argument); m terms.
            if (std::abs(k) <= 18 - (m - 1))
                CHECK(ip == Approx(expected).margin(m * 2e-13 + 4e-15));
            else
                CHECK(ip == Approx(expected).margin(tail + m * 2e-13 + 4e-15));
        }
    }
}

TEST_CASE("dual: the translates of DN_m sum to one, and DN_m integrates to one", "[dual]") {
    // sum_l mu_l = 1 / sum_n gamma_n = 1 (the symbol at z = 1), hence
    // sum_k DN_m(x - k) = sum_l mu_l sum_k N_m(x - k - l) = 1 and int DN_m = sum_l mu_l = 1:
    // the dual of a partition of unity is one too, and the projection of a constant is that
    // constant (DESIGN.md section 2).
    const unsigned seed = 303;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 2; m <= 5; ++m) {
        CAPTURE(m);
        const DualTable table(m);
        const std::vector<double>& mu = table.mu();
        double sum_mu = mu[0];
        for (size_t l = 1; l < mu.size(); ++l) sum_mu += 2 * mu[l];
        // ~2L terms alternating in sign, largest mu_0 < 3: rounding 1e-15; truncation
        // (2L + 1) error_bound.
        CHECK(sum_mu == Approx(1.0).margin(1e-14));
        const int H = static_cast<int>(std::ceil(table.half_width()));
        std::uniform_real_distribution<double> u(-10, 10);
        for (int trial = 0; trial < 100; ++trial) {
            const double x = u(rng);
            CAPTURE(x);
            double sum = 0;
            for (int k = static_cast<int>(std::floor(x)) - H - m;
                 k <= static_cast<int>(std::ceil(x)) + H; ++k)
                sum += table(x - k);
            // ~2H + m terms of the table, each within error_bound, rounding of an alternating
            // sum with terms < 3: 1e-13 covers both.
            CHECK(sum == Approx(1.0).margin(1e-13));
        }
        const double c = table.fulcrum();
        const double integral = integrate_pieces(
            [&](double x) { return table(x); }, static_cast<int>(std::floor(c - H - 1)),
            static_cast<int>(std::ceil(c + H + 1)), gauss_legendre(m));
        CHECK(integral == Approx(1.0).margin(1e-14));
    }
}

TEST_CASE("dual: projection onto V_0 by (13) reproduces polynomials of degree < m", "[dual]") {
    // c_k = <f, DN_m(. - k)>, then sum_k c_k N_m(x - k) = f(x) for f of degree < m (f lies in
    // V_0 locally; DN_m decays exponentially, so the inner products converge).
    for (int m = 2; m <= 5; ++m) {
        const DualTable table(m);
        const GaussLegendre rule = gauss_legendre(m);
        const int H = static_cast<int>(std::ceil(table.half_width()));
        const double centre = 2.0;
        for (int p = 0; p < m; ++p) {
            CAPTURE(m, p);
            auto f = [&](double y) { return std::pow(y - centre, p); };
            // Every basis function that is non-zero on [0, 5].
            std::vector<double> c;
            const int k_first = -m, k_last = 5;
            for (int k = k_first; k <= k_last; ++k)
                c.push_back(integrate_pieces([&](double y) { return f(y) * table(y - k); },
                                             k - H - 1, k + m + H + 1, rule));
            // Error: each mu_l carries an absolute error up to error_bound (and rounding,
            // 2.3e-16), and c_k weights mu_l by about |f| at distance |l|, up to (H + m + 2)^p:
            // sum over |l| <= H + m + 2 gives 2 (H + m + 2)^{p+1} / (p + 1). Measured 10..1000
            // times below this bound (1.9e-8 for m = 5, degree 4).
            const double tol =
                (table.error_bound() + 2.3e-16) * 2 * std::pow(H + m + 2.0, p + 1) / (p + 1) +
                1e-14;
            double worst = 0;
            for (double x : {0.0, 0.4, 1.7, 2.0, 3.3, 4.99}) {
                double sum = 0;
                for (int k = k_first; k <= k_last; ++k) sum += c[k - k_first] * bspline(m, x - k);
                CAPTURE(x);
                CHECK(sum == Approx(f(x)).margin(tol));
                worst = std::max(worst, std::fabs(sum - f(x)));
            }
            mbr::test::report() << "dual: m = " << m << ", degree " << p << ": reproduction error "
                                << worst << " (tolerance " << tol << ")\n";
        }
    }
}

TEST_CASE("dual: truncation_radius bounds the support where |DN_m| > eps max|DN_m|", "[dual]") {
    const int S = 128;  // samples per cell
    for (int m = 2; m <= 5; ++m) {
        const DualTable table(m);
        const double c = table.fulcrum(), max_dn = table.max_abs();
        const int n = static_cast<int>(table.half_width() * S) + S;
        std::vector<double> v(n + 1);  // |DN_m(c + i / S)|, one side (symmetry tested above)
        for (int i = 0; i <= n; ++i) v[i] = std::fabs(table(c + double(i) / S));
        double previous = 0;
        for (double eps : {1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12}) {
            CAPTURE(m, eps);
            const double R = table.truncation_radius(eps);
            double tightest = 0;  // the largest sampled |x| with |DN| above the threshold
            for (int i = 0; i <= n; ++i)
                if (v[i] > eps * max_dn) tightest = double(i) / S;
            CAPTURE(R, tightest);
            // Every sampled point beyond R is below eps (relative).
            CHECK(R >= tightest);
            // Not much larger than needed: R lies on a 1/16 grid, and the test sees the true
            // boundary to within 1/S. Measured slack 0 .. 0.062.
            CHECK(R - tightest <= 1.0 / 16 + 1.0 / S);
            CHECK(R >= previous);  // smaller eps, larger radius
            previous = R;
        }
    }
}

TEST_CASE("dual: rhombus_radius contains every point where |DN DN| > eps max^2", "[dual]") {
    // DESIGN.md section 3 stage 6: the region where |DN_m(x) DN_m(y)| > eps max^2 (coordinates
    // from the fulcrum) is nearly the rhombus |x| + |y| <= r. Check containment on a dense grid
    // and that r is at most 3/16 of a cell above the tightest rhombus: the radius is built from
    // a 1/16 envelope in each coordinate (2/16) and the test samples at 1/S (2/S < 1/16).
    const int S = 64;
    for (int m = 2; m <= 5; ++m) {
        const DualTable table(m);
        const double c = table.fulcrum(), max_dn = table.max_abs();
        const int n = static_cast<int>(table.half_width() * S) + S;
        std::vector<double> v(n + 1), suffix_max(n + 2, 0.0);
        for (int i = 0; i <= n; ++i) v[i] = std::fabs(table(c + double(i) / S));
        for (int i = n; i >= 0; --i) suffix_max[i] = std::max(suffix_max[i + 1], v[i]);
        double previous = 0;
        for (double eps : {1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10}) {
            CAPTURE(m, eps);
            const double r = table.rhombus_radius(eps);
            const double threshold = eps * max_dn * max_dn;
            // Tightest rhombus over the grid (one quadrant suffices: DN_m is symmetric): for each
            // x, the largest y with v[x] v[y] > threshold, found on the non-increasing suffix max.
            double tightest = 0;
            for (int i = 0; i <= n; ++i) {
                if (v[i] * max_dn <= threshold) continue;
                const double need = threshold / v[i];
                int lo = 0, hi = n;  // largest j with suffix_max[j] > need
                while (lo < hi) {
                    const int mid = (lo + hi + 1) / 2;
                    if (suffix_max[mid] > need)
                        lo = mid;
                    else
                        hi = mid - 1;
                }
                tightest = std::max(tightest, double(i + lo) / S);
            }
            CAPTURE(r, tightest);
            CHECK(r >= tightest);
            CHECK(r - tightest <= 3.0 / 16);
            // On the axis the rhombus is the 1D region: r >= the 1D tight radius for eps.
            CHECK(r >= table.truncation_radius(eps) - 1.0 / 16);
            CHECK(r >= previous);  // smaller eps, larger rhombus
            previous = r;
            mbr::test::report() << "dual: m = " << m << ", eps = " << eps << ": rhombus radius "
                                << r << " (tightest sampled " << tightest << "), 1D radius "
                                << table.truncation_radius(eps) << '\n';
        }
    }
}

TEST_CASE("dual: eps_for_rhombus_radius inverts rhombus_radius", "[dual]") {
    for (int m = 2; m <= 5; ++m) {
        const DualTable table(m);
        for (double r : {4.0, 8.0, 12.0, 14.0, 20.0, 24.0}) {
            CAPTURE(m, r);
            const double eps = table.eps_for_rhombus_radius(r);
            CAPTURE(eps);
            REQUIRE(eps > 0);
            // The eps found is (to bisection accuracy) the smallest whose rhombus fits in r.
            CHECK(table.rhombus_radius(eps) <= r);
            CHECK(table.rhombus_radius(eps * 0.99) > r);
        }
        for (double eps : {1e-3, 1e-6, 1e-9}) {
            CAPTURE(m, eps);
            const double r = table.rhombus_radius(eps);
            const double back = table.eps_for_rhombus_radius(r);
            CHECK(back <= eps * (1 + 1e-12));
            CHECK(table.rhombus_radius(back) == r);
        }
    }
}
