// math/convex2d.h - convex polygons of the plane: clipping by half-planes, intersection and
// difference, and a Gauss rule on triangles. The exact visibility of mbr's shadow stage (a
// shooter's visible part seen from a receiving point, radiosity/visibility/visible_parts.h) is
// built from these: the shooter's cells cut by the receiving point's horizon and by the central
// projections of occluders onto the shooter's plane (Sutherland and Hodgman 1974 for the clipping).
#pragma once

#include <vector>

#include "math/gauss_legendre.h"
#include "math/vec3.h"

namespace mbr {

/// A convex polygon of the plane, vertices counter-clockwise (positive area); may be empty.
using ConvexPolygon = std::vector<Vec2>;

/// The half-plane {x : dot(normal, x) + offset >= 0}.
struct HalfPlane {
    Vec2 normal;
    double offset = 0;
    double value(Vec2 x) const { return dot(normal, x) + offset; }
};

/// Signed area (positive for counter-clockwise vertices).
double signed_area(const ConvexPolygon& polygon);

/// The half-plane to the left of the directed line a -> b (the inside of a counter-clockwise
/// polygon with edge a b).
HalfPlane left_of(Vec2 a, Vec2 b);

/// The part of `polygon` in the half-plane (Sutherland-Hodgman against one line); fewer than
/// three vertices left means empty.
ConvexPolygon clip(const ConvexPolygon& polygon, const HalfPlane& h);

/// The intersection of two convex polygons (empty when they are disjoint or touch only).
ConvexPolygon intersect(const ConvexPolygon& a, const ConvexPolygon& b);

/// a minus b as disjoint convex pieces: the parts of a outside each edge line of b in turn.
/// Pieces of area below `min_area` are dropped.
std::vector<ConvexPolygon> subtract(const ConvexPolygon& a, const ConvexPolygon& b,
                                    double min_area = 0);

/// The smallest axis-aligned rectangle holding the polygon (x0 > x1 when it is empty).
Rect bounding_rect(const ConvexPolygon& polygon);

/// The narrowest width of a convex polygon (either orientation): the least, over its edges, of
/// the farthest corner's distance from the edge's line. A square's side, a strip's width (the
/// resolution check's width of a lamp, radiosity/solver/resolution.h).
double narrowest_width(const ConvexPolygon& polygon);

/// True when the polygon is at most `min_width` wide or its bounding box at most `min_extent`
/// across: fewer than three vertices, an area at most min_width times the box's diagonal (a
/// strip of length l and width w has area l w and diagonal about l), or a speck. A small but
/// full polygon, wider than min_width and larger than min_extent, is kept.
bool is_sliver(const ConvexPolygon& polygon, double min_width, double min_extent);

/// Removes the vertices within `tolerance` of the line through their two neighbours (repeated
/// and collinear vertices, and their near versions that rounding leaves), keeping at least
/// three. A near-repeated vertex would give the polygon an edge of no length whose line points
/// anywhere, and subtract() would cut along it.
void remove_flat_vertices(ConvexPolygon& polygon, double tolerance);

/// Rotates the vertex list so that it starts at the vertex lowest along one fixed generic
/// direction (angle 1 radian). A fan of triangles from the first vertex then depends on the
/// polygon alone, not on where clipping happened to start its list: two polygons that differ
/// by rounding (a scene in other units, a nearby receiving point) get the same fan, and a
/// quadrature over the fan the same error pattern.
void start_at_canonical_vertex(ConvexPolygon& polygon);

/// The convex hull of points, counter-clockwise (Andrew's monotone chain); collinear points on
/// its edges are dropped.
ConvexPolygon convex_hull(std::vector<Vec2> points);

/// The union of two convex polygons when it is convex (the hull's area equals area(a) +
/// area(b) - area(a and b) within rel_tolerance of the hull's area), else an empty polygon.
ConvexPolygon convex_union(const ConvexPolygon& a, const ConvexPolygon& b, double rel_tolerance = 1e-9);

/// How a convex polygon lies relative to another: disjoint (at most touching), inside it (every
/// vertex on or inside every edge line, no slack), or overlapping.
enum class Overlap { disjoint, inside, partial };
/// Where `a` lies relative to `b` (separating-axis test over both polygons' edges).
Overlap classify(const ConvexPolygon& a, const ConvexPolygon& b);

/// True when x lies in the closed convex polygon.
bool contains(const ConvexPolygon& polygon, Vec2 x);
/// True when x lies in the convex polygon grown by `slack` (a distance) beyond its edges' lines.
bool contains(const ConvexPolygon& polygon, Vec2 x, double slack);

/// The inverse of the bilinear map P(s,t) = (1-s)(1-t) q0 + s(1-t) q1 + s t q2 + (1-s) t q3 of
/// a convex quadrilateral: the (s,t) with P(s,t) = q, exact up to rounding (closed form, then
/// two Newton steps). For q outside the quadrilateral it extrapolates (the root nearest [0,1]).
Vec2 inverse_bilinear(Vec2 q0, Vec2 q1, Vec2 q2, Vec2 q3, Vec2 q);

/// An n x n collapsed Gauss-Legendre rule on the reference triangle (0,0), (1,0), (0,1)
/// (Duffy's map of the square): points and weights summing to 1/2, exact for polynomials of
/// total degree 2n - 2.
struct TriangleRule {
    std::vector<Vec2> points;
    std::vector<double> weights;
};
TriangleRule triangle_rule(int n);

/// A fully symmetric rule on the same reference triangle, exact for polynomials of total degree
/// `degree` = 2, 4 or 6 with 3, 6 or 12 points (Strang and Fix 1973; Dunavant 1985), weights
/// summing to 1/2: the collapsed rule of the same degree needs 4, 9 or 16 points, crowded at
/// the collapsed corner.
TriangleRule symmetric_triangle_rule(int degree);

/// The rule with the fewest points that this file knows exact for total degree 2n - 2: the
/// symmetric one for n = 2, 3, 4, else the collapsed n x n rule.
TriangleRule triangle_rule_of_degree_2n_minus_2(int n);

}  // namespace mbr
