// octree/octree.cpp - the paper's pointer octree (section 6, "Octree"): the three-step
// node-polygon test that builds it, and front-to-back ray traversal for the queries.
#include "octree/octree.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "math/check.h"

namespace mbr {

namespace {

// Decisions of the node-polygon test that could be flipped by rounding lean to "meet" by this
// much, relative to the largest coordinate involved: rounding of the dot and cross products below
// is a few 1e-16 of it, so a false "apart" is out of reach, and 1e-12 over-reports nothing visible.
constexpr double lean_rel = 1e-12;

double coordinate_scale(const Box3& cube, const Polygon& polygon) {
    double s = 0;
    for (Vec3 v : {cube.lo, cube.hi, polygon.bounds().lo, polygon.bounds().hi})
        s = std::max({s, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    return s;
}

// Liang-Barsky: does the closed segment p0 p1 meet the closed rectangle [lo, hi]?
bool segment_meets_rect(Vec2 p0, Vec2 p1, Vec2 lo, Vec2 hi) {
    double u0 = 0, u1 = 1;
    const double p[2] = {p0.x, p0.y}, d[2] = {p1.x - p0.x, p1.y - p0.y};
    const double l[2] = {lo.x, lo.y}, h[2] = {hi.x, hi.y};
    for (int k = 0; k < 2; ++k) {
        if (d[k] == 0) {
            if (p[k] < l[k] || p[k] > h[k]) return false;
            continue;
        }
        double ua = (l[k] - p[k]) / d[k], ub = (h[k] - p[k]) / d[k];
        if (ua > ub) std::swap(ua, ub);
        u0 = std::max(u0, ua);
        u1 = std::min(u1, ub);
        if (u0 > u1) return false;
    }
    return true;
}

// Child i of a cube: bit 0 of i selects the upper half in x, bit 1 in y, bit 2 in z. Build and
// traversal both split here, so their cubes are bit-identical.
Box3 child_cube(const Box3& cube, int i) {
    Vec3 mid = cube.centre();
    Box3 c;
    for (int k = 0; k < 3; ++k) {
        bool upper = (i >> k) & 1;
        c.lo[k] = upper ? mid[k] : cube.lo[k];
        c.hi[k] = upper ? cube.hi[k] : mid[k];
    }
    return c;
}

// Slab test: narrows [t0, t1] to the part of the ray inside the box; false if nothing is left.
// A zero direction component constrains only through the origin's position; a NaN bound (a
// denormal component times a zero distance) constrains nothing, which errs towards visiting.
bool clip_to_box(const Box3& box, const Ray& ray, Vec3 inv_dir, double& t0, double& t1) {
    for (int k = 0; k < 3; ++k) {
        if (ray.dir[k] == 0) {
            if (ray.origin[k] < box.lo[k] || ray.origin[k] > box.hi[k]) return false;
            continue;
        }
        double ta = (box.lo[k] - ray.origin[k]) * inv_dir[k];
        double tb = (box.hi[k] - ray.origin[k]) * inv_dir[k];
        if (ta > tb) std::swap(ta, tb);
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
        if (t0 > t1) return false;
    }
    return true;
}

}  // namespace

const char* to_string(NodeTestResult result) {
    switch (result) {
        case NodeTestResult::apart_by_bounds:
            return "apart_by_bounds";
        case NodeTestResult::meet_by_projection:
            return "meet_by_projection";
        case NodeTestResult::apart_by_projection:
            return "apart_by_projection";
        case NodeTestResult::apart_by_plane:
            return "apart_by_plane";
        case NodeTestResult::meet_by_plane:
            return "meet_by_plane";
    }
    return "?";
}

namespace {

// projection_relation with the lean tolerance given: classify_node_polygon computes it once for
// its three projections and its plane test.
ProjectionRelation projection_relation(const Box3& cube, const Polygon& polygon, int axis,
                                       double tol) {
    // The plane perpendicular to `axis`, with coordinates (a, b) in right-handed order.
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    // The projected vertices are read in place: this test runs for every polygon of a node
    // against each of its eight children, and a copy on the heap took a fifth of the build time.
    const std::vector<Vec3>& v3 = polygon.vertices();
    const int n = polygon.n_vertices();
    auto v = [&](int i) { return Vec2{v3[i][a], v3[i][b]}; };
    const Vec2 lo{cube.lo[a], cube.lo[b]}, hi{cube.hi[a], cube.hi[b]};

    // Contained: every vertex in the closed square (exact comparisons). A convex polygon is the
    // hull of its vertices, so the whole projection is inside.
    bool all_inside = true;
    for (int i = 0; i < n && all_inside; ++i) {
        const Vec2 p = v(i);
        if (p.x < lo.x || p.x > hi.x || p.y < lo.y || p.y > hi.y) all_inside = false;
    }
    if (all_inside) return ProjectionRelation::inside;

    // Intersecting: some edge meets the square (grown by the lean tolerance).
    const Vec2 lo_t{lo.x - tol, lo.y - tol}, hi_t{hi.x + tol, hi.y + tol};
    for (int i = 0; i < n; ++i)
        if (segment_meets_rect(v(i), v((i + 1) % n), lo_t, hi_t))
            return ProjectionRelation::undecided;

    // No edge meets the square, so the square is wholly inside the projection (surrounding) or
    // wholly outside it (disjoint): the square's centre decides. It is then at least half a side
    // away from every edge, so the signs below are far above rounding.
    Vec2 c{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y)};
    double area2 = 0;  // twice the signed projected area: its sign is the orientation
    for (int i = 1; i + 1 < n; ++i) area2 += cross(v(i) - v(0), v(i + 1) - v(0));
    if (area2 == 0) return ProjectionRelation::apart;  // a segment surrounds nothing
    for (int i = 0; i < n; ++i) {
        double side = cross(v((i + 1) % n) - v(i), c - v(i));
        if (area2 > 0 ? side < 0 : side > 0) return ProjectionRelation::apart;
    }
    return ProjectionRelation::undecided;
}

}  // namespace

ProjectionRelation projection_relation(const Box3& cube, const Polygon& polygon, int axis) {
    MBR_CHECK_MSG(axis >= 0 && axis < 3, "axis " << axis);
    return projection_relation(cube, polygon, axis, lean_rel * coordinate_scale(cube, polygon));
}

NodeTestResult classify_node_polygon(const Box3& cube, const Polygon& polygon) {
    // Step 1: bounding boxes (closed; exact comparisons).
    if (!overlaps(cube, polygon.bounds())) return NodeTestResult::apart_by_bounds;
    const double lean = lean_rel * coordinate_scale(cube, polygon);

    // Step 2: projections onto xy, yz, zx. "Inside" on any one decides "meet": the polygon is
    // connected and its bounding box overlaps the cube's along the projection axis, so some point
    // of it lies in the cube. "Apart" on any one decides "apart". Inside wins if both are found
    // (possible only within the lean tolerance), so that the answer stays conservative.
    bool apart = false;
    for (int axis : {2, 0, 1}) {
        ProjectionRelation r = projection_relation(cube, polygon, axis, lean);
        if (r == ProjectionRelation::inside) return NodeTestResult::meet_by_projection;
        if (r == ProjectionRelation::apart) apart = true;
    }
    if (apart) return NodeTestResult::apart_by_projection;

    // Step 3: the side of the polygon's plane of each of the eight corners. "Strictly one side"
    // must beat the lean tolerance and any non-planarity of the vertices.
    const Plane& plane = polygon.plane();
    const double tol = lean + polygon.planarity_error();
    bool any_above = false, any_below = false;
    for (int i = 0; i < 8; ++i) {
        Vec3 corner{(i & 1) ? cube.hi.x : cube.lo.x, (i & 2) ? cube.hi.y : cube.lo.y,
                    (i & 4) ? cube.hi.z : cube.lo.z};
        double s = plane.signed_distance(corner);
        if (s <= tol) any_below = true;  // on the plane counts on both sides
        if (s >= -tol) any_above = true;
    }
    return any_above && any_below ? NodeTestResult::meet_by_plane : NodeTestResult::apart_by_plane;
}

bool node_meets_polygon(const Box3& cube, const Polygon& polygon) {
    NodeTestResult r = classify_node_polygon(cube, polygon);
    return r == NodeTestResult::meet_by_projection || r == NodeTestResult::meet_by_plane;
}

std::ostream& operator<<(std::ostream& os, const Hit& hit) {
    return os << "hit(polygon " << hit.polygon << ", surface " << hit.surface << ", uv " << hit.uv
              << ", t " << hit.t << ')';
}

RayStats& RayStats::operator+=(const RayStats& other) {
    n_nodes_visited += other.n_nodes_visited;
    n_polygons_tested += other.n_polygons_tested;
    return *this;
}

// A cube of the tree. Internal nodes own up to eight children (null where the child would meet
// no polygon) and list nothing; leaves list the polygons that meet their (grown) cube.
struct Octree::Node {
    std::array<std::unique_ptr<Node>, 8> children;
    std::vector<int> polygons;
    bool is_leaf = true;
};

// The state of one ray query, all on the caller's stack (queries are thread-safe).
struct Octree::Query {
    Ray ray;                     // closest hit: t_max shrinks to the best hit found so far
    Vec3 inv_dir;                // 1 / dir per component (unused where dir is zero)
    bool any = false;            // any-hit query: stop at the first hit
    RayFilter filter;            // surfaces whose polygons are skipped
    std::array<Vec3, 2> ends;    // segment_ends(ray), when filter.ends_on_surfaces
    int best = -1;               // polygon of the best hit so far
    std::array<int, 32> recent;  // polygon tested recently, by polygon index mod 32
    RayStats stats;
};

Octree::~Octree() = default;
Octree::Octree(Octree&&) noexcept = default;
Octree& Octree::operator=(Octree&&) noexcept = default;

Octree::Octree(std::vector<Polygon> polygons, Options options)
    : polygons_(std::move(polygons)), options_(options) {
    MBR_CHECK_MSG(options_.max_depth >= 0, "max_depth " << options_.max_depth);
    MBR_CHECK_MSG(options_.max_polygons_per_leaf >= 1,
                  "max_polygons_per_leaf " << options_.max_polygons_per_leaf);
    if (polygons_.empty()) return;  // no root: every query misses

    // The root: a cube about the bounding box's centre, its side 1% above the largest extent.
    Box3 box;
    double slack = 0;
    for (const Polygon& p : polygons_) {
        box.extend(p.bounds());
        slack = std::max(slack, p.planarity_error() + p.edge_slack());
    }
    Vec3 e = box.extent();
    double side = 1.01 * std::max({e.x, e.y, e.z});
    Vec3 half{0.5 * side, 0.5 * side, 0.5 * side};
    root_cube_ = Box3{box.centre() - half, box.centre() + half};

    // DESIGN: every node's cube grows by one absolute margin, the same at all depths, both when
    // polygons are assigned to it and when rays are clipped to it. A hit point lies within
    // (slack of the inside test + non-planarity) of its polygon; the margin covers that twice
    // over, plus rounding of the slab tests, so the node holding the hit point lists the polygon
    // and the ray enters that node strictly before the hit. (The slack region sticks out beyond a
    // vertex of angle theta by edge_slack / sin(theta / 2): covered for angles above ~1e-3 rad.)
    margin_ = 1e-7 * side + 2 * slack;

    std::vector<int> ids(polygons_.size());
    for (int i = 0; i < static_cast<int>(ids.size()); ++i) ids[i] = i;
    root_ = build(root_cube_, std::move(ids), 0);
}

Box3 Octree::grown(const Box3& cube) const {
    Vec3 m{margin_, margin_, margin_};
    return Box3{cube.lo - m, cube.hi + m};
}

std::unique_ptr<Octree::Node> Octree::build(const Box3& cube, std::vector<int> ids, int depth) {
    auto node = std::make_unique<Node>();
    ++node_count_;
    depth_ = std::max(depth_, depth);
    const int n_ids = static_cast<int>(ids.size());
    if (n_ids > options_.max_polygons_per_leaf && depth < options_.max_depth) {
        std::array<std::vector<int>, 8> lists;
        long n_child_refs = 0;
        for (int i = 0; i < 8; ++i) {
            Box3 c = grown(child_cube(cube, i));
            for (int id : ids)
                if (node_meets_polygon(c, polygons_[id])) lists[i].push_back(id);
            n_child_refs += static_cast<long>(lists[i].size());
        }
        // DESIGN: split only if it pays, by the surface-area argument of kd-tree builders
        // [MacDonald and Booth 1990]: a random ray through this cube enters each child with
        // probability 1/4 (child surface / parent surface), so after the split it tests about
        // n_child_refs / 4 polygons plus the cost of visiting the children (taken as one
        // polygon test) instead of n_ids. Without this, places where more than
        // max_polygons_per_leaf polygons overlap (coplanar copies, dense coplanar layers) would
        // be split down to max_depth: 4^depth nodes holding the same lists.
        if (0.25 * static_cast<double>(n_child_refs) + 1 < n_ids) {
            node->is_leaf = false;
            for (int i = 0; i < 8; ++i)
                if (!lists[i].empty())
                    node->children[i] = build(child_cube(cube, i), std::move(lists[i]), depth + 1);
            return node;
        }
    }
    ++leaf_count_;
    reference_count_ += n_ids;
    node->polygons = std::move(ids);
    return node;
}

bool Octree::traverse(const Node& node, const Box3& cube, Query& q) const {
    ++q.stats.n_nodes_visited;
    if (node.is_leaf) {
        for (int id : node.polygons) {
            // A polygon listed by several leaves is tested once per ray unless another polygon
            // with the same index mod 32 was tested in between; a repeated test is only wasted
            // work. Skipping is sound: t_max only shrinks, so an earlier miss stays a miss and an
            // earlier hit is already recorded.
            int& slot = q.recent[id & 31];
            if (slot == id) continue;
            slot = id;
            if (q.filter.skips(polygons_[id].surface())) continue;
            ++q.stats.n_polygons_tested;
            std::optional<double> t = polygons_[id].intersect(q.ray);
            if (!t) continue;
            // The same polygon keeps the same answer for the same ends, so skipping repeated
            // tests stays sound.
            if (q.filter.ends_on_surfaces && !polygons_[id].hit_counts(q.ends[0], q.ends[1]))
                continue;
            if (q.any) {
                q.best = id;
                return true;
            }
            // intersect() accepts t <= t_max, so equal-t hits arrive here: keep the lowest index.
            if (*t < q.ray.t_max || q.best < 0 || id < q.best) {
                q.ray.t_max = *t;
                q.best = id;
            }
        }
        return false;
    }
    // Front to back: children ordered by the t at which the ray enters their grown cubes. The
    // cubes are disjoint but for the margin, so this is the order along the ray.
    struct Entry {
        double t;
        int child;
    };
    std::array<Entry, 8> order;
    int n_order = 0;
    std::array<Box3, 8> cubes;
    for (int i = 0; i < 8; ++i) {
        if (!node.children[i]) continue;
        cubes[i] = child_cube(cube, i);
        double t0 = q.ray.t_min, t1 = q.ray.t_max;
        if (!clip_to_box(grown(cubes[i]), q.ray, q.inv_dir, t0, t1)) continue;
        int j = n_order++;
        for (; j > 0 && order[j - 1].t > t0; --j) order[j] = order[j - 1];
        order[j] = {t0, i};
    }
    for (int k = 0; k < n_order; ++k) {
        // Early exit: this child and all after it start beyond the best hit so far.
        if (order[k].t > q.ray.t_max) break;
        int i = order[k].child;
        if (traverse(*node.children[i], cubes[i], q)) return true;
    }
    return false;
}

std::optional<Hit> Octree::closest_hit(const Ray& ray, RayStats* stats) const {
    return closest_hit(ray, RayFilter{}, stats);
}

std::optional<Hit> Octree::closest_hit(const Ray& ray, const RayFilter& filter,
                                       RayStats* stats) const {
    if (!root_) return std::nullopt;
    Query q;
    q.ray = ray;
    q.filter = filter;
    if (filter.ends_on_surfaces) q.ends = segment_ends(ray);
    q.recent.fill(-1);
    for (int k = 0; k < 3; ++k) q.inv_dir[k] = ray.dir[k] != 0 ? 1 / ray.dir[k] : 0;
    double t0 = ray.t_min, t1 = ray.t_max;
    if (t0 <= t1 && clip_to_box(grown(root_cube_), ray, q.inv_dir, t0, t1))
        traverse(*root_, root_cube_, q);
    if (stats) *stats += q.stats;
    if (q.best < 0) return std::nullopt;
    const Polygon& p = polygons_[q.best];
    double t = q.ray.t_max;
    return Hit{q.best, p.surface(), p.uv_at(ray.at(t)), t};
}

bool Octree::any_hit(const Ray& ray, RayStats* stats) const {
    return any_hit(ray, RayFilter{}, stats);
}

bool Octree::any_hit(const Ray& ray, const RayFilter& filter, RayStats* stats) const {
    if (!root_) return false;
    Query q;
    q.ray = ray;
    q.any = true;
    q.filter = filter;
    if (filter.ends_on_surfaces) q.ends = segment_ends(ray);
    q.recent.fill(-1);
    for (int k = 0; k < 3; ++k) q.inv_dir[k] = ray.dir[k] != 0 ? 1 / ray.dir[k] : 0;
    double t0 = ray.t_min, t1 = ray.t_max;
    bool hit = t0 <= t1 && clip_to_box(grown(root_cube_), ray, q.inv_dir, t0, t1) &&
               traverse(*root_, root_cube_, q);
    if (stats) *stats += q.stats;
    return hit;
}

bool Octree::node_is_leaf(const Node& node) { return node.is_leaf; }
const std::vector<int>& Octree::node_polygons(const Node& node) { return node.polygons; }
const Octree::Node* Octree::node_child(const Node& node, int i) { return node.children[i].get(); }
Box3 Octree::node_child_cube(const Box3& cube, int i) { return child_cube(cube, i); }

}  // namespace mbr
