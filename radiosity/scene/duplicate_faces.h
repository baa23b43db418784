// radiosity/scene/duplicate_faces.h - surfaces that repeat others, found when a scene is read
// (docs/scene-format.md, "Duplicate surfaces"). Surfaces are one-sided and each reflects and emits
// on its own (eq. (1) sums over every surface), so a face written twice reflects twice: the
// common public Cornell box OBJ carries two repeated faces and comes out 3.1 % too bright on
// average. The readers drop such a repeat with a warning, or refuse it when its material differs.
#pragma once

#include <vector>

#include "math/vec3.h"
#include "radiosity/geometry/surface.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// The distance within which two surfaces' points count as one: 1e-9 of the diagonal of
/// `bounds` (the scene's), and never below 64 rounding units of its largest coordinate, so that
/// a scene far from the origin still matches corners that differ by the rounding of their
/// arithmetic.
double duplicate_tolerance(const Box3& bounds);

/// True when a and b are one surface with one front side, their points within `tolerance`:
/// - planar quads and bilinear patches (both the bilinear map of their four corners, so they
///   are compared with each other): the same corners in the same cyclic order, from any
///   starting corner; the reverse order is the other side, not a duplicate;
/// - cylinders, spheres and disks: the same kind and the same map x(u,v) at a 5 x 5 grid of
///   (u,v) in [0,1]^2, which is what the same parameters give (also parameters that only move
///   angle 0: e1 turned and the angles shifted back), and the same normal at the centre.
bool same_surface(const Surface& a, const Surface& b, double tolerance);

/// A surface that repeats an earlier one (same_surface with the scene's tolerance).
struct DuplicateSurface {
    int earlier = -1;  // the first surface it repeats, which is kept
    int later = -1;    // the repeat
};

/// Every surface that repeats an earlier, non-repeated one, in increasing order of `later`.
/// Each surface is looked up by a quantised key (the point x(1/2,1/2) and the corner of the
/// box of its corners or samples, in cells of 256 tolerances, with the neighbouring cells a
/// tolerance reaches) in a hash table of the surfaces kept so far: expected O(N) for N
/// surfaces; only surfaces whose keys agree within the cells are compared in full.
std::vector<DuplicateSurface> find_duplicate_surfaces(const Scene& scene);

/// The readers' check, run once on the whole scene after every surface is in (scene files with
/// their includes and OBJ imports, and OBJ files alike). A repeat with the material of the
/// surface it repeats is dropped, with one warning of kind "duplicate surface" for the load
/// (the first repeated statement at its file:line naming the first statement's, and the number
/// of repeated statements); a repeat with another material is an InputError at its statement's
/// file:line naming both statements and both materials, raised before anything is dropped.
/// Surfaces that coincide but face opposite ways (a two-sided wall) are both kept. In a
/// forgiving import (options.strict off) a repeat with another material read from an OBJ or MGF
/// file is dropped instead, with one warning of kind "duplicate surface with another material".
/// Copies of one material made for texture coordinates (MATERIAL@LINE.K) count as the same.
void drop_duplicate_surfaces(Scene& scene, const ImportOptions& options = {});

}  // namespace mbr
