// math/polynomial.h - the tensor polynomial of degree m-1 through m x m Gauss-Legendre samples,
// and its resampling on sub-cells (paper section 5, "Projection": "If the scale of the current
// subdomain is larger than that of the dual basis function, we fit a double (m-1)th order
// polynomial to those m x m samples, subdivide the current subdomain to the desired scale and
// resample the fitted polynomial on each resulting leaf subdomain").
//
// Samples are on the reference square [-1,1]^2 at the nodes x_a of the m-point Gauss-Legendre
// rule, stored row-major: samples[a * m + b] = f(x_a, x_b) (a indexes the first coordinate).
#pragma once

#include <vector>

#include "math/gauss_legendre.h"

namespace mbr {

/// p(x, y) = sum_{i,j < m} c[i * m + j] x^i y^j on the reference square [-1,1]^2.
struct TensorPolynomial {
    int m = 0;
    std::vector<double> c;
    double operator()(double x, double y) const;
};

/// The unique tensor polynomial of degree m-1 in each variable through the m x m samples
/// (monomial coefficients by solving the Vandermonde systems on the Gauss-Legendre nodes).
TensorPolynomial fit_tensor_polynomial(int m, const std::vector<double>& samples);

/// Lagrange basis of the m-point Gauss-Legendre nodes: L[p * m + a] = l_a(points[p]), so that a
/// polynomial of degree m-1 with node values f_a has the value sum_a L[p*m + a] f_a at points[p].
std::vector<double> lagrange_matrix(const GaussLegendre& rule, const std::vector<double>& points);

/// Resampling matrix for a sub-cell: the reference square split 2^levels times in each
/// direction; sub-cell `index` (0 .. 2^levels - 1) along one axis. Row p gives the weights of the
/// m node values for the p-th Gauss-Legendre node of the sub-cell (a 1D Lagrange matrix; apply
/// it along both axes).
std::vector<double> subcell_resample_matrix(const GaussLegendre& rule, int levels, int index);

/// Resample m x m samples of a cell onto the Gauss-Legendre nodes of one of its sub-cells:
/// out = Rx * samples * Ry^T with the 1D matrices of subcell_resample_matrix. Exact for
/// polynomials of degree < m (the fit is the Lagrange interpolant).
void resample(int m, const double* samples, const double* Rx, const double* Ry, double* out);

}  // namespace mbr
