// radiosity/geometry/spline_field.h - a radiosity distribution on one surface as tensor B-spline
// coefficients at one scale 2^-j (paper sections 4-5: "only projection coefficients are
// stored", "Scale Unification and Superposition"; DESIGN.md sections 2-3).
//
// f(s,t) = sum_{k,l} c_{k,l} N_m(2^j s - k) N_m(2^j t - l) over the (2^j + m - 1)^2 basis
// functions that touch [0,1]^2, one coefficient grid per RGB channel. A constant field has every
// coefficient equal to the constant (the B-splines sum to one).
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <vector>

#include "math/bspline.h"
#include "math/vec3.h"

namespace mbr {

class SplineField {
public:
    SplineField() = default;
    /// The zero field of order m at level j.
    SplineField(int m, int level);
    /// Every coefficient equal to `value`: the constant function `value`.
    static SplineField constant(int m, int level, Rgb value);

    int order() const { return m_; }
    int level() const { return level_; }
    bool empty() const { return m_ == 0; }
    /// Coefficient grid of one channel (0 = red, 1 = green, 2 = blue), touching layout.
    const CoefficientGrid& channel(int c) const { return grid_[c]; }
    CoefficientGrid& channel(int c) { return grid_[c]; }
    /// c_{k,l} for k, l in [-(m-1), 2^j - 1].
    Rgb coefficient(int k, int l) const;
    void set_coefficient(int k, int l, Rgb value);

    /// Eq. (20): the reconstructed value at (s, t) in [0,1]^2.
    Rgb evaluate(double s, double t) const;
    /// Eq. (20) on a tensor grid: out[a * n_t + b] = f(s[a], t[b]). Separable, so it costs
    /// n_s m^2 + n_s n_t m instead of n_s n_t m^2 per channel.
    void evaluate_grid(const double* s, int n_s, const double* t, int n_t, Rgb* out) const;
    /// True when every coefficient of each channel is the same: the field is that constant.
    bool is_constant() const;
    /// The same function at a finer level, by eq. (17).
    SplineField refined_to(int level) const;
    /// The orthogonal projection onto a coarser level (eq. (11), math/wavelet.h): the shooter's
    /// "lower resolution version" of section 6.
    SplineField coarsened_to(int level) const;
    /// Superposition (section 5): this += other, after refining whichever is coarser (17).
    void add(const SplineField& other);
    /// this *= s.
    void scale(double s);
    /// Integral over the parameter domain [0,1]^2 (exact).
    Rgb integrate() const;
    /// Integral of f(s,t) w(s,t) over [0,1]^2 by an n x n Gauss-Legendre rule on every level-j
    /// cell: with w = A this is the power integral of section 4's shooter choice.
    Rgb integrate_weighted(const std::function<double(double, double)>& w, int n) const;
    /// Largest |coefficient| over the three channels.
    double max_abs_coefficient() const;

private:
    int m_ = 0;
    int level_ = 0;
    std::array<CoefficientGrid, 3> grid_;
};

/// Horner's rule in both directions on one cell of a PolynomialPatches of order 4: the 4 x 4
/// coefficients of x^p y^q, each four doubles (r, g, b and a zero), at (lx, ly) in the cell.
/// DESIGN: the four lanes are one vector of the compiler's vector extension, and the function is
/// compiled for AVX2 and the baseline (math/simd.h): 15 multiplications and additions of one
/// 256-bit vector (two 128-bit ones on the baseline) instead of three channels' scalars and
/// pairs; each lane's operations are horner_cell's in its order, so the values are the same to
/// the bit. Alone it did not shorten a shadow triangle's node (the chain's latency is the same);
/// with triangle_value's passes over independent nodes it does (docs/method.md, "A vectorised
/// kernel").
Rgb horner_patch_m4(const double* C, double lx, double ly);

/// The same function as a SplineField, stored per level-j knot cell as m x m tensor polynomials
/// in the cell's own coordinates: for evaluating one field at many scattered points (Horner's
/// rule instead of the B-spline recursion and m^2 coefficient look-ups of evaluate()).
class PolynomialPatches {
public:
    PolynomialPatches() = default;
    explicit PolynomialPatches(const SplineField& field);
    /// f(s, t) for (s, t) clamped to [0,1]^2; equal to SplineField::evaluate up to rounding.
    /// (Inline: the shadow triangles of exact visibility call it at every node.)
    Rgb operator()(double s, double t) const {
        if (c_.empty()) return {};
        const double x = std::clamp(s, 0.0, 1.0) * cells_, y = std::clamp(t, 0.0, 1.0) * cells_;
        const int i = std::min(cells_ - 1, static_cast<int>(x)),
                  j = std::min(cells_ - 1, static_cast<int>(y));
        const double lx = x - i, ly = y - j;
        const double* C = &c_[(size_t(j) * cells_ + i) * lanes * m_ * m_];
        return m_ == 4 ? horner_patch_m4(C, lx, ly) : horner_cell(C, m_, lx, ly);
    }
    /// Doubles per coefficient: the three channels and a zero (one 256-bit vector).
    static constexpr int lanes = 4;

    /// Horner's rule in both directions on one cell's m x m x lanes coefficients (channel
    /// innermost), the three channels at once (any m; horner_patch_m4 is the same for m = 4).
    /// DESIGN: each polynomial starts from its top coefficient (not from 0 x ly + c, the same
    /// value). For m = 4 horner_patch_m4 runs instead, at every node of the shadowed part's
    /// triangles (a tenth of the Cornell box's time).
    static Rgb horner_cell(const double* C, int m, double lx, double ly) {
        // The polynomial in y of x^p's coefficients (row p: y^0 .. y^(m-1)) at ly.
        auto in_y = [&](int p, double(&r)[3]) {
            const double* row = C + p * m * lanes;
            for (int k = 0; k < 3; ++k) r[k] = row[(m - 1) * lanes + k];
            for (int q = m - 2; q >= 0; --q)
                for (int k = 0; k < 3; ++k) r[k] = r[k] * ly + row[q * lanes + k];
        };
        double v[3], r[3];
        in_y(m - 1, v);
        for (int p = m - 2; p >= 0; --p) {
            in_y(p, r);
            for (int k = 0; k < 3; ++k) v[k] = v[k] * lx + r[k];
        }
        return {v[0], v[1], v[2]};
    }

private:
    int m_ = 0, cells_ = 0;
    // cell (i, j), x^p y^q, channel ch: c_[(j * cells + i) lanes m^2 + (p m + q) lanes + ch]
    // (the fourth lane zero)
    std::vector<double> c_;
};

}  // namespace mbr
