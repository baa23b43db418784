// math/bspline.h - cardinal B-splines and their two-scale structure (paper section 3,
// eqs. (14)-(18)). Order m means degree m-1; N_m is supported on [0, m] and its integer
// translates sum to one. Every routine takes m at run time (DESIGN.md section 2).
//
// A coefficient sequence at level j stands for f(s) = sum_k a_k N_m(2^j s - k): knot spacing
// 2^-j on the parameter axis. The basis functions that touch [0,1] have k in
// [-(m-1), 2^j - 1], 2^j + m - 1 of them.
#pragma once

#include <ostream>
#include <vector>

namespace mbr {

/// N_m(x), the cardinal B-spline of order m >= 1 (Cox-de Boor recursion). Zero outside [0, m);
/// N_1 is the indicator of [0, 1).
double bspline(int m, double x);

/// The r-th derivative of N_m at x, by N_m' = N_{m-1}(x) - N_{m-1}(x - 1) applied r times.
/// Defined for r <= m - 2 everywhere and for r = m - 1 away from the integers.
double bspline_derivative(int m, int r, double x);

/// The m values N_m(x - k) that can be non-zero at x, for k = first .. first + m - 1 with
/// first = floor(x) - m + 1; written to values[0..m-1]. Returns first. The hot-loop form.
int bspline_values(int m, double x, double* values);

/// Two-scale mask of eq. (14): p_{m,k} = 2^{1-m} binom(m, k), k = 0..m.
std::vector<double> two_scale_mask(int m);

/// omega_{m,k} = N_m(k) for k = 0..m, the weights of the dyadic evaluation (18).
std::vector<double> integer_values(int m);

/// Coefficients a_k of f(s) = sum_k a_k N_m(2^level s - k), k = first .. first + a.size() - 1.
struct CoefficientRow {
    int level = 0;
    int first = 0;
    std::vector<double> a;
    int last() const { return first + static_cast<int>(a.size()) - 1; }
    /// a_k, or zero outside the stored range.
    double at(int k) const;
};
std::ostream& operator<<(std::ostream& os, const CoefficientRow& row);

/// Coefficients of f(s, t) = sum_{k,l} a_{k,l} N_m(2^level s - k) N_m(2^level t - l),
/// stored row-major with k (the s index) slowest: a[(k - first_k) * n_l + (l - first_l)].
struct CoefficientGrid {
    int level = 0;
    int first_k = 0, first_l = 0;
    int n_k = 0, n_l = 0;
    std::vector<double> a;

    CoefficientGrid() = default;
    CoefficientGrid(int level, int first_k, int first_l, int n_k, int n_l, double value = 0)
        : level(level), first_k(first_k), first_l(first_l), n_k(n_k), n_l(n_l),
          a(static_cast<size_t>(n_k) * n_l, value) {}
    double& operator()(int k, int l) { return a[size_t(k - first_k) * n_l + (l - first_l)]; }
    double operator()(int k, int l) const { return a[size_t(k - first_k) * n_l + (l - first_l)]; }
    bool contains(int k, int l) const {
        return k >= first_k && k < first_k + n_k && l >= first_l && l < first_l + n_l;
    }
};

/// The range of basis indices k at `level` whose support meets [0,1]: [-(m-1), 2^level - 1].
int first_touching_index(int m);
int touching_count(int m, int level);

/// A row or grid covering exactly the basis functions that touch [0,1] (or [0,1]^2).
CoefficientRow touching_row(int m, int level, double value = 0);
CoefficientGrid touching_grid(int m, int level, double value = 0);

/// Eq. (17): the same function one level finer, a_fine[l] = sum_k p_{m,l-2k} a_coarse[k].
/// The result holds every fine coefficient the coarse row feeds (2 n + m - 1 of them).
CoefficientRow refine(int m, const CoefficientRow& coarse);
/// Eq. (17) in both directions (tensor product of the 1D rule).
CoefficientGrid refine(int m, const CoefficientGrid& coarse);
/// Refine, then keep only the basis functions that touch [0,1] (or [0,1]^2) at the new level.
CoefficientRow refine_touching(int m, const CoefficientRow& coarse);
CoefficientGrid refine_touching(int m, const CoefficientGrid& coarse);

/// Eq. (15)/(20): f(s) = sum_k a_k N_m(2^level s - k).
double evaluate(int m, const CoefficientRow& row, double s);
/// Eq. (20) in 2D.
double evaluate(int m, const CoefficientGrid& grid, double s, double t);

/// Eq. (18): the values f(i / 2^j1) of the level-j0 function `row`, j1 >= row.level, obtained by
/// refining to level j1 with (17) and convolving with omega_{m,k} = N_m(k). Returns the values
/// for i = first_i .. first_i + size - 1, where first_i is written to *first_i; every dyadic point
/// where f can be non-zero is included.
std::vector<double> dyadic_values(int m, const CoefficientRow& row, int j1, int* first_i);

}  // namespace mbr
