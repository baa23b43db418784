// octree/polygon.h - planar convex polygons with the paper's bounding planes and its ray-polygon
// test (paper section 6, "Octree", steps 1-2 of the ray-polygon test, and Figure 6).
//
// Through each edge passes a bounding plane that contains the edge and the polygon's normal; its
// normal points away from the polygon. A point of the polygon's plane is inside the polygon when
// it is on the inner side of every bounding plane.
//
// Conventions (the paper is silent on them):
// - The polygon is closed: a ray through an edge or a vertex hits it. The inner side is taken
//   with a slack of edge_slack() = 1e-10 x diameter so that rounding cannot open a crack along
//   the shared edge of two neighbouring polygons (light leaking through a tessellated wall).
// - Both sides are hit: the test does not cull back faces (surfaces are one-sided for
//   radiosity, but an occluder blocks from either side; culling is the caller's business).
// - A ray parallel to the plane (including a ray lying in it) never hits: the polygon has no
//   thickness, and the set of such rays has measure zero.
#pragma once

#include <cmath>
#include <optional>
#include <ostream>
#include <vector>

#include "math/vec3.h"

namespace mbr {

/// A ray origin + t dir for t in [t_min, t_max]. dir need not be unit length; t is measured in
/// units of dir. A shadow ray leaving a surface should start at a small t_min > 0.
struct Ray {
    Vec3 origin;
    Vec3 dir;
    double t_min = 0;
    double t_max = HUGE_VAL;
    /// The point origin + t dir.
    Vec3 at(double t) const { return origin + t * dir; }
};
/// Prints origin, direction and the t range.
std::ostream& operator<<(std::ostream& os, const Ray& ray);

/// An oriented plane {p : dot(normal, p) = offset} with unit normal; the normal side is positive.
struct Plane {
    Vec3 normal;
    double offset = 0;
    /// Signed distance of p from the plane, positive on the side the normal points to.
    double signed_distance(Vec3 p) const { return dot(normal, p) - offset; }
};

/// A planar convex polygon of a surface's tessellation: vertices counter-clockwise seen from the
/// front, the (u, v) of each vertex on its surface, and the surface's id; with its plane and its
/// bounding planes (Figure 6) precomputed.
class Polygon {
public:
    /// Checks (MBR_CHECK) that there are at least three finite vertices and as many (u, v) pairs,
    /// that no edge has zero length, that the area is non-zero, and that the polygon is planar
    /// (within 1e-6 of its diameter) and convex (no right turn beyond 1e-7 rad, one winding).
    /// Callers validate user input earlier and with clearer messages; this guards the library.
    Polygon(std::vector<Vec3> vertices, std::vector<Vec2> uv, int surface);

    /// The vertices, counter-clockwise seen from the front (the side normal() points to).
    const std::vector<Vec3>& vertices() const { return vertices_; }
    /// The (u, v) of each vertex on its surface.
    const std::vector<Vec2>& uv() const { return uv_; }
    /// Number of vertices (and of edges and bounding planes).
    int n_vertices() const { return static_cast<int>(vertices_.size()); }
    /// Id of the surface this polygon belongs to.
    int surface() const { return surface_; }
    /// Unit normal of the front side (Newell's normal of the counter-clockwise vertices).
    Vec3 normal() const { return plane_.normal; }
    /// The plane the polygon lies in, oriented by normal().
    const Plane& plane() const { return plane_; }
    /// Bounding plane i contains edge (vertex i, vertex i+1) and the normal; its unit normal
    /// points outward (Figure 6), so interior points have negative signed distance.
    const std::vector<Plane>& bounding_planes() const { return bounding_planes_; }
    /// Axis-aligned bounding box of the vertices.
    Box3 bounds() const { return bounds_; }
    /// Largest distance between two vertices.
    double diameter() const { return diameter_; }
    /// Area of the polygon.
    double area() const { return area_; }
    /// Largest distance of a vertex from plane() (zero up to rounding for a planar input).
    double planarity_error() const { return planarity_error_; }
    /// Outward tolerance of the inside test: a point counts as inside when no bounding plane
    /// puts it further out than this (1e-10 x diameter).
    double edge_slack() const { return edge_slack_; }

    /// True when p, taken to lie in the polygon's plane, is on the inner side of every bounding
    /// plane (closed, with edge_slack()): step 2 of the paper's ray-polygon test.
    bool contains(Vec3 p) const;

    /// The paper's ray-polygon test: the ray meets the plane at t (a miss if the ray is parallel
    /// to the plane or t is outside [t_min, t_max]); the hit point is inside iff contains() holds.
    /// Returns t. Front and back faces both count.
    std::optional<double> intersect(const Ray& ray) const;

    /// The surface parameters (u, v) at a point p of the polygon (p is first projected onto the
    /// plane): barycentric for triangles, inverse bilinear for quadrilaterals (vertex i at
    /// bilinear corner (0,0), (1,0), (1,1), (0,1) in order), mean-value coordinates beyond
    /// [Floater 2003; Hormann and Floater 2006]. Each reproduces the vertices' (u, v) at the
    /// vertices and is continuous across the polygon; for points slightly outside, it
    /// extrapolates.
    Vec2 uv_at(Vec3 p) const;

private:
    Vec2 to_local(Vec3 p) const;
    Vec2 uv_quad(Vec2 q) const;
    Vec2 uv_mean_value(Vec2 q) const;

    std::vector<Vec3> vertices_;
    std::vector<Vec2> uv_;
    int surface_ = -1;
    Plane plane_;
    std::vector<Plane> bounding_planes_;
    Box3 bounds_;
    double diameter_ = 0;
    double area_ = 0;
    double edge_slack_ = 0;
    double planarity_error_ = 0;
    // An orthonormal frame of the plane (origin at vertex 0) and the vertices in it, for uv_at.
    Vec3 axis_u_, axis_v_;
    std::vector<Vec2> local_;
};

/// Prints the surface id and the vertices.
std::ostream& operator<<(std::ostream& os, const Polygon& polygon);

}  // namespace mbr
