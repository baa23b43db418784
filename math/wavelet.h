// math/wavelet.h - one step of the semi-orthogonal wavelet decomposition f_N = f_{N-1} + g_{N-1}
// of eq. (11): the orthogonal projection of a level-j spline onto level j-1. The shooter's unshot
// field is coarsened this way before the quadrature of (21) (section 6, "Adaptive Quadrature":
// "replaced with a lower resolution version by applying the decomposition relation").
//
// The projection is orthogonal in L2 of the parameter domain [0,1] (or [0,1]^2): the coarse
// coefficients c of the basis functions touching [0,1] solve G c = C a, with the Gram matrix
// G_{kk'} = int_0^1 N_m(2^{j-1}s - k) N_m(2^{j-1}s - k') ds and the cross matrix
// C_{kl} = int_0^1 N_m(2^{j-1}s - k) N_m(2^j s - l) ds, both exact by Gauss-Legendre on the level-j
// cells. A function already in V_{j-1} on [0,1] comes back unchanged; the detail g_{j-1} = f - f_{j-1}
// is orthogonal to V_{j-1} on the domain.
#pragma once

#include "math/bspline.h"

namespace mbr {

/// Orthogonal projection onto level fine.level - 1 of a row covering the basis functions that
/// touch [0,1] (touching_row layout); the result has the touching layout one level coarser.
CoefficientRow coarsen(int m, const CoefficientRow& fine);

/// The same in 2D: the L2([0,1]^2) projection is the tensor product of the 1D projections.
CoefficientGrid coarsen(int m, const CoefficientGrid& fine);

/// The squared L2([0,1]) norm of sum_k a_k N_m(2^level s - k) (exact).
double squared_norm(int m, const CoefficientRow& row);

}  // namespace mbr
