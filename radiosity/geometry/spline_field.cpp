// radiosity/geometry/spline_field.cpp - storage, evaluation (20), refinement (17), coarsening (11),
// superposition and integration of a surface's radiosity coefficients.
#include "radiosity/geometry/spline_field.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/simd.h"
#include "math/wavelet.h"

namespace mbr {

SplineField::SplineField(int m, int level) : m_(m), level_(level) {
    MBR_CHECK_MSG(m >= 2 && m <= 16 && level >= 0 && level <= 20, "m = " << m << ", j = " << level);
    for (auto& g : grid_) g = touching_grid(m, level);
}

SplineField SplineField::constant(int m, int level, Rgb value) {
    SplineField f(m, level);
    for (int c = 0; c < 3; ++c) std::fill(f.grid_[c].a.begin(), f.grid_[c].a.end(), value[c]);
    return f;
}

Rgb SplineField::coefficient(int k, int l) const {
    return {grid_[0](k, l), grid_[1](k, l), grid_[2](k, l)};
}

void SplineField::set_coefficient(int k, int l, Rgb value) {
    for (int c = 0; c < 3; ++c) grid_[c](k, l) = value[c];
}

Rgb SplineField::evaluate(double s, double t) const {
    // Eq. (20) with the m x m basis functions that are non-zero at (s, t).
    double bs[16], bt[16];
    const int fk = bspline_values(m_, std::ldexp(s, level_), bs);
    const int fl = bspline_values(m_, std::ldexp(t, level_), bt);
    const CoefficientGrid& g0 = grid_[0];
    Rgb sum;
    for (int i = 0; i < m_; ++i) {
        const int k = fk + i;
        if (k < g0.first_k || k >= g0.first_k + g0.n_k || bs[i] == 0) continue;
        Rgb row;
        for (int j = 0; j < m_; ++j) {
            const int l = fl + j;
            if (l < g0.first_l || l >= g0.first_l + g0.n_l) continue;
            row += bt[j] * coefficient(k, l);
        }
        sum += bs[i] * row;
    }
    return sum;
}

void SplineField::evaluate_grid(const double* s, int n_s, const double* t, int n_t,
                                Rgb* out) const {
    MBR_CHECK(n_t >= 1 && n_s >= 0);
    const CoefficientGrid& g0 = grid_[0];
    double bs[16];
    // The m B-spline values at every t: on the stack for the quadrature's small grids, on the
    // heap for large ones (a 1024-column grid of an error check).
    constexpr int n_small = 64;
    double bt_small[n_small * 16];
    int fl_small[n_small];
    std::vector<double> bt_large;
    std::vector<int> fl_large;
    double* bt = bt_small;
    int* fl = fl_small;
    if (n_t > n_small) {
        bt_large.resize(size_t(n_t) * 16);
        fl_large.resize(size_t(n_t));
        bt = bt_large.data();
        fl = fl_large.data();
    }
    for (int b = 0; b < n_t; ++b)
        fl[b] = bspline_values(m_, std::ldexp(t[b], level_), &bt[size_t(b) * 16]);
    // The l needed by any t: one row of that many sums per s (any level: no fixed bound).
    int l_lo = fl[0], l_hi = fl[0];
    for (int b = 1; b < n_t; ++b) {
        l_lo = std::min(l_lo, fl[b]);
        l_hi = std::max(l_hi, fl[b]);
    }
    l_hi += m_ - 1;
    Rgb small[96];
    std::vector<Rgb> large;
    Rgb* row = small;
    if (l_hi - l_lo + 1 > 96) {
        large.resize(size_t(l_hi - l_lo + 1));
        row = large.data();
    }
    for (int a = 0; a < n_s; ++a) {
        const int fk = bspline_values(m_, std::ldexp(s[a], level_), bs);
        // row[l] = sum_k c_{k,l} N_m(2^j s_a - k) over the m values of k, for every l needed.
        for (int l = l_lo; l <= l_hi; ++l) {
            Rgb sum;
            if (l >= g0.first_l && l < g0.first_l + g0.n_l)
                for (int i = 0; i < m_; ++i) {
                    const int k = fk + i;
                    if (k >= g0.first_k && k < g0.first_k + g0.n_k)
                        sum += bs[i] * coefficient(k, l);
                }
            row[l - l_lo] = sum;
        }
        for (int b = 0; b < n_t; ++b) {
            Rgb v;
            const double* w = &bt[size_t(b) * 16];
            for (int j = 0; j < m_; ++j) v += w[j] * row[fl[b] + j - l_lo];
            out[a * n_t + b] = v;
        }
    }
}

MBR_VECTOR_CLONES
Rgb horner_patch_m4(const double* C, double lx, double ly) {
    // PolynomialPatches::horner_cell for m = 4, its operations in its order, lane by lane.
    typedef double Lanes __attribute__((vector_size(4 * sizeof(double))));
    constexpr int m = 4, lanes = PolynomialPatches::lanes;
    const Lanes X = {lx, lx, lx, lx}, Y = {ly, ly, ly, ly};
    Lanes row_value[m];  // the polynomial in y of x^p's coefficients, at ly
    for (int p = 0; p < m; ++p) {
        const double* row = C + p * m * lanes;
        Lanes r, c;
        std::memcpy(&r, row + (m - 1) * lanes, sizeof r);
        for (int q = m - 2; q >= 0; --q) {
            std::memcpy(&c, row + q * lanes, sizeof c);
            r = r * Y + c;
        }
        row_value[p] = r;
    }
    Lanes v = row_value[m - 1];
    for (int p = m - 2; p >= 0; --p) v = v * X + row_value[p];
    return {v[0], v[1], v[2]};
}

PolynomialPatches::PolynomialPatches(const SplineField& field) {
    if (field.empty()) return;
    const int m = m_ = field.order();
    const int level = field.level();
    cells_ = 1 << level;
    // The m pieces of N_m as polynomials on [0,1): P_r(x) = N_m(x + r) = sum_p P[r][p] x^p, by
    // interpolation at m points (exact: each piece has degree m - 1).
    std::vector<double> P(size_t(m) * m);
    {
        std::vector<double> V(size_t(m) * m), rhs(m);
        for (int r = 0; r < m; ++r) {
            for (int a = 0; a < m; ++a) {
                const double x = (a + 0.5) / m;
                double power = 1;
                for (int p = 0; p < m; ++p, power *= x) V[size_t(a) * m + p] = power;
                rhs[a] = bspline(m, x + r);
            }
            // Gaussian elimination with partial pivoting on the small Vandermonde system.
            std::vector<double> A = V, b = rhs;
            for (int col = 0; col < m; ++col) {
                int piv = col;
                for (int row = col + 1; row < m; ++row)
                    if (std::fabs(A[size_t(row) * m + col]) > std::fabs(A[size_t(piv) * m + col]))
                        piv = row;
                for (int k = 0; k < m; ++k)
                    std::swap(A[size_t(col) * m + k], A[size_t(piv) * m + k]);
                std::swap(b[col], b[piv]);
                for (int row = col + 1; row < m; ++row) {
                    const double f = A[size_t(row) * m + col] / A[size_t(col) * m + col];
                    for (int k = col; k < m; ++k)
                        A[size_t(row) * m + k] -= f * A[size_t(col) * m + k];
                    b[row] -= f * b[col];
                }
            }
            for (int row = m - 1; row >= 0; --row) {
                double s = b[row];
                for (int k = row + 1; k < m; ++k)
                    s -= A[size_t(row) * m + k] * P[size_t(r) * m + k];
                P[size_t(r) * m + row] = s / A[size_t(row) * m + row];
            }
        }
    }
    // Cell (i, j): basis k = i - r (r = 0 .. m-1) is P_r there; C[p][q] = sum c_{i-r, j-r'}
    // P[r][p] P[r'][q].
    c_.assign(size_t(cells_) * cells_ * lanes * m * m, 0.0);
    for (int j = 0; j < cells_; ++j)
        for (int i = 0; i < cells_; ++i)
            for (int ch = 0; ch < 3; ++ch) {
                double* C = &c_[(size_t(j) * cells_ + i) * lanes * m * m];
                for (int r = 0; r < m; ++r)
                    for (int r2 = 0; r2 < m; ++r2) {
                        const double a = field.coefficient(i - r, j - r2)[ch];
                        if (a == 0) continue;
                        for (int p = 0; p < m; ++p)
                            for (int q = 0; q < m; ++q)
                                C[(p * m + q) * lanes + ch] +=
                                    a * P[size_t(r) * m + p] * P[size_t(r2) * m + q];
                    }
            }
}

bool SplineField::is_constant() const {
    for (const auto& g : grid_)
        for (double v : g.a)
            if (v != g.a.front()) return false;
    return true;
}

SplineField SplineField::refined_to(int level) const {
    MBR_CHECK(level >= level_);
    SplineField f = *this;
    while (f.level_ < level) {
        for (auto& g : f.grid_) g = refine_touching(m_, g);  // eq. (17)
        ++f.level_;
    }
    return f;
}

SplineField SplineField::coarsened_to(int level) const {
    MBR_CHECK(level >= 0 && level <= level_);
    SplineField f = *this;
    while (f.level_ > level) {
        for (auto& g : f.grid_) g = coarsen(m_, g);  // orthogonal projection, eq. (11)
        --f.level_;
    }
    return f;
}

void SplineField::add(const SplineField& other) {
    if (other.empty()) return;
    if (empty()) {
        *this = other;
        return;
    }
    MBR_CHECK_MSG(other.m_ == m_, "orders differ: " << m_ << " and " << other.m_);
    if (other.level_ > level_) *this = refined_to(other.level_);
    const SplineField& o = other.level_ < level_ ? other.refined_to(level_) : other;
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < grid_[c].a.size(); ++i) grid_[c].a[i] += o.grid_[c].a[i];
}

void SplineField::scale(double s) {
    for (auto& g : grid_)
        for (double& v : g.a) v *= s;
}

Rgb SplineField::integrate() const {
    // int_0^1 N_m(2^j s - k) ds for every touching k, by m-point Gauss-Legendre per level-j cell
    // (exact: the integrand is a polynomial of degree m - 1 on each cell).
    const GaussLegendre rule = gauss_legendre(m_);
    const int first = first_touching_index(m_), n = touching_count(m_, level_);
    const int cells = 1 << level_;
    std::vector<double> I(n, 0.0);
    double b[16];
    for (int cell = 0; cell < cells; ++cell)
        for (int q = 0; q < m_; ++q) {
            const double s = (cell + 0.5 * (rule.x[q] + 1)) / cells;
            const int fk = bspline_values(m_, std::ldexp(s, level_), b);
            for (int i = 0; i < m_; ++i) {
                const int idx = fk + i - first;
                if (idx >= 0 && idx < n) I[idx] += rule.w[q] * 0.5 / cells * b[i];
            }
        }
    Rgb sum;
    for (int k = 0; k < n; ++k)
        for (int l = 0; l < n; ++l) sum += (I[k] * I[l]) * coefficient(first + k, first + l);
    return sum;
}

Rgb SplineField::integrate_weighted(const std::function<double(double, double)>& w, int n) const {
    const GaussLegendre rule = gauss_legendre(n);
    const int cells = 1 << level_;
    Rgb sum;
    for (int ci = 0; ci < cells; ++ci)
        for (int cj = 0; cj < cells; ++cj) {
            Rect r{double(ci) / cells, double(ci + 1) / cells, double(cj) / cells,
                   double(cj + 1) / cells};
            sum +=
                integrate_2d([&](double s, double t) { return w(s, t) * evaluate(s, t); }, r, rule);
        }
    return sum;
}

double SplineField::max_abs_coefficient() const {
    double best = 0;
    for (const auto& g : grid_)
        for (double v : g.a) best = std::max(best, std::fabs(v));
    return best;
}

}  // namespace mbr
