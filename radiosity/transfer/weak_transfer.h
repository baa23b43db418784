// radiosity/transfer/weak_transfer.h - the weak transfer (beyond the paper, cost follows
// energy): a transfer that cannot matter at the finest level keeps the root of its domain as its
// only leaf and takes the level-0 field through the root's samples, without edgefill, the
// expanded domain or the ring of project_fine_grid (docs/method.md, "Effort that follows
// energy").
#pragma once

#include "radiosity/geometry/spline_field.h"
#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// The weak transfer rule: the largest of the root's m x m samples of (21) is below
/// ReceiverOptions::weak_transfer absolute tolerances (never with weak_transfer or the absolute
/// tolerance at 0, as in the single transfers of Tables 1-2).
bool is_weak_transfer(const ReceiverOptions& options, double largest_root_sample);

/// The weak transfer rule's precondition: whether the root's m x m samples can stand for the
/// whole receiver. The kernel (3) varies over lengths like the distance to the shooter, so
/// samples spaced by about a quarter of the receiver's size miss no peak of it when the
/// shooter's bounding box is at least half the receiver's bounding-box diagonal away. Nearer
/// (a shared edge, a light a hair above a floor) a peak can fall between the samples: a light
/// 1e-4 above a floor lights a square that none of the floor's 16 root samples sees.
bool root_samples_represent(const Surface& shooter, const Surface& receiver);

/// The result of a weak transfer: eq. (19) at level 0 with the integral over [0,1]^2 taken by
/// the m-point Gauss-Legendre rule of the root's samples. On [0,1] the m level-0 basis functions
/// of each axis span the polynomials of degree m - 1, so this projection is the tensor
/// polynomial through the m x m samples, written in the level-0 B-spline basis (the inverse of
/// the m x m collocation matrix N_m(x_a - k) on each side).
SplineField project_root_polynomial(ReceiverState& state);

/// Stage 7's masking for a weak transfer under the paper's shadows: every coefficient of the
/// level-0 field times its fulcrum's fraction (28), at fraction_point (the domain's corners).
void mask_root_coefficients(SplineField& field, ReceiverState& state, IncrementSampler& sampler);

}  // namespace mbr
