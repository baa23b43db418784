// radiosity/transfer/receiver.h - one energy transfer from a shooting surface h to a receiving surface i,
// stage by stage (paper section 5, "Energy Transfer between a Pair of Surfaces", with section
// 6's adaptive quadrature, oracle, scale adjustment and extrapolation; DESIGN.md section 3).
//
// transfer() is the table of contents; every stage is a free function of its own, in the
// paper's order, that reads and writes a ReceiverState, so a student (or explain_transfer) can
// run the stages one at a time and look at what each produced:
//
//   subdivide_by_oracle      "Adaptive Subdivision of the Parametric Domain", section 6 "Oracle"
//   adjust_neighbour_scales  "Adjustment of the Scale of Adjacent Subdomains", NeighAdjust, Fig. 4
//   sample_leaves            "... and Computation of Sample Values", eq. (21)
//   fill_boundary            "Computation of Radiosity Increment and Its Partial Derivatives at
//                            Boundaries", eq. (22) and the recursive edgefill
//   expand_domain            "Adaptive Subdivision and Sampling on Expanded Domain", Figure 5,
//                            "Extrapolation of Radiosity Distribution", eqs. (23)-(27)
//   select_fulcrums          "Selection of Dual Basis Functions", Figure 2
//   project_in_rhombi        "Projection", eq. (19), Figure 3
//   apply_shadows            "Adaptive Subdivision in Shadow Computation", section 6
//                            "Shadow", eq. (28) (radiosity/transfer/shadows.cpp)
//   unify_scales             "Scale Unification and Superposition", eq. (17)
//
// Visibility: with ShadowMethod::Fractions (the paper's) stage 7 masks the coefficients; with
// ShadowMethod::Exact the samples of (21) already carry it (radiosity/visibility/visible_parts.h).
#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "math/dual_basis.h"
#include "radiosity/visibility/hidden_regions.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/geometry/quadtree.h"
#include "radiosity/visibility/visible_parts.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/geometry/surface.h"

namespace mbr {

/// How the increment is continued outside [0,1]^2 (section 6, "Extrapolation").
enum class Extrapolation {
    Linear,        // eqs. (23)-(25), derivatives clamped
    Quadratic,     // eq. (26): C^1 piecewise quadratic, zero from two units out
    Cubic          // eq. (27): cubic Hermite, zero from one unit out
};

/// How edgefill decides that a boundary segment may be linearly interpolated.
enum class EdgefillTest {
    Variation,     // the paper's test: |dB(s3) - dB(s1)| and |dB_t(s3) - dB_t(s1)| small
    Linearity      // the midpoint agrees with the chord: |dB(s3) - (dB(s1) + dB(s2)) / 2| small
};

/// How the oracle of stage 1 decides that a cell is "nearly sufficient".
enum class OracleTest {
    Means,          // the paper's: the means by ceil(m/2)^2 and m^2 Gauss-Legendre points agree
    Interpolation   // beyond the paper: the polynomial through the m^2 samples predicts the
                    //   ceil(m/2)^2 samples point by point (catches kinks the means hide)
};

struct ReceiverOptions {
    int m = 4;                         // B-spline order (the paper uses 4 and 3)
    int min_depth = 1;                 // oracle quadtree bounds; min = max = d gives the
    int max_depth = 6;                 //   uniform depth-d trees of Tables 1-2
    double oracle_tolerance = 1e-3;    // relative disagreement of the ceil(m/2)^2 and m^2 rules
    OracleTest oracle_test = OracleTest::Means;
    double truncation_eps = 1e-7;      // relative cut-off of |DN x DN| that sets the rhombus
    double rhombus_radius = 0;         // in cells of the fulcrum's scale; 0: from truncation_eps
    Extrapolation extrapolation = Extrapolation::Linear;
    double clamp_factor = 1.0;         // |dB_n| <= clamp_factor * max|dB| / h_min per edge
    bool clamp_values = true;          // DESIGN: extrapolated values also stay within the range
                                       //   of the samples [lo, hi] (lo <= 0) widened by its width
                                       //   on both sides: a steep edge (a surface meeting
                                       //   another) would otherwise be continued to many times
                                       //   max|dB| across the ring
    EdgefillTest edgefill_test = EdgefillTest::Linearity;  // DESIGN: the chord test; the
                                       //   paper's Variation test gives the same rea with ~3x
                                       //   the boundary samples (docs/method.md)
    double edgefill_tolerance = 1e-4;  // relative to the largest sample (derivatives: per
                                       //   finest boundary leaf)
    int edgefill_max_depth = 6;        // segments no shorter than 2^-6 of the finest boundary leaf
    double divided_difference_step = 1e-4;  // Delta t of (22), in units of the finest leaf
                                            //   on that edge
    double boundary_inset = 1e-3;      // boundary samples are taken this far inside the domain
                                       //   (same units) and moved to the edge with the divided
                                       //   difference: the limit from inside, where the kernel
                                       //   is singular on the edge itself
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
    OracleTest contact_oracle_test = OracleTest::Means;  // beyond the paper: the oracle's
                                       //   test in cells that touch a planar shooter
                                       //   (Interpolation sees the d log d growth there; scenes:
                                       //   `set contact_oracle`)
    double weak_receiver = 0;          // > 0: a receiver whose root samples are all below this
                                       //   many absolute tolerances starts the oracle at depth 0
    double oracle_share = 1;           // the oracle's absolute tolerance: this share of
                                       //   absolute_tolerance (a cell's means agree far better
                                       //   than its spline fits it)
    double absolute_tolerance = 0;     // radiosity below which differences never refine: the
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
    long n_kernel_evals = 0;        // evaluations of F (3) inside the quadrature of (21)
    long n_increments = 0;          // evaluations of (21) (sample values)
    long n_oracle_increments = 0;   //   of which for the oracle
    long n_boundary_increments = 0; //   of which for edgefill (values and divided differences)
    long n_unconverged = 0;         // quadratures that hit the depth cap
    int n_leaves = 0;               // leaves of the domain after scale adjustment
    int n_expanded_leaves = 0;      // leaves of the expanded domain
    int n_boundary_nodes = 0;       // edgefill nodes over the four edges
    int n_fulcrums = 0;             // selected fulcrums (both scales counted at shared corners)
    int n_projections = 0;          // coefficients computed by projection (selected + on demand)
    int n_refined = 0;              // coefficients obtained by (17) during unification
    int level = 0;                  // the unified level j of the result
    double rhombus_radius = 0;      // in cells
    long n_rays = 0;                // shadow rays (fractions (28), or per node on curved shooters)
    int n_fractions = 0;            // fractions (28) evaluated
    int n_shadow_splits = 0;        // leaves split by shadow subdivision (and scale adjustment)
    double seconds_sampling = 0, seconds_boundary = 0, seconds_expanded = 0,
           seconds_projection = 0, seconds_shadows = 0, seconds_total = 0;
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
    double h_min = 1;            // size of the finest domain leaf along the edge
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
    GaussLegendre rule;                       // the m-point rule of the leaf samples
    int first_offset = 0, n_offsets = 0;      // cell offsets o = i - k covered
    std::vector<double> dn_at_nodes;          // DN_m(o + (x_a + 1) / 2) at [(o - first) m + a]
    std::vector<std::vector<double>> resample;  // [levels][index * m * m ...] sub-cell matrices
    /// DN_m at node a of the unit cell at offset o (zero beyond the table).
    double dn(int o, int a) const {
        const int i = o - first_offset;
        return (i >= 0 && i < n_offsets) ? dn_at_nodes[size_t(i) * m + a] : 0.0;
    }
};
/// Everything one transfer builds, stage after stage.
struct ReceiverState {
    ReceiverOptions options;
    Forest forest;                        // domain root (0,0) and, from stage 4, the ring
    std::vector<Rgb> samples;             // m*m values per sampled leaf (node.samples indexes)
    double max_sample = 0;                // largest |dB| seen in the domain (scale of tests)
    Rgb sample_lo, sample_hi;             // per channel: the samples' range (lo <= 0 <= hi)
    std::array<EdgeProfile, 4> edges;     // bottom (t=0), right (s=1), top (t=1), left (s=0)
    std::vector<Fulcrum> fulcrums;        // stage 5
    std::map<Fulcrum, Rgb> coefficients;  // stage 6 (and on-demand ones from stage 8)
    double rhombus_radius = 0;            // in cells of each fulcrum's own scale
    std::shared_ptr<const ProjectionTables> tables;  // built by project_in_rhombi
    const OcclusionContext* occlusion = nullptr;     // the pair's occluders (null: none)
    std::map<std::pair<double, double>, Rgb> fractions;  // (28) at domain points (s, t)
    /// Set by stage 7 while the transfer runs: the factor of a coefficient projected on demand
    /// in stage 8 (its fulcrum's fraction), so that every coefficient of the result is masked.
    std::function<Rgb(const Fulcrum&)> mask;
    std::vector<Vec2> split_fulcrums;  // stage 7: fulcrums whose fractions split leaves
    TransferStats stats;
};

/// Evaluates sample values dB_i(s,t) = rho_i(s,t) I(x_i(s,t)) of eq. (21), with one quadrature
/// cache per thread.
class IncrementSampler {
public:
    /// `occlusion` (may be null) puts VIS into (21): exact visibility (ShadowMethod::Exact).
    IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                     const QuadratureOptions& options, const OcclusionContext* occlusion = nullptr);
    /// dB at (s, t); `thread` selects the integrator (0 <= thread < n_threads()).
    Rgb sample(double s, double t, int thread, long* n_kernel_evals, bool* converged = nullptr);
    /// dB at (s, t) and at (s, t) + delta, the second on the first's shooter partition, for the
    /// divided differences of (22).
    void sample_pair(double s, double t, double ds, double dt, int thread, Rgb& at_p, Rgb& at_q,
                     long* n_kernel_evals);
    int n_threads() const { return static_cast<int>(integrators_.size()); }
    const ReceiverSurface& receiver() const { return receiver_; }
    const Shooter& shooter() const { return shooter_; }
    /// The integrator of one thread (the shadow stage asks it for shooter partitions).
    IncrementIntegrator& integrator(int thread) { return *integrators_[thread]; }
    /// Rays cast by the integrators' exact visibility so far (all threads).
    long n_rays() const;

private:
    const Shooter& shooter_;
    const ReceiverSurface& receiver_;
    std::vector<std::unique_ptr<IncrementIntegrator>> integrators_;
    std::vector<long> rays_;  // per thread
};

// ---- The stages, in the paper's order ----------------------------------------------------

/// Stage 1. Predictive top-down subdivision of [0,1]^2: on each cell compare the integrals of
/// dB with ceil(m/2)^2 and m^2 Gauss-Legendre points; when they agree within the oracle
/// tolerance the cell is "nearly sufficient": split once more and stop. min_depth and
/// max_depth bound the tree.
void subdivide_by_oracle(ReceiverState& state, IncrementSampler& sampler);

/// Stage 2a. NeighAdjust (section 6, Figure 4): split until no leaf is more than twice the size
/// of any of its twelve edge and corner neighbours. Checks only leaves of `region`, but sees
/// neighbours anywhere in the forest. Returns the number of splits.
int adjust_neighbour_scales(Forest& forest, Forest::Region region);

/// Stage 2b. The m x m Gauss-Legendre samples of dB, eq. (21), on every domain leaf that has
/// none yet.
void sample_leaves(ReceiverState& state, IncrementSampler& sampler);

/// Stage 3. Boundary values and normal derivatives (22) along the four edges by the recursive
/// edgefill bisection with linear interpolation where it is smooth enough.
void fill_boundary(ReceiverState& state, IncrementSampler& sampler);

/// The extrapolated value at (s, t) outside [0,1]^2 (section 6): linear (23)-(25) with clamped
/// derivatives, or the higher-order forms meeting (26) or (27).
Rgb extrapolate(const ReceiverState& state, double s, double t);

/// Stage 4. The expanded domain (Figure 5): roots around [0,1]^2 wide enough for the rhombus of
/// every boundary fulcrum, subdivided adaptively with expanded cells next to the domain no
/// larger than the domain leaves they touch, scale-adjusted, and sampled by extrapolation.
/// Domain leaves that scale adjustment splits are sampled by (21).
void expand_domain(ReceiverState& state, IncrementSampler& sampler);

/// Samples for leaves made after stage 4 (shadow subdivision and its scale adjustment): a domain
/// leaf gets its parent's tensor polynomial resampled (and is marked `resampled`), an expanded
/// leaf the extrapolation.
void sample_split_leaves(ReceiverState& state);

/// Stage 5. Fulcrums (Figure 2): odd m, the centre of every domain leaf at the leaf's scale;
/// even m, every corner of every domain leaf at that leaf's scale (a corner shared by leaves of
/// two sizes carries two fulcrums); and the fulcrums of expanded leaves whose basis function
/// reaches into the domain.
std::vector<Fulcrum> select_fulcrums(const Forest& forest, int m);

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

/// Stage 7 (the paper's shadows, ShadowMethod::Fractions): fractions (28) at the fulcrums of
/// the domain leaves; leaves between neighbouring fulcrums whose fractions differ by more than
/// the threshold are split (then NeighAdjust; their samples are resampled from the parent's
/// polynomial), the new fulcrums' coefficients carried from the coarser ones by (17), until no
/// leaf splits or the maximum shadow depth; then every stored coefficient is multiplied by its
/// fulcrum's fraction. Does nothing without occluders. (radiosity/transfer/shadows.cpp)
void apply_shadows(ReceiverState& state, IncrementSampler& sampler, const DualTable& dn);

/// Eq. (28) at the domain point (s, t): cast options.shadows.rays_per_patch rays to random
/// points of every cell of the shooter partition the adaptive quadrature of (21) forms there;
/// sum r_i e_i / sum e_i per channel (1 where nothing arrives). Memoised in state.fractions;
/// the rays are seeded from the point and the pair's seed. `thread` picks the integrator.
Rgb fraction_at(ReceiverState& state, IncrementSampler& sampler, double s, double t, int thread);

/// The fraction a fulcrum's coefficient is masked with: at its position, or for a fulcrum
/// outside the domain at the nearest point of the domain (DESIGN, docs/method.md).
Vec2 fraction_point(const Fulcrum& f, int m);

/// Stage 8's rule for one coefficient (shared with stage 7): a stored one is used; a missing one
/// whose fulcrum's neighbourhood holds (21) samples at least as fine as its scale (or at level
/// 0, or with unify_by_projection) is projected on demand (then stored, and masked with
/// state.mask when set); otherwise it comes from (17) applied to the coefficients one level
/// coarser, recursively (memoised in `refined`).
Rgb resolve_coefficient(ReceiverState& state, const DualTable& dn, const Fulcrum& f,
                        std::map<Fulcrum, Rgb>& refined);

/// Stages 6 and 8 at once when ReceiverOptions::unify_by_projection is set (beyond the paper):
/// every coefficient of the finest level J of the domain's leaves by (19), as two
/// one-dimensional sums over the values at the m x m Gauss-Legendre nodes of every level-J cell
/// within reach: the leaves' samples (a coarser leaf's polynomial resampled, as project() does)
/// inside [0,1]^2, the extrapolation (23)-(27) evaluated at the nodes themselves outside (the
/// limit of an infinitely fine expanded domain). DN is truncated to the square |x|, |y| <= r
/// around each fulcrum, which holds the rhombus |x| + |y| <= r of Figure 3 (a tensor region is
/// what makes the sums separable). Coefficients are masked with state.mask when it is set.
SplineField project_fine_grid(ReceiverState& state, const DualTable& dn);

/// Stage 8. Every coefficient at the finest fulcrum scale 2^-j, for the basis functions that
/// touch [0,1]^2: a stored one is used; a missing one at a fulcrum whose neighbourhood is at
/// least as fine as its scale is projected on demand; otherwise it comes from (17) applied to
/// the coefficients one level coarser, recursively.
SplineField unify_scales(ReceiverState& state, const DualTable& dn);

/// The whole transfer: dB_i of one shooting, as coefficients at one scale. `occlusion` (may be
/// null) names the pair's occluders; options.shadows.method says how they enter. `dual` (may be
/// null) is DN_m for options.m, built once by a caller that runs many transfers.
SplineField transfer(const Shooter& shooter, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats = nullptr,
                     ReceiverState* keep_state = nullptr,
                     const OcclusionContext* occlusion = nullptr,
                     const DualTable* dual = nullptr);

/// The shooter as section 6 uses it: its unshot field coarsened by `levels` (not below 0).
Shooter make_shooter(const Surface& surface, const SplineField& unshot, int levels);

/// The rhombus radius (cells) the options ask for.
double rhombus_radius_cells(const ReceiverOptions& options, const DualTable& dn);

}  // namespace mbr
