// octree/polygon.cpp - planar convex polygons, their bounding planes (Figure 6) and the paper's
// ray-polygon test (section 6, "Octree"); plus (u, v) interpolation for hit points.
#include "octree/polygon.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"
#include "math/convex2d.h"

namespace mbr {

namespace {

// Relative tolerances of the constructor's checks (in units of the diameter, or radians).
constexpr double planarity_tol = 1e-6;    // vertex distance from the plane / diameter
constexpr double convexity_tol = 1e-7;    // largest allowed right turn (radians)
constexpr double degeneracy_tol = 1e-12;  // shortest edge / diameter; area / diameter^2
// DESIGN: the closed inside test's slack, relative to the diameter (see polygon.h).
constexpr double edge_slack_rel = 1e-10;

}  // namespace

std::ostream& operator<<(std::ostream& os, const Ray& ray) {
    return os << "ray(" << ray.origin << " + t " << ray.dir << ", t in [" << ray.t_min << ", "
              << ray.t_max << "])";
}

std::array<Vec3, 2> segment_ends(const Ray& ray) {
    const Vec3 a = ray.at(ray.t_min);
    return {a, std::isfinite(ray.t_max) ? ray.at(ray.t_max) : a};
}

std::ostream& operator<<(std::ostream& os, const Polygon& polygon) {
    os << "polygon(surface " << polygon.surface() << ':';
    for (Vec3 v : polygon.vertices()) os << ' ' << v;
    return os << ')';
}

Polygon::Polygon(std::vector<Vec3> vertices, std::vector<Vec2> uv, int surface)
    : vertices_(std::move(vertices)), uv_(std::move(uv)), surface_(surface) {
    const int n = n_vertices();
    MBR_CHECK_MSG(n >= 3, "a polygon needs at least 3 vertices, got " << n);
    MBR_CHECK_MSG(uv_.size() == vertices_.size(), uv_.size()
                                                      << " (u,v) pairs for " << n << " vertices");
    for (Vec3 v : vertices_) MBR_CHECK_MSG(is_finite(v), "vertex " << v);
    for (Vec3 v : vertices_) bounds_.extend(v);
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            diameter_ = std::max(diameter_, length(vertices_[j] - vertices_[i]));
    MBR_CHECK_MSG(diameter_ > 0, "all vertices coincide at " << vertices_[0]);

    // Newell's normal: sum of cross products about vertex 0, twice the vector area. Its direction
    // is the side from which the vertices run counter-clockwise.
    Vec3 area_vector;
    for (int i = 1; i + 1 < n; ++i)
        area_vector += cross(vertices_[i] - vertices_[0], vertices_[i + 1] - vertices_[0]);
    area_ = 0.5 * length(area_vector);
    MBR_CHECK_MSG(area_ > degeneracy_tol * diameter_ * diameter_, "zero-area polygon " << *this);
    Vec3 n_p = normalize(area_vector);
    Vec3 centroid;
    for (Vec3 v : vertices_) centroid += v;
    centroid = centroid / n;
    plane_ = Plane{n_p, dot(n_p, centroid)};
    for (Vec3 v : vertices_)
        planarity_error_ = std::max(planarity_error_, std::fabs(plane_.signed_distance(v)));
    for (Vec3 v : vertices_)
        MBR_CHECK_MSG(std::fabs(plane_.signed_distance(v)) <= planarity_tol * diameter_,
                      "non-planar polygon " << *this << ": vertex " << v << " is "
                                            << plane_.signed_distance(v) << " off its plane");

    // Convexity: every turn is to the left (about n_p) or straight, and the turns add up to one
    // full circle (which rules out star-shaped windings whose turns are all left).
    double total_turn = 0;
    for (int i = 0; i < n; ++i) {
        Vec3 a = vertices_[i] - vertices_[(i + n - 1) % n];
        Vec3 b = vertices_[(i + 1) % n] - vertices_[i];
        MBR_CHECK_MSG(length(b) > degeneracy_tol * diameter_,
                      "zero-length edge at vertex " << i << " of " << *this);
        double turn = std::atan2(dot(n_p, cross(a, b)), dot(a, b));
        MBR_CHECK_MSG(
            turn >= -convexity_tol && turn < Pi - convexity_tol,
            "non-convex polygon " << *this << ": turn of " << turn << " rad at vertex " << i);
        total_turn += turn;
    }
    MBR_CHECK_MSG(std::fabs(total_turn - 2 * Pi) < 1e-6,
                  "polygon " << *this << " winds " << total_turn / (2 * Pi) << " times");

    // Figure 6: bounding plane through edge (v_i, v_i+1) containing the normal. With the vertices
    // counter-clockwise about n_p, edge x n_p points away from the polygon.
    bounding_planes_.reserve(n);
    for (int i = 0; i < n; ++i) {
        Vec3 edge = vertices_[(i + 1) % n] - vertices_[i];
        Vec3 outward = normalize(cross(edge, n_p));
        bounding_planes_.push_back(Plane{outward, dot(outward, vertices_[i])});
    }
    edge_slack_ = edge_slack_rel * diameter_;

    axis_u_ = normalize(vertices_[1] - vertices_[0]);
    axis_v_ = cross(n_p, axis_u_);
    local_.reserve(n);
    for (Vec3 v : vertices_) local_.push_back(to_local(v));
    // DESIGN: a quad whose twist q0 - q1 + q2 - q3 vanishes to rounding (the rule of
    // make_shooter_plane) is a parallelogram: its bilinear map is affine, and uv_at inverts it
    // by two dot products in space instead of inverse_bilinear's closed form and Newton steps
    // (a fifth of a closest-hit query on the room, whose facets are rectangles).
    if (n == 4) {
        const Vec2 e = local_[1] - local_[0], f = local_[3] - local_[0];
        const Vec2 g = local_[0] - local_[1] + local_[2] - local_[3];
        const double det = cross(e, f);
        if (det != 0 && std::sqrt(dot(g, g)) <= 1e-14 * std::sqrt(std::fabs(det))) {
            parallelogram_ = true;
            inverse_s_ = (f.y / det) * axis_u_ - (f.x / det) * axis_v_;
            inverse_t_ = (e.x / det) * axis_v_ - (e.y / det) * axis_u_;
            origin_ = vertices_[0];
            std::copy(uv_.begin(), uv_.end(), corner_uv_.begin());
        }
    }
}

bool Polygon::contains(Vec3 p) const {
    // Step 2 of the paper's test: substitute p into each bounding plane's equation. The paper asks
    // for all results negative (open polygon); we accept up to +edge_slack_ (closed, see header).
    return inside_bounding_planes(bounding_planes_.data(), n_vertices(), edge_slack_, p);
}

std::optional<double> Polygon::intersect(const Ray& ray) const {
    // Steps 1 and 2 of the paper's test, in the function the octree calls on its packed copy.
    return intersect_planes(plane_, bounding_planes_.data(), n_vertices(), edge_slack_, ray);
}

void Polygon::set_thickness(double thickness) {
    MBR_CHECK_MSG(std::isfinite(thickness) && thickness >= 0, "thickness " << thickness);
    thickness_ = thickness;
}

bool Polygon::within_thickness(Vec3 p) const {
    if (!(thickness_ > 0)) return false;
    // Written as !(|d| <= thickness) so that a NaN counts as far.
    if (!(std::fabs(plane_.signed_distance(p)) <= thickness_)) return false;
    // DESIGN: laterally, the box grown by the diameter: the points of a neighbour's true surface
    // that stand within the thickness of this plane reach that far beyond the shared edge (for
    // a sphere, up to the circle the plane cuts, through the polygon's corners, which is within
    // a diameter of them). Grown by the thickness alone, the sphere of 5 bands kept false
    // shadows: 0.134 % too dark at worst with paper shadows, 0.119 % with exact ones, against
    // 0.020 % (its error without any shadows) with the diameter.
    const Vec3 grow{diameter_, diameter_, diameter_};
    const Vec3 lo = bounds_.lo - grow, hi = bounds_.hi + grow;
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
}

std::optional<double> Polygon::intersect_segment(const Ray& ray) const {
    const std::optional<double> t = intersect(ray);
    if (!t || thickness_ == 0) return t;
    const std::array<Vec3, 2> ends = segment_ends(ray);
    if (!hit_counts(ends[0], ends[1])) return std::nullopt;
    return t;
}

Vec2 Polygon::to_local(Vec3 p) const {
    Vec3 d = p - vertices_[0];
    return {dot(d, axis_u_), dot(d, axis_v_)};
}

namespace {

// Four corners' (u, v) blended at (s, t) of the unit square (corner 0 at (0, 0), then
// counter-clockwise): uv_bilinear's, and uv_at's on a parallelogram's inline copy.
Vec2 bilinear_blend(const Vec2* corner, double s, double t) {
    return (1 - s) * (1 - t) * corner[0] + s * (1 - t) * corner[1] + s * t * corner[2] +
           (1 - s) * t * corner[3];
}

}  // namespace

Vec2 Polygon::uv_at(Vec3 p) const {
    if (parallelogram_) {
        const Vec3 d = p - origin_;
        const double s = dot(d, inverse_s_), t = dot(d, inverse_t_);
        return bilinear_blend(corner_uv_.data(), s, t);  // the inline copy of the corners
    }
    Vec2 q = to_local(p);
    if (n_vertices() == 3) {
        // Barycentric coordinates from signed areas of the sub-triangles opposite each vertex.
        double a = cross(local_[1] - local_[0], local_[2] - local_[0]);
        double b0 = cross(local_[1] - q, local_[2] - q) / a;
        double b1 = cross(local_[2] - q, local_[0] - q) / a;
        double b2 = 1 - b0 - b1;
        return b0 * uv_[0] + b1 * uv_[1] + b2 * uv_[2];
    }
    if (n_vertices() == 4) return uv_quad(q);
    return uv_mean_value(q);
}

Vec2 Polygon::uv_quad(Vec2 q) const {
    const Vec2 st = inverse_bilinear(local_[0], local_[1], local_[2], local_[3], q);
    return uv_bilinear(st.x, st.y);
}

Vec2 Polygon::uv_bilinear(double s, double t) const {
    return bilinear_blend(uv_.data(), s, t);
}

Vec2 Polygon::uv_mean_value(Vec2 q) const {
    // Mean-value coordinates in the form of Hormann and Floater (2006), which needs no angles and
    // handles points on a vertex or an edge explicitly.
    const int n = n_vertices();
    std::vector<Vec2> s(n);
    std::vector<double> r(n), a(n), d(n);
    for (int i = 0; i < n; ++i) {
        s[i] = local_[i] - q;
        r[i] = std::sqrt(dot(s[i], s[i]));
        if (r[i] == 0) return uv_[i];
    }
    for (int i = 0; i < n; ++i) {
        int j = (i + 1) % n;
        a[i] = 0.5 * cross(s[i], s[j]);
        d[i] = dot(s[i], s[j]);
        if (a[i] == 0 && d[i] < 0)  // on edge (i, j): linear along it
            return (1 / (r[i] + r[j])) * (r[j] * uv_[i] + r[i] * uv_[j]);
    }
    Vec2 sum;
    double w_sum = 0;
    for (int i = 0; i < n; ++i) {
        int prev = (i + n - 1) % n, next = (i + 1) % n;
        double w = 0;
        if (a[prev] != 0) w += (r[prev] - d[prev] / r[i]) / a[prev];
        if (a[i] != 0) w += (r[next] - d[i] / r[i]) / a[i];
        sum = sum + w * uv_[i];
        w_sum += w;
    }
    return (1 / w_sum) * sum;
}

}  // namespace mbr
