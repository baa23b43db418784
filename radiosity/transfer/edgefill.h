// radiosity/transfer/edgefill.h - stage 3 of one transfer: "Computation of Radiosity Increment and
// Its Partial Derivatives at Boundaries" (paper section 5): the values and normal derivatives
// (22) along the four edges of [0,1]^2 by the recursive edgefill bisection.
#pragma once

#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 3. Boundary values and normal derivatives (22) along the four edges by the recursive
/// edgefill bisection with linear interpolation where it is smooth enough.
void fill_boundary(ReceiverState& state, IncrementSampler& sampler);

}  // namespace mbr
