// test/test_polynomial.cpp - the tensor polynomial of degree m-1 through m x m Gauss-Legendre
// samples and its resampling on sub-cells (paper section 5, "Projection"; math/polynomial.h).
//
// Reference: random tensor polynomials written out as explicit double sums, evaluated at the
// nodes of the parent cell and of its sub-cells.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/check.h"
#include "math/polynomial.h"

using namespace mbr;

namespace {

/// Random coefficients c[i * m + j] of x^i y^j, i, j < m, in [-1, 1].
std::vector<double> random_coefficients(std::mt19937& rng, int m) {
    std::uniform_real_distribution<double> coef(-1, 1);
    std::vector<double> c(size_t(m) * m);
    for (double& v : c) v = coef(rng);
    return c;
}

/// sum_{i,j} c[i m + j] x^i y^j term by term (no Horner, unlike TensorPolynomial).
double explicit_sum(int m, const std::vector<double>& c, double x, double y) {
    double sum = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) sum += c[size_t(i) * m + j] * std::pow(x, i) * std::pow(y, j);
    return sum;
}

/// samples[a m + b] = p(x_a, x_b) on the m-point Gauss-Legendre nodes of [-1, 1]^2.
std::vector<double> samples_of(int m, const std::vector<double>& c) {
    const GaussLegendre rule = gauss_legendre(m);
    std::vector<double> s(size_t(m) * m);
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) s[size_t(a) * m + b] = explicit_sum(m, c, rule.x[a], rule.x[b]);
    return s;
}

}  // namespace

TEST_CASE("polynomial: TensorPolynomial evaluates sum c_ij x^i y^j", "[polynomial]") {
    const unsigned seed = 401;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int m = 1; m <= 6; ++m) {
        TensorPolynomial p;
        p.m = m;
        p.c = random_coefficients(rng, m);
        for (int trial = 0; trial < 20; ++trial) {
            const double x = u(rng), y = u(rng);
            CAPTURE(m, x, y);
            // |x|, |y| <= 1 and |c| <= 1: m^2 terms of size <= 1, rounded. 1e-14.
            CHECK(p(x, y) == Approx(explicit_sum(m, p.c, x, y)).margin(1e-14));
        }
    }
}

TEST_CASE("polynomial: fit_tensor_polynomial reproduces polynomials of degree < m",
          "[polynomial]") {
    const unsigned seed = 402;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int m = 1; m <= 6; ++m)
        for (int trial = 0; trial < 10; ++trial) {
            CAPTURE(m, trial);
            const std::vector<double> c = random_coefficients(rng, m);
            const TensorPolynomial p = fit_tensor_polynomial(m, samples_of(m, c));
            REQUIRE(p.m == m);
            REQUIRE(p.c.size() == c.size());
            for (size_t i = 0; i < c.size(); ++i) {
                CAPTURE(i);
                // Two Vandermonde solves on Gauss-Legendre nodes; their condition number stays
                // below ~1e2 for m <= 6, so the coefficients come back to ~1e-13.
                CHECK(p.c[i] == Approx(c[i]).margin(1e-12));
            }
            for (int q = 0; q < 10; ++q) {
                const double x = u(rng), y = u(rng);
                CHECK(p(x, y) == Approx(explicit_sum(m, c, x, y)).margin(1e-12));
            }
        }
}

TEST_CASE("polynomial: the fit interpolates arbitrary samples", "[polynomial]") {
    const unsigned seed = 403;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-5, 5);
    for (int m = 1; m <= 6; ++m) {
        std::vector<double> samples(size_t(m) * m);
        for (double& s : samples) s = u(rng);
        const TensorPolynomial p = fit_tensor_polynomial(m, samples);
        const GaussLegendre rule = gauss_legendre(m);
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                CAPTURE(m, a, b);
                // Values up to 5 through two solves (see above): 1e-12.
                CHECK(p(rule.x[a], rule.x[b]) == Approx(samples[size_t(a) * m + b]).margin(1e-12));
            }
    }
    CHECK_THROWS_AS(fit_tensor_polynomial(3, std::vector<double>(8)), CheckFailure);
}

TEST_CASE("polynomial: lagrange_matrix rows sum to one and reproduce degree < m", "[polynomial]") {
    const unsigned seed = 404;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int m = 1; m <= 8; ++m) {
        const GaussLegendre rule = gauss_legendre(m);
        std::vector<double> points;
        for (int p = 0; p < 12; ++p) points.push_back(u(rng));
        points.push_back(-1);
        points.push_back(1);
        const std::vector<double> L = lagrange_matrix(rule, points);
        REQUIRE(L.size() == points.size() * m);
        for (size_t p = 0; p < points.size(); ++p) {
            CAPTURE(m, points[p]);
            double row = 0;
            for (int a = 0; a < m; ++a) row += L[p * m + a];
            // Lebesgue constant of m <= 8 Gauss-Legendre nodes on [-1, 1] is below 4: sums of
            // m terms of that size. 1e-14.
            CHECK(row == Approx(1.0).margin(1e-14));
            for (int k = 1; k < m; ++k) {
                double v = 0;
                for (int a = 0; a < m; ++a) v += L[p * m + a] * std::pow(rule.x[a], k);
                CHECK(v == Approx(std::pow(points[p], k)).margin(1e-14));
            }
        }
        // At the nodes themselves the matrix is the identity (exactly: each factor is 0 or 1).
        const std::vector<double> I = lagrange_matrix(rule, rule.x);
        for (int p = 0; p < m; ++p)
            for (int a = 0; a < m; ++a) CHECK(I[size_t(p) * m + a] == (p == a ? 1.0 : 0.0));
    }
}

TEST_CASE("polynomial: subcell_resample_matrix + resample reproduce degree < m on sub-cells",
          "[polynomial]") {
    const unsigned seed = 405;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 6; ++m) {
        const GaussLegendre rule = gauss_legendre(m);
        const std::vector<double> c = random_coefficients(rng, m);
        const std::vector<double> parent = samples_of(m, c);
        for (int levels = 0; levels <= 3; ++levels) {
            const int n_sub = 1 << levels;
            std::vector<std::vector<double>> R(n_sub);
            for (int i = 0; i < n_sub; ++i) {
                R[i] = subcell_resample_matrix(rule, levels, i);
                REQUIRE(R[i].size() == size_t(m) * m);
                for (int p = 0; p < m; ++p) {
                    double row = 0;
                    for (int a = 0; a < m; ++a) row += R[i][size_t(p) * m + a];
                    CHECK(row == Approx(1.0).margin(1e-14));  // see the Lagrange test
                }
            }
            for (int ix = 0; ix < n_sub; ++ix)
                for (int iy = 0; iy < n_sub; ++iy) {
                    CAPTURE(m, levels, ix, iy);
                    std::vector<double> out(size_t(m) * m);
                    resample(m, parent.data(), R[ix].data(), R[iy].data(), out.data());
                    // Sub-cell [x0, x0 + 2/n] x [y0, y0 + 2/n] of the reference square.
                    const double x0 = -1 + 2.0 * ix / n_sub, y0 = -1 + 2.0 * iy / n_sub;
                    for (int p = 0; p < m; ++p)
                        for (int q = 0; q < m; ++q) {
                            const double x = x0 + (rule.x[p] + 1) / n_sub;
                            const double y = y0 + (rule.x[q] + 1) / n_sub;
                            // Two Lagrange interpolations (Lebesgue constant < 3 each) of values
                            // up to m^2: 1e-13.
                            CHECK(out[size_t(p) * m + q] ==
                                  Approx(explicit_sum(m, c, x, y)).margin(1e-13));
                        }
                }
        }
        // Level 0 is the identity (to rounding of -1 + (x + 1)).
        const std::vector<double> R0 = subcell_resample_matrix(rule, 0, 0);
        for (int p = 0; p < m; ++p)
            for (int a = 0; a < m; ++a)
                CHECK(R0[size_t(p) * m + a] == Approx(p == a ? 1.0 : 0.0).margin(1e-14));
        CHECK_THROWS_AS(subcell_resample_matrix(rule, 2, 4), CheckFailure);
        CHECK_THROWS_AS(subcell_resample_matrix(rule, 2, -1), CheckFailure);
    }
}

TEST_CASE("polynomial: resampling twice to level 1 equals resampling once to level 2",
          "[polynomial]") {
    // Sub-cell (1, 2) at level 2 is sub-cell (0, 1) of the level-1 sub-cell (0, 1): the
    // projection stage may reach the fulcrum's scale in steps or at once.
    const unsigned seed = 406;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int m = 1; m <= 6; ++m) {
        CAPTURE(m);
        const GaussLegendre rule = gauss_legendre(m);
        std::vector<double> samples(size_t(m) * m);  // arbitrary data: both are the same
        for (double& s : samples) s = u(rng);        // interpolant, resampled
        const std::vector<double> R10 = subcell_resample_matrix(rule, 1, 0);
        const std::vector<double> R11 = subcell_resample_matrix(rule, 1, 1);
        const std::vector<double> R21 = subcell_resample_matrix(rule, 2, 1);
        const std::vector<double> R22 = subcell_resample_matrix(rule, 2, 2);
        std::vector<double> mid(size_t(m) * m), twice(size_t(m) * m), once(size_t(m) * m);
        resample(m, samples.data(), R10.data(), R11.data(), mid.data());
        resample(m, mid.data(), R11.data(), R10.data(), twice.data());
        resample(m, samples.data(), R21.data(), R22.data(), once.data());
        for (size_t i = 0; i < once.size(); ++i)
            CHECK(twice[i] == Approx(once[i]).margin(1e-13));  // four vs two interpolations
    }
}

TEST_CASE("polynomial: sub-cell quadrature of the resampled values gives the cell integral",
          "[polynomial]") {
    // What the projection stage relies on: integrating the resampled samples with each sub-cell's
    // m x m rule and summing over sub-cells is the integral of the fitted polynomial over the
    // parent cell (exact: degree m - 1 < 2m - 1 per variable).
    const unsigned seed = 407;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 6; ++m) {
        const GaussLegendre rule = gauss_legendre(m);
        const std::vector<double> c = random_coefficients(rng, m);
        const std::vector<double> parent = samples_of(m, c);
        double whole = 0;  // int over [-1,1]^2 of x^i y^j = (2 or 0 / (i+1)) (2 or 0 / (j+1))
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                whole += c[size_t(i) * m + j] * (i % 2 ? 0.0 : 2.0 / (i + 1)) *
                         (j % 2 ? 0.0 : 2.0 / (j + 1));
        for (int levels = 1; levels <= 3; ++levels) {
            CAPTURE(m, levels);
            const int n_sub = 1 << levels;
            const double jacobian = 1.0 / (double(n_sub) * n_sub);  // sub-cell area / 4
            double sum = 0;
            for (int ix = 0; ix < n_sub; ++ix)
                for (int iy = 0; iy < n_sub; ++iy) {
                    const std::vector<double> Rx = subcell_resample_matrix(rule, levels, ix);
                    const std::vector<double> Ry = subcell_resample_matrix(rule, levels, iy);
                    std::vector<double> out(size_t(m) * m);
                    resample(m, parent.data(), Rx.data(), Ry.data(), out.data());
                    for (int p = 0; p < m; ++p)
                        for (int q = 0; q < m; ++q)
                            sum += rule.w[p] * rule.w[q] * out[size_t(p) * m + q] * jacobian;
                }
            CHECK(sum == Approx(whole).margin(1e-13));  // values <= m^2, area 4: rounding
        }
    }
}
