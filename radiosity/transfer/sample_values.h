// radiosity/transfer/sample_values.h - the sample value of one energy transfer (paper section 4,
// eq. (21); section 6, "Adaptive Quadrature"): the integral over the shooter of the kernel of
// radiosity/transfer/form_factor.h, with exact visibility when asked
// (radiosity/visibility/visible_parts.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "math/convex2d.h"
#include "math/gauss_legendre.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/transfer/form_factor.h"
#include "radiosity/visibility/occlusion.h"
#include "radiosity/visibility/visible_parts.h"

namespace mbr {

/// The shooting surface of one transfer and its unshot radiosity (already at the level the
/// caller wants; section 6 coarsens it first). `patches` (optional) is `unshot` as polynomial
/// pieces, built once for all the shot's receivers (make_shooter); without it each transfer's
/// integrator builds its own.
struct Shooter {
    const Surface* surface = nullptr;
    SplineField unshot;
    std::shared_ptr<const PolynomialPatches> patches;
};

/// The near-field guard of the adaptive quadrature of (21): a shooter cell whose extent exceeds
/// this many times its distance from the receiving point is split whatever its error estimate
/// (0: never).
constexpr double near_field_guard = 4.0;
/// The near-field guard when the singularity is subtracted (QuadratureOptions::subtract; 0:
/// off: the remainder has no peak a cell's nodes could miss).
constexpr double near_field_guard_subtracted = 0;
/// A shooter cell the horizon or a shadow cuts is split down to this level before its visible
/// pieces are integrated (the root's pieces would be many; deeper cells are split by the error
/// test when their pieces disagree).
constexpr int min_cut_level = 1;
/// The deepest patch of a fraction's partition (fraction_partition): about 1e-4 of the
/// shooter's side, far below what the fraction's few hundred rays resolve.
constexpr int max_fraction_depth = 14;

/// Options of the adaptive quadrature of (21) over the shooter (section 6).
struct QuadratureOptions {
    int n = 6;                    // compare n x n with (n+1) x (n+1) Gauss-Legendre points
    double rel_tolerance = 1e-4;  // allowed error relative to a first estimate of the integral
    double abs_tolerance = 0;     // and never below this absolute error (the integral's units:
                                  //   radiosity); a scene sets it from its accuracy, so a weak
                                  //   shot's partitions stay coarse
    int max_depth = 24;           // cap on the shooter's subdivision (at most 28)
    int min_depth = 1;            // the whole shooter is never accepted as one cell
    double min_share = 1e-6;  // floor of a cell's share of the tolerance (math/gauss_legendre.h)
    bool global = false;      // refine the worst cell first until the error estimates sum
                              //   to the tolerance (AdaptiveOptions::global), instead of
                              //   the paper's quarter tolerance per child
    bool analytic = true;     // a planar quad shooter of constant radiosity (an emitter's
                              //   first shot): I(p) by the contour formula over the
                              //   visible pieces, no quadrature (not when a partition is
                              //   asked for)
    bool shadow_subtraction = true;  // planar shooters with occluders: the cells see only the
                                     //   horizon, and the shadowed part (the union of the shadows
                                     //   in front) is integrated on its own and subtracted; else
                                     //   each cut cell's visible pieces are integrated
    int n_pieces = 0;                // the rule pair on cut cells' pieces and shadow triangles:
                                     //   the triangle rules of degrees 2 n_pieces - 2 and
                                     //   2 n_pieces (0: n, as cells)
    bool subtract = true;            // planar quad shooters of varying radiosity: I(p) =
                                     //   B_h(x*) F(p -> visible part) + int F (B_h - B_h(x*)),
                                     //   the first term by the contour formula (x* the foot of p
                                     //   on the shooter), so the peak of F near a receiving point
                                     //   close to the shooter (surfaces that meet) is exact and the
                                     //   remainder is nearly flat there
    bool clip_horizon = true;        // planar shooters: integrate cells the receiving point's
                                     //   tangent plane cuts over their front part only (exact
                                     //   convex pieces), instead of chasing the kink of the
                                     //   clamped cosine of (3) down to max_depth
    int max_visibility_depth = 10;   // exact visibility on a curved shooter: cells whose nodes
                                     //   disagree on visibility are split down to this level
};

/// One shooter point of the quadrature with everything that does not depend on the receiver:
/// position, normal and e = w_a w_b J A_h(u,v) B_h(u,v) (Gauss-Legendre weights, the Jacobian
/// J of the map from [-1,1]^2 to the cell, the area factor (4), the unshot radiosity).
struct ShooterPoint {
    Vec3 x;
    Vec3 n;
    Rgb e;
    double a = 0;  // w_a w_b J A_h(u,v): e without B_h (for the singularity subtraction)
};

/// Bounds of an integrator's caches of shooter points (tensor cells, and pieces only the
/// horizon cuts), beyond which each starts over: values never depend on them. DESIGN: 2^17
/// and 2^16 points (16 and 8 MiB with their nodes' arrays, 128 bytes a point; 10 and 5 MiB
/// before the arrays); 2^20 made the room peak at 195 MiB, 126 MiB of it these caches
/// (docs/method.md, "Memory and threads").
constexpr size_t max_cached_points = size_t(1) << 17;
constexpr size_t max_cached_horizon_points = size_t(1) << 16;
/// The most one integrator's caches hold, in bytes (the memory estimate counts it per thread).
double cached_points_bytes();

/// A triangle of the shadowed part of a shooter (shadow subtraction): fan triangle `fan` of the
/// shadow region `region`, and three points in its barycentric coordinates (weights of its
/// second and third corners), `level` halvings deep.
struct ShadowTriangle {
    int region = 0, fan = 1;
    Vec2 bary[3];
    int level = 0;
    /// The four triangles of its edges' midpoints.
    std::array<ShadowTriangle, 4> children() const {
        const Vec2 ab = 0.5 * (bary[0] + bary[1]), bc = 0.5 * (bary[1] + bary[2]),
                   ca = 0.5 * (bary[2] + bary[0]);
        return {ShadowTriangle{region, fan, {bary[0], ab, ca}, level + 1},
                ShadowTriangle{region, fan, {ab, bary[1], bc}, level + 1},
                ShadowTriangle{region, fan, {ca, bc, bary[2]}, level + 1},
                ShadowTriangle{region, fan, {ab, bc, ca}, level + 1}};
    }
    bool operator<(const ShadowTriangle& o) const {
        if (region != o.region) return region < o.region;
        if (fan != o.fan) return fan < o.fan;
        if (level != o.level) return level < o.level;
        for (int k = 0; k < 3; ++k) {
            if (bary[k].x != o.bary[k].x) return bary[k].x < o.bary[k].x;
            if (bary[k].y != o.bary[k].y) return bary[k].y < o.bary[k].y;
        }
        return false;
    }
};

/// The integral of eq. (21) without the receiver's reflectance:
///   I(p) = int_{[0,1]^2} F(p, x_h(u,v)) VIS B_h(u,v) A_h(u,v) du dv,
/// by the adaptive rule of section 6 (n against n + 1 points per cell, split in four with a
/// quarter of the tolerance). VIS = 1 unless an occlusion context is given (exact visibility,
/// radiosity/visibility/visible_parts.h): then a planar shooter's cells are clipped to what p sees,
/// and a curved shooter's nodes each cast a ray. Shooter points are cached per dyadic cell, so one
/// integrator per thread: the cache changes speed, never values, so results do not depend on
/// thread count.
class IncrementIntegrator {
public:
    IncrementIntegrator(const Shooter& shooter, const QuadratureOptions& options,
                        const OcclusionContext* occlusion = nullptr);

    struct Result {
        Rgb value;
        long n_evaluations = 0;  // kernel evaluations
        long n_rays = 0;         // visibility rays (exact visibility on a curved shooter)
        Rgb subtracted;          // B_h(x*) when the singularity was subtracted (the partition's
                                 //   cell values are then those of the remainder)
        bool shadow_subtracted = false;  // the shadowed part was integrated on its own
        std::vector<ShadowTriangle> shadow_triangles;  // its triangles (integrate_on reuses them)
        std::vector<int> shadow_shape;  // the vertex count of each shadow region they refer to
        double shadow_tolerance = 0;    // the tolerance the shadowed part was integrated to,
        double shadow_near_field = 0;   //   and its near-field guard
        bool converged = true;
        std::vector<AcceptedCell<Rgb>> partition;  // the shooter's cells, when asked for
    };
    /// I(p) by the adaptive rule; the shooter partition is kept when keep_partition is set
    /// (the shadow stage casts rays to its cells; edgefill reuses it for divided differences).
    /// min_depth >= 0 overrides the options' smallest depth of the partition.
    Result integrate(const SurfacePoint& p, bool keep_partition = false, int min_depth = -1,
                     bool allow_subtraction = true);
    /// I(p) on a given partition with the (n+1)-point rule on each cell: the same quadrature
    /// error pattern as the run that made the partition, so divided differences (22) of nearby
    /// points are not swamped by it. `made_by`, the result that made the partition, says
    /// whether (and what) it subtracted: the same constant is subtracted here.
    Rgb integrate_on(const SurfacePoint& p, const std::vector<AcceptedCell<Rgb>>& partition,
                     long* n_evaluations, long* n_rays = nullptr, const Result* made_by = nullptr);
    /// The shooter partition of a visible fraction (28) at p, with each patch's energy toward p
    /// (its n-point rule): the uniform 2^depth x 2^depth grid, the paper's fixed partition, with
    /// the cells too near p for their size (the near-field guard of integrate) and the horizon's
    /// coarse cut cells split further, down to max_fraction_depth. The energies only weigh the
    /// patches' rays, so one rule per cell suffices (not the n against n + 1 refinement of (21),
    /// whose partition near a contact or a horizon has thousands of cells). Adds the kernel
    /// evaluations to *n_evaluations.
    std::vector<AcceptedCell<Rgb>> fraction_partition(const SurfacePoint& p, int depth,
                                                      long* n_evaluations);
    /// Points the tensor cache has room for now (at most max_cached_points).
    size_t cached_point_capacity() const { return pool_.capacity(); }
    /// The points of a cell for the n-point rule (cached): n*n points from `first`, valid until
    /// the next call.
    struct PointSpan {
        const ShooterPoint* first;
        int count;
        const double* nodes;  // their positions and normals as arrays (shooting_nodes' block)
    };
    PointSpan points(const QuadCell& cell, int n);
    /// The shooter's plane when it is a planar quad, else null.
    const ShooterPlane* shooter_plane() const { return planar_ ? &plane_ : nullptr; }
    /// B_h(u, v), the shooter's unshot radiosity (the field's polynomial patches where it has
    /// them: one Horner evaluation, for a fraction's rays).
    Rgb shooter_radiosity(double u, double v) const;
    /// True when integrate() uses the closed form (QuadratureOptions::analytic).
    bool analytic() const { return analytic_; }
    /// Closed-form form factors to the visible part of the shooter computed so far (the
    /// analytic path of an emitter's shot and the singularity subtraction), counted apart from
    /// kernel evaluations: each is one evaluation of the point-to-polygon formula.
    long n_analytic() const { return n_analytic_; }
    /// Every receiving point lies on this plane (a planar receiver): the horizon is one line,
    /// and the points of the cells it cuts are cached like the others.
    void set_receiver_plane(const Plane& plane) { receiver_plane_ = plane; }

private:
    Rgb sum_over(const SurfacePoint& p, PointSpan pts) const;
    /// The visible part's form factor from p by the contour formula (after set_view).
    double visible_form_factor(const SurfacePoint& p);
    /// The n x n rule on one cell as p sees it (the view of the last set_view): cached points
    /// for a clear cell, zero for a hidden one, convex pieces for a cut one; per-node rays on
    /// a curved shooter with an occlusion context.
    Rgb cell_value(const SurfacePoint& p, const QuadCell& cell, int n);
    /// Fills local_ with the occluders that can come between p and the nodes `pts` of `cell`
    /// (ray visibility: a curved shooter, or too many occluders to project); on a planar
    /// shooter those of the whole cell, kept per cell until the next set_view.
    void collect_shaft_occluders(const SurfacePoint& p, const QuadCell& cell, const PointSpan& pts);
    void set_view(const SurfacePoint& p);
    /// The near-field guard: the cell's nodes and corners span more than near_field times their
    /// distance from p (its rule cannot be trusted there).
    bool too_near(const SurfacePoint& p, const QuadCell& cell, double near_field);
    void cell_image(const QuadCell& cell, ConvexPolygon& image) const;
    ConvexPolygon image_;                // scratch of cell_value: the current cell's image
    std::vector<Vec3> lambert_polygon_;  // scratch of visible_form_factor: a piece in space
    Rgb pieces_value(const SurfacePoint& p, const std::vector<ConvexPolygon>& pieces, int n);
    /// A triangle of the shooter's plane, the (u, v) of its corners (unless B_h is constant)
    /// and twice its area: what both rules of a shadow triangle share.
    struct ShadowTriangleCorners {
        Vec2 a, b, c;
        Vec2 uv_a, uv_b, uv_c;
        double jacobian;
    };
    ShadowTriangleCorners triangle_corners(Vec2 a, Vec2 b, Vec2 c) const;
    /// The triangle rule of degree 2n - 2 (tri_rules_[n]) of F (B_h - b*) on the triangle.
    Rgb triangle_value(const SurfacePoint& p, const ShadowTriangleCorners& t, int n);
    /// Adds w |ab x ac| F (B_h - b*) at each node of `rule` on the triangle (a, b, c) of the
    /// shooter's plane to `sum`, node after node; B_h's (u, v) by two Newton steps from the
    /// corners' when `corners` is given, else by the exact inverse of the bilinear map.
    void add_triangle_rule(const SurfacePoint& p, Vec2 a, Vec2 b, Vec2 c, double jacobian,
                           const TriangleRule& rule, const ShadowTriangleCorners* corners,
                           Rgb& sum);
    /// int F (B_h - b*) over the shadowed part (shadow_regions_) to `tolerance`, adaptively
    /// over its fan triangles; the triangles kept are appended to *kept.
    Rgb shadow_integral(const SurfacePoint& p, double tolerance, double near_field,
                        std::vector<ShadowTriangle>* kept);
    /// The same on given triangles (those another point kept), with the n + 1 rule.
    Rgb shadow_on(const SurfacePoint& p, const std::vector<ShadowTriangle>& triangles);
    std::vector<ConvexPolygon> shadow_regions_;  // disjoint convex parts of the shadows in front
    void take_shadows_apart();  // view_'s shadows -> shadow_regions_ (then view_ has none)

    const Shooter& shooter_;
    QuadratureOptions options_;
    const OcclusionContext* occlusion_ = nullptr;  // exact visibility when set (and not clear)
    bool planar_ = false;                  // the shooter is a planar quad: exact clipping works
    bool analytic_ = false;                // and of constant radiosity: closed form
    long n_analytic_ = 0;                  // visible_form_factor calls (n_analytic())
    ShooterPlane plane_;                   // its frame
    BlockedView view_;                     // what the current point cannot see
    std::vector<TriangleRule> tri_rules_;  // tri_rules_[n]: exact for degree 2n - 2
    long extra_evaluations_ = 0;           // kernel evaluations on cut pieces (current point)
    long rays_ = 0;                        // rays cast for the current point
    Rgb b_star_;                           // the constant subtracted from B_h (zero: none)
    std::vector<int> local_;               // scratch: the occluders of one cell's shaft
    /// Per cell of a planar shooter, the occluders of its shaft from the current point (cleared
    /// by set_view): collect_shaft_occluders filters a child's from its parent's.
    std::unordered_map<std::uint64_t, std::vector<int>> shaft_lists_;
    RecentBlockers recent_blockers_;       // the last blockers of the nodes' rays, tried first
    std::vector<std::uint64_t> mixed_;     // cells whose nodes disagreed on visibility (curved), or
                                           //   cut cells above min_cut_level (planar): split
    // DESIGN: with ray visibility, a cell whose nodes disagree on visibility is split only while
    // its value without occluders exceeds the whole tolerance (the most its visibility can get
    // wrong); smaller, the global rule weighs its n against n + 1 estimate with the others.
    // Splitting every such cell down to max_visibility_depth made ~20000 cells (max_cells) for
    // each receiving point near a shadow's edge on a curved shooter: a disk lamp over a cylinder
    // on a floor did not finish its first shot in 300 s.
    double mixed_tolerance_ = 0;        // integrate's tolerance with ray visibility, else 0
    std::uint64_t pieces_key_ = ~0ULL;  // the cut cell whose pieces are in pieces_
    std::vector<ConvexPolygon> pieces_;
    std::shared_ptr<const PolynomialPatches> unshot_patches_;  // B_h at scattered points
    std::optional<Plane> receiver_plane_;  // set_receiver_plane
    /// The front pieces' points of cells only the (fixed) horizon cuts, per cell and rule.
    struct HorizonPoints {
        std::vector<ShooterPoint> points;
        std::vector<double> nodes;  // shooting_nodes' block of the points
    };
    std::unordered_map<std::uint64_t, HorizonPoints> horizon_cache_;
    size_t horizon_points_ = 0;  // points in horizon_cache_ (each entry counts at least one)
    PointSpan horizon_points(const QuadCell& cell, int n, const ConvexPolygon& image);
    std::vector<GaussLegendre> rules_;  // rules_[n]
    std::vector<ShooterPoint> pool_;    // every cached cell's points, one after the other
    std::vector<double> pool_nodes_;    // each cell's shooting_nodes block, at 6 x its offset
    std::vector<Rgb> unshot_values_;    // scratch: B_h on one cell's grid
    std::unordered_map<std::uint64_t, std::uint32_t> cache_;  // cell key -> offset in pool_
    double unshot_bound_ = 0;       // max |B_h| bound: the largest coefficient
    bool unshot_constant_ = false;  // B_h is one constant (an emitter's first shot)
};

}  // namespace mbr
