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

/// Distance from q to the boundary (the edges) of a polygon in its plane.
double distance_to_outline(const ConvexPolygon& outline, Vec2 q);

/// Distance from x to a planar shooter's closed polygon (its frame and outline): the contact
/// rule's measure (and the resolution check's, radiosity/solver/resolution.h).
double distance_to_shooter(const ShooterPlane& plane, Vec3 x);

}  // namespace mbr
