// radiosity/transfer/transfer.h - one energy transfer from a shooting surface h to a receiving
// surface i, stage by stage (paper section 5, "Energy Transfer between a Pair of Surfaces", with
// section 6's adaptive quadrature, oracle, scale adjustment and extrapolation; DESIGN.md section
// 3).
//
// transfer() is the table of contents; every stage is a free function of its own, in the
// paper's order, that reads and writes a ReceiverState (receiver_state.h), so a student (or
// explain_transfer) can run the stages one at a time and look at what each produced. One
// header per stage, all included here:
//
//   1 subdivide_by_oracle      oracle.h            "Adaptive Subdivision of the Parametric
//                                                   Domain", section 6 "Oracle"
//   2 adjust_neighbour_scales  scale_adjustment.h  "Adjustment of the Scale of Adjacent
//                                                   Subdomains", NeighAdjust, Figure 4
//     sample_leaves            scale_adjustment.h  "... and Computation of Sample Values", (21)
//                                                   (increment_sampler.h)
//   3 fill_boundary            edgefill.h          "Computation of Radiosity Increment and Its
//                                                   Partial Derivatives at Boundaries", (22)
//   4 expand_domain            expanded_domain.h   "Adaptive Subdivision and Sampling on
//                                                   Expanded Domain", Figure 5; extrapolation
//                                                   (23)-(27)
//   5 select_fulcrums          projection.h        "Selection of Dual Basis Functions", Fig. 2
//   6 project_in_rhombi        projection.h        "Projection", eq. (19), Figure 3
//   7 apply_shadows            shadows.h           "Adaptive Subdivision in Shadow
//                                                   Computation", section 6 "Shadow", (28)
//   8 unify_scales             unification.h       "Scale Unification and Superposition", (17)
//   6+8 project_fine_grid      fine_grid.h         beyond the paper (unify_by_projection)
//   3-8 project_root_polynomial weak_transfer.h   beyond the paper: a weak transfer (its root
//                                                   samples below weak_transfer tolerances)
//                                                   keeps the root and takes its polynomial
//
// Visibility: with ShadowMethod::Fractions (the paper's) stage 7 masks the coefficients; with
// ShadowMethod::Exact the samples of (21) already carry it (radiosity/visibility/visible_parts.h).
#pragma once

#include "math/dual_basis.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/transfer/edgefill.h"
#include "radiosity/transfer/expanded_domain.h"
#include "radiosity/transfer/fine_grid.h"
#include "radiosity/transfer/increment_sampler.h"
#include "radiosity/transfer/oracle.h"
#include "radiosity/transfer/projection.h"
#include "radiosity/transfer/receiver_state.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/transfer/scale_adjustment.h"
#include "radiosity/transfer/shadows.h"
#include "radiosity/transfer/unification.h"
#include "radiosity/transfer/weak_transfer.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

/// The whole transfer: dB_i of one shooting, as coefficients at one scale. `occlusion` (may be
/// null) names the pair's occluders; options.shadows.method says how they enter. `dual` (may be
/// null) is DN_m for options.m, built once by a caller that runs many transfers.
SplineField transfer(const Shooter& shooter, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats = nullptr,
                     ReceiverState* keep_state = nullptr,
                     const OcclusionContext* occlusion = nullptr, const DualTable* dual = nullptr);

/// The same for shooters whose fields add up (a planar cluster's members, each with its pair's
/// occluders; ShooterPart): one receiver tree, one fit and one projection for the sum (the
/// oracle's contact rule asks every part's plane). options.shadows.method says how every part's
/// occluders enter.
SplineField transfer(const std::vector<ShooterPart>& parts, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats = nullptr,
                     ReceiverState* keep_state = nullptr, const DualTable* dual = nullptr);

/// The shooter as section 6 uses it: its unshot field coarsened by `levels` (not below 0).
Shooter make_shooter(const Surface& surface, const SplineField& unshot, int levels);

}  // namespace mbr
