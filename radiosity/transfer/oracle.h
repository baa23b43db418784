// radiosity/transfer/oracle.h - stage 1 of one transfer: "Adaptive Subdivision of the Parametric
// Domain" (paper section 5) by the oracle of section 6, with the extensions beside the paper's
// two-means test (the interpolation test, the contact rule, the weak receiver rule).
#pragma once

#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 1. Predictive top-down subdivision of [0,1]^2: on each cell compare the integrals of
/// dB with ceil(m/2)^2 and m^2 Gauss-Legendre points; when they agree within the oracle
/// tolerance the cell is "nearly sufficient": split once more and stop. min_depth and
/// max_depth bound the tree.
void subdivide_by_oracle(ReceiverState& state, IncrementSampler& sampler);

}  // namespace mbr
