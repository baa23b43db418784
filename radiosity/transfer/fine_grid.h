// radiosity/transfer/fine_grid.h - stages 6 and 8 at once on the finest grid (beyond the paper,
// ReceiverOptions::unify_by_projection): eq. (19) for every coefficient of the finest level, with
// the extrapolation (23)-(27) evaluated where the paper samples the expanded domain.
#pragma once

#include "math/dual_basis.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stages 6 and 8 at once when ReceiverOptions::unify_by_projection is set (beyond the paper):
/// every coefficient of the finest level J of the domain's leaves by (19), as two
/// one-dimensional sums over the values at the m x m Gauss-Legendre nodes of every level-J cell
/// within reach: the leaves' samples (a coarser leaf's polynomial resampled, as project() does)
/// inside [0,1]^2, the extrapolation (23)-(27) evaluated at the nodes themselves outside (the
/// limit of an infinitely fine expanded domain). DN is truncated to the square |x|, |y| <= r
/// around each fulcrum, which holds the rhombus |x| + |y| <= r of Figure 3 (a tensor region is
/// what makes the sums separable). Coefficients are masked with state.mask when it is set.
SplineField project_fine_grid(ReceiverState& state, const DualTable& dn);

}  // namespace mbr
