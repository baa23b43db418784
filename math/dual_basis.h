// math/dual_basis.h - the dual scaling function DN_m of the cardinal B-spline (paper section 3,
// eq. (13), Figure 1, and the appendix, eqs. (30)-(32)).
//
// With the Gram sequence gamma_{m;k,l} = <N_m(. - k), N_m(. - l)> = N_{2m}(m + k - l), the
// inverse matrix [mu_{m;k,l}] gives DN_m(x - k) = sum_l mu_{m;k,l} N_m(x - l) (32). Because
// mu_{m;k,l} = mu_{m;0,l-k}, only the central row mu_l := mu_{m;0,l} is needed; it is symmetric,
// mu_{-l} = mu_l, and decays geometrically. DN_m is then a spline of degree m - 1 with integer
// knots, symmetric about its fulcrum m/2, and <N_m(. - k), DN_m(. - l)> = delta_kl.
#pragma once

#include <vector>

namespace mbr {

/// gamma_n = <N_m, N_m(. - n)> = N_{2m}(m + n) for n = 0..m-1 (zero beyond; gamma_{-n} = gamma_n).
std::vector<double> gram_sequence(int m);

/// The result of the appendix's method.
struct DualCoefficients {
    int m = 0;
    std::vector<double> mu;       // mu[l] = mu_{m;0,l} for l = 0..N (mu_{-l} = mu_l)
    int n_matrices = 0;           // how many matrices M_{m;N}, M_{m;N+1}, ... were inverted
    int final_half_width = 0;     // the half-width N + p of the last matrix
    double last_change = 0;       // max |mu^{N+p+1}_l - mu^{N+p}_l| over |l| <= N at the stop
};

/// The appendix: invert M_{m;N}, M_{m;N+1}, M_{m;N+2}, ... (the (2K+1)^2 sections of the Gram
/// matrix, -K <= k, l <= K) until the central rows of two successive inverses agree within eps
/// for |l| <= N. The central row of M^{-1} is its central column (M is symmetric), found by one
/// banded Cholesky solve per matrix: the same numbers as the full inverse at O(K m^2) cost.
DualCoefficients dual_coefficients(int m, int N, double eps);

/// DN_m(x) by its defining sum (32) over the given coefficients: sum_{|l| <= N} mu_l N_m(x - l).
double dual_basis(int m, const std::vector<double>& mu, double x);

/// DN_m as a table of polynomial pieces: on each interval [i, i + 1] it is a polynomial of
/// degree m - 1, whose m coefficients are precomputed from the mu_l. A look-up is a floor and a
/// Horner evaluation, and introduces no interpolation error: the only error is the truncation
/// of the mu series, bounded by error_bound(). (The paper's "precalculated discrete values",
/// section 5 "Projection"; see docs/method.md.)
class DualTable {
public:
    /// Builds the table of DN_m from mu_{m;0,l} computed to relative accuracy ~1e-16 and kept
    /// while |mu_l| >= tail_eps * mu_0.
    explicit DualTable(int m, double tail_eps = 1e-16);

    int order() const { return m_; }
    /// The fulcrum (centre of symmetry) of DN_m: x = m/2.
    double fulcrum() const { return 0.5 * m_; }
    /// DN_m(x); zero beyond the table (|x - m/2| > half_width()).
    double operator()(double x) const;
    /// The central row used, mu[l] for l = 0..L.
    const std::vector<double>& mu() const { return mu_; }
    /// Half-width of the tabulated support, measured from the fulcrum.
    double half_width() const { return last_ - fulcrum() + 1; }
    /// Largest |DN_m|, attained at the fulcrum (sampled there: exact up to rounding).
    double max_abs() const { return max_abs_; }
    /// Bound on |DN_m(x) - table(x)| for all x: the largest dropped |mu_l| plus the solve's
    /// convergence tolerance (the N_m(x - l) at any x sum to one).
    double error_bound() const { return error_bound_; }
    /// Upper bound of |DN_m| over [a, b] (pieces sampled densely, plus a bound on how far the
    /// true maximum can exceed the samples, from |DN_m''|); used by the truncation radii.
    double max_abs_on(double a, double b) const;

    /// 1D truncation radius for relative eps: the smallest R (a multiple of 1/16) such that
    /// |DN_m(m/2 + x)| <= eps * max|DN_m| for all |x| >= R. In units of the basis scale.
    double truncation_radius(double eps) const;
    /// 2D rhombus radius (section 5 "Projection", Figure 3; DESIGN.md section 3 stage 6): an r
    /// such that every (x, y) with |DN_m(m/2 + x) DN_m(m/2 + y)| > eps * max|DN_m|^2 satisfies
    /// |x| + |y| <= r. Found from the monotone envelope of |DN_m| on a 1/16 grid.
    double rhombus_radius(double eps) const;
    /// The eps whose rhombus radius is (about) r: inverse of rhombus_radius by bisection.
    double eps_for_rhombus_radius(double r) const;

private:
    int m_;
    std::vector<double> mu_;
    int first_ = 0, last_ = 0;          // pieces cover [first_, last_ + 1)
    std::vector<double> coef_;          // m_ power-basis coefficients in t = x - i per piece
    double max_abs_ = 0;
    double error_bound_ = 0;
    std::vector<double> envelope_;      // envelope_[q] = max |DN| over |x - m/2| >= q / 16
};

}  // namespace mbr
