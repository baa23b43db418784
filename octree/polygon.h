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
//
// Beyond the paper: a polygon of a curved surface's tessellation is a chord of it. Its
// thickness() (set by whoever made it from the surface; zero for an exact, planar facet) bounds
// how far the true surface stands off the polygon's plane over the polygon and just beyond. A
// segment between two points of true surfaces that starts (or ends) within that thickness of the
// plane, near the polygon, starts on the surface this polygon, or its neighbour across a shared
// edge, only approximates: a hit there is the tessellation's, not the surface's, and does not
// block (hit_counts, intersect_segment). Two sphere bands meeting along a circle: the plane of a
// facet of one cuts the sphere in a circle through the facet's corners, and the other band's
// points inside that circle stand on the far side of the plane, so their rays to the facet's side
// crossed it. A closed curved occluder is crossed twice, so a discounted hit near an end leaves
// it blocking; an open one leaks only where the tessellation already does (within the thickness).
#pragma once

#include <array>
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
/// The ends of a ray taken as a segment: ray.at(t_min), and ray.at(t_max) when t_max is finite
/// (else the first again).
std::array<Vec3, 2> segment_ends(const Ray& ray);

/// An oriented plane {p : dot(normal, p) = offset} with unit normal; the normal side is positive.
struct Plane {
    Vec3 normal;
    double offset = 0;
    /// Signed distance of p from the plane, positive on the side the normal points to.
    double signed_distance(Vec3 p) const { return dot(normal, p) - offset; }
};

/// One step of Sutherland and Hodgman's clipping: appends to `out`, in order, the part of the
/// polygon `in` (vertices in order) where value(v) >= 0, an edge whose ends lie on either side
/// crossing at a + value(a) / (value(a) - value(b)) (b - a). value is an affine function of
/// the point (a signed distance from a plane); a vertex where it is 0 is kept.
template <class Value>
void clip_polygon(const std::vector<Vec3>& in, Value value, std::vector<Vec3>& out) {
    for (size_t i = 0; i < in.size(); ++i) {
        const Vec3& a = in[i];
        const Vec3& b = in[(i + 1) % in.size()];
        const double da = value(a), db = value(b);
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) out.push_back(a + (da / (da - db)) * (b - a));
    }
}

/// Step 2 of the paper's ray-polygon test on bare planes: p, taken to lie in the polygon's plane,
/// is on the inner side of each of the n bounding planes, by at most `slack` outside (closed).
/// Written as !(d <= slack) so that a NaN counts as outside.
inline bool inside_bounding_planes(const Plane* bounding, int n, double slack, Vec3 p) {
    for (int i = 0; i < n; ++i)
        if (!(bounding[i].signed_distance(p) <= slack)) return false;
    return true;
}

/// Step 1 of the paper's ray-polygon test: the t at which the ray meets the plane,
/// (offset - n.o) / n.d; infinite or NaN when the ray is parallel to the plane (or in it).
inline double plane_crossing(const Plane& plane, const Ray& ray) {
    return -plane.signed_distance(ray.origin) / dot(plane.normal, ray.dir);
}

/// Whether a plane_crossing() counts: finite (a ray parallel to the plane, or in it, misses by
/// convention) and in [t_min, t_max].
inline bool crossing_within(double t, const Ray& ray) {
    return std::isfinite(t) && !(t < ray.t_min) && !(t > ray.t_max);
}

/// The paper's ray-polygon test (section 6, "Octree") on bare planes: the ray meets `plane` at
/// t = plane_crossing(), a miss unless crossing_within(); the hit point is inside iff
/// inside_bounding_planes() holds. Polygon::intersect and the octree's packed copy of the planes
/// (octree.h) both use these three functions, so they return the same t bit for bit.
inline std::optional<double> intersect_planes(const Plane& plane, const Plane* bounding, int n,
                                              double slack, const Ray& ray) {
    const double t = plane_crossing(plane, ray);
    if (!crossing_within(t, ray)) return std::nullopt;
    if (!inside_bounding_planes(bounding, n, slack, ray.at(t))) return std::nullopt;
    return t;
}

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
    /// How far the true surface this polygon approximates may stand off plane() over the polygon
    /// and just beyond (0, the default: the polygon is exact). See the file comment.
    double thickness() const { return thickness_; }
    /// Sets thickness(); checks (MBR_CHECK) that it is finite and not negative.
    void set_thickness(double thickness);

    /// True when p, taken to lie in the polygon's plane, is on the inner side of every bounding
    /// plane (closed, with edge_slack()): step 2 of the paper's ray-polygon test.
    bool contains(Vec3 p) const;

    /// The paper's ray-polygon test: the ray meets the plane at t (a miss if the ray is parallel
    /// to the plane or t is outside [t_min, t_max]); the hit point is inside iff contains() holds.
    /// Returns t. Front and back faces both count.
    std::optional<double> intersect(const Ray& ray) const;

    /// True when p may lie on the true surface near this polygon rather than on the polygon:
    /// within thickness() of plane() and inside bounds() grown by diameter() on every side.
    /// Never for a polygon of zero thickness (or a p that is not finite).
    bool within_thickness(Vec3 p) const;
    /// The rule of visibility between points of true surfaces: a hit on this polygon by the
    /// segment from `a` to `b` blocks unless within_thickness() holds at an end.
    bool hit_counts(Vec3 a, Vec3 b) const { return !within_thickness(a) && !within_thickness(b); }
    /// intersect() for a segment between points of true surfaces, its ends ray.at(ray.t_min) and
    /// ray.at(ray.t_max) (only the first when t_max is infinite): the hit unless hit_counts()
    /// discounts it. Equal to intersect() for a polygon of zero thickness.
    std::optional<double> intersect_segment(const Ray& ray) const;

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
    Vec2 uv_bilinear(double s, double t) const;  // the vertices' (u, v) blended at (s, t)
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
    double thickness_ = 0;
    // An orthonormal frame of the plane (origin at vertex 0) and the vertices in it, for uv_at.
    Vec3 axis_u_, axis_v_;
    std::vector<Vec2> local_;
    // A parallelogram's inverse map: (s, t) = (dot(p - vertex 0, inverse_s_), dot(.., inverse_t_)).
    bool parallelogram_ = false;
    Vec3 inverse_s_, inverse_t_;
    // And, for it, vertex 0 and the four vertices' (u, v) inline: a closest hit's (u, v) then
    // reads this object only (the octree asks for it as soon as the hit is found), not the
    // vectors' storage.
    Vec3 origin_;
    std::array<Vec2, 4> corner_uv_;
};

/// Prints the surface id and the vertices.
std::ostream& operator<<(std::ostream& os, const Polygon& polygon);

}  // namespace mbr
