// math/bspline.cpp - cardinal B-splines, the two-scale relation (14), refinement (17) and the
// dyadic evaluation (18) of paper section 3.
#include "math/bspline.h"

#include <cmath>

#include "math/check.h"

namespace mbr {

double bspline(int m, double x) {
    MBR_CHECK_MSG(m >= 1, "order m = " << m);
    if (!(x >= 0 && x < m)) return 0;
    double values[64];
    MBR_CHECK_MSG(m <= 64, "order m = " << m);
    int first = bspline_values(m, x, values);
    // N_m(x) is the value for k = 0.
    return values[-first];
}

double bspline_derivative(int m, int r, double x) {
    MBR_CHECK(r >= 0 && r < m);
    if (r == 0) return bspline(m, x);
    // N_m^{(r)}(x) = sum_i (-1)^i binom(r, i) N_{m-r}(x - i).
    double sum = 0, binom = 1;
    for (int i = 0; i <= r; ++i) {
        sum += ((i % 2) ? -binom : binom) * bspline(m - r, x - i);
        binom = binom * (r - i) / (i + 1);
    }
    return sum;
}

int bspline_values(int m, double x, double* values) {
    // Cox-de Boor on the integer knots: with i = floor(x) and t = x - i, the order-q values
    // N_q(t + o), o = 0..q-1, follow from the order q-1 ones by
    //   N_q(t + o) = ((t + o) N_{q-1}(t + o) + (q - t - o) N_{q-1}(t + o - 1)) / (q - 1).
    const double fl = std::floor(x);
    const int i = static_cast<int>(fl);
    const double t = x - fl;
    // b[o] holds N_q(t + o); stored reversed into values at the end.
    double b[64];
    MBR_CHECK_MSG(m >= 1 && m <= 64, "order m = " << m);
    b[0] = 1;
    for (int q = 2; q <= m; ++q) {
        double inv = 1.0 / (q - 1);
        b[q - 1] = 0;
        for (int o = q - 1; o >= 0; --o) {
            double left = (t + o) * b[o];                       // (t+o) N_{q-1}(t+o)
            double right = o > 0 ? (q - t - o) * b[o - 1] : 0;  // (q-t-o) N_{q-1}(t+o-1)
            b[o] = (left + right) * inv;
        }
    }
    // N_m(x - k) with k = i - o: k ascending means o descending.
    for (int o = 0; o < m; ++o) values[m - 1 - o] = b[o];
    return i - m + 1;
}

std::vector<double> two_scale_mask(int m) {
    MBR_CHECK(m >= 1);
    std::vector<double> p(m + 1);
    double binom = 1, scale = std::ldexp(1.0, 1 - m);  // 2^{1-m}
    for (int k = 0; k <= m; ++k) {
        p[k] = scale * binom;  // eq. (14)
        binom = binom * (m - k) / (k + 1);
    }
    return p;
}

std::vector<double> integer_values(int m) {
    std::vector<double> omega(m + 1);
    for (int k = 0; k <= m; ++k) omega[k] = bspline(m, k);
    return omega;
}

double CoefficientRow::at(int k) const {
    return (k >= first && k <= last()) ? a[k - first] : 0.0;
}

std::ostream& operator<<(std::ostream& os, const CoefficientRow& row) {
    os << "level " << row.level << ", k from " << row.first << ": [";
    for (size_t i = 0; i < row.a.size(); ++i) os << (i ? ", " : "") << row.a[i];
    return os << ']';
}

int first_touching_index(int m) { return -(m - 1); }
int touching_count(int m, int level) { return (1 << level) + m - 1; }

CoefficientRow touching_row(int m, int level, double value) {
    CoefficientRow row;
    row.level = level;
    row.first = first_touching_index(m);
    row.a.assign(touching_count(m, level), value);
    return row;
}

CoefficientGrid touching_grid(int m, int level, double value) {
    int n = touching_count(m, level), first = first_touching_index(m);
    return CoefficientGrid(level, first, first, n, n, value);
}

CoefficientRow refine(int m, const CoefficientRow& coarse) {
    const std::vector<double> p_mk = two_scale_mask(m);
    const int n_coarse = static_cast<int>(coarse.a.size());
    CoefficientRow fine;
    fine.level = coarse.level + 1;
    fine.first = 2 * coarse.first;
    fine.a.assign(n_coarse > 0 ? 2 * (n_coarse - 1) + m + 1 : 0, 0.0);
    // Eq. (17) scattered: coarse coefficient k feeds fine l = 2k + i with weight p_{m,i}.
    for (int k = 0; k < n_coarse; ++k)
        for (int i = 0; i <= m; ++i) fine.a[2 * k + i] += p_mk[i] * coarse.a[k];
    return fine;
}

namespace {

/// Applies the 1D refinement (17) along one axis of a grid.
CoefficientGrid refine_axis(int m, const CoefficientGrid& g, bool along_k) {
    const std::vector<double> p_mk = two_scale_mask(m);
    CoefficientGrid out;
    out.level = g.level;  // the caller sets the level once both axes are done
    if (along_k) {
        out = CoefficientGrid(g.level, 2 * g.first_k, g.first_l, 2 * (g.n_k - 1) + m + 1, g.n_l);
        for (int k = 0; k < g.n_k; ++k)
            for (int i = 0; i <= m; ++i)
                for (int l = 0; l < g.n_l; ++l)
                    out.a[size_t(2 * k + i) * out.n_l + l] += p_mk[i] * g.a[size_t(k) * g.n_l + l];
    } else {
        out = CoefficientGrid(g.level, g.first_k, 2 * g.first_l, g.n_k, 2 * (g.n_l - 1) + m + 1);
        for (int k = 0; k < g.n_k; ++k)
            for (int l = 0; l < g.n_l; ++l) {
                double c = g.a[size_t(k) * g.n_l + l];
                for (int i = 0; i <= m; ++i) out.a[size_t(k) * out.n_l + 2 * l + i] += p_mk[i] * c;
            }
    }
    return out;
}

}  // namespace

CoefficientGrid refine(int m, const CoefficientGrid& coarse) {
    if (coarse.n_k == 0 || coarse.n_l == 0) {
        CoefficientGrid empty = coarse;
        empty.level = coarse.level + 1;
        return empty;
    }
    CoefficientGrid fine = refine_axis(m, refine_axis(m, coarse, true), false);
    fine.level = coarse.level + 1;
    return fine;
}

CoefficientRow refine_touching(int m, const CoefficientRow& coarse) {
    CoefficientRow fine = refine(m, coarse);
    CoefficientRow out = touching_row(m, fine.level);
    for (int k = out.first; k <= out.last(); ++k) out.a[k - out.first] = fine.at(k);
    return out;
}

CoefficientGrid refine_touching(int m, const CoefficientGrid& coarse) {
    CoefficientGrid fine = refine(m, coarse);
    CoefficientGrid out = touching_grid(m, fine.level);
    for (int k = out.first_k; k < out.first_k + out.n_k; ++k)
        for (int l = out.first_l; l < out.first_l + out.n_l; ++l)
            if (fine.contains(k, l)) out(k, l) = fine(k, l);
    return out;
}

double evaluate(int m, const CoefficientRow& row, double s) {
    double values[64];
    MBR_CHECK(m <= 64);
    const double x = std::ldexp(s, row.level);
    const int first = bspline_values(m, x, values);
    double sum = 0;
    for (int i = 0; i < m; ++i) sum += values[i] * row.at(first + i);
    return sum;
}

double evaluate(int m, const CoefficientGrid& grid, double s, double t) {
    double bs[64], bt[64];
    MBR_CHECK(m <= 64);
    const int fk = bspline_values(m, std::ldexp(s, grid.level), bs);
    const int fl = bspline_values(m, std::ldexp(t, grid.level), bt);
    double sum = 0;
    for (int i = 0; i < m; ++i) {
        int k = fk + i;
        if (k < grid.first_k || k >= grid.first_k + grid.n_k) continue;
        double row = 0;
        for (int j = 0; j < m; ++j) {
            int l = fl + j;
            if (l < grid.first_l || l >= grid.first_l + grid.n_l) continue;
            row += bt[j] * grid(k, l);
        }
        sum += bs[i] * row;
    }
    return sum;
}

std::vector<double> dyadic_values(int m, const CoefficientRow& row, int j1, int* first_i) {
    MBR_CHECK(j1 >= row.level);
    CoefficientRow fine = row;
    while (fine.level < j1) fine = refine(m, fine);  // (17) applied recursively
    const std::vector<double> omega = integer_values(m);
    // Eq. (18): f(i / 2^j1) = sum_l omega_{m, i-l} a_l, omega non-zero for i - l in d0..m-1:
    // d0 = 1 for m >= 2 (N_m(0) = 0), but d0 = 0 for m = 1 (N_1 is the indicator of [0, 1)).
    const int d0 = (m == 1) ? 0 : 1;
    const int first = fine.first + d0;
    const int count = static_cast<int>(fine.a.size()) + m - 1 - d0;
    std::vector<double> values(std::max(count, 0), 0.0);
    for (int idx = 0; idx < count; ++idx) {
        int i = first + idx;
        double sum = 0;
        for (int d = d0; d <= m - 1; ++d) sum += omega[d] * fine.at(i - d);
        values[idx] = sum;
    }
    if (first_i) *first_i = first;
    return values;
}

}  // namespace mbr
