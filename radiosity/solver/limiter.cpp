// radiosity/solver/limiter.cpp - clipping a field's coefficients to its physical bounds where
// its values leave them (limiter.h).
#include "radiosity/solver/limiter.h"

#include <algorithm>
#include <vector>

#include "math/bspline.h"

namespace mbr {

namespace {

/// A field's values on a tensor grid of q intervals per level-j cell and direction.
struct SampledField {
    int cells = 0, q = 0, n = 0;  // n = cells q + 1 points a direction
    std::vector<Rgb> values;      // values[a * n + b] = f(a / (n - 1), b / (n - 1))
};

SampledField sample_field(const SplineField& field, int q) {
    SampledField s;
    s.cells = 1 << field.level();
    s.q = q;
    s.n = s.cells * q + 1;
    std::vector<double> x(s.n);
    for (int a = 0; a < s.n; ++a) x[a] = double(a) / (s.n - 1);
    s.values.resize(size_t(s.n) * s.n);
    field.evaluate_grid(x.data(), s.n, x.data(), s.n, s.values.data());
    return s;
}

/// Per channel, with g = side (f - bound) (side +1: f >= bound is asked, -1: f <= bound; the
/// B-splines sum to one on the domain, so g's coefficients are side (c - bound)): where g is
/// below -slack at the points of a grid of q intervals a cell, the negative coefficients of g
/// of the B-splines covering those points are scaled by 1 - theta, with theta the least that
/// makes each such point >= 0 (g = P + N, P of the positive coefficients and N of the negative
/// ones: theta >= 1 - P(x) / |N(x)|). Raising a coefficient of g raises g everywhere, so each
/// coefficient takes the largest theta of the cells it covers. Other coefficients keep their
/// bits.
void lift_to_bound(SplineField& field, Rgb bound, double side, int q, double slack) {
    const int m = field.order(), cells = 1 << field.level();
    const auto g_of = [&](int c, double a) { return side * (a - bound[c]); };
    // With no negative coefficient of g, g >= 0 everywhere (the B-splines are non-negative):
    // nothing to sample (most fields of a big scene, which would otherwise cost two grids).
    bool any_negative = false;
    for (int c = 0; c < 3 && !any_negative; ++c)
        for (double a : field.channel(c).a)
            if (g_of(c, a) < 0) {
                any_negative = true;
                break;
            }
    if (!any_negative) return;
    SplineField positive = field, negative = field;
    for (int c = 0; c < 3; ++c) {
        for (double& a : positive.channel(c).a) a = std::max(g_of(c, a), 0.0);
        for (double& a : negative.channel(c).a) a = std::min(g_of(c, a), 0.0);
    }
    const SampledField P = sample_field(positive, q), N = sample_field(negative, q);
    for (int c = 0; c < 3; ++c) {
        std::vector<double> theta_cell(size_t(cells) * cells, 0.0);
        bool any = false;
        for (int a = 0; a < P.n; ++a)
            for (int b = 0; b < P.n; ++b) {
                const size_t x = size_t(a) * P.n + b;
                const double p = P.values[x][c], n = N.values[x][c];
                if (p + n >= -slack) continue;
                any = true;
                // 1e-9 of P to spare, so that rounding cannot leave f(x) below zero.
                const double theta = std::min(1.0, 1 - (1 - 1e-9) * p / -n);
                for (int ci = std::max(0, (a - 1) / q); ci <= std::min(cells - 1, a / q); ++ci)
                    for (int cj = std::max(0, (b - 1) / q); cj <= std::min(cells - 1, b / q); ++cj)
                        theta_cell[size_t(ci) * cells + cj] =
                            std::max(theta_cell[size_t(ci) * cells + cj], theta);
            }
        if (!any) continue;
        CoefficientGrid& g = field.channel(c);
        for (int k = g.first_k; k < g.first_k + g.n_k; ++k)
            for (int l = g.first_l; l < g.first_l + g.n_l; ++l) {
                double& a = g(k, l);
                if (g_of(c, a) >= 0) continue;
                double theta = 0;  // the largest of the cells its B-spline covers
                for (int ci = std::max(0, k); ci <= std::min(cells - 1, k + m - 1); ++ci)
                    for (int cj = std::max(0, l); cj <= std::min(cells - 1, l + m - 1); ++cj)
                        theta = std::max(theta, theta_cell[size_t(ci) * cells + cj]);
                if (theta > 0) a = bound[c] + side * (1 - theta) * g_of(c, a);
            }
    }
}

}  // namespace

void limit_increment(SplineField& field, Rgb upper, double slack) {
    if (field.empty()) return;
    Rgb hi;
    for (int c = 0; c < 3; ++c) hi[c] = std::max(0.0, upper[c]);
    lift_to_bound(field, hi, -1, 2, slack);  // corners, edge midpoints and centres of the cells
}

void limit_positive(SplineField& field) {
    if (field.empty()) return;
    const int cells = 1 << field.level();
    lift_to_bound(field, Rgb{}, +1, std::max(4, 256 / cells), 0);  // >= 4 a cell, 256 in all
}

}  // namespace mbr
