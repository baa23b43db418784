// test/test_unification.cpp - stage 8 of one transfer (paper section 5, "Scale Unification and
// Superposition", eq. (17); radiosity/transfer/unification.h): the unified field's smoothness
// across leaves of different size.
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

namespace {

/// The derivatives of order 0..m-1 at x0 of the degree m-1 polynomial through the values of
/// `f` at the m Gauss-Legendre nodes of [a, b] (x0 = a or b), and the sums of |weights| of each
/// (the amplification of errors in the values).
void endpoint_derivatives(const std::function<double(double)>& f, double a, double b, double x0,
                          int m, std::vector<double>& derivative, std::vector<double>& weight) {
    const GaussLegendre rule = gauss_legendre(m);
    std::vector<double> x(m), y(m);
    for (int i = 0; i < m; ++i) {
        x[i] = a + 0.5 * (rule.x[i] + 1) * (b - a);
        y[i] = f(x[i]);
    }
    derivative.assign(m, 0.0);
    weight.assign(m, 0.0);
    for (int i = 0; i < m; ++i) {
        // Lagrange basis l_i as monomial coefficients in (x - x0), then its derivatives at x0.
        std::vector<double> c{1.0};
        double denominator = 1;
        for (int j = 0; j < m; ++j) {
            if (j == i) continue;
            denominator *= x[i] - x[j];
            std::vector<double> next(c.size() + 1, 0.0);  // c * ((x - x0) - (x_j - x0))
            for (size_t k = 0; k < c.size(); ++k) {
                next[k + 1] += c[k];
                next[k] -= c[k] * (x[j] - x0);
            }
            c = next;
        }
        double factorial = 1;
        for (int r = 0; r < m; ++r) {
            if (r > 0) factorial *= r;
            const double w = factorial * c[r] / denominator;  // l_i^(r)(x0)
            derivative[r] += w * y[i];
            weight[r] += std::fabs(w);
        }
    }
}

}  // namespace

TEST_CASE("receiver: the unified field is C^(m-2) across leaves of different size",
          "[receiver][unification]") {
    // Parallel squares at h = 0.1, adaptive depths 1..4 (oracle 2e-3): leaves of two sizes
    // meet (levels 3 and 4, 32 edges between them). Along the normal through points of every edge
    // shared by leaves of different size, the field is one polynomial of degree m - 1 on each side
    // within one knot interval of the unified level; its one-sided derivatives at the edge, from
    // the interpolant through m points on each side, must agree up to order m - 2. Tolerance: the
    // classical rounding bound of (20), a convex combination of m^2 coefficients, taken as
    // m^2 DBL_EPSILON max|c|, amplified by the interpolants' derivative weights (measured jumps
    // are 6 % of it at most). Order m - 1 must jump somewhere by far more (measured 1e10 times
    // the tolerance): the check resolves a knot.
    ReceiverOptions options;
    options.min_depth = 1;
    options.max_depth = 4;
    options.oracle_tolerance = 2e-3;
    for (int m : {3, 4}) {
        CAPTURE(m);
        options.m = m;
        const Run run = run_transfer(parallel_squares(0.1), options);
        const Forest& forest = run.state.forest;
        const std::vector<int> domain = forest.leaves(Forest::Region::Domain);
        std::set<int> levels;
        for (int index : domain) levels.insert(forest.node(index).cell.level);
        REQUIRE(levels.size() >= 2);
        const double H = std::ldexp(1.0, -run.field.level());  // knot spacing of the result
        const double noise =
            m * m * std::numeric_limits<double>::epsilon() * run.field.max_abs_coefficient();
        int edges = 0;
        double worst_ratio = 0, largest_jump = 0, jump_tolerance = 0;
        for (int a : domain)
            for (int b : domain) {
                const DyadicCell ca = forest.node(a).cell, cb = forest.node(b).cell;
                if (ca.level >= cb.level) continue;  // each pair once: a coarser than b
                const Rect ra = ca.rect(), rb = cb.rect();
                // Shared vertical edge (s = x0) or horizontal edge (t = y0), of positive length.
                const bool vertical = (ra.x1 == rb.x0 || rb.x1 == ra.x0) &&
                                      std::min(ra.y1, rb.y1) > std::max(ra.y0, rb.y0);
                const bool horizontal = (ra.y1 == rb.y0 || rb.y1 == ra.y0) &&
                                        std::min(ra.x1, rb.x1) > std::max(ra.x0, rb.x0);
                if (!vertical && !horizontal) continue;
                ++edges;
                const double x0 =
                    vertical ? (ra.x1 == rb.x0 ? ra.x1 : ra.x0) : (ra.y1 == rb.y0 ? ra.y1 : ra.y0);
                const double lo = vertical ? std::max(ra.y0, rb.y0) : std::max(ra.x0, rb.x0);
                const double hi = vertical ? std::min(ra.y1, rb.y1) : std::min(ra.x1, rb.x1);
                for (double frac : {0.25, 0.5, 0.8}) {
                    const double along = lo + frac * (hi - lo);
                    std::function<double(double)> f = [&](double x) {
                        return (vertical ? run.field.evaluate(x, along)
                                         : run.field.evaluate(along, x))
                            .r;
                    };
                    std::vector<double> left, right, w_left, w_right;
                    endpoint_derivatives(f, x0 - H, x0, x0, m, left, w_left);
                    endpoint_derivatives(f, x0, x0 + H, x0, m, right, w_right);
                    for (int r = 0; r < m; ++r) {
                        const double jump = std::fabs(left[r] - right[r]);
                        const double tol = noise * (w_left[r] + w_right[r]);
                        if (r <= m - 2) {
                            CAPTURE(ca, cb, along, r, jump, tol);
                            CHECK(jump <= tol);
                            worst_ratio = std::max(worst_ratio, jump / tol);
                        } else if (jump > largest_jump) {
                            largest_jump = jump;
                            jump_tolerance = tol;
                        }
                    }
                }
            }
        CHECK(edges > 0);
        CHECK(largest_jump > 1e3 * jump_tolerance);
        mbr::test::report() << "receiver continuity m=" << m << ": " << domain.size()
                            << " leaves of " << levels.size() << " sizes, " << edges
                            << " edges between sizes, worst jump / tolerance " << worst_ratio
                            << " (orders <= m-2), largest jump of order m-1 " << largest_jump
                            << " = " << largest_jump / jump_tolerance << " tolerances\n";
    }
}
