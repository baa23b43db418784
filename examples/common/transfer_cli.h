// examples/common/transfer_cli.h - the options every single-transfer program understands, and
// the measurement of one transfer against the analytic form factor (Tables 1-2, Figure 7).
#pragma once

#include <string>

#include "examples/common/cli.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"

namespace mbr {

/// Usage lines for the options below.
extern const char* receiver_options_usage;

/// Reads --order, --extrapolation linear|higher|quadratic|cubic, --rhombus-radius R, --eps E,
/// --quadrature-tolerance, --unify paper|projection, --edgefill-tolerance, --clamp,
/// --coarsen-shooter into ReceiverOptions (depths are left to the caller).
ReceiverOptions read_receiver_options(Args& args);

/// The receiver tree of one transfer: "--depth d" (uniform, 0..12, default 3) or "--adaptive"
/// (the oracle of section 6) with --oracle-tolerance T and --min-depth a --max-depth b (0..12,
/// default 1 and 6). Each mode refuses the other's options with a UsageError instead of
/// ignoring them ("--depth has no effect with --adaptive"). Returns base with min_depth,
/// max_depth and oracle_tolerance set. Also reads --memory-budget (memory_budget_usage) and
/// refuses, before anything is allocated, a tree whose estimated memory exceeds it
/// (radiosity/solver/cost.h); a depth of slow_receiver_depth or more prints one warning on stderr.
ReceiverOptions read_tree_options(Args& args, ReceiverOptions base);

/// True when the fronts of two planar quads face each other somewhere: some corner of each lies
/// strictly in front of the other's plane. Exact for convex quads (the signed distance to a plane
/// is largest at a corner, and each plane is the same for all points of its quad), so a quad
/// that faces the other only in part is accepted; testing the centres alone would refuse it.
bool fronts_face_each_other(const Surface& shooter, const Surface& receiver);

/// A one-line description of the options that matter for the tables.
std::string describe(const ReceiverOptions& options);

/// One transfer with shooter radiosity 1 and receiver reflectance 1, measured on the n x n grid.
struct TransferRun {
    ErrorStats errors;
    TransferStats stats;
    SplineField field;
    int n_coefficients = 0;
};
TransferRun run_transfer(const TransferSetup& setup, const ReceiverOptions& options,
                         int grid = 256, ReceiverState* keep_state = nullptr);

}  // namespace mbr
