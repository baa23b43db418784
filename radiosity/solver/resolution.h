// radiosity/solver/resolution.h - whether a receiver's finest cells can hold a light's peak
// (beyond the paper; issue 19, "a large receiver loses the light").
//
// Under a small lamp at height h above a receiver, the direct light is a peak about
// max(h, lamp width) wide (its narrowest width: a strip's peak is narrow across it). A B-spline
// field whose finest cells (max_depth) are much wider than that peak cannot hold it: a 2e4 x 2e4
// floor under a 1 x 1 lamp at height 1 read 6e-11 of the light under the lamp at max_depth 4 and 6
// (a 2e3 x 2e3 floor: 1e-5 at 4, 0.2 % at 6, 10 % at 8), with no word. Where the finest cells are
// fine enough the oracle finds the peak by itself (floors of 300 to 800 under lamps off their
// centres at max_depth 10 and 11: within 0.1 %). So this check, run before any work, says when
// max_depth is too coarse, so that the user hears it instead of reading a dark floor.
#pragma once

#include <vector>

#include "radiosity/scene/scene.h"

namespace mbr {

/// A receiver whose finest cells are too wide for an emitter's peak.
struct UnresolvedLight {
    int receiver = -1;       // surface index
    int emitter = -1;        // surface index
    double spot = 0;         // the peak's width, max(distance, the emitter's narrowest
                             //   width), at its narrowest
    double cell = 0;         // the receiver's cells at max_depth there (their longer side)
    int needed_depth = 0;    // the least depth whose cells are fine enough (may exceed 12)
    double form_factor = 0;  // from the emitter's centre to the receiver: its share of the light
};

/// DESIGN: the finest cell under a peak may be at most this fraction of the peak's width
/// max(d, the emitter's narrowest width), d the distance from the cell's nearest corner, edge
/// midpoint or centre to the emitter. Measured under a 1 x 1 lamp at height 1 (`mbr probe`, value
/// under the lamp's centre against the analytic rho E F): cells of 0.2, 0.31, 0.78 and 1.25 wide
/// read +0.0 %, +0.05 %, +1.7 % and -8.1 %; so 0.8 keeps that value within 2 %.
constexpr double resolution_fraction = 0.8;
/// DESIGN: only receivers that take at least this share of an emitter's light (the point form
/// factor from the emitter's centre to the receiver) are checked: a receiver that takes less
/// cannot lose much of it.
constexpr double resolution_share = 0.01;

/// Every pair of a planar-quad emitter and a planar-quad receiver with a reflectance, the emitter
/// wholly in front of the receiver, whose receiver, at `max_depth`, cannot hold the emitter's peak
/// and takes at least resolution_share of its light; in receiver order, then emitter order.
std::vector<UnresolvedLight> unresolved_lights(const Scene& scene, int max_depth);

/// Throws InputError at the first receiver's statement naming it, the emitter, the sizes and
/// what to change (`max_depth`, or splitting the receiver) when unresolved_lights is not empty.
void check_resolution(const Scene& scene, int max_depth);

}  // namespace mbr
