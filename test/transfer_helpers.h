// test/transfer_helpers.h - what the tests of one transfer's stages share (paper section 5):
// a receiver state built by hand (a forest to order, the expanded ring as expand_domain builds
// it, leaf samples of a known function at the Gauss-Legendre nodes), polynomials of degree < m
// with the bound on their projection's truncation error, and one whole transfer as the
// examples run it.
#pragma once

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

namespace mbr::test {

// ---- A receiver state built by hand ---------------------------------------------------------

/// Splits every domain leaf down to `depth`.
inline void split_domain_uniform(Forest& forest, int depth) {
    for (int level = 0; level < depth; ++level)
        for (int index : forest.leaves(Forest::Region::Domain))
            if (forest.node(index).cell.level < depth) forest.split(index);
}

/// Splits the leaf holding `cell` until the cell itself is a node.
inline void split_to(Forest& forest, const DyadicCell& cell) {
    for (;;) {
        const int index = forest.find(cell);
        REQUIRE(index >= 0);
        if (forest.node(index).cell.level >= cell.level) return;
        forest.split(index);
    }
}

/// Closed rectangles meet.
inline bool touching(const Rect& a, const Rect& b) {
    return a.x0 <= b.x1 && b.x0 <= a.x1 && a.y0 <= b.y1 && b.y0 <= a.y1;
}

/// The expanded ring as expand_domain builds it: roots out to its width rule
/// (rhombus radius + m + 1 coarsest boundary leaves), an expanded cell that touches a domain leaf
/// split down to the smallest such leaf, every other expanded cell split to `far_level`, then
/// NeighAdjust over the whole forest.
inline void build_ring(ReceiverState& state, int far_level) {
    Forest& forest = state.forest;
    const int m = state.options.m;
    std::vector<Rect> boundary;
    double h_coarse = 0;
    for (int index : forest.leaves(Forest::Region::Domain)) {
        const Rect r = forest.node(index).cell.rect();
        if (r.x0 == 0 || r.y0 == 0 || r.x1 == 1 || r.y1 == 1) {
            boundary.push_back(r);
            h_coarse = std::max(h_coarse, r.width());
        }
    }
    forest.grow(static_cast<int>(std::ceil((state.rhombus_radius + m + 1) * h_coarse)));
    std::vector<int> work = forest.leaves(Forest::Region::Expanded);
    while (!work.empty()) {
        const int index = work.back();
        work.pop_back();
        const DyadicCell c = forest.node(index).cell;
        double h_touch = 0;
        for (const Rect& b : boundary)
            if (touching(c.rect(), b))
                h_touch = h_touch == 0 ? b.width() : std::min(h_touch, b.width());
        if ((h_touch > 0 && c.size() > h_touch) || c.level < far_level) {
            const int first = forest.split(index);
            for (int ch = 0; ch < 4; ++ch) work.push_back(first + ch);
        }
    }
    adjust_neighbour_scales(forest, Forest::Region::All);
}

/// The m x m Gauss-Legendre samples of f (three channels: f, -2f, f/2) on every leaf.
template <class F>
inline void fill_samples(ReceiverState& state, F&& f) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    Forest& forest = state.forest;
    state.samples.clear();
    state.max_sample = 0;
    int block = 0;
    for (int index : forest.leaves()) {
        Forest::Node& node = forest.node(index);
        node.samples = block++;
        const Rect r = node.cell.rect();
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                const double v = f(r.x0 + 0.5 * (rule.x[a] + 1) * r.width(),
                                   r.y0 + 0.5 * (rule.x[b] + 1) * r.height());
                state.samples.push_back({v, -2 * v, 0.5 * v});
                if (node.cell.in_domain())
                    state.max_sample = std::max(state.max_sample, 2 * std::fabs(v));
            }
    }
}

/// A state of order m with the given rhombus radius (cells) and an empty domain tree.
inline ReceiverState make_state(int m, double radius) {
    ReceiverOptions options;
    options.m = m;
    options.rhombus_radius = radius;
    return ReceiverState(options, radius);
}

/// Stages 5, 6 and 8 on a state whose leaves all carry samples.
inline SplineField select_project_unify(ReceiverState& state, const DualTable& dn) {
    state.fulcrums = select_fulcrums(state.forest, state.options.m);
    state.coefficients.clear();
    project_in_rhombi(state, dn);
    return unify_scales(state, dn);
}

// ---- Polynomials and the truncation bound ---------------------------------------------------

/// p(s,t) = sum_{i,j < m} a_ij (s - 1/2)^i (t - 1/2)^j: degree < m in each variable, so in every
/// spline space of order m.
struct Poly {
    int m = 0;
    std::vector<double> a;
    double operator()(double s, double t) const {
        double sum = 0, ps = 1;
        for (int i = 0; i < m; ++i, ps *= s - 0.5) {
            double pt = 1;
            for (int j = 0; j < m; ++j, pt *= t - 0.5) sum += a[i * m + j] * ps * pt;
        }
        return sum;
    }
};

inline Poly random_poly(int m, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1, 1);
    Poly p{m, std::vector<double>(size_t(m) * m)};
    for (double& c : p.a) c = u(rng);
    return p;
}

/// An upper bound on the error of any projected coefficient of scale h = 2^-L whose fulcrum is
/// within `c` of (1/2, 1/2) in each coordinate, for data bounded by
/// P(s,t) = sum |a_ij| |s - 1/2|^i |t - 1/2|^j, rhombus radius r (cells of h):
/// - truncation: project() drops only cells that miss the rhombus, so the dropped part is at most
///   the integral of P |DN(x) DN(y)| over |x| + |y| > r (x, y in cells of h from the fulcrum;
///   4^L ds dt = dx dy), with |s - 1/2| <= h|x| + c;
/// - the table's own error (dual_basis.h: |DN - table| <= error_bound() everywhere) over the
///   rhombus: 2 error_bound max|DN| times the rhombus area 2 r^2 times max P there;
/// - rounding: 1e-15 of the whole integral of P |DN DN|.
/// The integrals are midpoint sums with step 1/32 on the table's support (|DN| is smooth between
/// integer knots; the sums of this monotone-enveloped tail are accurate to a few per mille, and a
/// factor 1.1 covers it).
inline double projection_error_bound(const DualTable& dn, double r, double h, double c,
                                     const std::vector<double>& abs_a, int m) {
    const double delta = 1.0 / 32;
    const int N = static_cast<int>(std::ceil(dn.half_width() / delta));
    std::vector<double> x(N), D(N);
    for (int q = 0; q < N; ++q) {
        x[q] = (q + 0.5) * delta;
        D[q] = std::fabs(dn(0.5 * m + x[q]));
    }
    // g_i(x) = (h|x| + c)^i |D(x)| for x = +-x_q; tail_i[q] = sum over |y| >= x_q of g_i(y) delta.
    std::vector<std::vector<double>> g(m, std::vector<double>(N)),
        tail(m, std::vector<double>(N + 1, 0.0));
    for (int i = 0; i < m; ++i) {
        for (int q = 0; q < N; ++q) g[i][q] = std::pow(h * x[q] + c, i) * D[q];
        for (int q = N - 1; q >= 0; --q) tail[i][q] = tail[i][q + 1] + 2 * g[i][q] * delta;
    }
    auto tail_beyond = [&](int j, double rho) {  // sum over |y| > rho of g_j(y) delta
        if (rho < 0) return tail[j][0];
        const int q0 = std::max(0, static_cast<int>(std::floor(rho / delta - 0.5)) + 1);
        return q0 < N ? tail[j][q0] : 0.0;
    };
    double truncation = 0, total = 0, table = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            const double w = abs_a[i * m + j];
            if (w == 0) continue;
            double t_ij = 0;
            for (int q = 0; q < N; ++q) t_ij += 2 * g[i][q] * delta * tail_beyond(j, r - x[q]);
            truncation += w * t_ij;
            total += w * tail[i][0] * tail[j][0];
            table += w * std::pow(h * r + c, i + j);
        }
    table *= 2 * dn.error_bound() * dn.max_abs() * 2 * r * r;
    return 1.1 * truncation + table + 1e-15 * total;
}

/// The largest distance of a stored coefficient's fulcrum from (1/2, 1/2), per level.
inline std::vector<double> fulcrum_reach(const ReceiverState& state) {
    std::vector<double> reach;
    for (const auto& kv : state.coefficients) {
        const Fulcrum& f = kv.first;
        if (int(reach.size()) <= f.level) reach.resize(f.level + 1, -1);
        const Vec2 p = f.position(state.options.m);
        reach[f.level] = std::max({reach[f.level], std::fabs(p.x - 0.5), std::fabs(p.y - 0.5)});
    }
    return reach;
}

/// The bound above, maximised over the levels of the stored coefficients from the coarsest
/// domain leaf's level on: by the partition of unity it bounds the error of the unified field
/// anywhere in [0,1]^2, since (17) mixes coarse coefficients with weights p_{m,l-2k} that sum to
/// one for each fine l. Coarser coefficients (fulcrums of coarse expanded leaves whose basis
/// reaches into the domain) are selected but never refined into the result, because every leaf
/// near the domain is at least that fine; leaving them out makes the bound stricter, never
/// looser.
inline double field_error_bound(const ReceiverState& state, const DualTable& dn,
                                const std::vector<double>& abs_a) {
    const std::vector<double> reach = fulcrum_reach(state);
    int min_level = 64;
    for (int index : state.forest.leaves(Forest::Region::Domain))
        min_level = std::min(min_level, state.forest.node(index).cell.level);
    double bound = 0;
    for (int level = min_level; level < int(reach.size()); ++level)
        if (reach[level] >= 0)
            bound = std::max(
                bound, projection_error_bound(dn, state.rhombus_radius, std::ldexp(1.0, -level),
                                              reach[level], abs_a, state.options.m));
    return bound;
}

/// max |field - f| over an n x n grid of [0,1]^2 including its edges, red channel; also checks
/// that the other channels carry -2f and f/2 to rounding.
template <class F>
inline double max_field_error(const SplineField& field, F&& f, int n = 33) {
    double worst = 0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double s = double(a) / (n - 1), t = double(b) / (n - 1);
            const Rgb v = field.evaluate(s, t);
            worst = std::max(worst, std::fabs(v.r - f(s, t)));
            CHECK(v.g == Approx(-2 * v.r).margin(1e-12));
            CHECK(v.b == Approx(0.5 * v.r).margin(1e-12));
        }
    return worst;
}

/// Mixed-depth domain: uniform depth d, then the corner cell (0,0) of level d and one cell
/// touching the right edge split once more, then NeighAdjust over the domain.
inline void build_mixed_domain(Forest& forest, int d) {
    split_domain_uniform(forest, d);
    const int n = 1 << d;
    split_to(forest, DyadicCell{d + 1, 0, 0});
    split_to(forest, DyadicCell{d + 1, 2 * n - 1, n});
    adjust_neighbour_scales(forest, Forest::Region::Domain);
}

/// One transfer as the examples run it: shooter radiosity 1 (its unshot field coarsened as
/// section 6 does), receiver reflectance 1.
struct Run {
    TransferSetup setup;
    SplineField field;
    ReceiverState state;
};

inline Run run_transfer(const TransferSetup& setup, const ReceiverOptions& options) {
    Run run{setup, {}, {}};
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(run.setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&run.setup.receiver, [](double, double) {
                                       return Rgb{1, 1, 1};
                                   }};
    run.field = transfer(shooter, receiver, options, nullptr, &run.state);
    return run;
}

inline ReceiverOptions uniform_options(int d) {
    ReceiverOptions o;
    o.min_depth = o.max_depth = d;
    return o;
}

}  // namespace mbr::test
