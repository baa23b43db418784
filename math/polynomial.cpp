// math/polynomial.cpp - tensor polynomial fit to Gauss-Legendre samples and resampling.
#include "math/polynomial.h"

#include <cmath>

#include "math/check.h"

namespace mbr {

double TensorPolynomial::operator()(double x, double y) const {
    double sum = 0;
    for (int i = m - 1; i >= 0; --i) {
        double row = 0;
        for (int j = m - 1; j >= 0; --j) row = row * y + c[size_t(i) * m + j];
        sum = sum * x + row;
    }
    return sum;
}

namespace {

/// Solves the m x m system V c = f for the monomial coefficients of the interpolant through
/// (x_a, f_a): Gaussian elimination with partial pivoting on the Vandermonde matrix.
std::vector<double> solve_vandermonde(const std::vector<double>& x, std::vector<double> f) {
    const int m = static_cast<int>(x.size());
    std::vector<double> V(size_t(m) * m);
    for (int a = 0; a < m; ++a) {
        double p = 1;
        for (int i = 0; i < m; ++i, p *= x[a]) V[size_t(a) * m + i] = p;
    }
    for (int col = 0; col < m; ++col) {
        int piv = col;
        for (int r = col + 1; r < m; ++r)
            if (std::fabs(V[size_t(r) * m + col]) > std::fabs(V[size_t(piv) * m + col])) piv = r;
        if (piv != col) {
            for (int i = 0; i < m; ++i) std::swap(V[size_t(col) * m + i], V[size_t(piv) * m + i]);
            std::swap(f[col], f[piv]);
        }
        for (int r = col + 1; r < m; ++r) {
            double factor = V[size_t(r) * m + col] / V[size_t(col) * m + col];
            for (int i = col; i < m; ++i) V[size_t(r) * m + i] -= factor * V[size_t(col) * m + i];
            f[r] -= factor * f[col];
        }
    }
    std::vector<double> c(m);
    for (int r = m - 1; r >= 0; --r) {
        double sum = f[r];
        for (int i = r + 1; i < m; ++i) sum -= V[size_t(r) * m + i] * c[i];
        c[r] = sum / V[size_t(r) * m + r];
    }
    return c;
}

}  // namespace

TensorPolynomial fit_tensor_polynomial(int m, const std::vector<double>& samples) {
    MBR_CHECK_MSG(samples.size() == size_t(m) * m, "need m x m samples, m = " << m);
    const GaussLegendre rule = gauss_legendre(m);
    // Fit along y for each row a, then along x for each power j: the tensor structure.
    std::vector<double> partial(size_t(m) * m);  // partial[a * m + j]: coefficient of y^j at x_a
    for (int a = 0; a < m; ++a) {
        std::vector<double> row(samples.begin() + size_t(a) * m, samples.begin() + size_t(a + 1) * m);
        std::vector<double> cy = solve_vandermonde(rule.x, row);
        for (int j = 0; j < m; ++j) partial[size_t(a) * m + j] = cy[j];
    }
    TensorPolynomial p;
    p.m = m;
    p.c.assign(size_t(m) * m, 0.0);
    for (int j = 0; j < m; ++j) {
        std::vector<double> column(m);
        for (int a = 0; a < m; ++a) column[a] = partial[size_t(a) * m + j];
        std::vector<double> cx = solve_vandermonde(rule.x, column);
        for (int i = 0; i < m; ++i) p.c[size_t(i) * m + j] = cx[i];
    }
    return p;
}

std::vector<double> lagrange_matrix(const GaussLegendre& rule, const std::vector<double>& points) {
    const int m = rule.n();
    std::vector<double> L(points.size() * m);
    for (size_t p = 0; p < points.size(); ++p)
        for (int a = 0; a < m; ++a) {
            double l = 1;
            for (int b = 0; b < m; ++b)
                if (b != a) l *= (points[p] - rule.x[b]) / (rule.x[a] - rule.x[b]);
            L[p * m + a] = l;
        }
    return L;
}

std::vector<double> subcell_resample_matrix(const GaussLegendre& rule, int levels, int index) {
    const int n_sub = 1 << levels;
    MBR_CHECK(index >= 0 && index < n_sub);
    // Sub-cell `index` of [-1, 1] is [-1 + 2 index / n_sub, -1 + 2 (index + 1) / n_sub].
    std::vector<double> points(rule.n());
    for (int p = 0; p < rule.n(); ++p)
        points[p] = -1 + (2.0 * index + (rule.x[p] + 1)) / n_sub;
    return lagrange_matrix(rule, points);
}

void resample(int m, const double* samples, const double* Rx, const double* Ry, double* out) {
    // tmp = samples * Ry^T (resample along y), then out = Rx * tmp (along x).
    double tmp[16 * 16];
    MBR_CHECK(m <= 16);
    for (int a = 0; a < m; ++a)
        for (int q = 0; q < m; ++q) {
            double sum = 0;
            for (int b = 0; b < m; ++b) sum += samples[a * m + b] * Ry[q * m + b];
            tmp[a * m + q] = sum;
        }
    for (int p = 0; p < m; ++p)
        for (int q = 0; q < m; ++q) {
            double sum = 0;
            for (int a = 0; a < m; ++a) sum += Rx[p * m + a] * tmp[a * m + q];
            out[p * m + q] = sum;
        }
}

}  // namespace mbr
