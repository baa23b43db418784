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

private:
    int texel(double s, double t) const;
    int n_ = 0;
    int n_hidden_ = 0;
    std::vector<std::uint8_t> hidden_;
    std::vector<Vec2> substitute_;  // per texel (its own centre when visible)
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
/// meets a front face or leaves the scene as visible. A texel is tested with 4 rays first and the
/// rest only when all 4 were hidden. Rays are seeded from the surface and the texel (reproducible,
/// thread-count independent).
HiddenMask find_hidden(const Surface& surface, int surface_id, const Octree& octree);

}  // namespace mbr
