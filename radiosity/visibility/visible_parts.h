// radiosity/visibility/visible_parts.h - visibility in one energy transfer (paper section 5,
// "Adaptive Subdivision in Shadow Computation"; section 6, "Shadow" and "Octree"; eq. (28);
// DESIGN.md section 3, stage 7).
//
// Two methods, chosen by ShadowOptions::method (radiosity/transfer/receiver_state.h):
//   Fractions (the paper's, the default): the transfer is computed without shadows; then, for
//     each selected fulcrum, rays are cast to every patch of the shooter partition that the
//     adaptive quadrature of (21) formed for that point, the visible fraction is (28), leaves
//     between fulcrums whose fractions differ are split (shadow subdivision), and every
//     coefficient is multiplied by its fulcrum's fraction.
//   Exact (beyond the paper): VIS enters (21) itself. For a planar shooter the occluders are
//     projected from the receiving point onto the shooter's plane, and the quadrature integrates
//     over exactly the visible part of each shooter cell (cells the projections cut are split
//     into convex pieces); the shadowed samples are then projected like any others, so the
//     oracle refines the receiver where the shadow needs it. Other shooters fall back to one
//     ray per quadrature node, splitting the shooter cells whose nodes disagree.
// Both use the paper's octree: a pair of surfaces that no polygon can come between (none meets
// the convex hull of the two) casts no rays and projects nothing.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "math/convex2d.h"
#include "octree/octree.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/visibility/convex_solids.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

/// A planar quad shooter in a 2D frame of its plane: what exact visibility clips.
struct ShooterPlane {
    Vec3 origin, e1, e2, normal;  // orthonormal frame; normal is the shooter's front
    Vec2 corner[4];               // corners at (u,v) = (0,0), (1,0), (1,1), (0,1)
    ConvexPolygon outline;        // the same, counter-clockwise
    double size = 0;              // the square root of its area: the scale of its tolerances
    Vec2 to_plane(Vec3 x) const { return {dot(x - origin, e1), dot(x - origin, e2)}; }
    Vec3 to_space(Vec2 q) const { return origin + q.x * e1 + q.y * e2; }
    /// The point of the bilinear map at (u, v), in the frame.
    Vec2 at(double u, double v) const;
    bool parallelogram = false;       // the map is affine: parameters() by a 2 x 2 inverse
    Vec2 inverse_row0, inverse_row1;  // that inverse (when parallelogram)
    /// (u, v) of a point of the plane (inverse bilinear map).
    Vec2 parameters(Vec2 q) const {
        if (parallelogram) {
            const Vec2 d = q - corner[0];
            return {dot(inverse_row0, d), dot(inverse_row1, d)};
        }
        return inverse_bilinear(corner[0], corner[1], corner[2], corner[3], q);
    }
    /// (u, v) of q from a nearby guess: one Newton step on the bilinear map (exact for a
    /// parallelogram; from a guess off by d, off by about |twist| d^2 after it).
    Vec2 refine_parameters(Vec2 q, Vec2 guess) const {
        if (parallelogram) return parameters(q);
        const Vec2 e = corner[1] - corner[0], f = corner[3] - corner[0];
        const Vec2 g = corner[0] - corner[1] + corner[2] - corner[3];
        const double u = guess.x, v = guess.y;
        const Vec2 r = corner[0] + u * e + v * f + (u * v) * g - q;
        const Vec2 pu = e + v * g, pv = f + u * g;
        const double det = cross(pu, pv);
        if (det == 0) return guess;
        const double inverse = 1 / det;
        return {u - cross(r, pv) * inverse, v - cross(pu, r) * inverse};
    }
};
/// The frame of a planar quad (its corners projected onto their mean plane).
ShooterPlane make_shooter_plane(const Surface& planar_quad);

/// What a receiving point cannot see of a planar shooter: the part behind its tangent plane
/// (the horizon, where the clamped cosine of (3) has a kink) and, with exact visibility, the
/// central projections of the occluders onto the shooter's plane, clipped to the shooter.
struct BlockedView {
    bool behind_all = false;             // the whole shooter is behind the horizon
    bool horizon_cuts = false;           // the horizon line crosses the shooter
    HalfPlane front;                     // the visible side of the horizon line
    double front_tolerance = 0;          // points within it of the line lie on it
    std::vector<ConvexPolygon> shadows;  // projected occluders (counter-clockwise)
    bool use_rays = false;               // too many occluders for projection (exact_limit):
                                         //   visibility by one ray per quadrature node
    std::vector<int> occluders;          // then: the occluders that meet p's pyramid
    bool trivial() const { return !behind_all && !horizon_cuts && shadows.empty() && !use_rays; }
};
/// Up to this many candidates of a pair, occluders_toward tests each of them; beyond, it walks
/// the octree.
constexpr size_t max_scanned_candidates = 2048;

/// The context's candidates that meet the pyramid from p to a planar shooter (the convex hull
/// of p and the shooter's outline, within 1e-9 of the coordinates' size), increasing: the only
/// polygons that can block a segment from p to a point of the shooter. Each candidate is tested
/// when they are at most max_scanned_candidates; else the octree's walk finds them among the
/// polygons of the leaves the pyramid meets. With a `limit`, the search stops as soon as more
/// than `limit` distinct occluders are found and returns those (more than `limit`, not all):
/// enough for a caller that tests rays against the list when it is short and against the octree
/// otherwise.
std::vector<int> occluders_toward(const OcclusionContext& context, const ShooterPlane& plane,
                                  Vec3 p, size_t limit = SIZE_MAX);

/// What casts a shadow among `occluders` (polygons of the pair's candidates, increasing): the
/// pair's convex solids they belong to (indices into context.solids, each once; attach_solids)
/// and the loose polygons. The grouping stops once more than `limit` casters are found.
struct ShadowCasters {
    std::vector<int> solids, loose;
    int count() const { return static_cast<int>(solids.size() + loose.size()); }
};
ShadowCasters casters_among(const OcclusionContext& context, const std::vector<int>& occluders,
                            int limit);

/// How many casters blocked_view projects at p (the pair's own when at most exact_limit, else
/// those meeting p's pyramid to the shooter, counted up to exact_limit + 1): more than
/// exact_limit, and p's visibility is one ray per quadrature node (BlockedView::use_rays).
int casters_toward(const OcclusionContext& context, const ShooterPlane& plane, Vec3 p);

/// The view from point p (normal n_p). `context` may be null (horizon only). When p lies on a
/// planar receiver, `receiver_plane` (may be null) gives its plane: the horizon is then the
/// same line for every point of the receiver, to the last bit.
BlockedView blocked_view(const ShooterPlane& plane, Vec3 p, Vec3 n_p,
                         const OcclusionContext* context, const Plane* receiver_plane = nullptr);

/// Why solid_shadow gives no silhouette: p within the solid, or an opening p sees that rays
/// pass through (see convex_solids.h).
enum class SolidRefusal { none, inside, opening };

/// The shadow of a convex solid (convex_solids.h) on a planar shooter seen from p, at height
/// h_p > 0 above its plane: the convex hull of the central projections of its corners and of
/// its edges' crossings with the slab that each face is cut to (as blocked_view cuts them),
/// clipped to the shooter's outline; empty when it hides nothing. Nothing (std::nullopt) where
/// the solid's rule does not hold at p (why says which, when given): p within 1e-6 of the
/// longest ray's length of the solid, or an opening that p sees through which a ray reaches the
/// shooter (it ends on the shooter inside a solid that reaches the shooter's plane, or leaves
/// through the other opening), unless openings_covered: the caller has found every ray through
/// the openings p sees blocked by other casters (blocked_view), and the union is the same.
std::optional<ConvexPolygon> solid_shadow(const ShooterPlane& plane, Vec3 p, double h_p,
                                          const ConvexSolid& solid, bool openings_covered = false,
                                          SolidRefusal* why = nullptr);

/// The shadow of a sheet (convex_solids.h) on a planar shooter seen from p, at height h_p > 0
/// above its plane: the projection of its boundary loop, when p sees every face from the same
/// side, every corner lies between the shooter's plane and p, and the projected loop is convex
/// (its area equals its hull's), clipped to the shooter's outline; empty when it hides nothing.
/// Nothing (std::nullopt) where that does not hold (then its faces are projected one by one).
std::optional<ConvexPolygon> sheet_shadow(const ShooterPlane& plane, Vec3 p, double h_p,
                                          const ConvexSheet& sheet);

/// The plane of a planar quad (Newell's normal through the corners' mean; only when its corners
/// lie on it to rounding) or a disk, oriented by its front; nothing for other surfaces.
std::optional<Plane> surface_plane(const Surface& surface);

/// Drops shadows inside another and merges pairs whose union is convex, until none merges.
void merge_shadows(std::vector<ConvexPolygon>& shadows);

/// How a shooter cell (its image, a convex quad of the plane) lies in a view.
enum class CellVisibility { clear, hidden, cut };
/// The same, also saying whether a shadow takes part in the cut (*shadowed; false when only
/// the horizon cuts the cell).
CellVisibility classify_cell(const ConvexPolygon& cell, const BlockedView& view,
                             bool* shadowed = nullptr);
/// The visible part of a cut cell as disjoint convex pieces.
std::vector<ConvexPolygon> visible_pieces(const ConvexPolygon& cell, const BlockedView& view);

}  // namespace mbr
