// test/test_expanded_domain.cpp - stage 4 of one transfer (paper section 5, "Adaptive Subdivision
// and Sampling on Expanded Domain", Figure 5) and the extrapolation of section 6, eqs. (23)-(27)
// (radiosity/transfer/expanded_domain.h), with the edge profiles of stage 3 it reads.
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

// ---- Extrapolation, eqs. (23)-(27) ----------------------------------------------------------

namespace {

/// A smooth stand-in for dB near the domain and its partial derivatives.
double g(double s, double t) {
    return 0.6 + 0.3 * s - 0.2 * t + 0.15 * s * t + 0.05 * s * s;
}
double g_s(double s, double t) {
    return 0.3 + 0.15 * t + 0.1 * s;
}
double g_t(double s, double) {
    return -0.2 + 0.15 * s;
}

/// Edge profiles of g at nine nodes per edge (h_min = 1/4), as fill_boundary would leave them:
/// values on the edge and the derivative along the edge's normal coordinate (t on the bottom
/// and top edges, s on the left and right ones).
ReceiverState extrapolation_state(Extrapolation kind) {
    ReceiverOptions options;
    options.extrapolation = kind;
    options.clamp_factor = 1e6;  // no clamping unless a test asks for it
    options.clamp_values = false;
    ReceiverState state(options);
    state.max_sample = 1;
    for (int e = 0; e < 4; ++e) {
        EdgeProfile& p = state.edges[e];
        p.h_min = 0.25;
        for (int i = 0; i <= 8; ++i) {
            const double sigma = i / 8.0;
            const double s = e == 0 || e == 2 ? sigma : (e == 1 ? 1.0 : 0.0);
            const double t = e == 1 || e == 3 ? sigma : (e == 2 ? 1.0 : 0.0);
            const double d = e == 0 || e == 2 ? g_t(s, t) : g_s(s, t);
            p.sigma.push_back(sigma);
            p.value.push_back({g(s, t), 2 * g(s, t), 0});
            p.derivative.push_back({d, 2 * d, 0});
        }
    }
    return state;
}

/// The point at distance x outside edge e at edge parameter sigma.
Vec2 outside(int e, double sigma, double x) {
    switch (e) {
        case 0:
            return {sigma, -x};
        case 1:
            return {1 + x, sigma};
        case 2:
            return {sigma, 1 + x};
        default:
            return {-x, sigma};
    }
}

double extrapolated(const ReceiverState& state, Vec2 p) {
    const Rgb v = extrapolate(state, p.x, p.y);
    CHECK(v.g == Approx(2 * v.r).margin(1e-14));  // channels are extrapolated alike
    CHECK(v.b == 0);
    return v.r;
}

}  // namespace

TEST_CASE("receiver: edge profiles interpolate linearly between edgefill nodes",
          "[receiver][expanded_domain]") {
    EdgeProfile p;
    p.sigma = {0, 0.25, 1};
    p.value = {{1, 0, 0}, {3, 0, 0}, {0, 0, 0}};
    p.derivative = {{-2, 0, 0}, {2, 0, 0}, {4, 0, 0}};
    Rgb v, d;
    p.at(0.125, v, d);
    CHECK(v.r == Approx(2));
    CHECK(d.r == Approx(0));
    p.at(0.625, v, d);
    CHECK(v.r == Approx(1.5));
    CHECK(d.r == Approx(3));
    p.at(-0.5, v, d);  // beyond the ends: the end values
    CHECK(v.r == 1);
    p.at(1.5, v, d);
    CHECK(d.r == 4);
}

TEST_CASE("receiver: linear extrapolation (23)-(25) continues value and slope of each edge",
          "[receiver][expanded_domain]") {
    const ReceiverState state = extrapolation_state(Extrapolation::Linear);
    for (int e = 0; e < 4; ++e)
        for (double sigma : {0.0, 0.1, 0.5, 0.8125, 1.0}) {
            CAPTURE(e, sigma);
            const EdgeProfile& p = state.edges[e];
            Rgb v, d;
            p.at(sigma, v, d);
            // Value: the limit from outside is the profile's value (continuity at the edge;
            // at 1e-12 out the linear term is below 1e-12).
            CHECK(extrapolated(state, outside(e, sigma, 1e-12)) == Approx(v.r).margin(1e-11));
            // Slope along the normal coordinate is the profile's derivative, exactly linear:
            // d/dt on the bottom edge (t decreasing outwards), d/ds on the right, and so on.
            if (sigma > 0 && sigma < 1) {  // on the side patches (the corner ones use both)
                const double sign = e == 0 || e == 3 ? -1.0 : 1.0;
                const double slope = (extrapolated(state, outside(e, sigma, 0.7)) -
                                      extrapolated(state, outside(e, sigma, 0.2))) /
                                     (sign * 0.5);
                CHECK(slope == Approx(d.r).epsilon(1e-12));
            }
        }
    // Corner patches, eqs. (24)-(25): v(corner) + (s - s_c) B_s + (t - t_c) B_t with B_s from the
    // vertical edge and B_t from the horizontal one at the corner.
    for (double a : {0.01, 0.3, 1.7})
        for (double b : {0.02, 0.9}) {
            CAPTURE(a, b);
            CHECK(extrapolated(state, {-a, -b}) ==
                  Approx(g(0, 0) - a * g_s(0, 0) - b * g_t(0, 0)).epsilon(1e-13));
            CHECK(extrapolated(state, {1 + a, -b}) ==
                  Approx(g(1, 0) + a * g_s(1, 0) - b * g_t(1, 0)).epsilon(1e-13));
            CHECK(extrapolated(state, {1 + a, 1 + b}) ==
                  Approx(g(1, 1) + a * g_s(1, 1) + b * g_t(1, 1)).epsilon(1e-13));
            CHECK(extrapolated(state, {-a, 1 + b}) ==
                  Approx(g(0, 1) - a * g_s(0, 1) + b * g_t(0, 1)).epsilon(1e-13));
            // Continuity across the lines that separate corner and side patches (the profiles
            // agree at the corners, as edgefill's do: both sample the same corner points).
            const double z = 1e-12;
            CHECK(extrapolated(state, {-z, -b}) ==
                  Approx(extrapolated(state, {z, -b})).margin(1e-11));
            CHECK(extrapolated(state, {-a, -z}) ==
                  Approx(extrapolated(state, {-a, z})).margin(1e-11));
            CHECK(extrapolated(state, {1 + a, 1 - z}) ==
                  Approx(extrapolated(state, {1 + a, 1 + z})).margin(1e-11));
            CHECK(extrapolated(state, {1 - z, 1 + b}) ==
                  Approx(extrapolated(state, {1 + z, 1 + b})).margin(1e-11));
        }
}

TEST_CASE("receiver: linear extrapolation clamps steep derivatives",
          "[receiver][expanded_domain]") {
    // Section 6: "If ... too large ... reduced into a predetermined range": here
    // |B_n| <= clamp_factor * max|dB| / h_min = 1 * 1 / 0.25 = 4.
    ReceiverState state = extrapolation_state(Extrapolation::Linear);
    state.options.clamp_factor = 1;
    for (Rgb& d : state.edges[0].derivative) d = {1e3, 1e3, 0};
    for (Rgb& d : state.edges[1].derivative) d = {-1e3, -1e3, 0};
    Rgb v, d;
    state.edges[0].at(0.5, v, d);
    CHECK(extrapolate(state, 0.5, -0.1).r == Approx(v.r - 0.1 * 4).epsilon(1e-14));
    state.edges[1].at(0.5, v, d);
    CHECK(extrapolate(state, 1.2, 0.5).r == Approx(v.r + 0.2 * -4).epsilon(1e-14));
    // Unclamped derivatives within the range pass through (the top edge's g_t is about -0.1).
    state.edges[2].at(0.5, v, d);
    CHECK(extrapolate(state, 0.5, 1.3).r == Approx(v.r + 0.3 * g_t(0.5, 1)).epsilon(1e-14));
}

TEST_CASE("receiver: linear extrapolation keeps values near the samples' range",
          "[receiver][expanded_domain]") {
    // clamp_values: each channel of (23)-(25) stays within [lo - w, hi + w] for the samples'
    // range [lo, hi] of width w. With a steep edge (derivative 1e3, as where a surface meets its
    // shooter) the unclamped values 1 unit out would be about 1e3; clamped they are at most
    // hi + w. Inside the band the extrapolation is untouched.
    ReceiverState state = extrapolation_state(Extrapolation::Linear);
    state.options.clamp_values = true;
    state.sample_lo = {0, 0, 0};
    state.sample_hi = {2, 4, 0};
    for (Rgb& d : state.edges[0].derivative) d = {-1e3, -1e3, 0};  // grows below t = 0
    const Rgb far = extrapolate(state, 0.5, -1.0);
    CHECK(far.r == Approx(4).epsilon(1e-12));  // hi + w = 2 + 2
    CHECK(far.g == Approx(8).epsilon(1e-12));  // 4 + 4
    state.options.clamp_values = false;
    CHECK(extrapolate(state, 0.5, -1.0).r > 500);  // what the clamp prevents
    // Close to the edge the value is within the band and unchanged by the clamp.
    state.options.clamp_values = true;
    for (Rgb& d : state.edges[0].derivative) d = {-1, -1, 0};
    Rgb v, d;
    state.edges[0].at(0.5, v, d);
    const Rgb near = extrapolate(state, 0.5, -0.01);
    CHECK(near.r == Approx(v.r - 0.01 * d.r).epsilon(1e-12));
}

TEST_CASE("receiver: higher-order extrapolation meets (26) and (27)",
          "[receiver][expanded_domain]") {
    // Along the outward normal, in units of the boundary cell w = h_min = 1/4: value and normal
    // derivative continue the edge's; the quadratic form (26) is C^1 at one cell out and zero
    // with zero derivative from two cells on; the cubic form (27) is zero from one cell on.
    // Derivatives by one-sided differences with step delta = 1e-7: truncation error
    // delta/2 |f''| with |f''| <= (|v| + w |f'|) * 3 / w^2 ~ 40, so 1e-5 is ample; rounding
    // 1e-16 / delta ~ 1e-9.
    const double w = 0.25, delta = 1e-7, tol = 1e-5;
    for (Extrapolation kind : {Extrapolation::Quadratic, Extrapolation::Cubic}) {
        const double reach = kind == Extrapolation::Quadratic ? 2 : 1;  // cells
        const ReceiverState state = extrapolation_state(kind);
        for (int e = 0; e < 4; ++e)
            for (double sigma : {0.2, 0.5, 0.875}) {
                CAPTURE(int(kind), e, sigma);
                Rgb v, d;
                state.edges[e].at(sigma, v, d);
                const double inward =
                    e == 0 || e == 3 ? 1.0 : -1.0;  // normal coordinate grows inwards
                auto f = [&](double x) { return extrapolated(state, outside(e, sigma, x)); };
                // At the edge: value and derivative (d/dx outward = -inward * d).
                CHECK(f(1e-13) == Approx(v.r).margin(1e-11));
                CHECK((f(delta) - f(1e-13)) / delta == Approx(-inward * d.r).margin(tol));
                // Zero from `reach` cells on, with zero derivative arriving there.
                for (double x : {reach * w, reach * w + 1e-9, reach * w + 0.1, 3.0})
                    CHECK(f(x) == 0);
                CHECK((f(reach * w) - f(reach * w - delta)) / delta == Approx(0).margin(tol));
                CHECK(f(reach * w - 0.05) != 0);
                if (kind == Extrapolation::Quadratic) {
                    // C^1 at one cell out: one-sided derivatives agree, the values too.
                    const double left = (f(w) - f(w - delta)) / delta,
                                 right = (f(w + delta) - f(w)) / delta;
                    CHECK(left == Approx(right).margin(2 * tol));
                    CHECK(f(w - 1e-12) == Approx(f(w + 1e-12)).margin(1e-10));
                }
            }
        // Corner patches: the tensor form, v at the corner, nothing beyond the reach in s or t.
        CHECK(extrapolated(state, {-1e-13, -1e-13}) == Approx(g(0, 0)).margin(1e-11));
        CHECK(extrapolated(state, {1 + 1e-13, 1 + 1e-13}) == Approx(g(1, 1)).margin(1e-11));
        CHECK(extrapolated(state, {-reach * w - 0.01, -0.05}) == 0);
        CHECK(extrapolated(state, {1.05, 1 + reach * w + 0.01}) == 0);
        CHECK(extrapolated(state, {-0.05, -0.05}) != 0);
    }
}

TEST_CASE("receiver: uniform trees keep the expanded cells next to the domain at the leaves' size",
          "[receiver][expanded_domain]") {
    // Section 6, "Scale Adjustment": "the scale of boundary subdomains in R[a,b;c,d] [must] be
    // equal to that of its neighboring expanded subdomains".
    const Run run = run_transfer(parallel_squares(1.0), uniform_options(3));
    const Forest& forest = run.state.forest;
    int touching_leaves = 0;
    for (int index : forest.leaves(Forest::Region::Expanded)) {
        const DyadicCell c = forest.node(index).cell;
        if (!touching(c.rect(), Rect{0, 1, 0, 1})) continue;
        ++touching_leaves;
        CHECK(c.level == 3);
    }
    CHECK(touching_leaves == 4 * 8 + 4);
    for (int index : forest.leaves(Forest::Region::Domain))
        CHECK(forest.node(index).cell.level == 3);
}
