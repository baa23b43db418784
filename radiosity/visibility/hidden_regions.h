// radiosity/visibility/hidden_regions.h - the parts of a surface that see no front face of the
// scene: the floor under a box resting on it, a ceiling behind a light hung a hair's breadth below
// it. No light reaches them and nobody sees them, so their radiosity is zero from every shot, and
// the projection (19) of samples that drop to zero across a footprint's edge rings into the visible
// part next to it (a C^2 spline cannot follow a step). Beyond the paper: a sample at a hidden
// point takes the value of the nearest visible point instead, a continuous extension that the
// splines follow (docs/method.md, "Hidden regions").
#pragma once

#include <cstdint>
#include <vector>

#include "math/vec3.h"
#include "octree/octree.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/visibility/convex_solids.h"

namespace mbr {

/// Which texels of a surface's parameter domain are hidden, and for each hidden one the
/// nearest visible texel's centre.
class HiddenMask {
public:
    HiddenMask() = default;
    /// n x n texels over [0,1]^2; hidden[j * n + i] for the texel [i/n, (i+1)/n] x [j/n, ...].
    HiddenMask(int n, std::vector<std::uint8_t> hidden);
    /// True when some texel is hidden.
    bool any() const { return n_hidden_ > 0; }
    int resolution() const { return n_; }
    int hidden_count() const { return n_hidden_; }
    /// Whether the texel holding (s, t) is hidden.
    bool hidden(double s, double t) const;
    /// (s, t) itself when visible; else the centre of the nearest visible texel (the whole
    /// surface hidden: (s, t) itself).
    Vec2 substitute(double s, double t) const;
    /// True when the texels that meet the closed rectangle [s0, s1] x [t0, t1] of [0,1]^2 are
    /// some hidden and some visible: the rectangle holds part of a hidden region's rim. A texel
    /// that only touches the rectangle's far edge s1 or t1 counts (a dyadic cell then looks one
    /// texel beyond its own: a rim found a little early, never missed).
    bool mixed(double s0, double s1, double t0, double t1) const;
    /// True when the rectangle holds part of a hidden region's rim (as `mixed`) and the
    /// narrowest hidden region it meets is thin beside it: its thickness (twice the largest
    /// distance from one of its texels' centres to the nearest visible texel's centre, in
    /// [0,1]^2) times `ratio` is below the rectangle's shorter side. The strip a shelf hides on
    /// a wall is such a region, the footprint of a block on a floor is not.
    bool thin_rim(double s0, double s1, double t0, double t1, double ratio) const;

private:
    int texel(double s, double t) const;
    int n_ = 0;
    int n_hidden_ = 0;
    std::vector<std::uint8_t> hidden_;
    std::vector<Vec2> substitute_;  // per texel (its own centre when visible)
    std::vector<float> thickness_;  // per hidden texel: its region's thickness (thin_rim)
};

/// What find_contacts finds: the polygons in contact with each surface, and the scene's convex
/// solids (whose faces show their backs only from inside, or through a missing face).
struct HiddenContacts {
    ConvexSolids solids;
    std::vector<std::vector<int>> occluders;  // per surface: polygon indices, increasing
};

/// The hidden-region test's constants.
constexpr int hidden_resolution = 64;            // texels along each parameter direction, at most
constexpr int hidden_min_resolution = 4;         //   and at least
constexpr double hidden_min_texel = 1.0 / 2048;  // a texel's least size, over the scene's
                                                 //   diagonal
constexpr int hidden_rays = 16;                  // cosine-distributed rays per texel centre
constexpr double hidden_back_share = 0.9;  // hidden when at least this share of the rays hit a
                                           //   back face

/// The texels along each direction of the mask of a surface whose bounding box's diagonal is
/// `size` in a scene of diagonal `scene_size`: 64, or fewer for a surface so small that its
/// texels would be smaller than 1/2048 of the scene (at least 4). DESIGN: the test's cost then
/// follows the scene's area rather than its count of surfaces (a chair's leg among 9,804
/// surfaces no longer costs 64 x 64 texels), while the Cornell box's and the room's surfaces,
/// all larger than 64 such texels (the room's fruit and stool legs too), keep their 64 x 64.
int hidden_texels(double size, double scene_size);

/// The mask of `surface` (its index in the octree's polygons' surface ids is `surface_id`):
/// hidden_texels x hidden_texels texels; from each texel centre, rays over the hemisphere in
/// front; a ray that meets a polygon's back before anything else counts as hidden, one that
/// meets a front face or leaves the scene as visible. A texel is hidden when its first 4 rays
/// and at least hidden_back_share of all hidden_rays are; the rays stop as soon as the answer
/// is known (the first visible ray among the first 4, the second among the rest). Rays are
/// seeded from the surface and the texel (reproducible, thread-count independent).
///
/// With `contacts` (find_contacts; the surface's occluder list at most
/// hidden_max_seed_occluders long) only some texels cast rays: the seeds, whose centres lie
/// behind an occluder and within its reach (contact_reach) and a texel, or, for a face of a
/// convex solid, inside the solid grown by a texel (or beyond an open solid's missing face),
/// then, wave after wave, the neighbours of the texels found hidden. Every other texel is
/// visible. Without contacts (or with a longer list), every texel casts its rays.
HiddenMask find_hidden(const Surface& surface, int surface_id, const Octree& octree,
                       const HiddenContacts* contacts = nullptr);

/// How near a polygon must come to a point to hide it, over the polygon's width (its area over
/// its diameter: a rectangle's short side, 0.71 of a square's): contact_reach. Under the middle
/// of a long strip of width w at a gap g, the strip covers w / sqrt(w^2 + 4 g^2) of the
/// cosine-weighted hemisphere (a square of side w less), and a texel needs about 90 % of it
/// covered: g <= 0.24 w. Only the texels next to the contact need to be within reach: the
/// hidden region grows from them (find_hidden). DESIGN: 1.0 w. At 0.5 w the classroom.mgf
/// scene lost 20 hidden texels of one surface (a part of a region whose rim no seed reached)
/// against the full test (`hidden_contact`); at 1.0 w no texel of the seven scenes measured.
constexpr double hidden_contact_reach = 1.0;

/// hidden_contact_reach x the polygon's area / its diameter.
double contact_reach(const Polygon& occluder);

/// A surface's occluder list longer than this makes find_hidden test every texel (a floor
/// under thousands of blocks: one surface, 64 x 64 texels, cheaper than the seed test).
constexpr int hidden_max_seed_occluders = 256;

/// The polygons that can hide part of each surface, found with the octree (the neighbours in
/// contact only), so that the setup follows the polygons' neighbourhoods instead of casting
/// rays from every texel of every surface. Polygon P is listed for surface Q when P (of any
/// other surface; of Q's own too when Q is curved) comes within contact_reach(P) of one of
/// Q's polygons (boxes), reaches in front of that polygon's plane, and the polygon has part of
/// it behind P's plane: the configuration in which Q's points see P's back (the floor under a
/// resting block, a ceiling above a one-sided lamp hung near it, a face sunk into another).
/// When P is a face of a convex solid (convex_solids.h), Q's polygon must also enter the solid
/// or, for an open solid, reach the outer side of its missing face: from anywhere else the
/// solid shows only its fronts (the faces of the neighbouring block). A surface with an empty
/// list sees no polygon's back nearby: its points see front faces or the open scene, or lie
/// wholly inside an enclosure that no light enters, where a mask changes nothing.
HiddenContacts find_contacts(const Octree& octree, int n_surfaces);

}  // namespace mbr
