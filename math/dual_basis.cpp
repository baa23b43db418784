// math/dual_basis.cpp - the appendix's numerical method for the dual basis, and DN_m as a
// table of polynomial pieces with its truncation radii (section 5 "Projection", Figure 3).
#include "math/dual_basis.h"

#include <algorithm>
#include <cmath>

#include "math/bspline.h"
#include "math/check.h"

namespace mbr {

std::vector<double> gram_sequence(int m) {
    MBR_CHECK(m >= 1);
    std::vector<double> gamma(m);
    for (int n = 0; n < m; ++n) gamma[n] = bspline(2 * m, m + n);  // N_{2m}(m + n)
    return gamma;
}

namespace {

/// Central column of the inverse of M_{m;K} = [gamma_{k-l}], -K <= k, l <= K, by a banded
/// Cholesky factorisation (bandwidth m - 1) and one solve with the unit vector e_0.
std::vector<double> central_column_of_inverse(const std::vector<double>& gamma, int K) {
    const int n = 2 * K + 1;
    const int bw = static_cast<int>(gamma.size()) - 1;
    // L stored by diagonals: Ld[i][d] = L(i, i - d), d = 0..bw.
    std::vector<double> Ld(size_t(n) * (bw + 1), 0.0);
    auto L = [&](int i, int d) -> double& { return Ld[size_t(i) * (bw + 1) + d]; };
    for (int i = 0; i < n; ++i) {
        for (int d = std::min(bw, i); d >= 0; --d) {
            int j = i - d;  // column
            double sum = gamma[d];
            for (int k = std::max(0, i - bw); k < j; ++k) sum -= L(i, i - k) * L(j, j - k);
            if (d == 0) {
                MBR_CHECK_MSG(sum > 0, "Gram matrix not positive definite at row " << i);
                L(i, 0) = std::sqrt(sum);
            } else {
                L(i, d) = sum / L(j, 0);
            }
        }
    }
    // Solve L y = e_K, then L^T x = y.
    std::vector<double> x(n, 0.0);
    for (int i = 0; i < n; ++i) {
        double sum = (i == K) ? 1.0 : 0.0;
        for (int k = std::max(0, i - bw); k < i; ++k) sum -= L(i, i - k) * x[k];
        x[i] = sum / L(i, 0);
    }
    for (int i = n - 1; i >= 0; --i) {
        double sum = x[i];
        for (int k = i + 1; k <= std::min(n - 1, i + bw); ++k) sum -= L(k, k - i) * x[k];
        x[i] = sum / L(i, 0);
    }
    return x;
}

/// The polynomial pieces of N_m in the power basis of t: piece[o][c] is the coefficient of t^c
/// in N_m(t + o), t in [0, 1), o = 0..m-1. Built by the Cox-de Boor recursion on polynomials.
std::vector<std::vector<double>> bspline_pieces(int m) {
    std::vector<std::vector<double>> piece{{1.0}};  // N_1(t) = 1 on [0, 1)
    for (int q = 1; q < m; ++q) {
        // N_{q+1}(t + o) = ((t + o) N_q(t + o) + (q + 1 - t - o) N_q(t + o - 1)) / q.
        std::vector<std::vector<double>> next(q + 1, std::vector<double>(q + 1, 0.0));
        for (int o = 0; o <= q; ++o) {
            if (o < q)
                for (int c = 0; c < q; ++c) {  // (t + o) * piece[o]
                    next[o][c + 1] += piece[o][c] / q;
                    next[o][c] += o * piece[o][c] / q;
                }
            if (o >= 1)
                for (int c = 0; c < q; ++c) {  // (q + 1 - o - t) * piece[o - 1]
                    next[o][c] += (q + 1 - o) * piece[o - 1][c] / q;
                    next[o][c + 1] -= piece[o - 1][c] / q;
                }
        }
        piece = std::move(next);
    }
    return piece;
}

/// Largest |p(t)| over 17 equally spaced t in [lo, hi] (0 <= lo <= hi <= 1) for the piece
/// p(t) = sum_k c[k] t^k of degree m - 1. With upper_bound, adds the largest possible excess of
/// the true maximum over the samples: at an interior maximum t* of |p|, p'(t*) = 0, so at the
/// nearest sample (within h/2) |p| is smaller by at most max|p''| (h/2)^2 / 2, and on [0, 1]
/// max|p''| <= sum_k k (k-1) |c_k|. (A first-derivative margin, h/2 max|p'|, is far looser:
/// it inflated max|DN_4| by 42% and made the radii too small.)
double piece_max_abs(const double* c, int m, double lo, double hi, bool upper_bound) {
    const int samples = 16;
    const double h = (hi - lo) / samples;
    double best = 0;
    for (int s = 0; s <= samples; ++s) {
        double t = lo + s * h, v = c[m - 1];
        for (int k = m - 2; k >= 0; --k) v = v * t + c[k];  // Horner
        best = std::max(best, std::fabs(v));
    }
    if (upper_bound) {
        double d2bound = 0;
        for (int k = 2; k < m; ++k) d2bound += k * (k - 1) * std::fabs(c[k]);
        best += 0.125 * h * h * d2bound;
    }
    return best;
}

}  // namespace

DualCoefficients dual_coefficients(int m, int N, double eps) {
    MBR_CHECK_MSG(m >= 2, "the dual basis needs m >= 2, got " << m);
    MBR_CHECK(N >= 0 && eps > 0);
    const std::vector<double> gamma = gram_sequence(m);
    DualCoefficients result;
    result.m = m;
    auto central_row = [&](int K) {
        std::vector<double> col = central_column_of_inverse(gamma, K);
        return std::vector<double>(col.begin() + K, col.begin() + K + N + 1);  // l = 0..N
    };
    // M_{m;N}, M_{m;N+1}, ... until two successive central rows agree within eps (appendix).
    int K = N;
    std::vector<double> prev = central_row(K);
    result.n_matrices = 1;
    const int max_K = 4 * N + 400;  // rounding stops the changes long before this
    for (;;) {
        ++K;
        std::vector<double> cur = central_row(K);
        ++result.n_matrices;
        double change = 0;
        for (int l = 0; l <= N; ++l) change = std::max(change, std::fabs(cur[l] - prev[l]));
        prev = std::move(cur);
        result.last_change = change;
        if (change < eps || K >= max_K) break;
    }
    result.mu = std::move(prev);
    result.final_half_width = K;
    return result;
}

double dual_basis(int m, const std::vector<double>& mu, double x) {
    // Eq. (32) with k = 0: DN_m(x) = sum_l mu_l N_m(x - l).
    const int L = static_cast<int>(mu.size()) - 1;
    double sum = 0;
    for (int l = -L; l <= L; ++l) sum += mu[std::abs(l)] * bspline(m, x - l);
    return sum;
}

DualTable::DualTable(int m, double tail_eps) : m_(m) {
    MBR_CHECK_MSG(m >= 2 && m <= 20, "order m = " << m);
    // Grow N until the computed tail is below tail_eps * mu_0.
    DualCoefficients dc;
    int N = 16;
    int L = -1;
    for (;;) {
        dc = dual_coefficients(m, N, 1e-16);
        const double threshold = tail_eps * dc.mu[0];
        for (int l = 0; l <= N; ++l)
            if (std::fabs(dc.mu[l]) < threshold && std::fabs(dc.mu[std::min(l + 1, N)]) < threshold) {
                L = l;
                break;
            }
        if (L >= 0 || N > 4000) break;
        N *= 2;
    }
    if (L < 0) L = N;
    mu_.assign(dc.mu.begin(), dc.mu.begin() + L + 1);
    double dropped = 0;
    for (int l = L + 1; l <= N; ++l) dropped = std::max(dropped, std::fabs(dc.mu[l]));
    error_bound_ = dropped + dc.last_change;

    // Pieces: on [i, i + 1], DN_m(i + t) = sum_{o=0}^{m-1} mu_{i-o} N_m(t + o).
    const std::vector<std::vector<double>> piece = bspline_pieces(m);
    first_ = -L;
    last_ = L + m - 1;
    coef_.assign(size_t(last_ - first_ + 1) * m, 0.0);
    for (int i = first_; i <= last_; ++i)
        for (int o = 0; o < m; ++o) {
            int l = i - o;
            if (std::abs(l) > L) continue;
            for (int c = 0; c < m; ++c) coef_[size_t(i - first_) * m + c] += mu_[std::abs(l)] * piece[o][c];
        }
    // The largest |DN_m| is attained at the fulcrum, which is one of the sample points; the
    // plain sampled maximum (no margin) is therefore exact up to rounding. An upper bound here
    // would raise every relative threshold eps * max_abs_ and shrink the radii below the truth.
    max_abs_ = 0;
    for (int i = static_cast<int>(std::floor(fulcrum() - 1)); i <= static_cast<int>(fulcrum()); ++i)
        max_abs_ = std::max(max_abs_, piece_max_abs(&coef_[size_t(i - first_) * m_], m_, 0, 1,
                                                    /*upper_bound=*/false));

    // Monotone envelope on a 1/16 grid of distances from the fulcrum.
    const int n_env = static_cast<int>(std::ceil(half_width() * 16)) + 1;
    envelope_.assign(n_env + 1, 0.0);
    for (int q = n_env - 1; q >= 0; --q) {
        double a = fulcrum() + q / 16.0, b = fulcrum() + (q + 1) / 16.0;
        envelope_[q] = std::max(envelope_[q + 1], max_abs_on(a, b));  // symmetric: one side
    }
}

double DualTable::operator()(double x) const {
    const double fl = std::floor(x);
    if (fl < first_ || fl > last_) return 0;
    const int i = static_cast<int>(fl);
    const double t = x - fl;
    const double* c = &coef_[size_t(i - first_) * m_];
    double v = c[m_ - 1];
    for (int k = m_ - 2; k >= 0; --k) v = v * t + c[k];  // Horner
    return v;
}

double DualTable::max_abs_on(double a, double b) const {
    if (b < a) std::swap(a, b);
    double best = 0;
    const int i0 = static_cast<int>(std::floor(a)), i1 = static_cast<int>(std::floor(b));
    for (int i = std::max(i0, first_); i <= std::min(i1, last_); ++i) {
        double lo = std::max(a, double(i)) - i, hi = std::min(b, double(i + 1)) - i;
        best = std::max(best, piece_max_abs(&coef_[size_t(i - first_) * m_], m_, lo, hi,
                                            /*upper_bound=*/true));
    }
    return best;
}

double DualTable::truncation_radius(double eps) const {
    const double threshold = eps * max_abs_;
    for (size_t q = 0; q < envelope_.size(); ++q)
        if (envelope_[q] <= threshold) return q / 16.0;
    return half_width();
}

double DualTable::rhombus_radius(double eps) const {
    const double threshold = eps * max_abs_ * max_abs_;
    const int n = static_cast<int>(envelope_.size());
    // Smallest grid index whose envelope is at or below v (the envelope does not increase: a
    // binary search; n - 1 when none is).
    auto first_below = [&](double v) {
        const auto it = std::partition_point(envelope_.begin(), envelope_.end(),
                                             [v](double e) { return e > v; });
        return std::min(static_cast<int>(it - envelope_.begin()), n - 1);
    };
    double r = 0;
    for (int q = 0; q < n; ++q) {
        // Points with |x| in [q/16, (q+1)/16) have |DN(x)| <= envelope_[q]; they can exceed the
        // threshold only where |DN(y)| > threshold / envelope_[q].
        if (envelope_[q] * max_abs_ <= threshold) break;
        int qy = first_below(threshold / envelope_[q]);
        r = std::max(r, (q + 1 + qy) / 16.0);
    }
    return r;
}

double DualTable::eps_for_rhombus_radius(double r) const {
    double lo = -40, hi = 0;  // log10 eps
    for (int it = 0; it < 60; ++it) {
        double mid = 0.5 * (lo + hi);
        if (rhombus_radius(std::pow(10.0, mid)) > r) lo = mid; else hi = mid;
    }
    return std::pow(10.0, hi);
}

}  // namespace mbr
