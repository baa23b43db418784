// test/test_wavelet.cpp - one step of the semi-orthogonal decomposition f_j = f_{j-1} + g_{j-1}
// of eq. (11): the L2([0,1]) projection of a level-j spline onto level j-1 (math/wavelet.h),
// used to coarsen the shooter before the quadrature of (21) (section 6).
//
// The defining properties are checked, not the matrix: a function already in V_{j-1} is a fixed
// point; the residual f - coarsen(f) is orthogonal to every level-(j-1) basis function on [0,1]
// (inner products by Gauss-Legendre, exact on the level-j cells); hence Pythagoras and a norm
// that never grows.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/bspline.h"
#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/wavelet.h"

using namespace mbr;

namespace {

CoefficientRow random_touching_row(std::mt19937& rng, int m, int level) {
    std::uniform_real_distribution<double> coef(-1, 1);
    CoefficientRow row = touching_row(m, level);
    for (double& a : row.a) a = coef(rng);
    return row;
}

CoefficientGrid random_touching_grid(std::mt19937& rng, int m, int level) {
    std::uniform_real_distribution<double> coef(-1, 1);
    CoefficientGrid grid = touching_grid(m, level);
    for (double& a : grid.a) a = coef(rng);
    return grid;
}

/// int_0^1 f(s) g(s) ds for f, g piecewise polynomials of degree < m on the level-`level` cells:
/// m-point Gauss-Legendre per cell is exact (degree 2m - 2).
template <class F, class G>
double inner_product(int m, int level, F&& f, G&& g) {
    const GaussLegendre rule = gauss_legendre(m);
    const int cells = 1 << level;
    double sum = 0;
    for (int c = 0; c < cells; ++c)
        sum += integrate_1d([&](double s) { return f(s) * g(s); }, double(c) / cells,
                            double(c + 1) / cells, rule);
    return sum;
}

/// The 2D analogue over [0,1]^2 on the level-`level` cells (m x m points per cell, exact).
template <class F, class G>
double inner_product_2d(int m, int level, F&& f, G&& g) {
    const GaussLegendre rule = gauss_legendre(m);
    const int cells = 1 << level;
    double sum = 0;
    for (int i = 0; i < cells; ++i)
        for (int j = 0; j < cells; ++j)
            sum += integrate_2d([&](double s, double t) { return f(s, t) * g(s, t); },
                                Rect{double(i) / cells, double(i + 1) / cells, double(j) / cells,
                                     double(j + 1) / cells},
                                rule);
    return sum;
}

/// How far a coefficient of coarsen() may be off: the solve with the level-(j-1) Gram matrix on
/// [0,1] loses what its condition number costs. The first basis function N_m(2^{j-1} s + m - 1)
/// meets [0,1] only on one cell where it is below N_m(m - 1) = 1/(m-1)!, so its diagonal entry
/// is tiny (int_{m-1}^m N_m^2 = 1/((2m-1) ((m-1)!)^2): 1.9e-4 for m = 5) and the condition number
/// grows to ~1e4 (m = 5). Measured worst over j = 1..8: 2e-15 (m <= 3), 1.7e-13 (m = 4),
/// 3.2e-12 (m = 5), always in that first coefficient; the function values stay within 1e-13.
double coefficient_margin(int m) {
    return m <= 3 ? 1e-14 : (m == 4 ? 1e-12 : 1e-11);
}

/// The coarse row on the fine row's level and layout, to subtract coefficient-wise.
CoefficientRow difference(int m, const CoefficientRow& fine, const CoefficientRow& coarse) {
    CoefficientRow d = refine_touching(m, coarse);
    for (size_t i = 0; i < d.a.size(); ++i) d.a[i] = fine.a[i] - d.a[i];
    return d;
}

}  // namespace

TEST_CASE("wavelet: coarsen returns a level-(j-1) function unchanged", "[wavelet]") {
    const unsigned seed = 501;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m)
        for (int j = 1; j <= 6; ++j)
            for (int trial = 0; trial < 3; ++trial) {
                const CoefficientRow coarse = random_touching_row(rng, m, j - 1);
                const CoefficientRow fine = refine_touching(m, coarse);  // same function, level j
                CAPTURE(m, j, coarse);
                const CoefficientRow back = coarsen(m, fine);
                REQUIRE(back.level == j - 1);
                REQUIRE(back.first == coarse.first);
                REQUIRE(back.a.size() == coarse.a.size());
                for (size_t i = 0; i < back.a.size(); ++i) {
                    CAPTURE(i);
                    CHECK(back.a[i] == Approx(coarse.a[i]).margin(coefficient_margin(m)));
                }
                // As functions on [0,1] they agree to rounding (measured <= 1e-13 for m = 5).
                for (int q = 0; q <= 64; ++q) {
                    const double s = q / 64.0;
                    CAPTURE(s);
                    CHECK(evaluate(m, back, s) == Approx(evaluate(m, coarse, s)).margin(5e-13));
                }
            }
}

TEST_CASE("wavelet: the residual f - coarsen(f) is orthogonal to level j-1 on the unit interval",
          "[wavelet]") {
    const unsigned seed = 502;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m)
        for (int j = 1; j <= 5; ++j) {
            const CoefficientRow fine = random_touching_row(rng, m, j);
            const CoefficientRow coarse = coarsen(m, fine);
            CAPTURE(m, j, fine);
            auto residual = [&](double s) { return evaluate(m, fine, s) - evaluate(m, coarse, s); };
            for (int k = coarse.first; k <= coarse.last(); ++k) {
                CAPTURE(k);
                auto basis = [&](double s) { return bspline(m, std::ldexp(s, j - 1) - k); };
                const double ip = inner_product(m, j, residual, basis);
                // Exact quadrature; |f| <= 1, basis <= 1, integrals over at most m 2^{1-j}: only
                // rounding and the ~1e-13 of the solve remain.
                CHECK(ip == Approx(0.0).margin(1e-13));
            }
        }
}

TEST_CASE("wavelet: coarsening is an orthogonal projection (Pythagoras, norm never grows)",
          "[wavelet]") {
    const unsigned seed = 503;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m)
        for (int j = 1; j <= 5; ++j)
            for (int trial = 0; trial < 3; ++trial) {
                const CoefficientRow fine = random_touching_row(rng, m, j);
                const CoefficientRow coarse = coarsen(m, fine);
                const CoefficientRow detail = difference(m, fine, coarse);
                CAPTURE(m, j, fine);
                const double f2 = squared_norm(m, fine), c2 = squared_norm(m, coarse),
                             g2 = squared_norm(m, detail);
                // squared_norm against the independent quadrature of this file.
                auto f = [&](double s) { return evaluate(m, fine, s); };
                CHECK(f2 == Approx(inner_product(m, j, f, f)).epsilon(1e-14));
                // ||f||^2 = ||f_{j-1}||^2 + ||g_{j-1}||^2; values O(0.1..1), rounding 1e-14.
                CHECK(f2 == Approx(c2 + g2).margin(1e-13));
                CHECK(c2 <= f2 * (1 + 1e-14));
                CHECK(g2 >= 0);
                // Projecting twice changes nothing: coarsen(refine(coarsen(f))) = coarsen(f).
                const CoefficientRow again = coarsen(m, refine_touching(m, coarse));
                for (size_t i = 0; i < again.a.size(); ++i)
                    CHECK(again.a[i] == Approx(coarse.a[i]).margin(coefficient_margin(m)));
            }
}

TEST_CASE("wavelet: coarsening several levels keeps constants and linear functions", "[wavelet]") {
    // Polynomials of degree < m lie in every V_j on [0,1]: coarsening down to level 0 must keep
    // them (the touching coefficients of 1 are all 1; of s they are the Greville abscissae
    // (k + m/2) 2^-j for m >= 2).
    for (int m = 1; m <= 5; ++m) {
        CAPTURE(m);
        CoefficientRow row = touching_row(m, 5, 1.0);
        while (row.level > 0) {
            row = coarsen(m, row);
            for (double a : row.a) CHECK(a == Approx(1.0).margin(coefficient_margin(m)));
        }
        if (m < 2) continue;
        CoefficientRow lin = touching_row(m, 5);
        for (int k = lin.first; k <= lin.last(); ++k)
            lin.a[k - lin.first] = std::ldexp(k + 0.5 * m, -5);
        while (lin.level > 0) {
            lin = coarsen(m, lin);
            for (int k = lin.first; k <= lin.last(); ++k)
                CHECK(lin.a[k - lin.first] ==
                      Approx(std::ldexp(k + 0.5 * m, -lin.level)).margin(coefficient_margin(m)));
        }
    }
}

TEST_CASE("wavelet: coarsen rejects rows not in the touching layout", "[wavelet]") {
    CoefficientRow row = touching_row(3, 2, 1.0);
    row.first += 1;
    CHECK_THROWS_AS(coarsen(3, row), CheckFailure);
    CHECK_THROWS_AS(coarsen(3, touching_row(3, 0, 1.0)), CheckFailure);  // nothing below level 0
}

TEST_CASE("wavelet: 2D coarsen returns a level-(j-1) grid unchanged", "[wavelet]") {
    const unsigned seed = 504;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m)
        for (int j = 1; j <= 4; ++j) {
            const CoefficientGrid coarse = random_touching_grid(rng, m, j - 1);
            const CoefficientGrid fine = refine_touching(m, coarse);
            CAPTURE(m, j);
            const CoefficientGrid back = coarsen(m, fine);
            REQUIRE(back.level == j - 1);
            REQUIRE(back.n_k == coarse.n_k);
            REQUIRE(back.n_l == coarse.n_l);
            REQUIRE(back.first_k == coarse.first_k);
            for (size_t i = 0; i < back.a.size(); ++i) {
                CAPTURE(i);
                // Two 1D solves, each within coefficient_margin of coefficients <= 1 in size
                // times a row sum of the 1D projection (<= 2): twice the 1D margin, doubled.
                CHECK(back.a[i] == Approx(coarse.a[i]).margin(4 * coefficient_margin(m)));
            }
        }
}

TEST_CASE("wavelet: 2D coarsen is the tensor product of 1D coarsens", "[wavelet]") {
    const unsigned seed = 505;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 5; ++m)
        for (int j = 1; j <= 4; ++j) {
            CAPTURE(m, j);
            const CoefficientRow rs = random_touching_row(rng, m, j),
                                 rt = random_touching_row(rng, m, j);
            CoefficientGrid g = touching_grid(m, j);
            for (int k = rs.first; k <= rs.last(); ++k)
                for (int l = rt.first; l <= rt.last(); ++l) g(k, l) = rs.at(k) * rt.at(l);
            const CoefficientGrid cg = coarsen(m, g);
            const CoefficientRow cs = coarsen(m, rs), ct = coarsen(m, rt);
            for (int k = cs.first; k <= cs.last(); ++k)
                for (int l = ct.first; l <= ct.last(); ++l)
                    CHECK(cg(k, l) == Approx(cs.at(k) * ct.at(l)).margin(1e-13));  // rounding
        }
}

TEST_CASE("wavelet: 2D residual is orthogonal to level j-1 on the unit square and the norm drops",
          "[wavelet]") {
    const unsigned seed = 506;
    CAPTURE(seed);
    std::mt19937 rng(seed);
    for (int m = 1; m <= 4; ++m)
        for (int j = 1; j <= 3; ++j) {
            const CoefficientGrid fine = random_touching_grid(rng, m, j);
            const CoefficientGrid coarse = coarsen(m, fine);
            CAPTURE(m, j);
            auto f = [&](double s, double t) { return evaluate(m, fine, s, t); };
            auto c = [&](double s, double t) { return evaluate(m, coarse, s, t); };
            auto residual = [&](double s, double t) { return f(s, t) - c(s, t); };
            for (int k = coarse.first_k; k < coarse.first_k + coarse.n_k; ++k)
                for (int l = coarse.first_l; l < coarse.first_l + coarse.n_l; ++l) {
                    CAPTURE(k, l);
                    auto basis = [&](double s, double t) {
                        return bspline(m, std::ldexp(s, j - 1) - k) *
                               bspline(m, std::ldexp(t, j - 1) - l);
                    };
                    // Exact quadrature (m x m points per level-j cell); rounding only.
                    CHECK(inner_product_2d(m, j, residual, basis) == Approx(0.0).margin(1e-13));
                }
            const double f2 = inner_product_2d(m, j, f, f), c2 = inner_product_2d(m, j, c, c),
                         g2 = inner_product_2d(m, j, residual, residual);
            CHECK(f2 == Approx(c2 + g2).margin(1e-13));  // Pythagoras
            CHECK(c2 <= f2 * (1 + 1e-14));
        }
}
