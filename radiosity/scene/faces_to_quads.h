// radiosity/scene/faces_to_quads.h - planar quads for the readers: the test that four corners make
// a valid planar quad (the bilinear map of paper section 2 must not fold), and OBJ faces of any
// number of corners turned into such quads (docs/scene-format.md, "OBJ import").
#pragma once

#include <array>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/scene/line_reader.h"

namespace mbr {

/// Largest relative deviation from planarity accepted for a planar quad: every corner lies
/// within this fraction of the quad's size (its largest corner-to-corner distance) of the
/// corners' mean plane. The Cornell box's red wall (1.02e-3) passes.
constexpr double planarity_tolerance = 2.5e-3;

/// Largest absolute coordinate or length accepted in scene and OBJ files.
constexpr double max_coordinate = 1e8;

/// Why four corners do not make a valid planar quad, or an empty string when they do: corners
/// that coincide, zero area, self-intersection, non-planarity beyond planarity_tolerance, or a
/// corner that is not strictly convex (a non-convex quad folds its bilinear map). The tests are
/// invariant under translation and scaling: they work relative to corner 0, in units of the
/// largest coordinate difference, so that quads near max_coordinate cannot overflow and small
/// quads far from the origin do not lose their shape to cancellation.
std::string planar_quad_problem(const std::array<Vec3, 4>& corners);

namespace detail {

/// Four corners p00, p10, p11, p01 of a planar quad.
using Quad = std::array<Vec3, 4>;

/// The largest distance between two of the points.
double max_pairwise_distance(const std::vector<Vec3>& p);

/// Refuses a point with a coordinate beyond max_coordinate; `what` names it in the message.
void check_point(const Line& line, Vec3 p, const std::string& what);

/// The quads of one OBJ face (docs/scene-format.md, "OBJ import"): a valid planar quad stays
/// one quad; a planar convex polygon of n != 4 corners becomes n quads around its vertex
/// average; anything else is triangulated (ear clipping) and each triangle becomes three quads.
/// A degenerate or self-intersecting face fails `line`.
std::vector<Quad> face_to_quads(const Line& line, std::vector<Vec3> p);

/// One triangle of an imported face, for pair_triangles: its corners in the face's order (its
/// front is the side (b - a) x (c - a) faces) and the group it may be joined within (the same
/// material and surface name).
struct Triangle {
    std::array<Vec3, 3> corner;
    int group = 0;
};

/// Largest interior angle, in degrees, of a quad that pair_triangles makes: flatter corners
/// would leave the bilinear map's area factor A(u, v) of eq. (4) near zero there.
constexpr double max_pair_angle = 160;

/// Triangles joined in pairs into planar quads (docs/scene-format.md, "Triangle pairs"): two
/// triangles of one group that share an edge, walked in opposite directions (the same front),
/// become the quad of their four corners when it is a valid planar quad (planar_quad_problem)
/// with no interior angle above max_pair_angle. Greedy in the triangles' order: each triangle
/// not yet joined takes, among the later ones not yet joined, the partner whose quad has the
/// smallest largest angle (ties to the first found, by the triangle's edges in order). Shared edges
/// are found by exact equality of the corners (the files name the same vertex). Returns partner[t]
/// (-1 for none) and, for the first triangle t of each pair, quad[t]: the first triangle's corners
/// with the partner's third corner between the shared edge's ends, in the first triangle's turn.
struct TrianglePairs {
    std::vector<int> partner;
    std::vector<Quad> quad;
};
TrianglePairs pair_triangles(const std::vector<Triangle>& triangles);

}  // namespace detail

}  // namespace mbr
