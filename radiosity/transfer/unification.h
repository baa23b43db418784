// radiosity/transfer/unification.h - stage 8 of one transfer: "Scale Unification and
// Superposition" (paper section 5, eq. (17)): every coefficient at the finest fulcrum scale.
#pragma once

#include <map>

#include "math/dual_basis.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 8's rule for one coefficient (shared with stage 7): a stored one is used; a missing one
/// whose fulcrum's neighbourhood holds (21) samples at least as fine as its scale (or at level
/// 0, or with unify_by_projection) is projected on demand (then stored, and masked with
/// state.mask when set); otherwise it comes from (17) applied to the coefficients one level
/// coarser, recursively (memoised in `refined`).
Rgb resolve_coefficient(ReceiverState& state, const DualTable& dn, const Fulcrum& f,
                        std::map<Fulcrum, Rgb>& refined);

/// Stage 8. Every coefficient at the finest fulcrum scale 2^-j, for the basis functions that
/// touch [0,1]^2: a stored one is used; a missing one at a fulcrum whose neighbourhood is at
/// least as fine as its scale is projected on demand; otherwise it comes from (17) applied to
/// the coefficients one level coarser, recursively.
SplineField unify_scales(ReceiverState& state, const DualTable& dn);

}  // namespace mbr
