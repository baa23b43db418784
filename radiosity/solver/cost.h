// radiosity/solver/cost.h - bounded cost, said before it is spent: the memory and rough time
// a run will need, estimated from its settings before anything big is allocated, so that the
// programs can refuse a run that would exhaust the machine and warn about one that is slow.
// The per-leaf figures are calibrated against measured peaks (cost.cpp says which).
#pragma once

#include <string>

#include "radiosity/scene/scene.h"
#include "radiosity/solver/solver.h"
#include "radiosity/transfer/transfer.h"

namespace mbr {

/// What a run will hold at its peak and roughly how long it takes, from its settings alone.
struct CostEstimate {
    double bytes = 0;    // peak memory (worst case: every adaptive tree at its max depth)
    double seconds = 0;  // rough wall time on one core (0: not estimated); a scene's: its setup
                         //   and one shot whose trees all reach the max depth
    double setup_seconds = 0;  // of which the setup before the first shot (hidden regions)
    std::string detail;  // the parts of `bytes`, for a message ("fields 1.2 GiB, ...")
};

/// Receiver depth from which a run is valid but slow enough to deserve a warning.
constexpr int slow_receiver_depth = 9;

/// Bytes of one spline field of order m at level j: (2^j + m - 1)^2 coefficients x 3 doubles.
double field_bytes(int m, int level);
/// Working memory of one transfer whose domain tree is full to `depth` (4^depth leaves with
/// their m x m samples, the fulcrums, coefficients and expanded ring), its result included.
double transfer_bytes(int m, int depth);
/// Rough seconds of such a transfer on one core (unshadowed, the paper's default tolerances).
double transfer_seconds(int m, int depth);
/// One transfer with these options (the tree at options.max_depth: the uniform tree, or the
/// adaptive tree's worst case).
CostEstimate transfer_cost(const ReceiverOptions& options);
/// A whole-scene solve: the program itself; per surface its radiosity and unshot fields at the
/// receiver's max depth, one shot's received fields, its hidden-region mask and its rows of the
/// measured coupling; one transfer's working memory per thread (`threads` transfers at once, one
/// with the paper's shadow fractions) and each thread's quadrature caches at their bound; the
/// tessellation's polygons and octree; and each distinct texture image once.
CostEstimate scene_cost(const Scene& scene, const SolverOptions& options, int threads);

/// Physical memory of the machine in bytes (0 when the system does not say).
double physical_memory_bytes();
/// The default budget: half the physical memory (4 GiB when the system does not say).
double default_memory_budget();
/// "1.5 GiB", "300 MiB", "12 KiB", "100 B".
std::string format_bytes(double bytes);
/// "2 h", "15 min", "40 s".
std::string format_seconds(double seconds);

}  // namespace mbr
