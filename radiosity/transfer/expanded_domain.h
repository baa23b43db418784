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

/// What the extrapolation reads of one edge at one point of it: the increment and its
/// derivative along the edge's normal, clamped (stage 3's profile, EdgeProfile::at).
struct EdgeValue {
    Rgb v, d;
};
/// Edge e (0: t = 0, 1: s = 1, 2: t = 1, 3: s = 0) at sigma (s on edges 0 and 2, t on 1 and 3).
EdgeValue edge_value(const ReceiverState& state, int e, double sigma);
/// extrapolate() on the side patch beyond edge e (patches 1, 3, 5, 7), from the edge's value at
/// the point's foot, `offset` the point's signed distance from the edge along its normal
/// coordinate (t, s - 1, t - 1 or s): eq. (23), or (26)/(27).
Rgb extrapolate_side(const ReceiverState& state, int e, const EdgeValue& at_foot, double offset);
/// The side patch (1, 3, 5 or 7) that (s, t) lies in, outside [0,1]^2 beside one edge only:
/// the edge e, the point's foot on it (s on edges 0 and 2, t on 1 and 3) and its signed offset
/// from the edge along the normal coordinate (t, s - 1, t - 1 or s).
struct SidePatch {
    int e;
    double foot, offset;
};
SidePatch side_patch(double s, double t);
/// extrapolate() on the corner patch of corner (s_c, t_c) (patches 0, 2, 4, 6), from the value
/// and clamped derivatives there: eqs. (24)-(25), or the tensor form.
struct CornerValue {
    Rgb v, d_s, d_t;
};
CornerValue corner_value(const ReceiverState& state, double s_c, double t_c);
Rgb extrapolate_corner(const ReceiverState& state, const CornerValue& corner, double s, double t);

/// Stage 4. The expanded domain (Figure 5): roots around [0,1]^2 wide enough for the rhombus of
/// every boundary fulcrum, subdivided adaptively with expanded cells next to the domain no
/// larger than the domain leaves they touch, scale-adjusted, and sampled by extrapolation.
/// Domain leaves that scale adjustment splits are sampled by (21).
void expand_domain(ReceiverState& state, IncrementSampler& sampler);

}  // namespace mbr
