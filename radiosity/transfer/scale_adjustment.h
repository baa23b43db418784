// radiosity/transfer/scale_adjustment.h - stage 2 of one transfer: "Adjustment of the Scale of
// Adjacent Subdomains" (paper section 6, NeighAdjust, Figure 4) and the samples (21) of the
// leaves (section 5, "... and Computation of Sample Values"), and the samples of leaves split
// after stage 4.
#pragma once

#include "radiosity/geometry/quadtree.h"
#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 2a. NeighAdjust (section 6, Figure 4): split until no leaf is more than twice the size
/// of any of its twelve edge and corner neighbours. Checks only leaves of `region`, but sees
/// neighbours anywhere in the forest. Returns the number of splits.
int adjust_neighbour_scales(Forest& forest, Forest::Region region);

/// Stage 2b. The m x m Gauss-Legendre samples of dB, eq. (21), on every domain leaf that has
/// none yet.
void sample_leaves(ReceiverState& state, IncrementSampler& sampler);

/// Gives the leaf `index` (without samples yet) the m x m samples `values` ([a * m + b] at
/// (s_a, t_b) of its Gauss-Legendre nodes, as sample_leaves takes them) and widens the state's
/// sample range by them.
void store_leaf_samples(ReceiverState& state, int index, const Rgb* values);

/// Samples for leaves made after stage 4 (shadow subdivision and its scale adjustment): a domain
/// leaf gets its parent's tensor polynomial resampled (and is marked `resampled`), an expanded
/// leaf the extrapolation.
void sample_split_leaves(ReceiverState& state);

}  // namespace mbr
