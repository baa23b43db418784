// radiosity/transfer/expanded_domain.h - stage 4 of one transfer: "Adaptive Subdivision and
// Sampling on Expanded Domain" (paper section 5, Figure 5) and the "Extrapolation of Radiosity
// Distribution" of section 6 that samples it, eqs. (23)-(27).
#pragma once

#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// The extrapolated value at (s, t) outside [0,1]^2 (section 6): linear (23)-(25) with clamped
/// derivatives, or the higher-order forms meeting (26) or (27).
Rgb extrapolate(const ReceiverState& state, double s, double t);

/// Stage 4. The expanded domain (Figure 5): roots around [0,1]^2 wide enough for the rhombus of
/// every boundary fulcrum, subdivided adaptively with expanded cells next to the domain no
/// larger than the domain leaves they touch, scale-adjusted, and sampled by extrapolation.
/// Domain leaves that scale adjustment splits are sampled by (21).
void expand_domain(ReceiverState& state, IncrementSampler& sampler);

}  // namespace mbr
