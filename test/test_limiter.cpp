// test/test_limiter.cpp - the limiter's two clips (radiosity/solver/limiter.h): an increment's
// overshoot clipped to its bound, and a field lifted to zero where it rings below it, each
// changing the field only where it leaves its bounds.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "radiosity/solver/limiter.h"
#include "radiosity/solver/solver.h"

using namespace mbr;

namespace {

/// The L2 projection at level 3 of a step: `high` on s < 0.3, `low` beyond (a shadow's edge
/// the level does not resolve: the projection overshoots on one side and rings on the other).
SplineField projected_step(double high, double low) {
    return l2_projection(
        [=](double s, double) {
            const double v = s < 0.3 ? high : low;
            return Rgb{v, 0.5 * v, 0.25 * v};
        },
        4, 3);
}

/// Channel c of f on an n x n grid over [0,1]^2, the edges included.
std::vector<double> grid_values(const SplineField& f, int c, int n) {
    std::vector<double> out;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            out.push_back(f.evaluate(double(a) / (n - 1), double(b) / (n - 1))[c]);
    return out;
}

}  // namespace

TEST_CASE("limiter: limit_positive lifts a ringing step to zero and only raises it", "[limiter]") {
    const SplineField before = projected_step(1.0, 0.0);
    SplineField after = before;
    limit_positive(after);
    for (int c = 0; c < 3; ++c) {
        CAPTURE(c);
        const std::vector<double> b = grid_values(before, c, 257), a = grid_values(after, c, 257);
        CHECK(*std::min_element(b.begin(), b.end()) < -0.01 * std::ldexp(1.0, -c));  // it rings
        CHECK(*std::min_element(a.begin(), a.end()) >= 0);
        // It only grows, and by no more than the dip it lifts plus what lifting a coefficient
        // carries to its neighbours.
        double largest_rise = 0;
        for (size_t i = 0; i < a.size(); ++i) {
            CHECK(a[i] >= b[i] - 1e-15);
            largest_rise = std::max(largest_rise, a[i] - b[i]);
        }
        const double dip = -*std::min_element(b.begin(), b.end());
        CHECK(largest_rise <= 3 * dip);
    }
    // Only negative coefficients move, towards zero and never past it.
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < after.channel(c).a.size(); ++i) {
            const double was = before.channel(c).a[i], is = after.channel(c).a[i];
            if (was >= 0)
                CHECK(is == was);
            else
                CHECK((is >= was && is <= 0));
        }
}

TEST_CASE("limiter: limit_positive leaves a non-negative field as it is", "[limiter]") {
    SplineField f = projected_step(1.0, 0.2);  // rings, but stays above zero
    const std::vector<double> b = grid_values(f, 0, 257);
    REQUIRE(*std::min_element(b.begin(), b.end()) > 0);
    const SplineField before = f;
    limit_positive(f);
    for (int c = 0; c < 3; ++c) CHECK(f.channel(c).a == before.channel(c).a);
}

TEST_CASE("limiter: limit_increment clips the overshoot above its bound and nothing else",
          "[limiter]") {
    const SplineField before = projected_step(0.5, 0.0);
    SplineField after = before;
    const Rgb upper{0.5, 0.25, 0.125};
    const double slack = 1e-6;
    limit_increment(after, upper, slack);
    for (int c = 0; c < 3; ++c) {
        CAPTURE(c);
        const std::vector<double> b = grid_values(before, c, 33), a = grid_values(after, c, 33);
        CHECK(*std::max_element(b.begin(), b.end()) > upper[c] * 1.02);  // it overshoots
        // The clip checks the corners, midpoints and centres of the level-3 cells: on that
        // grid (17 points a direction, a subset of these 33) the field is within its bound.
        for (int i = 0; i < 33; i += 2)
            for (int j = 0; j < 33; j += 2) CHECK(a[size_t(i) * 33 + j] <= upper[c] + slack);
        for (size_t i = 0; i < a.size(); ++i) CHECK(a[i] <= b[i] + 1e-15);  // only lowered
        // Negative lobes are not its business: they stay (limit_positive is the view's).
        CHECK(*std::min_element(a.begin(), a.end()) < 0);
    }
}
