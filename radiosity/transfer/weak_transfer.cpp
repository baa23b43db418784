// radiosity/transfer/weak_transfer.cpp - the weak transfer: the level-0 field through the root's
// samples (beyond the paper, cost follows energy).
#include "radiosity/transfer/weak_transfer.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "math/bspline.h"
#include "math/check.h"
#include "math/gauss_legendre.h"
#include "radiosity/transfer/shadows.h"

namespace mbr {

namespace {

/// The inverse of the collocation matrix V[a][k] = N_m(x_a - k) of the level-0 basis functions
/// touching [0,1] (k = first_touching_index(m) + k') at the m Gauss-Legendre nodes x_a of [0,1]:
/// Gauss-Jordan elimination with partial pivoting on an m x m matrix (m <= 8).
std::vector<double> inverse_collocation(int m) {
    const GaussLegendre rule = gauss_legendre(m);
    const int first = first_touching_index(m);
    std::vector<double> a(size_t(m) * m), inv(size_t(m) * m, 0.0);
    for (int r = 0; r < m; ++r) {
        const double x = 0.5 * (rule.x[r] + 1);
        for (int k = 0; k < m; ++k) a[size_t(r) * m + k] = bspline(m, x - (first + k));
        inv[size_t(r) * m + r] = 1;
    }
    for (int c = 0; c < m; ++c) {
        int pivot = c;
        for (int r = c + 1; r < m; ++r)
            if (std::fabs(a[size_t(r) * m + c]) > std::fabs(a[size_t(pivot) * m + c])) pivot = r;
        MBR_CHECK_MSG(std::fabs(a[size_t(pivot) * m + c]) > 1e-12,
                      "singular collocation matrix for m = " << m);
        for (int k = 0; k < m; ++k) {
            std::swap(a[size_t(c) * m + k], a[size_t(pivot) * m + k]);
            std::swap(inv[size_t(c) * m + k], inv[size_t(pivot) * m + k]);
        }
        const double d = a[size_t(c) * m + c];
        for (int k = 0; k < m; ++k) {
            a[size_t(c) * m + k] /= d;
            inv[size_t(c) * m + k] /= d;
        }
        for (int r = 0; r < m; ++r) {
            if (r == c) continue;
            const double f = a[size_t(r) * m + c];
            if (f == 0) continue;
            for (int k = 0; k < m; ++k) {
                a[size_t(r) * m + k] -= f * a[size_t(c) * m + k];
                inv[size_t(r) * m + k] -= f * inv[size_t(c) * m + k];
            }
        }
    }
    return inv;  // inv[k * m + a]: coefficient k from the sample at node a
}

}  // namespace

bool is_weak_transfer(const ReceiverOptions& options, double largest_root_sample) {
    return options.weak_transfer > 0 && options.absolute_tolerance > 0 &&
           largest_root_sample < options.weak_transfer * options.absolute_tolerance;
}

bool root_samples_represent(const Surface& shooter, const Surface& receiver) {
    const Box3 a = shooter.bounds(), b = receiver.bounds();
    double gap2 = 0;  // squared distance between the boxes
    for (int c = 0; c < 3; ++c) {
        const double g = std::max({0.0, a.lo[c] - b.hi[c], b.lo[c] - a.hi[c]});
        gap2 += g * g;
    }
    const double diagonal = length(b.extent());
    return gap2 >= 0.25 * diagonal * diagonal;
}

SplineField project_root_polynomial(ReceiverState& state) {
    const int m = state.options.m;
    const Forest::Node& root = state.forest.node(state.forest.domain_root());
    MBR_CHECK_MSG(root.is_leaf() && root.samples >= 0, "a weak transfer needs the root's samples");
    const Rgb* f = &state.samples[size_t(root.samples) * m * m];  // f[a * m + b] at (s_a, t_b)
    const std::vector<double> inv = inverse_collocation(m);
    // C = V^-1 F V^-T: first along t (b -> l), then along s (a -> k).
    std::vector<Rgb> g(size_t(m) * m);  // g[a * m + l]
    for (int a = 0; a < m; ++a)
        for (int l = 0; l < m; ++l) {
            Rgb sum;
            for (int b = 0; b < m; ++b) sum += inv[size_t(l) * m + b] * f[a * m + b];
            g[size_t(a) * m + l] = sum;
        }
    const int first = first_touching_index(m);
    SplineField field(m, 0);
    for (int k = 0; k < m; ++k)
        for (int l = 0; l < m; ++l) {
            Rgb c;
            for (int a = 0; a < m; ++a) c += inv[size_t(k) * m + a] * g[size_t(a) * m + l];
            field.set_coefficient(first + k, first + l, c);
        }
    state.stats.n_projections += m * m;
    state.stats.level = 0;
    return field;
}

void mask_root_coefficients(SplineField& field, ReceiverState& state, IncrementSampler& sampler) {
    const int m = state.options.m, first = first_touching_index(m);
    for (int k = first; k < first + m; ++k)
        for (int l = first; l < first + m; ++l) {
            const Vec2 p = fraction_point(Fulcrum{0, k, l}, m);
            field.set_coefficient(
                k, l, field.coefficient(k, l) * fraction_at(state, sampler, p.x, p.y, 0));
        }
}

}  // namespace mbr
