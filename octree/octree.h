// octree/octree.h - the paper's pointer octree (section 6, "Octree"): a tree of cubes linked by
// pointers, built with the three-step node-polygon test, answering closest-hit and any-hit ray
// queries with the bounding-plane ray-polygon test of polygon.h.
//
// The node-polygon test is the paper's algorithm, kept as is. Step 3 on its own is conservative:
// it answers "meet" whenever the polygon's PLANE passes through the cube, even if the polygon
// misses it. It never answers "apart" for a cube and polygon that meet, so at worst a node lists
// a polygon it does not meet (a wasted ray-polygon test, never a wrong answer).
// After steps 1 and 2, though, step 3 is exact for convex polygons. If the plane meets the cube
// in Q and the polygon P misses the cube, some line of the plane separates P from Q while
// touching Q, either along an edge of Q, which lies in a face of the cube (P is then beyond that
// face: step 1 says apart), or at a vertex of Q, which lies on an edge of the cube (some plane
// through that line parallel to a cube edge then separates, and the projection along that axis
// is apart: step 2). The tests find no over-report against exact clipping, including polygons
// placed in a plane through the cube right next to its cross-section, where step 3 alone errs.
// Only the tolerances that steer rounding towards "meet" (1e-12 of the coordinates) remain.
//
// Layout (beyond the paper, for the cache; the tree, its subdivision and every query's path
// through it are those of the pointer octree it replaced). A node is 8 bytes: a leaf holds where
// its list starts and its length, an internal node the index of its block and which octants have
// a child. A block holds an internal node's eight child nodes (the pointers of the paper's
// octree become indices), 64 bytes on one cache line; the blocks lie in one array in depth-first
// order. A node's cube is not stored: the query splits it from its parent's on the way down
// (child_cube, as the build did) and works out the six slabs of the children's grown cubes once.
// A leaf's list is a slice of one array of 32-byte entries, each a polygon's index and surface
// and the box, in floats, that a hit on it must lie in; only a ray that meets the box reads the
// polygon's "ray record": what the ray-polygon test reads of it (its plane, bounding planes
// and slack) in three cache lines. Queries keep their state on the stack. When
// the records outgrow the cache (OctreeOptions::prefetch_bytes), queries ask the memory for the
// children and lists they will read next before reading them, and for the polygon of a new best
// hit (prefetch_).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <ostream>
#include <vector>

#include "math/vec3.h"
#include "octree/polygon.h"

namespace mbr {

/// How the three-step node-polygon test decided, in the order of its steps.
enum class NodeTestResult {
    apart_by_bounds,      // step 1: the bounding boxes are disjoint
    meet_by_projection,   // step 2: a projection of the polygon lies inside the node's square
    apart_by_projection,  // step 2: a projection of the polygon is separate from the square
    apart_by_plane,       // step 3: all eight corners strictly on one side of the plane
    meet_by_plane,        // step 3: corners on both sides (or on the plane)
};
/// The name of the enumerator, for messages.
const char* to_string(NodeTestResult result);

/// How a projection of a polygon relates to a square of the node, as Warnock's algorithm sorts a
/// polygon against a window: contained, disjoint, or neither (intersecting or surrounding).
enum class ProjectionRelation { inside, apart, undecided };

/// Step 2 for one axis plane: axis 2 projects onto xy, 0 onto yz, 1 onto zx. Warnock's tests:
/// every vertex inside the (closed) square -> inside; else an edge meeting the square ->
/// undecided; else (no edge meets it) the square is either inside the polygon (its centre is in
/// the polygon: surrounding -> undecided) or apart. Decisions lean to "undecided" by a tolerance
/// of 1e-12 x the coordinates' magnitude, so rounding never produces a false "apart".
ProjectionRelation projection_relation(const Box3& cube, const Polygon& polygon, int axis);

/// The paper's three-step node-polygon test with the step that decided (see node_meets_polygon).
NodeTestResult classify_node_polygon(const Box3& cube, const Polygon& polygon);

/// The paper's node-polygon test: (1) disjoint bounding boxes -> apart; (2) over the projections
/// onto xy, yz and zx, one inside its square -> meet, one apart from it -> apart; (3) all eight
/// corners strictly on one side of the polygon's plane -> apart, else meet. Never a false
/// "apart"; exact for convex polygons up to 1e-12 of the coordinates (see the file comment).
/// Touching counts as meeting.
bool node_meets_polygon(const Box3& cube, const Polygon& polygon);

/// A ray's first intersection: which polygon, its surface, the surface's (u, v) there, and t.
struct Hit {
    int polygon = -1;  // index into Octree::polygons()
    int surface = -1;  // Polygon::surface() of that polygon
    Vec2 uv;           // Polygon::uv_at() of the hit point
    double t = 0;      // ray parameter, in units of ray.dir
};
/// Prints the fields of a hit.
std::ostream& operator<<(std::ostream& os, const Hit& hit);

/// Work done by ray queries; each query adds to the counters it is given.
struct RayStats {
    long n_nodes_visited = 0;    // octree nodes entered (root included)
    long n_polygons_tested = 0;  // ray-polygon tests performed
    /// Adds another query's (or thread's) counts.
    RayStats& operator+=(const RayStats& other);
};

/// Polygons a ray query skips: those of up to two surfaces (a shadow ray between a shooter and a
/// receiver is never blocked by the two surfaces themselves), and, for a ray between points of
/// true surfaces, the hits Polygon::hit_counts discounts near its ends.
struct RayFilter {
    int skip_surface_a = -1;
    int skip_surface_b = -1;
    bool ends_on_surfaces = false;  // the ray's ends, ray.at(t_min) and ray.at(t_max) (the first
                                    //   only when t_max is infinite), lie on true surfaces
    /// When set, a hit on a polygon missing from this list (indices, increasing) is skipped: the
    /// shadow rays of a pair count only the pair's occluder candidates, the same answer as
    /// testing the list one by one (checked after the ray-polygon test: hits only).
    const std::vector<int>* only_polygons = nullptr;
    bool skips(int surface) const { return surface == skip_surface_a || surface == skip_surface_b; }
};

/// Build options of the octree.
struct OctreeOptions {
    int max_depth = 10;             // depth of the deepest allowed node (the root has depth 0)
    int max_polygons_per_leaf = 8;  // a node listing more is split (below max_depth, if it pays)
    // Queries prefetch (Octree::prefetch_) when the ray records take more than this many bytes
    // (about 21,800 polygons); 0: always. Answers and RayStats do not depend on it.
    double prefetch_bytes = 4.0 * 1024 * 1024;
};

/// The paper's pointer octree over a set of polygons (its pointers are indices: see the file
/// comment). Immutable after construction; its queries
/// keep all state on the stack, so any number of threads may query one octree at once.
class Octree {
public:
    /// Build options.
    using Options = OctreeOptions;

    /// Builds the tree. The root is the cube around the polygons' bounding box (side 1% above the
    /// box's largest extent); a node listing more than options.max_polygons_per_leaf polygons is
    /// split into eight, unless it is at options.max_depth or the split does not pay: it is made
    /// only if the children's list lengths sum to less than 4 (n - 1) for n polygons in the
    /// node (a surface-area cost rule, see octree.cpp).
    /// Zero polygons give an empty tree whose queries always miss.
    explicit Octree(std::vector<Polygon> polygons, Options options = {});
    ~Octree();
    Octree(Octree&&) noexcept;
    Octree& operator=(Octree&&) noexcept;

    /// The first hit along the ray with t in [ray.t_min, ray.t_max]; among hits at the same t,
    /// the polygon with the smallest index. Visits nodes front to back and stops at the first
    /// node that starts beyond the best hit so far. Adds its work to *stats if given.
    std::optional<Hit> closest_hit(const Ray& ray, RayStats* stats = nullptr) const;
    /// The same, skipping the polygons and hits `filter` names.
    std::optional<Hit> closest_hit(const Ray& ray, const RayFilter& filter,
                                   RayStats* stats = nullptr) const;
    /// Whether any polygon is hit with t in [ray.t_min, ray.t_max] (shadow rays). Visits nodes in
    /// the order of the direction's signs (no sort) and stops at the first hit found. Adds its
    /// work to *stats if given.
    bool any_hit(const Ray& ray, RayStats* stats = nullptr) const;
    /// The same, skipping the polygons and hits `filter` names.
    bool any_hit(const Ray& ray, const RayFilter& filter, RayStats* stats = nullptr) const;
    /// The same, saying which polygon it found (-1: none): for callers that test it first on
    /// the next ray (a shadow cache).
    int any_hit_polygon(const Ray& ray, const RayFilter& filter, RayStats* stats = nullptr) const;
    /// The polygons listed by the leaves whose grown cubes `node_may_meet` accepts (it is asked
    /// for every node on the way down, so a region query prunes whole subtrees), each once, in
    /// increasing order.
    template <class NodeTest>
    std::vector<int> polygons_near(NodeTest&& node_may_meet) const {
        std::vector<int> out;
        append_polygons_near(node_may_meet, out);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    }
    /// The same polygons appended to `out` in the order of the walk, a polygon listed by several
    /// accepted leaves once for each (for callers that filter first and sort what is left).
    template <class NodeTest>
    void append_polygons_near(NodeTest&& node_may_meet, std::vector<int>& out) const {
        if (has_root_) collect(root_, root_cube_, node_may_meet, out);
    }

    /// The polygons, in the order given to the constructor (Hit::polygon indexes them).
    const std::vector<Polygon>& polygons() const { return polygons_; }
    /// Number of polygons.
    int polygon_count() const { return static_cast<int>(polygons_.size()); }
    /// The root cube (an empty box when there are no polygons).
    Box3 bounds() const { return root_cube_; }
    /// Number of nodes, root included (0 for an empty tree). Children that would meet no polygon
    /// are not allocated.
    int node_count() const { return node_count_; }
    /// Number of leaves.
    int leaf_count() const { return leaf_count_; }
    /// Depth of the deepest node (0 when the root is a leaf).
    int depth() const { return depth_; }
    /// Sum over the leaves of the number of polygons each lists.
    long reference_count() const { return reference_count_; }
    /// The options the tree was built with.
    const Options& options() const { return options_; }

private:
    // A cube of the tree, 8 bytes. An internal node's children are the nodes of its block,
    // blocks_[first].child[i] for the octants i with bit i of child_mask() set; a leaf lists the
    // entries leaf_entries_[first .. first + count()).
    struct Node {
        int first = 0;  // internal: index of its block; leaf: start of its list
        int code = 0;   // leaf: count() >= 0; internal: -1 - child_mask()
        static Node leaf(int first, int count) { return Node{first, count}; }
        static Node internal(int block, unsigned mask) {
            return Node{block, -1 - static_cast<int>(mask)};
        }
        bool is_leaf() const { return code >= 0; }
        int count() const { return code; }
        unsigned child_mask() const { return static_cast<unsigned>(-1 - code); }
    };
    // An internal node's eight children (slot i is octant i, unused where the node has no child
    // there): one cache line, all that a visit of the node reads of the tree. Its cube is not
    // stored: a query splits it from its parent's on the way down, as the build did, to the
    // same values (one line a node instead of two: on 200,000 quads 1.06 times the closest-hit
    // and 1.09 times the any-hit rays a second, docs/method.md).
    struct alignas(64) Block {
        std::array<Node, 8> child;
    };
    // What the ray-polygon test reads of one polygon, packed: copies of Polygon's plane, slack
    // and bounding planes (inline up to four, else extra_planes_[first_extra ..]). Its index
    // and surface are in the list entries that lead to it.
    struct alignas(64) RayRecord {
        Plane plane;
        double slack = 0;
        int n_planes = 0;
        int first_extra = 0;
        std::array<Plane, 4> planes;
        const Plane* bounding(const std::vector<Plane>& extra) const {
            return n_planes <= 4 ? planes.data() : extra.data() + first_extra;
        }
    };
    // An entry of a leaf's list: the box a hit on the polygon can lie in (list_entry), in
    // floats (lo rounded down, hi up), with the polygon's index and surface. A ray that misses
    // the box misses the polygon, so only the few rays that meet it read the polygon's ray
    // record (octree_stats on 200,000 quads: 6 % of the tests; the room 11 %). Two to a cache
    // line, a leaf's entries one after the other.
    struct alignas(32) ListEntry {
        std::array<float, 3> lo, hi;
        int polygon = -1;
        int surface = -1;
    };
    static Box3 child_cube(const Box3& cube, int i);
    struct Query;
    struct ChildHits;
    Node build(const Box3& cube, std::vector<int> ids, int depth,
               const std::vector<ListEntry>& entry_of);
    void make_records();
    Box3 grown(const Box3& cube) const;
    bool traverse(const Node& node, const Box3& cube, Query& query) const;
    bool test_leaf(const Node& node, Query& query) const;
    void prefetch_list(const Node& leaf) const;
    ListEntry list_entry(int id) const;
    ChildHits child_hits(const Box3& cube, unsigned mask, const Query& query) const;
    template <class NodeTest>
    void collect(const Node& node, const Box3& cube, NodeTest& test, std::vector<int>& out) const;

    std::vector<Polygon> polygons_;
    Options options_;
    Box3 root_cube_;
    double margin_ = 0;          // every node cube grows by this much for building and traversal
    Box3 grown_root_;            // grown(root_cube_)
    bool has_root_ = false;      // false for an empty tree
    Node root_;                  // the root (its cube is root_cube_)
    std::vector<Block> blocks_;  // the internal nodes' blocks, in depth-first order
    std::vector<ListEntry> leaf_entries_;  // the leaves' lists, one after another
    std::vector<RayRecord> records_;       // records_[id]: polygon id's
    std::vector<Plane> extra_planes_;      // bounding planes of polygons with more than four
    // DESIGN: past Options::prefetch_bytes of records, random rays wait on memory at every node and
    // record (octree_stats on 200,000 quads, 37 MiB of records: `perf` put a third of the
    // time on the load of a record's first line and a fifth on the leaf's list), so queries
    // ask for the children they will visit and for a leaf's list ahead of reading them (the
    // records themselves were asked for too until the lists held the boxes), and for the
    // polygon of each new best hit, which the hit's (u, v) reads at the end. Below it the tree
    // stays in the cache and the prefetches only cost (the room, 2,558 polygons: any-hit rays
    // 15 % slower). Measured in docs/method.md, "Octree and rays".
    bool prefetch_ = false;
    int node_count_ = 0;
    int leaf_count_ = 0;
    int depth_ = 0;
    long reference_count_ = 0;
};

// `cube` is the node's cube (a leaf's is not stored: it is split from its parent's, as the build
// split it).
template <class NodeTest>
void Octree::collect(const Node& node, const Box3& cube, NodeTest& test,
                     std::vector<int>& out) const {
    if (!test(grown(cube))) return;
    if (node.is_leaf()) {
        for (int r = node.first, end = node.first + node.count(); r < end; ++r)
            out.push_back(leaf_entries_[size_t(r)].polygon);
        return;
    }
    const Block& block = blocks_[node.first];
    for (int i = 0; i < 8; ++i)
        if ((node.child_mask() >> i) & 1) collect(block.child[i], child_cube(cube, i), test, out);
}

}  // namespace mbr
