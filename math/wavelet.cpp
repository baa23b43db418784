// math/wavelet.cpp - orthogonal projection V_j -> V_{j-1} on the parameter interval (eq. (11)).
#include "math/wavelet.h"

#include <cmath>

#include "math/check.h"
#include "math/gauss_legendre.h"

namespace mbr {

namespace {

/// The 1D projection as a dense matrix P (n_coarse x n_fine): c = P a.
struct Projection1D {
    int n_coarse = 0, n_fine = 0;
    std::vector<double> P;
};

/// Exact integrals over [0,1] of products of level-(j-1) and level-j basis functions that touch
/// it, by m-point Gauss-Legendre on each level-j cell (the products are polynomials of degree
/// 2m - 2 there).
Projection1D projection_matrix(int m, int j) {
    MBR_CHECK_MSG(j >= 1, "cannot coarsen below level 0");
    const int first = first_touching_index(m);
    const int nc = touching_count(m, j - 1), nf = touching_count(m, j);
    std::vector<double> G(size_t(nc) * nc, 0.0), C(size_t(nc) * nf, 0.0);
    const GaussLegendre rule = gauss_legendre(m);
    const int cells = 1 << j;
    std::vector<double> bc(m), bf(m);
    for (int cell = 0; cell < cells; ++cell)
        for (int q = 0; q < m; ++q) {
            const double s = (cell + 0.5 * (rule.x[q] + 1)) / cells;
            const double w = rule.w[q] * 0.5 / cells;
            const int kc = bspline_values(m, std::ldexp(s, j - 1), bc.data());
            const int kf = bspline_values(m, std::ldexp(s, j), bf.data());
            for (int a = 0; a < m; ++a) {
                const int ia = kc + a - first;
                if (ia < 0 || ia >= nc) continue;
                for (int b = 0; b < m; ++b) {
                    const int ib = kc + b - first;
                    if (ib >= 0 && ib < nc) G[size_t(ia) * nc + ib] += w * bc[a] * bc[b];
                    const int jf = kf + b - first;
                    if (jf >= 0 && jf < nf) C[size_t(ia) * nf + jf] += w * bc[a] * bf[b];
                }
            }
        }
    // P = G^{-1} C by Gaussian elimination with partial pivoting (G is small and SPD).
    Projection1D proj;
    proj.n_coarse = nc;
    proj.n_fine = nf;
    proj.P = C;
    for (int col = 0; col < nc; ++col) {
        int piv = col;
        for (int r = col + 1; r < nc; ++r)
            if (std::fabs(G[size_t(r) * nc + col]) > std::fabs(G[size_t(piv) * nc + col])) piv = r;
        if (piv != col) {
            for (int i = 0; i < nc; ++i) std::swap(G[size_t(col) * nc + i], G[size_t(piv) * nc + i]);
            for (int i = 0; i < nf; ++i) std::swap(proj.P[size_t(col) * nf + i], proj.P[size_t(piv) * nf + i]);
        }
        for (int r = 0; r < nc; ++r) {
            if (r == col) continue;
            double f = G[size_t(r) * nc + col] / G[size_t(col) * nc + col];
            if (f == 0) continue;
            for (int i = 0; i < nc; ++i) G[size_t(r) * nc + i] -= f * G[size_t(col) * nc + i];
            for (int i = 0; i < nf; ++i) proj.P[size_t(r) * nf + i] -= f * proj.P[size_t(col) * nf + i];
        }
    }
    for (int r = 0; r < nc; ++r) {
        double d = G[size_t(r) * nc + r];
        for (int i = 0; i < nf; ++i) proj.P[size_t(r) * nf + i] /= d;
    }
    return proj;
}

}  // namespace

CoefficientRow coarsen(int m, const CoefficientRow& fine) {
    MBR_CHECK_MSG(fine.first == first_touching_index(m) &&
                      int(fine.a.size()) == touching_count(m, fine.level),
                  "coarsen expects the touching layout");
    const Projection1D proj = projection_matrix(m, fine.level);
    CoefficientRow coarse = touching_row(m, fine.level - 1);
    for (int r = 0; r < proj.n_coarse; ++r) {
        double sum = 0;
        for (int i = 0; i < proj.n_fine; ++i) sum += proj.P[size_t(r) * proj.n_fine + i] * fine.a[i];
        coarse.a[r] = sum;
    }
    return coarse;
}

CoefficientGrid coarsen(int m, const CoefficientGrid& fine) {
    const int n = touching_count(m, fine.level);
    MBR_CHECK_MSG(fine.first_k == first_touching_index(m) && fine.first_l == fine.first_k &&
                      fine.n_k == n && fine.n_l == n,
                  "coarsen expects the touching layout");
    const Projection1D proj = projection_matrix(m, fine.level);
    const int nc = proj.n_coarse, nf = proj.n_fine;
    // Along t (the second index) for each fine row k, then along s.
    std::vector<double> tmp(size_t(nf) * nc, 0.0);
    for (int k = 0; k < nf; ++k)
        for (int r = 0; r < nc; ++r) {
            double sum = 0;
            for (int i = 0; i < nf; ++i) sum += proj.P[size_t(r) * nf + i] * fine.a[size_t(k) * nf + i];
            tmp[size_t(k) * nc + r] = sum;
        }
    CoefficientGrid coarse = touching_grid(m, fine.level - 1);
    for (int r = 0; r < nc; ++r)
        for (int c = 0; c < nc; ++c) {
            double sum = 0;
            for (int k = 0; k < nf; ++k) sum += proj.P[size_t(r) * nf + k] * tmp[size_t(k) * nc + c];
            coarse.a[size_t(r) * nc + c] = sum;
        }
    return coarse;
}

double squared_norm(int m, const CoefficientRow& row) {
    const GaussLegendre rule = gauss_legendre(m);
    const int cells = 1 << row.level;
    double sum = 0;
    for (int cell = 0; cell < cells; ++cell)
        for (int q = 0; q < m; ++q) {
            double s = (cell + 0.5 * (rule.x[q] + 1)) / cells;
            double f = evaluate(m, row, s);
            sum += rule.w[q] * 0.5 / cells * f * f;
        }
    return sum;
}

}  // namespace mbr
