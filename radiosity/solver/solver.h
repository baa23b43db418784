// radiosity/solver/solver.h - the radiosity of a whole scene by progressive refinement (paper
// section 4, the algorithm box, and section 5 "Iteration"; DESIGN.md section 4).
//
//   for each emitting surface: project its emission; B = dB_unshot = E
//   while not converged:
//     shoot from the surface with the largest unshot power  int B_unshot A
//     every surface that can receive from it gets dB by one transfer
//     (radiosity/transfer/transfer.h),
//       with shadows; B += dB, B_unshot += dB (SplineField::add)
//     B_unshot of the shooter = 0
//
// Cost follows energy: every tolerance of a transfer is the larger of its relative value and
// an absolute one in radiosity units, options.tolerance times the scene's radiosity scale
// (emitted power / total area), so a shot that carries little power builds coarse trees,
// coarse shooter partitions and casts few rays. The receivers of one shot run in parallel; the
// solution does not depend on the number of threads.
#pragma once

#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "octree/octree.h"
#include "radiosity/geometry/quadtree.h"
#include "radiosity/geometry/radiosity_view.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/scene/scene.h"
#include "radiosity/solver/ambient_gather.h"
#include "radiosity/solver/limiter.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/visibility/convex_solids.h"
#include "radiosity/visibility/hidden_regions.h"

namespace mbr {

struct GaussLegendre;

/// Options of the progressive loop and of its transfers.
struct SolverOptions {
    ReceiverOptions receiver;   // every transfer's options (order, depths, shadows, ...); its
                                //   order m is that of the surfaces without their own
                                //   (SceneSurface::order), each transfer takes its receiver's
    int max_shots = 100;        // stop after this many shots
    double convergence = 1e-3;  // stop when the largest unshot power < this x emitted
    bool self_transfer = true;  // concave curved surfaces receive from themselves
    bool cluster_shots = false;  // beyond the paper: a planar cluster shoots in one shot
                                 //   (planar_cluster, cluster_far)
    double tolerance = 2e-3;    // accuracy relative to the scene's radiosity scale: the
                                //   absolute tolerance of every transfer (see file comment)
    /// The quadrature's absolute tolerance, as a share of the transfer's (a constant).
    static constexpr double quadrature_share = 1;
    /// The level at which a textured emission is projected (a constant).
    static constexpr int emission_level = 5;
    bool hidden_regions = true;     // beyond the paper: samples at points that see no front
                                    //   face take the nearest visible point's value
                                    //   (radiosity/visibility/hidden_regions.h)
    int shooter_level = 4;          // a shooter's unshot field is coarsened to at most this
                                    //   level (the paper's "lower resolution version", section
                                    //   6); the receiver options' shooter_coarsening levels at
                                    //   least (levels 4 and 5 measured: docs/method.md)
    bool limiter = true;            // beyond the paper: increments clipped to at most
                                    //   rho_max max B_h (limiter.h; radiosity_view makes what
                                    //   is viewed non-negative by the scene's setting)
    bool irradiance_fields = true;  // beyond the paper: a surface with a textured reflectance
                                    //   stores H (B = E + rho H, radiosity_view.h)
    int exact_shadow_casters = 0;   // > 0 with exact shadows (`set shadows auto`): a pair with
                                    //   more shadow casters than this (convex solids and the
                                    //   surfaces of other occluders: shadow_casters) takes the
                                    //   paper's fractions instead
    bool ambient = true;            // beyond the paper: at the end, the power still unshot is
                                    //   sent on through the measured coupling of the surfaces
                                    //   (the fraction of each shooter's power each receiver got,
                                    //   over all its shots) and added as a constant radiosity per
                                    //   surface (Cohen et al. 1988's ambient term, with measured
                                    //   instead of area-weighted coupling)
    int ambient_rays = 256;         //   gathered by this many rays per Gauss point of each
                                    //   surface (ambient_gather.h, gather_rays_per_point); 0:
                                    //   the constant per surface
    int ambient_level = 1;          //   at the Gauss points of this level's cells
    bool ambient_final = true;      //   and the final gather after it (ambient_gather.h)
};

/// The scene's `set` statements as solver options (shadows: the scene's method and rays).
SolverOptions solver_options(const SolverSettings& settings);

/// A surface b that lies in front of planar surface a's plane, but by no more than the plane
/// tolerance of the receiver test (1e-9 of a's size): the solver treats it as lying on that
/// plane, so no light passes between a and b (a light 1e-9 below a ceiling or above a floor).
struct NearContact {
    int a = -1, b = -1;  // surface indices
    double gap = 0;      // how far b reaches in front of a's plane
};
/// The near contacts between each emitter and every other surface (O(emitters x surfaces)),
/// found before solving so that programs can warn about them.
std::vector<NearContact> near_contacts(const Scene& scene);

/// A planar cluster (beyond the paper; issue 21's shooter clusters in their simplest form): the
/// planar surfaces that lie in the shooter's plane, face its way, hold at least cluster_share
/// of its unshot power and lie next to it or to another member (planar_cluster) shoot with it in
/// one shot. They cannot see one another, so they receive nothing from each other, and a
/// receiver cluster_far away takes one transfer of their summed fields (transfer() with several
/// ShooterParts): one tree, one fit and one projection for the pieces of a floor or the tubes
/// of a luminaire, instead of one per piece. DESIGN: a tenth.
constexpr double cluster_share = 0.1;
/// Next to: a member's bounding box grown by this share of the smaller of the two boxes'
/// diagonals meets the other's. DESIGN: a quarter (lamps spread over a ceiling stay apart: each
/// sample of a cluster's transfers integrates over every member, and with every coplanar
/// surface joining, and every receiver taking one transfer of the sum, corridor.mgf took twice
/// its time).
constexpr double cluster_reach = 0.25;
/// A planar cluster's bounds stay within this many times the lead's diagonal: the pieces of one
/// face (the three quads of a triangle, a floor's pieces around a block), not a whole floor of
/// tiles, whose near receivers would each take a transfer from every tile in one shot (without
/// it the classroom's third shot had 30,711 transfers; with it its 25th still had 27,248, a
/// large piece with many small ones beside it, where a shot without clusters has about 5,000).
/// DESIGN: 2.
constexpr double cluster_extent = 2;
/// A receiver at least this many of a planar cluster's diagonals (of the members' bounds
/// together) away takes one transfer of their sum; a nearer one takes a transfer from each member
/// on its own, as if each shot alone (the members' shares of a near receiver differ in shape, and
/// every sample of one transfer would integrate over all of them). DESIGN: 1.
constexpr double cluster_far = 1;
/// At most this many surfaces in one planar cluster. DESIGN.
constexpr int max_cluster_members = 64;

/// The planar cluster of shooter h (h first, then the others in index order), given every
/// surface's unshot power; {h} when h is not planar. Coplanar: normals within 1e-9 of each other
/// and every hull point within the `behind` test's plane tolerance of h's plane. Grown from h by
/// cluster_reach within cluster_extent; beyond max_cluster_members the candidates met first (in
/// index order) stay.
std::vector<int> planar_cluster(const Scene& scene, int h, const std::vector<double>& unshot);

/// One shot of the loop, measured.
struct ShotStats {
    int shot = 0;              // 1, 2, ...
    int shooter = -1;          // surface index
    int members = 1;           // surfaces that shot (a planar cluster: the shooter and others)
    double shooter_power = 0;  // its unshot power int B_unshot A (sum of channels) before (a
                               //   planar cluster's: its members' together)
    double unshot_before = 0;  // the scene's total unshot power before the shot
    double unshot_after = 0;   //   and after
    double reflected = 0;      // power the receivers reflect: sum_i int dB_i A
    double incident = 0;       // power arriving: sum_i int dB_i A / rho_i (constant rho)
    int receivers = 0;         // transfers made
    long kernel_evals = 0;     // evaluations of (3) in all its transfers
    long analytic_evals = 0;   // closed-form form factors (an emitter's analytic path)
    double limited = 0;        // power the limiter changed (clipping overshoots down: <= 0),
                               //   sum of channels
    long rays = 0;             // shadow rays
    int paper_transfers = 0;   // transfers that took the paper's fractions under shadows auto
    int weak_transfers = 0;    // transfers the weak transfer rule kept at the root
    int finest_level = 0;      // finest level of its results
    double seconds = 0;
};

/// The whole run.
struct SolveStats {
    int shots = 0;
    double seconds = 0;
    double emitted_power = 0;    // sum over emitters and channels of int E A
    double unshot_power = 0;     // what remains unshot at the end (same units)
    bool converged = false;      // the convergence test stopped the loop (not max_shots)
    long peak_memory_bytes = 0;  // the process's peak resident memory
    long coefficients = 0;       // coefficients of the solved fields (all surfaces, per channel)
    long kernel_evals = 0, rays = 0;
    long analytic_evals = 0;     // closed-form form factors (ShotStats::analytic_evals)
    long transfers = 0;          // of all shots (ShotStats::receivers)
    long paper_transfers = 0;    //   of which with the paper's fractions under shadows auto
    long weak_transfers = 0;     //   of which weak transfers (ShotStats::weak_transfers)
    long clustered_shots = 0;    // shots of planar clusters (ShotStats::members > 1)
    long clustered_surfaces = 0;  //   and the surfaces that shot in them
    double ambient_power = 0;    // power the ambient correction added (sum of channels)
    long ambient_rays = 0;       //   and the rays its gather cast
    double ambient_seconds = 0;  //   and the gather's wall time
    double limited_power = 0;    // the limiter's change of the reflected power, all shots (<= 0)
    std::vector<ShotStats> per_shot;
};

/// The most occluder candidates (polygon indices, a box counting as 12) a solver keeps from one
/// shot to the next, over all pairs (ProgressiveSolver; 16 MiB; the memory estimate counts it).
constexpr size_t max_cached_candidates = size_t(1) << 22;

/// A solved scene: per surface (in scene order) its field, what it holds (quantity: B with the
/// emission included, or H for a textured reflectance, B = E + rho H; radiosity_view() forms
/// B either way), what is still unshot (always B), and the union of the receiver quadtrees each
/// surface was given (leaves).
struct Solution {
    std::vector<SplineField> radiosity;
    std::vector<FieldQuantity> quantity;  // per surface; empty means every field holds B
    std::vector<SplineField> unshot;
    std::vector<std::vector<DyadicCell>> leaves;
    SolveStats stats;
};

/// Per channel the largest coefficient of `field`, at least 0: a bound of the field's values.
Rgb coefficient_bound(const SplineField& field);

/// B_i(u, v) of every surface of a solution of `scene` (both must outlive the view). With the
/// scene's `limiter` setting on, the view reads copies of the fields made non-negative by
/// limit_positive; the solution is unchanged.
RadiosityView radiosity_view(const Scene& scene, const Solution& solution);

/// The power weights of a surface's fields of order m at `level`: w[k * n + l] = int int
/// N_m(2^j s - k) N_m(2^j t - l) A(s, t) ds dt over [0,1]^2 (A the area factor (4); k, l over
/// the n touching indices from first_touching_index), so that int B A = sum_kl c_kl w_kl. On a
/// planar quad A is linear in s and t and the weights separate into one-dimensional moments
/// (O(n^2)); on other surfaces (m + 2)-point Gauss per cell in both directions.
std::vector<double> area_weights(const Surface& surface, int m, int level);
/// The same by the two-dimensional rule on every surface (the reference of area_weights).
std::vector<double> area_weights_by_cells(const Surface& surface, int m, int level);

/// True when surface i of `scene` stores H under `options` (a textured reflectance with
/// irradiance_fields on).
bool stores_irradiance(const Scene& scene, int surface, const SolverOptions& options);

/// The progressive loop, one shot at a time (for progress reports and tests).
class ProgressiveSolver {
public:
    /// Projects the emission; the scene and octree must outlive the solver. The octree is the
    /// one shadow rays use (build_octree(scene)).
    /// on_setup (may be empty) is called after each surface's hidden regions are found, with
    /// the surfaces done and their total (the setup before the first shot, for progress).
    ProgressiveSolver(const Scene& scene, const Octree& octree, const SolverOptions& options,
                      const std::function<void(int done, int total)>& on_setup = {});
    /// True when the convergence test or the shot limit says stop.
    bool done() const;
    /// One shot: from the surface with the largest unshot power to every surface that can
    /// receive. Returns its statistics (also appended to solution().stats.per_shot).
    ShotStats shoot();
    /// Called during each shot after every receiver's transfer, with the transfers done and
    /// their total (for progress inside a long shot). Calls come one at a time, from whichever
    /// thread finished the transfer; the function must not call back into the solver.
    void on_transfer(std::function<void(int done, int total)> f) { on_transfer_ = std::move(f); }
    /// The fields so far.
    const Solution& solution() const { return solution_; }
    /// The fields so far, with run statistics filled (seconds, memory, coefficients) and the
    /// ambient correction added. Call it last: the fields move into the result, and the solver
    /// is left without them (solution() is empty after).
    Solution finish();
    /// The scene's radiosity scale: emitted power (the largest channel) / total area.
    double radiosity_scale() const { return radiosity_scale_; }
    /// Unshot power of surface i: int B_unshot A over its domain, summed over channels.
    double unshot_power(int surface) const;

private:
    const Scene& scene_;
    const Octree& octree_;
    SolverOptions options_;
    std::function<void(int done, int total)> on_transfer_;
    /// Per surface the order m of its fields (surface_order: its own, else options.receiver.m).
    std::vector<int> order_;
    /// DN_m for every order m in use, built once (index m; null for an order no surface has).
    std::vector<std::unique_ptr<DualTable>> duals_;
    Solution solution_;
    std::vector<std::vector<std::uint64_t>> split_cells_;  // per surface: cells split in some tree
    /// coupling_[j][i]: the power (per channel) surface i received from all of j's shots, and
    /// shot_power_[j] the power j shot in them: their ratio is the measured fraction of j's
    /// power that reaches i (empty until j shoots).
    std::vector<std::vector<Rgb>> coupling_;
    std::vector<Rgb> shot_power_;
    /// The ambient correction of SolverOptions::ambient, per surface: a constant radiosity.
    std::vector<Rgb> ambient_correction() const;
    double radiosity_scale_ = 0;
    double largest_area_ = 0;  // of the scene's surfaces (the shadow split rule's scale)
    double start_seconds_ = 0;
    /// Power weights w_kl = int int N_k N_l A per surface and level (cached).
    const std::vector<double>& power_weights(int surface, int level) const;
    mutable std::vector<std::vector<std::vector<double>>> weights_;
    std::vector<HiddenMask> hidden_;    // per surface (empty masks when the option is off)
    std::vector<double> last_seconds_;  // per surface: its last transfer's seconds (scheduling)
    /// The occluder candidates of a shooter -> receiver pair (make_occlusion_context), kept from
    /// the pair's first transfer for its later ones: they depend on the two surfaces only.
    /// Bounded by max_cached_candidates ints in all (beyond, a pair's are found every time).
    std::map<std::pair<int, int>, OcclusionContext> candidates_;
    /// The scene's convex solids (exact visibility only; the contexts point into it).
    std::unique_ptr<const ConvexSolids> solids_;
    size_t cached_candidates_ = 0;
    /// The occlusion context of shooter h -> receiver i in shot `shot` (none without shadows).
    OcclusionContext occlusion_of(int h, int i, int shot) const;
    Rgb power(int surface, const SplineField& field) const;
    /// The unshot increment of an irradiance receiver: the L2 projection of rho dH (eq. (2)).
    SplineField reflected_field(int surface, const SplineField& dH) const;

    /// What one receiver got from a shot: dB_i, its transfer's counts, the cells its tree split.
    struct Received {
        SplineField field;  // dB_i, or dH_i for an irradiance receiver
        TransferStats stats;
        std::vector<std::uint64_t> splits;
        bool paper = false;  // shadows auto gave it the paper's fractions
    };
    /// The surfaces that receive from shooter h: every other surface that reflects and faces h
    /// (front to front), and h itself when it is concave and self_transfer is on.
    std::vector<int> receivers_of(int h) const;
    /// The same for the members of a planar cluster (h first): the union of their receivers.
    std::vector<int> receivers_of(const std::vector<int>& members) const;
    /// One transfer per receiver (section 5) from the members that face it (all of them for
    /// one shooter), in parallel over receivers; the results do not depend on the order.
    std::vector<Received> transfer_to(const std::vector<int>& receivers,
                                      const std::vector<int>& members,
                                      const std::vector<Shooter>& shooters,
                                      const ReceiverOptions& options, int shot_number);
    /// Superposition in receiver order: B_i += dB_i, B_unshot_i += dB_i, the measured coupling
    /// of the members to each receiver (a cluster's shared in proportion to the members'
    /// power) and the cells split, then every member's B_unshot = 0 (or what a concave shooter
    /// received from itself). Fills the shot's power and count fields.
    void superpose(const std::vector<int>& receivers, std::vector<Received>& results,
                   const std::vector<int>& members, const std::vector<Shooter>& shooters,
                   ShotStats& shot);
};

/// Solves the scene: shots until done(), calling on_shot (may be empty) after each.
/// on_setup is passed to the solver (progress of the hidden regions), and on_transfer to its
/// on_transfer (progress inside each shot).
Solution solve(const Scene& scene, const Octree& octree, const SolverOptions& options,
               const std::function<void(const ShotStats&, const ProgressiveSolver&)>& on_shot = {},
               const std::function<void(int done, int total)>& on_setup = {},
               const std::function<void(int done, int total)>& on_transfer = {});

/// The projection of a surface's emission: constant coefficients for a constant texture, else
/// the L2 projection at `level` (Gauss-Legendre quadrature of the texture against the basis,
/// then the Gram solve of math/wavelet.h's kind).
SplineField project_emission(const Texture& emission, int m, int level);
/// The L2([0,1]^2) projection of f onto the order-m basis of `level` (the same rule, f at 8 x 8
/// Gauss-Legendre points per cell).
SplineField l2_projection(const std::function<Rgb(double, double)>& f, int m, int level);
/// The same projection from samples at the `points`-point Gauss-Legendre nodes of every
/// level-`level` cell: a grid of side = 2^level x points values, samples[S * side + T] at
/// ((S / points + x_(S % points)) / 2^level, (T / points + x_(T % points)) / 2^level), x the
/// nodes on [0,1]. With points >= m the Gram matrix is exact; at level 0 with points = m it is
/// the tensor polynomial through the samples.
SplineField l2_projection_of_samples(int m, int level, int points, const Rgb* samples);
/// The coordinate on [0,1] of sample `index` along one direction of that grid: (index / points
/// + x_(index % points)) / 2^level, with the nodes of `rule` (points = rule.n()).
double projection_sample_coordinate(const GaussLegendre& rule, int index, int level);

}  // namespace mbr

// Saving and loading solutions: solution_file.h, included here so that includers of solver.h
// keep compiling.
#include "radiosity/solver/solution_file.h"
