// radiosity/transfer/shadows.h - stage 7 of one transfer, the paper's shadows
// (ShadowMethod::Fractions): "Adaptive Subdivision in Shadow Computation" (paper section 5) and
// section 6 "Shadow": visible fractions (28) at fulcrums, shadow subdivision, and masking of
// the coefficients (DESIGN.md section 3, stage 7).
#pragma once

#include "math/dual_basis.h"
#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 7 (the paper's shadows, ShadowMethod::Fractions): fractions (28) at the fulcrums of
/// the domain leaves; leaves between neighbouring fulcrums whose fractions differ by more than
/// the threshold are split (then NeighAdjust; their samples are resampled from the parent's
/// polynomial), the new fulcrums' coefficients carried from the coarser ones by (17), until no
/// leaf splits or the maximum shadow depth; then every stored coefficient is multiplied by its
/// fulcrum's fraction. Does nothing without occluders.
void apply_shadows(ReceiverState& state, IncrementSampler& sampler, const DualTable& dn);

/// Eq. (28) at the domain point (s, t): cast options.shadows.rays_per_patch rays to random
/// points of every cell of the shooter partition the adaptive quadrature of (21) forms there;
/// sum r_i e_i / sum e_i per channel (1 where nothing arrives). Memoised in state.fractions;
/// the rays are seeded from the point and the pair's seed. `thread` picks the integrator.
Rgb fraction_at(ReceiverState& state, IncrementSampler& sampler, double s, double t, int thread);

/// The fraction a fulcrum's coefficient is masked with: at its position, or for a fulcrum
/// outside the domain at the nearest point of the domain (DESIGN, docs/method.md).
Vec2 fraction_point(const Fulcrum& f, int m);

}  // namespace mbr
