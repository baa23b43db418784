// test/test_octree_reference.cpp - the paper's octree (section 6, "Octree") in its flat layout
// against the pointer octree it replaced: the same nodes visited, the same polygons tested, the
// same answers, the same walk of region queries.
//
// ReferenceOctree below is the pointer octree as octree.cpp had it before the flat layout: nodes
// owning their children through pointers, child cubes recomputed on every visit, children sorted
// by where the ray enters them. It is kept here, small and slow, as the oracle: the flat layout
// must follow it node for node (RayStats equal, not only the hits), which brute force alone
// cannot check (a traversal that visits too much still finds the right hit).
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "octree/octree.h"

using namespace mbr;

namespace {

class ReferenceOctree {
public:
    ReferenceOctree(const std::vector<Polygon>& polygons, OctreeOptions options)
        : polygons_(polygons), options_(options) {
        Box3 box;
        double slack = 0;
        for (const Polygon& p : polygons_) {
            box.extend(p.bounds());
            slack = std::max(slack, p.planarity_error() + p.edge_slack());
        }
        const Vec3 e = box.extent();
        const double side = 1.01 * std::max({e.x, e.y, e.z});
        const Vec3 half{0.5 * side, 0.5 * side, 0.5 * side};
        root_cube_ = Box3{box.centre() - half, box.centre() + half};
        margin_ = 1e-7 * side + 2 * slack;
        std::vector<int> ids(polygons_.size());
        for (int i = 0; i < static_cast<int>(ids.size()); ++i) ids[i] = i;
        root_ = build(root_cube_, std::move(ids), 0);
    }

    std::optional<Hit> closest_hit(const Ray& ray, RayStats& stats) const {
        Query q;
        q.ray = ray;
        q.recent.fill(-1);
        for (int k = 0; k < 3; ++k) q.inv_dir[k] = ray.dir[k] != 0 ? 1 / ray.dir[k] : 0;
        double t0 = ray.t_min, t1 = ray.t_max;
        if (t0 <= t1 && clip(grown(root_cube_), q, t0, t1)) traverse(*root_, root_cube_, q);
        stats += q.stats;
        if (q.best < 0) return std::nullopt;
        const Polygon& p = polygons_[q.best];
        return Hit{q.best, p.surface(), p.uv_at(ray.at(q.ray.t_max)), q.ray.t_max};
    }

    // The cubes a region query is shown, in order, when it accepts each one `accept` accepts.
    template <class Accept>
    void walk(Accept accept, std::vector<Box3>& shown, std::vector<int>& listed) const {
        walk(*root_, root_cube_, accept, shown, listed);
    }

private:
    struct Node {
        std::array<std::unique_ptr<Node>, 8> children;
        std::vector<int> polygons;
        bool is_leaf = true;
    };
    struct Query {
        Ray ray;
        Vec3 inv_dir;
        int best = -1;
        std::array<int, 32> recent;
        RayStats stats;
    };

    static Box3 child_cube(const Box3& cube, int i) {
        const Vec3 mid = cube.centre();
        Box3 c;
        for (int k = 0; k < 3; ++k) {
            const bool upper = (i >> k) & 1;
            c.lo[k] = upper ? mid[k] : cube.lo[k];
            c.hi[k] = upper ? cube.hi[k] : mid[k];
        }
        return c;
    }
    Box3 grown(const Box3& cube) const {
        const Vec3 m{margin_, margin_, margin_};
        return Box3{cube.lo - m, cube.hi + m};
    }
    static bool clip(const Box3& box, const Query& q, double& t0, double& t1) {
        for (int k = 0; k < 3; ++k) {
            if (q.ray.dir[k] == 0) {
                if (q.ray.origin[k] < box.lo[k] || q.ray.origin[k] > box.hi[k]) return false;
                continue;
            }
            double ta = (box.lo[k] - q.ray.origin[k]) * q.inv_dir[k];
            double tb = (box.hi[k] - q.ray.origin[k]) * q.inv_dir[k];
            if (ta > tb) std::swap(ta, tb);
            if (ta > t0) t0 = ta;
            if (tb < t1) t1 = tb;
            if (t0 > t1) return false;
        }
        return true;
    }

    std::unique_ptr<Node> build(const Box3& cube, std::vector<int> ids, int depth) {
        auto node = std::make_unique<Node>();
        const int n_ids = static_cast<int>(ids.size());
        if (n_ids > options_.max_polygons_per_leaf && depth < options_.max_depth) {
            std::array<std::vector<int>, 8> lists;
            long n_child_refs = 0;
            for (int i = 0; i < 8; ++i) {
                const Box3 c = grown(child_cube(cube, i));
                for (int id : ids)
                    if (node_meets_polygon(c, polygons_[id])) lists[i].push_back(id);
                n_child_refs += static_cast<long>(lists[i].size());
            }
            if (0.25 * static_cast<double>(n_child_refs) + 1 < n_ids) {
                node->is_leaf = false;
                for (int i = 0; i < 8; ++i)
                    if (!lists[i].empty())
                        node->children[i] =
                            build(child_cube(cube, i), std::move(lists[i]), depth + 1);
                return node;
            }
        }
        node->polygons = std::move(ids);
        return node;
    }

    void test_leaf(const Node& node, Query& q) const {
        for (int id : node.polygons) {
            int& slot = q.recent[id & 31];
            if (slot == id) continue;
            slot = id;
            ++q.stats.n_polygons_tested;
            const std::optional<double> t = polygons_[id].intersect(q.ray);
            if (t && (*t < q.ray.t_max || q.best < 0 || id < q.best)) {
                q.ray.t_max = *t;
                q.best = id;
            }
        }
    }

    void traverse(const Node& node, const Box3& cube, Query& q) const {
        ++q.stats.n_nodes_visited;
        if (node.is_leaf) return test_leaf(node, q);
        struct Entry {
            double t;
            int child;
        };
        std::array<Entry, 8> order;
        int n = 0;
        for (int i = 0; i < 8; ++i) {
            if (!node.children[i]) continue;
            double t0 = q.ray.t_min, t1 = q.ray.t_max;
            if (!clip(grown(child_cube(cube, i)), q, t0, t1)) continue;
            int j = n++;
            for (; j > 0 && order[j - 1].t > t0; --j) order[j] = order[j - 1];
            order[j] = {t0, i};
        }
        for (int k = 0; k < n; ++k) {
            if (order[k].t > q.ray.t_max) break;
            traverse(*node.children[order[k].child], child_cube(cube, order[k].child), q);
        }
    }

    template <class Accept>
    void walk(const Node& node, const Box3& cube, Accept& accept, std::vector<Box3>& shown,
              std::vector<int>& listed) const {
        shown.push_back(grown(cube));
        if (!accept(grown(cube))) return;
        if (node.is_leaf) {
            listed.insert(listed.end(), node.polygons.begin(), node.polygons.end());
            return;
        }
        for (int i = 0; i < 8; ++i)
            if (node.children[i])
                walk(*node.children[i], child_cube(cube, i), accept, shown, listed);
    }

    const std::vector<Polygon>& polygons_;
    OctreeOptions options_;
    Box3 root_cube_;
    double margin_ = 0;
    std::unique_ptr<Node> root_;
};

std::uint64_t bits(double d) {
    std::uint64_t u;
    std::memcpy(&u, &d, sizeof u);
    return u;
}

bool same_box(const Box3& a, const Box3& b) {
    for (int k = 0; k < 3; ++k)
        if (bits(a.lo[k]) != bits(b.lo[k]) || bits(a.hi[k]) != bits(b.hi[k])) return false;
    return true;
}

Polygon make_polygon(std::vector<Vec3> v, int surface) {
    std::vector<Vec2> uv;
    for (size_t i = 0; i < v.size(); ++i) uv.push_back({0.1 * i, 1 - 0.1 * i});
    return Polygon(std::move(v), std::move(uv), surface);
}

// Convex polygons of 3 to 6 vertices in [0, 10]^3, every fifth one axis-aligned, a tessellated
// wall (shared edges) and two exact duplicates (ties in t).
std::vector<Polygon> scene(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> u01(0, 1), pos(0, 10);
    std::normal_distribution<double> g;
    std::vector<Polygon> out;
    for (int i = 0; i < n; ++i) {
        Vec3 normal = i % 5 == 0 ? Vec3{0, 0, 1} : normalize(Vec3{g(rng), g(rng), g(rng)});
        const Vec3 a = std::fabs(normal.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        const Vec3 t1 = normalize(cross(a, normal)), t2 = cross(normal, t1);
        const int k = 3 + static_cast<int>(4 * u01(rng));
        const double r = 0.05 * std::pow(40.0, u01(rng)), aspect = 0.2 + 0.8 * u01(rng);
        const Vec3 c{pos(rng), pos(rng), pos(rng)};
        const double theta0 = 2 * Pi * u01(rng);
        std::vector<Vec3> v;
        for (int j = 0; j < k; ++j) {
            const double theta = theta0 + 2 * Pi * (j + 0.8 * u01(rng)) / k;
            v.push_back(c + r * std::cos(theta) * t1 + r * aspect * std::sin(theta) * t2);
        }
        out.push_back(make_polygon(v, i % 13));
    }
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            out.push_back(make_polygon({{i * 1.0, j * 1.0, 5.0},
                                        {i + 1.0, j * 1.0, 5.0},
                                        {i + 1.0, j + 1.0, 5.0},
                                        {i * 1.0, j + 1.0, 5.0}},
                                       40));
    out.push_back(out[3]);
    out.push_back(out[10]);
    return out;
}

// Rays of every kind the traversal treats apart: random, along an axis, with zero and denormal
// components, from the root's mid-planes and faces and from the faces of the nodes' grown cubes
// (`cubes`), through vertices, segments, short, single-t and empty t ranges.
Ray ray_of_kind(std::mt19937& rng, const Octree& octree, const std::vector<Box3>& cubes, int r) {
    std::uniform_real_distribution<double> u01(0, 1), pos(-5, 15);
    std::normal_distribution<double> g;
    const Box3 root = octree.bounds();
    const Vec3 mid = root.centre();
    const double tiny[] = {0.0, -0.0, 1e-310, -1e-310, 5e-324, -4e-320};
    Vec3 o{pos(rng), pos(rng), pos(rng)};
    Vec3 d{g(rng), g(rng), g(rng)};
    const int k = r % 3, k2 = (r / 3) % 3;
    double t0 = 0, t1 = HUGE_VAL;
    switch ((r / 9) % 10) {
        case 0:
            break;
        case 1:
            d = Vec3{};
            d[k] = u01(rng) < 0.5 ? 1 : -1;
            break;
        case 2:
            d[k] = tiny[r % 6];
            if (r % 2) d[k2] = tiny[(r / 2) % 6];
            break;
        case 3:
            o[k] = mid[k];
            if (r % 2) o[k2] = mid[k2];
            if (r % 4 < 2) d[k] = tiny[r % 6];
            break;
        case 4:
            o[k] = r % 2 ? root.lo[k] : root.hi[k];
            if (r % 4 < 2) d[k] = tiny[r % 6];
            break;
        case 5: {
            const std::vector<Polygon>& p = octree.polygons();
            d = p[static_cast<size_t>(r) % p.size()].vertices()[0] - o;
            break;
        }
        case 6: {
            const Vec3 b{pos(rng), pos(rng), pos(rng)};
            d = b - o;
            t0 = 1e-6;
            t1 = 1 - 1e-6;
            break;
        }
        case 7:
            t0 = u01(rng) < 0.3 ? 0 : 10 * u01(rng);
            t1 = r % 3 == 0 ? t0 : t0 + 10 * u01(rng);
            break;
        case 8: {
            const Box3& c = cubes[static_cast<size_t>(r) % cubes.size()];
            o = c.centre() +
                0.4 * c.extent().x * Vec3{u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5};
            o[k] = r % 2 ? c.lo[k] : c.hi[k];
            if (r % 4 < 2) d[k] = tiny[r % 6];
            break;
        }
        default:
            t0 = 1;
            t1 = u01(rng) < 0.5 ? 0.5 : std::nan("");
            break;
    }
    return Ray{o, d, t0, t1};
}

}  // namespace

TEST_CASE("octree: the flat layout visits and tests as the pointer octree did", "[octree]") {
    const unsigned seed = 777;
    std::mt19937 rng(seed);
    const std::vector<Polygon> polygons = scene(rng, 900);
    // The last two prefetch (prefetch_bytes 0), as trees of large scenes do: the same walk.
    for (OctreeOptions options :
         {OctreeOptions{}, OctreeOptions{6, 4}, OctreeOptions{0, 8}, OctreeOptions{12, 1},
          OctreeOptions{10, 8, 0}, OctreeOptions{12, 1, 0}}) {
        CAPTURE(seed, options.max_depth, options.max_polygons_per_leaf, options.prefetch_bytes);
        const Octree octree(polygons, options);
        const ReferenceOctree reference(polygons, options);
        std::vector<Box3> cubes;  // every node's grown cube
        std::vector<int> listed;
        octree.append_polygons_near(
            [&](const Box3& c) {
                cubes.push_back(c);
                return true;
            },
            listed);
        long n_hits = 0;
        for (int r = 0; r < 5000; ++r) {
            const Ray ray = ray_of_kind(rng, octree, cubes, r);
            CAPTURE(r, ray);
            RayStats got_stats, expected_stats;
            const std::optional<Hit> got = octree.closest_hit(ray, &got_stats);
            const std::optional<Hit> expected = reference.closest_hit(ray, expected_stats);
            REQUIRE(got.has_value() == expected.has_value());
            if (got) {
                ++n_hits;
                CHECK(got->polygon == expected->polygon);
                CHECK(bits(got->t) == bits(expected->t));
                CHECK(bits(got->uv.x) == bits(expected->uv.x));
                CHECK(bits(got->uv.y) == bits(expected->uv.y));
            }
            // The same nodes entered and the same polygons tested, in the same order.
            CHECK(got_stats.n_nodes_visited == expected_stats.n_nodes_visited);
            CHECK(got_stats.n_polygons_tested == expected_stats.n_polygons_tested);
            // Any hit: the answer of the closest hit (no filter, so no hit is discounted).
            CHECK(octree.any_hit(ray) == expected.has_value());
        }
        CHECK(n_hits > 1000);
    }
}

TEST_CASE("octree: region queries walk the cubes the pointer octree walked", "[octree]") {
    const unsigned seed = 4242;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0, 1);
    const std::vector<Polygon> polygons = scene(rng, 700);
    for (OctreeOptions options : {OctreeOptions{}, OctreeOptions{8, 2}}) {
        const Octree octree(polygons, options);
        const ReferenceOctree reference(polygons, options);
        for (int r = 0; r < 100; ++r) {
            CAPTURE(seed, options.max_polygons_per_leaf, r);
            const Vec3 lo{12 * u01(rng) - 1, 12 * u01(rng) - 1, 12 * u01(rng) - 1};
            const double s = 4 * u01(rng) * u01(rng);
            const Box3 region{lo, lo + Vec3{s, 0.3 * s, s}};
            auto accept = [&](const Box3& c) { return overlaps(c, region); };
            std::vector<Box3> shown, expected_shown;
            std::vector<int> listed, expected_listed;
            octree.append_polygons_near(
                [&](const Box3& c) {
                    shown.push_back(c);
                    return accept(c);
                },
                listed);
            reference.walk(accept, expected_shown, expected_listed);
            REQUIRE(shown.size() == expected_shown.size());
            for (size_t i = 0; i < shown.size(); ++i) CHECK(same_box(shown[i], expected_shown[i]));
            CHECK(listed == expected_listed);
        }
    }
}
