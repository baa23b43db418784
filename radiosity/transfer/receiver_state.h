// radiosity/transfer/receiver_state.h - what one energy transfer from a shooting surface h to a
// receiving surface i reads and builds (paper section 5, "Energy Transfer between a Pair of
// Surfaces"): its options, its counts, the receiving surface, and the state the stages of
// radiosity/transfer/transfer.h share (DESIGN.md section 3).
#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "math/gauss_legendre.h"
#include "radiosity/geometry/quadtree.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/visibility/hidden_regions.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

/// How visibility enters a transfer.
enum class ShadowMethod {
    None,       // VIS = 1
    Fractions,  // the paper's: fractions (28) at fulcrums, shadow subdivision, masking (stage 7)
    Exact       // VIS inside (21): the visible part of the shooter, projected like any samples
                //   (radiosity/visibility/visible_parts.h)
};

/// Options of the shadow stage (stage 7, radiosity/transfer/shadows.h).
struct ShadowOptions {
    ShadowMethod method = ShadowMethod::Fractions;
    int rays_per_patch = 4;   // rays from a fulcrum to each patch of its shooter partition (28)
    double threshold = 0.05;  // fractions of neighbouring fulcrums differing by more split the
                              //   leaves between them (largest channel)
    int max_depth = 6;        // shadow subdivision stops at leaves of this level
    double split_area = 0;    // > 0: a leaf splits only if its area times the largest sample
                              //   reaches absolute_tolerance times this (shadows.cpp,
                              //   worth_splitting; the solver sets it)
    bool kernel_weighted = false;  // beyond the paper: r_i of (28) weights each ray by the
                                   //   kernel (3) times A (4) at its end (scenes: `set
                                   //   fraction_rays kernel`, their default)
};

/// The partition of a fraction (28) is at least this deep: the adaptive quadrature of (21) run
/// with this minimum depth (the paper's fixed partition; a weak shot's is shallower).
constexpr int min_patch_depth = 3;

/// Delta t of the divided difference (22), in units of the finest leaf on that edge.
constexpr double divided_difference_step = 1e-4;

/// Boundary samples (edgefill, and the fractions of stage 7) are taken this far inside the
/// domain (in units of the finest leaf on the edge) and moved to the edge with the divided
/// difference: the limit from inside, where the kernel is singular on the edge itself.
constexpr double boundary_inset = 1e-3;

/// The oracle's absolute tolerance is this share of ReceiverOptions::absolute_tolerance (a
/// cell's means agree far better than its spline fits it).
constexpr double oracle_share = 1;

/// The hybrid oracle (OracleTest::Hybrid) fits a cell point by point within this many oracle
/// floors where the floor governs. DESIGN, measured (docs/method.md, "The hybrid oracle"): 1
/// costs the Cornell box 36 % more kernel evaluations and its worst reference point 0.3 %;
/// 4 leaves cube.mgf's penumbrae blurred (+36 % at its worst point, as the means do).
constexpr double fit_share = 2;
/// The contact rule splits a cell that comes within this share of its size of a planar shooter
/// (ReceiverOptions::contact_depth, oracle.cpp) ...
constexpr double contact_split_reach = 0.5;
/// ... and asks the contact oracle's test (contact_oracle_test) of a cell within this share.
constexpr double contact_test_reach = 0.25;
/// The thin rim rule (part of the contact rule in scenes, oracle.cpp; ReceiverOptions::thin_rim)
/// splits a cell on the rim of a hidden region more than this many times thinner than the cell.
/// DESIGN (docs/method.md, "Hidden regions"): 3 takes the wall of corridor.mgf to level 4 along
/// a board's strip (0.3 m of a 10 m wall), 12 % -> 0.3 % 22 cm under the board, and leaves a
/// block's footprint on a floor (as wide as the cells there) to the hidden rim rule: the Cornell
/// box's count is unchanged.
constexpr double thin_rim_ratio = 3;

/// How the increment is continued outside [0,1]^2 (section 6, "Extrapolation").
enum class Extrapolation {
    Linear,     // eqs. (23)-(25), derivatives clamped
    Quadratic,  // eq. (26): C^1 piecewise quadratic, zero from two units out
    Cubic       // eq. (27): cubic Hermite, zero from one unit out
};

/// How edgefill decides that a boundary segment may be linearly interpolated.
enum class EdgefillTest {
    Variation,  // the paper's test: |dB(s3) - dB(s1)| and |dB_t(s3) - dB_t(s1)| small
    Linearity   // the midpoint agrees with the chord: |dB(s3) - (dB(s1) + dB(s2)) / 2| small
};

/// How the oracle of stage 1 decides that a cell is "nearly sufficient".
enum class OracleTest {
    Means,          // the paper's: the means by ceil(m/2)^2 and m^2 Gauss-Legendre points agree
    Interpolation,  // beyond the paper: the polynomial through the m^2 samples predicts the
                    //   ceil(m/2)^2 samples point by point (catches kinks the means hide)
    Hybrid          // beyond the paper: Means where the relative tolerance governs a cell,
                    //   Interpolation where the absolute tolerance does (oracle.cpp)
};

struct ReceiverOptions {
    int m = 4;                       // B-spline order (the paper uses 4 and 3)
    int min_depth = 1;               // oracle quadtree bounds; min = max = d gives the
    int max_depth = 6;               //   uniform depth-d trees of Tables 1-2
    double oracle_tolerance = 1e-3;  // relative disagreement of the ceil(m/2)^2 and m^2 rules
    OracleTest oracle_test = OracleTest::Hybrid;  // DESIGN (oracle.cpp, hybrid_agrees); with
                                                  //   no absolute tolerance the paper's means
    double truncation_eps = 1e-7;  // relative cut-off of |DN x DN| that sets the rhombus
    double rhombus_radius = 0;     // in cells of the fulcrum's scale; 0: from truncation_eps
    Extrapolation extrapolation = Extrapolation::Linear;
    double clamp_factor = 1.0;  // |dB_n| <= clamp_factor * max|dB| / h_min per edge
    bool clamp_values = true;   // DESIGN: extrapolated values also stay within the range
                                //   of the samples [lo, hi] (lo <= 0) widened by its width
                                //   on both sides: a steep edge (a surface meeting
                                //   another) would otherwise be continued to many times
                                //   max|dB| across the ring
    EdgefillTest edgefill_test =
        EdgefillTest::Linearity;       // DESIGN: the chord test; the
                                       //   paper's Variation test gives the same rea with ~3x
                                       //   the boundary samples (docs/method.md)
    double edgefill_tolerance = 1e-4;  // relative to the largest sample (derivatives: per
                                       //   finest boundary leaf)
    int edgefill_max_depth = 6;        // segments no shorter than 2^-6 of the finest boundary leaf
    int shooter_coarsening = 1;        // levels by which the shooter's unshot field is coarsened
    bool unify_by_projection = false;  // stage 8: project every finest-scale coefficient instead
                                       //   of refining coarse ones by (17) (not the paper's rule)
    QuadratureOptions quadrature;      // the adaptive rule over the shooter, section 6
    ShadowOptions shadows;             // stage 7 (used when the transfer has occluders)
    int contact_depth = 0;             // beyond the paper: a cell that touches a planar shooter
                                       //   (within half its own size) splits down to this level,
                                       //   whatever the oracle says: along an edge shared with
                                       //   the shooter dB grows like d log d, whose cell means
                                       //   agree long before the spline can follow it (0: off)
    double thin_rim = 0;               // > 0: the thin rim rule (oracle.cpp) splits a cell on the
                                       //   rim of a hidden region more than this many times
                                       //   thinner than the cell (scenes: thin_rim_ratio; 0: off)
    OracleTest contact_oracle_test =
        OracleTest::Means;          // beyond the paper: the oracle's
                                    //   test in cells that touch a planar shooter
                                    //   (Interpolation sees the d log d growth there; scenes:
                                    //   `set contact_oracle`)
    double weak_receiver = 0;       // > 0: a receiver whose root samples are all below this
                                    //   many absolute tolerances starts the oracle at depth 0
    double weak_transfer = 0;       // > 0: a transfer whose root samples are all below this
                                    //   many absolute tolerances keeps the root as its only
                                    //   leaf and takes the level-0 field through its samples
                                    //   (weak_transfer.h: no edgefill, no ring)
    double absolute_tolerance = 0;  // radiosity below which differences never refine: the
                                    //   oracle, edgefill and shadow tests use the larger of
                                    //   their relative tolerance and this, and the truncation
                                    //   eps grows to absolute_tolerance / max|dB| (at most
                                    //   1e-3). 0: relative tests only (single transfers); a
                                    //   scene sets it from its accuracy option, so that cost
                                    //   follows the energy of each shot
};

/// Counts and times of one transfer (summed after the parallel loops, so they do not depend
/// on the number of threads).
struct TransferStats {
    long n_kernel_evals = 0;         // evaluations of F (3) inside the quadrature of (21)
    long n_analytic_evals = 0;       // closed-form form factors instead of (or beside) them
    long n_increments = 0;           // evaluations of (21) (sample values)
    long n_oracle_increments = 0;    //   of which for the oracle
    long n_boundary_increments = 0;  //   of which for edgefill (values and divided differences)
    long n_unconverged = 0;          // quadratures that hit the depth cap
    int n_leaves = 0;                // leaves of the domain after scale adjustment
    int n_expanded_leaves = 0;       // leaves of the expanded domain
    int n_boundary_nodes = 0;        // edgefill nodes over the four edges
    int n_fulcrums = 0;              // selected fulcrums (both scales counted at shared corners)
    int n_projections = 0;           // coefficients computed by projection (selected + on demand)
    int n_refined = 0;               // coefficients obtained by (17) during unification
    int level = 0;                   // the unified level j of the result
    double rhombus_radius = 0;       // in cells
    long n_rays = 0;                 // shadow rays (fractions (28), or per node on curved shooters)
    int n_fractions = 0;             // fractions (28) evaluated
    int n_shadow_splits = 0;         // leaves split by shadow subdivision (and scale adjustment)
    bool weak = false;               // the weak transfer rule kept the root (weak_transfer.h)
    double seconds_sampling = 0, seconds_boundary = 0, seconds_expanded = 0, seconds_projection = 0,
           seconds_shadows = 0, seconds_total = 0;
};

/// The receiving surface: its geometry and its reflectance rho_i(s, t).
struct ReceiverSurface {
    const Surface* surface = nullptr;
    std::function<Rgb(double, double)> reflectance;
    const HiddenMask* hidden = nullptr;  // may be null: a sample at a hidden point takes the
                                         //   value of (21) at the nearest visible point
};

/// Boundary values and derivatives along one edge of [0,1]^2 (stage 3): nodes at edge
/// parameters sigma (s on the bottom and top edges, t on the left and right ones) with dB and
/// its derivative with respect to the coordinate normal to the edge (t or s, not "outward").
struct EdgeProfile {
    std::vector<double> sigma;
    std::vector<Rgb> value;
    std::vector<Rgb> derivative;
    double h_min = 1;  // size of the finest domain leaf along the edge
    /// Linear interpolation between nodes (section 5, edgefill).
    void at(double sigma, Rgb& value, Rgb& derivative) const;
};

/// A selected dual basis function: DN_m(2^level s - k) DN_m(2^level t - l), with its fulcrum
/// at ((k + m/2) 2^-level, (l + m/2) 2^-level).
struct Fulcrum {
    int level = 0, k = 0, l = 0;
    Vec2 position(int m) const;
    bool operator<(const Fulcrum& o) const {
        return level != o.level ? level < o.level : (k != o.k ? k < o.k : l < o.l);
    }
    bool operator==(const Fulcrum& o) const { return level == o.level && k == o.k && l == o.l; }
};

/// What projection looks up instead of recomputing (section 5, "Projection": "The sample values
/// of the dual basis function are approximated by precalculated discrete values"): DN_m at the
/// m Gauss-Legendre nodes of every unit cell within reach of a fulcrum, and the matrices that
/// resample a leaf's samples onto its sub-cells 1, 2, ... levels finer.
struct ProjectionTables {
    int m = 0;
    GaussLegendre rule;                         // the m-point rule of the leaf samples
    int first_offset = 0, n_offsets = 0;        // cell offsets o = i - k covered
    std::vector<double> dn_at_nodes;            // DN_m(o + (x_a + 1) / 2) at [(o - first) m + a]
    std::vector<std::vector<double>> resample;  // [levels][index * m * m ...] sub-cell matrices
    /// DN_m at node a of the unit cell at offset o (zero beyond the table).
    double dn(int o, int a) const {
        const int i = o - first_offset;
        return (i >= 0 && i < n_offsets) ? dn_at_nodes[size_t(i) * m + a] : 0.0;
    }
};
/// Everything one transfer builds, stage after stage: the blackboard the stages read and write.
struct ReceiverState {
    /// An empty state, for transfer() to fill (its keep_state argument).
    ReceiverState() = default;
    /// A state for running stages one at a time: the options they read, the rhombus radius
    /// (cells) stages 4-8 use (rhombus_radius_cells(options, dn) is transfer()'s; 0 when only
    /// stages 1-3 run), and the pair's occluders (null: none; stage 7 reads them).
    explicit ReceiverState(const ReceiverOptions& options, double rhombus_radius = 0,
                           const OcclusionContext* occlusion = nullptr);

    ReceiverOptions options;
    Forest forest;                        // domain root (0,0) and, from stage 4, the ring
    std::vector<Rgb> samples;             // m*m values per sampled leaf (node.samples indexes)
    double max_sample = 0;                // largest |dB| seen in the domain (scale of tests)
    Rgb sample_lo, sample_hi;             // per channel: the samples' range (lo <= 0 <= hi)
    std::array<EdgeProfile, 4> edges;     // bottom (t=0), right (s=1), top (t=1), left (s=0)
    std::vector<Fulcrum> fulcrums;        // stage 5
    std::map<Fulcrum, Rgb> coefficients;  // stage 6 (and on-demand ones from stage 8)
    double rhombus_radius = 0;            // in cells of each fulcrum's own scale
    std::shared_ptr<const ProjectionTables> tables;      // built by project_in_rhombi
    const OcclusionContext* occlusion = nullptr;         // the pair's occluders (null: none)
    std::map<std::pair<double, double>, Rgb> fractions;  // (28) at domain points (s, t)
    /// Set by stage 7 while the transfer runs: the factor of a coefficient projected on demand
    /// in stage 8 (its fulcrum's fraction), so that every coefficient of the result is masked.
    std::function<Rgb(const Fulcrum&)> mask;
    std::vector<Vec2> split_fulcrums;  // stage 7: fulcrums whose fractions split leaves
    TransferStats stats;
};

}  // namespace mbr
