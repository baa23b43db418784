// octree/octree.cpp - the paper's pointer octree (section 6, "Octree"): the three-step
// node-polygon test that builds it, its flat layout (octree.h), and front-to-back ray traversal
// for the queries, node for node the traversal of the pointer layout it replaced.
#include "octree/octree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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

// Child i of a cube: bit 0 of i selects the upper half in x, bit 1 in y, bit 2 in z. Build,
// traversal and collect all split here, so their cubes are bit-identical.
Box3 Octree::child_cube(const Box3& cube, int i) {
    Vec3 mid = cube.centre();
    Box3 c;
    for (int k = 0; k < 3; ++k) {
        bool upper = (i >> k) & 1;
        c.lo[k] = upper ? mid[k] : cube.lo[k];
        c.hi[k] = upper ? cube.hi[k] : mid[k];
    }
    return c;
}

// The state of one ray query, all on the caller's stack (queries are thread-safe).
struct Octree::Query {
    Ray ray;                     // closest hit: t_max shrinks to the best hit found so far
    Vec3 inv_dir;                // 1 / dir per component (unused where dir is zero)
    int flip = 0;                // bit k set when dir[k] < 0
    bool finite_inv_dir = true;  // every component of inv_dir is finite
    bool any = false;            // any-hit query: stop at the first hit
    RayFilter filter;            // surfaces whose polygons are skipped
    std::array<Vec3, 2> ends;    // segment_ends(ray), when filter.ends_on_surfaces
    int best = -1;               // polygon of the best hit so far
    std::array<int, 32> recent;  // polygon tested recently, by polygon index mod 32
    RayStats stats;
    Query(const Ray& r, const RayFilter& f, bool any_hit);
    void slab(int k, double lo, double hi, double& entry, double& exit) const;
    bool meets_box(const Box3& box) const;
};

// The slab test along axis k of a box with faces lo < hi: the t at which the ray enters and
// leaves the slab. The pointer octree's slab test (clip_to_box, before the flat layout) took
// ta = (lo - o) * inv_dir and tb = (hi - o) * inv_dir, swapped them if ta > tb, raised t0 to ta
// and lowered t1 to tb (comparisons that pass over NaN), and answered "apart" once t0 > t1; a
// zero dir[k] answered "apart" when the origin was outside the slab. These are its values: where
// dir[k] is zero, (-inf, inf) if the origin lies in the slab and (inf, -inf) if not, which the
// comparisons of meets_box and child_hits turn into its answers.
inline void Octree::Query::slab(int k, double lo, double hi, double& entry, double& exit) const {
    if (ray.dir[k] == 0) {
        const bool in = !(ray.origin[k] < lo || ray.origin[k] > hi);
        entry = in ? -HUGE_VAL : HUGE_VAL;
        exit = in ? HUGE_VAL : -HUGE_VAL;
        return;
    }
    if (finite_inv_dir) {
        // The swap makes the near face's t the entry: rounding keeps the order of the faces'
        // t, and with a finite 1 / dir both are NaN (a NaN origin) or neither is.
        const bool down = (flip >> k) & 1;
        entry = ((down ? hi : lo) - ray.origin[k]) * inv_dir[k];
        exit = ((down ? lo : hi) - ray.origin[k]) * inv_dir[k];
        return;
    }
    // 1 / dir[k] may be infinite (a denormal dir[k]) and one t NaN: the old steps as they were.
    double ta = (lo - ray.origin[k]) * inv_dir[k];
    double tb = (hi - ray.origin[k]) * inv_dir[k];
    if (ta > tb) std::swap(ta, tb);
    entry = ta;
    exit = tb;
}

// Whether the ray meets the box with t in [t_min, t_max], as the pointer octree's slab test
// decided (t_min <= t_max first). t0 only grows and t1 only shrinks, so testing t0 > t1 once at
// the end decides as its test after every axis did.
bool Octree::Query::meets_box(const Box3& box) const {
    double t0 = ray.t_min, t1 = ray.t_max;
    if (!(t0 <= t1)) return false;
    for (int k = 0; k < 3; ++k) {
        double entry, exit;
        slab(k, box.lo[k], box.hi[k], entry, exit);
        if (entry > t0) t0 = entry;
        if (exit < t1) t1 = exit;
    }
    return !(t0 > t1);
}

Octree::Query::Query(const Ray& r, const RayFilter& f, bool any_hit)
    : ray(r), any(any_hit), filter(f) {
    if (filter.ends_on_surfaces) ends = segment_ends(ray);
    recent.fill(-1);
    for (int k = 0; k < 3; ++k) {
        inv_dir[k] = ray.dir[k] != 0 ? 1 / ray.dir[k] : 0;
        if (ray.dir[k] < 0) flip |= 1 << k;
        if (!std::isfinite(inv_dir[k])) finite_inv_dir = false;
    }
}

namespace {

// The index of the lowest bit set in an 8-bit mask (8 for none), a table built at compile time.
struct LowestBit {
    std::array<std::uint8_t, 256> of{};
    constexpr LowestBit() {
        for (int m = 0; m < 256; ++m) {
            of[m] = 8;
            for (int b = 7; b >= 0; --b)
                if ((m >> b) & 1) of[m] = static_cast<std::uint8_t>(b);
        }
    }
};
constexpr LowestBit lowest_bit;

// The mask with bit j set where bit j ^ flip of m is: the children in the order of a ray whose
// direction's signs are flip (see Octree::traverse).
unsigned flip_bits(unsigned m, int flip) {
    if (flip & 1) m = ((m & 0x55u) << 1) | ((m >> 1) & 0x55u);
    if (flip & 2) m = ((m & 0x33u) << 2) | ((m >> 2) & 0x33u);
    if (flip & 4) m = ((m & 0x0Fu) << 4) | ((m >> 4) & 0x0Fu);
    return m;
}

}  // namespace

// Where a ray meets the eight grown children of a node (the pointer octree's slab test of
// grown(child_cube(cube, i)) with t in [t_min, t_max], decision for decision).
struct Octree::ChildHits {
    std::array<double, 8> entry;  // entry[i]: where the ray enters child i's grown cube
    unsigned meets = 0;           // bit i: child i exists and the ray meets it
    // The children met in the order of the pointer octree's insertion sort: by entry, equal
    // entries in octant order. The order of the direction's signs (see Octree::traverse) nearly
    // always is that order already; where it is not, the children are sorted. Returns how many;
    // order[k] is the k-th octant.
    int sorted(int flip, std::array<int, 8>& order) const {
        auto before = [&](int a, int b) {
            return entry[a] < entry[b] || (entry[a] == entry[b] && a < b);
        };
        int n = 0;
        bool in_order = true;
        for (unsigned m = flip_bits(meets, flip); m != 0; m &= m - 1, ++n) {
            order[n] = lowest_bit.of[m] ^ flip;
            if (n > 0) in_order = in_order && before(order[n - 1], order[n]);
        }
        if (in_order) return n;
        for (int k = 1; k < n; ++k) {
            const int i = order[k];
            int j = k;
            for (; j > 0 && before(i, order[j - 1]); --j) order[j] = order[j - 1];
            order[j] = i;
        }
        return n;
    }
};

Octree::ChildHits Octree::child_hits(const Box3& cube, unsigned mask, const Query& q) const {
    // The faces of the grown children along each axis: the lower child spans [lo, mid_hi], the
    // upper one [mid_lo, hi] (grown(child_cube(cube, i)) component by component). Six slabs
    // serve the eight children.
    const Vec3 m{margin_, margin_, margin_};
    const Vec3 mid = cube.centre();
    const Vec3 lo = cube.lo - m, mid_lo = mid - m, mid_hi = mid + m, hi = cube.hi + m;
    double slab_entry[3][2], slab_exit[3][2];
    for (int k = 0; k < 3; ++k) {
        q.slab(k, lo[k], mid_hi[k], slab_entry[k][0], slab_exit[k][0]);
        q.slab(k, mid_lo[k], hi[k], slab_entry[k][1], slab_exit[k][1]);
    }
    // The slab test of each child without branches, in the old order of axes (x, y, z), the
    // children sharing the steps for x and y.
    auto later = [](double t, double t0) { return t > t0 ? t : t0; };    // the old t0 and t1
    auto earlier = [](double t, double t1) { return t < t1 ? t : t1; };  // updates
    double t0_x[2], t1_x[2], t0_xy[4], t1_xy[4];
    for (int u = 0; u < 2; ++u) {
        t0_x[u] = later(slab_entry[0][u], q.ray.t_min);
        t1_x[u] = earlier(slab_exit[0][u], q.ray.t_max);
    }
    for (int i = 0; i < 4; ++i) {
        t0_xy[i] = later(slab_entry[1][i >> 1], t0_x[i & 1]);
        t1_xy[i] = earlier(slab_exit[1][i >> 1], t1_x[i & 1]);
    }
    ChildHits h;
    for (int i = 0; i < 8; ++i) {
        const double t0 = later(slab_entry[2][i >> 2], t0_xy[i & 3]);
        const double t1 = earlier(slab_exit[2][i >> 2], t1_xy[i & 3]);
        h.entry[i] = t0;
        h.meets |= static_cast<unsigned>(!(t0 > t1)) << i;
    }
    h.meets &= mask;
    return h;
}

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
    grown_root_ = grown(root_cube_);

    make_records();
    std::vector<ListEntry> entry_of(polygons_.size());
    for (int id = 0; id < polygon_count(); ++id) entry_of[size_t(id)] = list_entry(id);
    std::vector<int> ids(polygons_.size());
    for (int i = 0; i < static_cast<int>(ids.size()); ++i) ids[i] = i;
    root_ = build(root_cube_, std::move(ids), 0, entry_of);
    has_root_ = true;
    prefetch_ = double(records_.size()) * sizeof(RayRecord) > options_.prefetch_bytes;
}

// The ray records, one for each polygon, in the polygons' order.
void Octree::make_records() {
    records_.resize(polygons_.size());
    for (int id = 0; id < polygon_count(); ++id) {
        const Polygon& p = polygons_[id];
        RayRecord& r = records_[size_t(id)];
        r.plane = p.plane();
        r.slack = p.edge_slack();
        r.n_planes = p.n_vertices();
        r.first_extra = static_cast<int>(extra_planes_.size());
        const std::vector<Plane>& b = p.bounding_planes();
        if (r.n_planes <= 4)
            std::copy(b.begin(), b.end(), r.planes.begin());
        else
            extra_planes_.insert(extra_planes_.end(), b.begin(), b.end());
    }
}

namespace {

// The largest float at most x, and the smallest at least x (infinite beyond the floats' range).
float float_below(double x) {
    if (!(x > -std::numeric_limits<float>::max())) return -std::numeric_limits<float>::infinity();
    if (x > std::numeric_limits<float>::max()) return std::numeric_limits<float>::max();
    const float f = static_cast<float>(x);
    return double(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
float float_above(double x) {
    return -float_below(-x);
}

}  // namespace

// Where intersect_planes can find a hit on the polygon: the computed hit point lies on the
// polygon's plane to rounding, and within `slack` of every bounding plane, so within the
// polygon grown by the slack, whose corners reach slack / sin(theta / 2) beyond a vertex of
// angle theta. Grown further by the nodes' margin (which covers the plane's distance from the
// vertices, twice the slack and the rounding of the slab tests), that is within the box below.
// A vertex sharper than 1e-3 rad (the nodes' margin covers such a corner no further) leaves the
// box unbounded: every ray reads the record.
Octree::ListEntry Octree::list_entry(int id) const {
    const Polygon& polygon = polygons_[size_t(id)];
    const std::vector<Vec3>& v = polygon.vertices();
    const int n = polygon.n_vertices();
    double min_sin_half = 1;
    for (int i = 0; i < n; ++i) {
        const Vec3 a = normalize(v[size_t(i)] - v[size_t((i + n - 1) % n)]);
        const Vec3 b = normalize(v[size_t((i + 1) % n)] - v[size_t(i)]);
        // The angle theta at vertex i between the edges: cos theta = -a.b, and
        // sin(theta / 2) = sqrt((1 - cos theta) / 2).
        min_sin_half = std::min(min_sin_half, std::sqrt(std::max(0.0, 0.5 * (1 + dot(a, b)))));
    }
    ListEntry box;
    box.polygon = id;
    box.surface = polygon.surface();
    const Box3 b = polygon.bounds();
    const double reach =
        min_sin_half >= 5e-4 ? margin_ + polygon.edge_slack() / min_sin_half : HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
        box.lo[size_t(k)] = float_below(b.lo[k] - reach);
        box.hi[size_t(k)] = float_above(b.hi[k] + reach);
    }
    return box;
}

Box3 Octree::grown(const Box3& cube) const {
    Vec3 m{margin_, margin_, margin_};
    return Box3{cube.lo - m, cube.hi + m};
}

// Builds the node of `cube` listing `ids` and its subtree. An internal node's block is appended
// before its children's (depth first); a leaf's list is the entries (entry_of) of its polygons.
Octree::Node Octree::build(const Box3& cube, std::vector<int> ids, int depth,
                           const std::vector<ListEntry>& entry_of) {
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
            const int b = static_cast<int>(blocks_.size());
            blocks_.emplace_back();
            unsigned mask = 0;
            for (int i = 0; i < 8; ++i) {
                if (lists[i].empty()) continue;
                mask |= 1u << i;
                const Node child =
                    build(child_cube(cube, i), std::move(lists[i]), depth + 1, entry_of);
                blocks_[b].child[i] = child;  // blocks_ may have grown: index again
            }
            return Node::internal(b, mask);
        }
    }
    ++leaf_count_;
    reference_count_ += n_ids;
    const Node leaf = Node::leaf(static_cast<int>(leaf_entries_.size()), n_ids);
    for (int id : ids) leaf_entries_.push_back(entry_of[size_t(id)]);
    return leaf;
}

// Asks the memory for a leaf's list (its entries are read one after the other); a record is
// read only by the rays that meet its polygon's hit box.
void Octree::prefetch_list(const Node& leaf) const {
    const char* first = reinterpret_cast<const char*>(&leaf_entries_[size_t(leaf.first)]);
    const char* end = first + size_t(leaf.count()) * sizeof(ListEntry);
    for (const char* line = first; line < end; line += 64) __builtin_prefetch(line);
}

bool Octree::test_leaf(const Node& node, Query& q) const {
    if (prefetch_) prefetch_list(node);
    for (int r = node.first, end = node.first + node.count(); r < end; ++r) {
        const ListEntry& box = leaf_entries_[size_t(r)];
        const int id = box.polygon;
        // A polygon listed by several leaves is tested once per ray unless another polygon
        // with the same index mod 32 was tested in between; a repeated test is only wasted
        // work. Skipping is sound: t_max only shrinks, so an earlier miss stays a miss and an
        // earlier hit is already recorded.
        int& slot = q.recent[id & 31];
        if (slot == id) continue;
        slot = id;
        if (q.filter.skips(box.surface)) continue;
        ++q.stats.n_polygons_tested;
        // A ray that misses the polygon's hit box misses the polygon (list_entry): the test's
        // answer without reading its record.
        if (!q.meets_box(
                Box3{{box.lo[0], box.lo[1], box.lo[2]}, {box.hi[0], box.hi[1], box.hi[2]}}))
            continue;
        const RayRecord& p = records_[size_t(id)];
        // Polygon::intersect's own function on the packed copy of its planes: the same t.
        std::optional<double> t =
            intersect_planes(p.plane, p.bounding(extra_planes_), p.n_planes, p.slack, q.ray);
        if (!t) continue;
        // The same polygon keeps the same answer for the same ends, so skipping repeated
        // tests stays sound.
        if (q.filter.ends_on_surfaces && !polygons_[id].hit_counts(q.ends[0], q.ends[1])) continue;
        if (q.filter.only_polygons &&
            !std::binary_search(q.filter.only_polygons->begin(), q.filter.only_polygons->end(), id))
            continue;
        if (q.any) {
            q.best = id;
            return true;
        }
        // intersect() accepts t <= t_max, so equal-t hits arrive here: keep the lowest index.
        if (*t < q.ray.t_max || q.best < 0 || id < q.best) {
            q.ray.t_max = *t;
            q.best = id;
            // The hit's (u, v) reads the polygon at the end (Polygon::uv_at): asked for now, it
            // arrives while the walk goes on.
            if (prefetch_) {
                const char* poly = reinterpret_cast<const char*>(&polygons_[size_t(id)]);
                for (size_t line = 0; line < sizeof(Polygon); line += 64)
                    __builtin_prefetch(poly + line);
            }
        }
    }
    return false;
}

// Visits a node and, front to back, the children the ray meets. True when an any-hit query is
// answered.
bool Octree::traverse(const Node& node, const Box3& cube, Query& q) const {
    ++q.stats.n_nodes_visited;
    if (node.is_leaf()) return test_leaf(node, q);
    const Block& block = blocks_[node.first];
    const ChildHits hits = child_hits(cube, node.child_mask(), q);
    // DESIGN (prefetch_, octree.h): every child met is asked for at once, so that their misses
    // overlap, and below, the list of the child visited next while this one is walked.
    if (prefetch_)
        for (unsigned m = hits.meets; m != 0; m &= m - 1) {
            const Node& c = block.child[lowest_bit.of[m]];
            if (c.is_leaf())
                __builtin_prefetch(&leaf_entries_[size_t(c.first)]);
            else
                __builtin_prefetch(&blocks_[c.first]);
        }
    if (q.any) {
        // Any hit: t_max stays put, so every child met is visited unless a hit ends the query,
        // and the answer does not depend on the order. The direction's signs give one no ray
        // contradicts: with bit k of flip set where dir[k] < 0, child j ^ flip for j = 0..7 (a
        // ray crosses from child a into child b only where b's bits differ from a's towards the
        // signs). No sort.
        for (unsigned order = flip_bits(hits.meets, q.flip); order != 0; order &= order - 1) {
            const unsigned rest = order & (order - 1);
            if (prefetch_ && rest) {
                const Node& next = block.child[lowest_bit.of[rest] ^ q.flip];
                if (next.is_leaf()) prefetch_list(next);
            }
            const int i = lowest_bit.of[order] ^ q.flip;
            if (traverse(block.child[i], child_cube(cube, i), q)) return true;
        }
        return false;
    }
    // Closest hit: by the t at which the ray enters the children's grown cubes (disjoint but for
    // the margin, so this is the order along the ray), stopping at the first that starts beyond
    // the best hit so far. The children, their order and the stop are the pointer octree's own,
    // so the query tests the same polygons in the same order as before the flat layout.
    std::array<int, 8> order;
    for (int k = 0, n = hits.sorted(q.flip, order); k < n; ++k) {
        if (hits.entry[order[k]] > q.ray.t_max) break;
        if (prefetch_ && k + 1 < n && block.child[order[k + 1]].is_leaf())
            prefetch_list(block.child[order[k + 1]]);
        traverse(block.child[order[k]], child_cube(cube, order[k]), q);
    }
    return false;
}

std::optional<Hit> Octree::closest_hit(const Ray& ray, RayStats* stats) const {
    return closest_hit(ray, RayFilter{}, stats);
}

std::optional<Hit> Octree::closest_hit(const Ray& ray, const RayFilter& filter,
                                       RayStats* stats) const {
    if (!has_root_) return std::nullopt;
    Query q(ray, filter, false);
    if (q.meets_box(grown_root_)) traverse(root_, root_cube_, q);
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
    return any_hit_polygon(ray, filter, stats) >= 0;
}

int Octree::any_hit_polygon(const Ray& ray, const RayFilter& filter, RayStats* stats) const {
    if (!has_root_) return -1;
    Query q(ray, filter, true);
    const bool hit = q.meets_box(grown_root_) && traverse(root_, root_cube_, q);
    if (stats) *stats += q.stats;
    return hit ? q.best : -1;
}

}  // namespace mbr
