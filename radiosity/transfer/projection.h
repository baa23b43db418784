// radiosity/transfer/projection.h - stages 5 and 6 of one transfer: "Selection of Dual Basis
// Functions" (paper section 5, Figure 2) and "Projection" (eq. (19), Figure 3): the fulcrums,
// the rhombus each is projected in, the tables projection looks up, and the projection itself.
#pragma once

#include <vector>

#include "math/dual_basis.h"
#include "radiosity/geometry/quadtree.h"
#include "radiosity/transfer/receiver_state.h"

namespace mbr {

/// Stage 5. Fulcrums (Figure 2): odd m, the centre of every domain leaf at the leaf's scale;
/// even m, every corner of every domain leaf at that leaf's scale (a corner shared by leaves of
/// two sizes carries two fulcrums); and the fulcrums of expanded leaves whose basis function
/// reaches into the domain.
std::vector<Fulcrum> select_fulcrums(const Forest& forest, int m);

/// The rhombus radius (cells) the options ask for.
double rhombus_radius_cells(const ReceiverOptions& options, const DualTable& dn);

/// Stage 6. Eq. (19) for the selected fulcrums: c = int int dB DN DN over the rhombus of each,
/// walking the quadtrees from their roots (done in parallel over fulcrums).
void project_in_rhombi(ReceiverState& state, const DualTable& dn);

/// Tables for fulcrums with the given rhombus radius (cells) and resampling up to max_levels.
ProjectionTables make_projection_tables(int m, const DualTable& dn, double rhombus_radius,
                                        int max_levels);

/// The projection of one coefficient: 4^L int int dB(s,t) DN_m(2^L s - k) DN_m(2^L t - l) ds dt
/// over the cells that meet the fulcrum's rhombus; m x m Gauss-Legendre on each leaf with the
/// leaf's samples, or, on a leaf coarser than the fulcrum, on the sub-cells of the fulcrum's
/// scale after fitting the tensor polynomial and resampling it.
Rgb project(const ReceiverState& state, const DualTable& dn, const Fulcrum& f);
/// The same with prepared tables (what the stages use).
Rgb project(const ReceiverState& state, const DualTable& dn, const ProjectionTables& tables,
            const Fulcrum& f);

}  // namespace mbr
