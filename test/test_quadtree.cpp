// test/test_quadtree.cpp - dyadic cells, the forest of quadtrees over the receiver's parameter
// plane (paper section 5, "Upon the domain R[a,b;c,d] and each patch of the expanded domain,
// there is a hierarchical structure"; Figure 5's eight patches) and NeighAdjust (section 5
// "Adjustment of the Scale of Adjacent Subdomains", section 6 "Scale Adjustment", Figure 4;
// radiosity/geometry/quadtree.h, adjust_neighbour_scales in radiosity/transfer/scale_adjustment.h).
//
// Independent references: brute force over all leaves (closed rectangles touching, half-open
// containment), and a global fixed-point balancing loop that knows nothing of the twelve
// neighbours of Figure 4.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "radiosity/geometry/quadtree.h"
#include "radiosity/transfer/transfer.h"
#include "test/report.h"

using namespace mbr;

namespace {

using CellKey = std::tuple<int, int, int>;
CellKey key(const DyadicCell& c) {
    return {c.level, c.i, c.j};
}

/// Closed rectangles meet (an edge or a corner in common counts).
bool touching(const Rect& a, const Rect& b) {
    return a.x0 <= b.x1 && b.x0 <= a.x1 && a.y0 <= b.y1 && b.y0 <= a.y1;
}

/// Splits `n_splits` leaves chosen at random (seeded) among those of level < max_level.
void split_at_random(Forest& forest, std::mt19937& rng, int n_splits, int max_level) {
    for (int s = 0; s < n_splits; ++s) {
        std::vector<int> candidates;
        for (int index : forest.leaves())
            if (forest.node(index).cell.level < max_level) candidates.push_back(index);
        if (candidates.empty()) return;
        forest.split(
            candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng)]);
    }
}

/// The set of leaf cells of a forest.
std::set<CellKey> leaf_set(const Forest& forest, Forest::Region region = Forest::Region::All) {
    std::set<CellKey> out;
    for (int index : forest.leaves(region)) out.insert(key(forest.node(index).cell));
    return out;
}

/// Every pair of touching leaves (closed rectangles) with sizes more than a factor 2 apart.
int unbalanced_pairs(const Forest& forest, Forest::Region region) {
    const std::vector<int> all = forest.leaves(), checked = forest.leaves(region);
    int bad = 0;
    for (int a : checked)
        for (int b : all) {
            const DyadicCell ca = forest.node(a).cell, cb = forest.node(b).cell;
            if (a == b || !touching(ca.rect(), cb.rect())) continue;
            if (std::abs(ca.level - cb.level) > 1) ++bad;
        }
    return bad;
}

/// The coarsest balanced refinement by a global fixed point: split every leaf that touches a
/// leaf more than twice smaller, until nothing changes. Slow (quadratic per pass), obviously
/// correct, and unique: any balanced refinement must contain every split this loop makes.
void balance_brute_force(Forest& forest) {
    for (bool changed = true; changed;) {
        changed = false;
        const std::vector<int> leaves = forest.leaves();
        for (int a : leaves) {
            if (!forest.node(a).is_leaf()) continue;
            bool split = false;
            for (int b : leaves) {
                const DyadicCell ca = forest.node(a).cell, cb = forest.node(b).cell;
                if (cb.level > ca.level + 1 && touching(ca.rect(), cb.rect())) split = true;
            }
            // Children made in this pass count too: look at them in the next pass.
            if (split) {
                forest.split(a);
                changed = true;
            }
        }
    }
}

}  // namespace

TEST_CASE("quadtree: dyadic cells have the documented rectangle, parent and children",
          "[quadtree]") {
    const DyadicCell c{3, -5, 6};
    CHECK(c.size() == 0.125);
    const Rect r = c.rect();
    CHECK(r.x0 == -0.625);
    CHECK(r.x1 == -0.5);
    CHECK(r.y0 == 0.75);
    CHECK(r.y1 == 0.875);
    // parent() floors towards minus infinity, also for negative indices.
    CHECK(c.parent() == DyadicCell{2, -3, 3});
    CHECK(DyadicCell{1, -1, -2}.parent() == DyadicCell{0, -1, -1});
    CHECK(DyadicCell{2, -4, 0}.parent() == DyadicCell{1, -2, 0});
    for (int di = 0; di <= 1; ++di)
        for (int dj = 0; dj <= 1; ++dj) {
            CAPTURE(di, dj);
            const DyadicCell ch = c.child(di, dj);
            CHECK(ch.parent() == c);
            const Rect rc = ch.rect();
            CHECK(rc.width() == 0.5 * r.width());
            CHECK(rc.x0 == r.x0 + di * rc.width());
            CHECK(rc.y0 == r.y0 + dj * rc.height());
        }
    CHECK(DyadicCell{0, 0, 0}.in_domain());
    CHECK(DyadicCell{2, 3, 0}.in_domain());
    CHECK_FALSE(DyadicCell{2, 4, 0}.in_domain());
    CHECK_FALSE(DyadicCell{2, 0, -1}.in_domain());
    CHECK_FALSE(DyadicCell{0, 1, 1}.in_domain());
}

TEST_CASE("quadtree: patches 0..7 run counter-clockwise from below-left of the domain",
          "[quadtree]") {
    // Figure 5 as documented in quadtree.h: 0 (s<0,t<0), 1 below, 2 (s>1,t<0), 3 right,
    // 4 (s>1,t>1), 5 above, 6 (s<0,t>1), 7 left; -1 for the domain itself.
    struct Expect {
        double s, t;
        int patch;
    };
    const Expect expect[] = {{-0.3, -0.2, 0}, {0.5, -0.7, 1},  {1.4, -0.1, 2}, {1.2, 0.5, 3},
                             {1.9, 1.3, 4},   {0.1, 1.6, 5},   {-0.6, 1.1, 6}, {-0.2, 0.99, 7},
                             {0.5, 0.5, -1},  {0.01, 0.99, -1}};
    for (int level = 0; level <= 4; ++level)
        for (const Expect& e : expect) {
            const double n = std::ldexp(1.0, level);
            const DyadicCell c{level, int(std::floor(e.s * n)), int(std::floor(e.t * n))};
            CAPTURE(level, e.s, e.t, c);
            CHECK(c.patch() == e.patch);
            CHECK(c.in_domain() == (e.patch == -1));
        }
    // Counter-clockwise: walking around the domain at level 0 visits 0, 1, ..., 7 in order.
    const int ring[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}};
    for (int p = 0; p < 8; ++p) CHECK(DyadicCell{0, ring[p][0], ring[p][1]}.patch() == p);
}

TEST_CASE("quadtree: grow keeps node indices and adds the ring of roots", "[quadtree]") {
    Forest forest(0);
    REQUIRE(forest.n_nodes() == 1);
    CHECK(forest.domain_root() == 0);
    CHECK(forest.root(1, 0) == -1);
    const int first = forest.split(0);
    forest.split(first + 3);
    const int before = forest.n_nodes();
    std::vector<DyadicCell> cells;
    for (int i = 0; i < before; ++i) cells.push_back(forest.node(i).cell);

    forest.grow(2);
    CHECK(forest.extent() == 2);
    CHECK(forest.n_nodes() == before + 24);  // 5 x 5 roots, the domain root already there
    for (int i = 0; i < before; ++i) {
        CAPTURE(i);
        CHECK(forest.node(i).cell == cells[i]);
    }
    CHECK(forest.domain_root() == 0);
    for (int J = -2; J <= 2; ++J)
        for (int I = -2; I <= 2; ++I) {
            CAPTURE(I, J);
            const int r = forest.root(I, J);
            REQUIRE(r >= 0);
            CHECK(forest.node(r).cell == DyadicCell{0, I, J});
            CHECK(forest.node(r).parent == -1);
        }
    CHECK(forest.root(3, 0) == -1);
    CHECK(forest.root(0, -3) == -1);
    // Growing to a smaller extent changes nothing; growing again keeps the ring's indices too.
    const int ring_node = forest.root(-2, 1);
    forest.grow(1);
    CHECK(forest.extent() == 2);
    forest.grow(3);
    CHECK(forest.root(-2, 1) == ring_node);
    CHECK(forest.n_nodes() == before + 48);
}

TEST_CASE("quadtree: leaves tile the forest and split by region", "[quadtree]") {
    for (unsigned seed : {1u, 2u, 3u}) {
        CAPTURE(seed);
        std::mt19937 rng(seed);
        Forest forest(1);
        split_at_random(forest, rng, 40, 5);
        double area = 0;
        for (int index : forest.leaves()) area += forest.node(index).cell.rect().area();
        CHECK(area == Approx(9.0).margin(1e-12));  // dyadic areas: the sum is exact
        const auto all = leaf_set(forest), domain = leaf_set(forest, Forest::Region::Domain),
                   expanded = leaf_set(forest, Forest::Region::Expanded);
        CHECK(domain.size() + expanded.size() == all.size());
        double domain_area = 0;
        for (int index : forest.leaves(Forest::Region::Domain)) {
            CHECK(forest.node(index).cell.in_domain());
            domain_area += forest.node(index).cell.rect().area();
        }
        CHECK(domain_area == Approx(1.0).margin(1e-12));
        for (int index : forest.leaves(Forest::Region::Expanded))
            CHECK(forest.node(index).cell.patch() >= 0);
        // Children are contiguous in the order (0,0), (1,0), (0,1), (1,1), and know their parent.
        for (int index = 0; index < forest.n_nodes(); ++index) {
            const Forest::Node& n = forest.node(index);
            if (n.is_leaf()) continue;
            for (int c = 0; c < 4; ++c) {
                const Forest::Node& ch = forest.node(forest.child(index, c));
                CHECK(ch.cell == n.cell.child(c & 1, c >> 1));
                CHECK(ch.parent == index);
            }
        }
    }
}

TEST_CASE("quadtree: find returns the cell's node or the coarser leaf holding it", "[quadtree]") {
    std::mt19937 rng(7);
    Forest forest(1);
    split_at_random(forest, rng, 60, 5);
    std::uniform_int_distribution<int> level_d(0, 6);
    std::uniform_real_distribution<double> pos(-0.999, 1.999);
    for (int trial = 0; trial < 500; ++trial) {
        const int level = level_d(rng);
        const double n = std::ldexp(1.0, level);
        const DyadicCell cell{level, int(std::floor(pos(rng) * n)), int(std::floor(pos(rng) * n))};
        CAPTURE(trial, cell);
        // Brute force: the node with exactly this cell, else the leaf whose rectangle holds it.
        int expect = -1;
        for (int index = 0; index < forest.n_nodes(); ++index) {
            const DyadicCell c = forest.node(index).cell;
            if (c == cell) expect = index;
        }
        if (expect < 0)
            for (int index : forest.leaves()) {
                const Rect a = forest.node(index).cell.rect(), b = cell.rect();
                if (a.x0 <= b.x0 && b.x1 <= a.x1 && a.y0 <= b.y0 && b.y1 <= a.y1) expect = index;
            }
        CHECK(forest.find(cell) == expect);
    }
    CHECK(forest.find(DyadicCell{0, 2, 0}) == -1);
    CHECK(forest.find(DyadicCell{3, -9, 0}) == -1);
    CHECK(forest.find(DyadicCell{3, 0, 16}) == -1);
}

TEST_CASE("quadtree: leaf_at returns the leaf whose half-open cell holds the point", "[quadtree]") {
    std::mt19937 rng(11);
    Forest forest(1);
    split_at_random(forest, rng, 60, 6);
    const std::vector<int> leaves = forest.leaves();
    auto brute = [&](double s, double t) {
        int found = -1, count = 0;
        for (int index : leaves) {
            const Rect r = forest.node(index).cell.rect();
            // Half-open [x0, x1) x [y0, y1), except that the forest's upper edges belong to the
            // last cell.
            const bool in_s = s >= r.x0 && (s < r.x1 || (s == 2.0 && r.x1 == 2.0));
            const bool in_t = t >= r.y0 && (t < r.y1 || (t == 2.0 && r.y1 == 2.0));
            if (in_s && in_t) {
                found = index;
                ++count;
            }
        }
        REQUIRE(count <= 1);
        return found;
    };
    std::uniform_real_distribution<double> pos(-1.0, 2.0);
    std::uniform_int_distribution<int> grid(-64, 128);
    for (int trial = 0; trial < 400; ++trial) {
        // Random points and points on the dyadic grid (edges and corners of cells).
        const double s = trial % 2 ? pos(rng) : grid(rng) / 64.0;
        const double t = trial % 3 ? pos(rng) : grid(rng) / 64.0;
        CAPTURE(trial, s, t);
        CHECK(forest.leaf_at(s, t) == brute(s, t));
    }
    CHECK(forest.leaf_at(2.0, 2.0) == brute(2.0, 2.0));
    CHECK(forest.leaf_at(2.0, 2.0) >= 0);
    CHECK(forest.leaf_at(-1.0, -1.0) >= 0);
    CHECK(forest.leaf_at(-1.0001, 0.5) == -1);
    CHECK(forest.leaf_at(0.5, 2.0001) == -1);
}

TEST_CASE("quadtree: after scale adjustment no leaf is more than twice any neighbour",
          "[quadtree]") {
    // Random forests (seeded): domain alone (K = 0) checked over the domain, and a forest with
    // the ring (K = 1) checked everywhere. Neighbours are the leaves whose closed rectangles
    // touch: the edge and corner neighbours of Figure 4, found by brute force.
    for (int K : {0, 1})
        for (unsigned seed = 1; seed <= 6; ++seed) {
            CAPTURE(K, seed);
            std::mt19937 rng(100 * K + seed);
            Forest forest(K);
            split_at_random(forest, rng, K == 0 ? 25 : 45, 7);
            const Forest::Region region = K == 0 ? Forest::Region::Domain : Forest::Region::All;
            const int before = unbalanced_pairs(forest, region);
            const int splits = adjust_neighbour_scales(forest, region);
            CAPTURE(before, splits);
            CHECK(unbalanced_pairs(forest, region) == 0);
            if (before > 0) CHECK(splits > 0);
            mbr::test::report() << "quadtree balance K=" << K << " seed=" << seed
                                << ": unbalanced pairs " << before << ", splits " << splits
                                << ", leaves " << forest.leaves().size() << "\n";
        }
}

TEST_CASE("quadtree: scale adjustment makes the coarsest balanced refinement", "[quadtree]") {
    // The coarsest refinement in which touching leaves differ by at most one level is unique;
    // NeighAdjust's local twelve-neighbour rule must reach the same leaves as the global loop,
    // i.e. it splits exactly what is needed and nothing more.
    for (unsigned seed = 1; seed <= 8; ++seed) {
        CAPTURE(seed);
        std::mt19937 rng(seed);
        Forest a(1);
        split_at_random(a, rng, 30, 7);
        Forest b = a;
        const int splits = adjust_neighbour_scales(a, Forest::Region::All);
        const int before = b.n_nodes();
        balance_brute_force(b);
        CHECK(splits == (b.n_nodes() - before) / 4);
        CHECK(leaf_set(a) == leaf_set(b));
    }
}

TEST_CASE("quadtree: scale adjustment leaves a balanced forest alone", "[quadtree]") {
    SECTION("uniform trees") {
        for (int depth = 0; depth <= 4; ++depth) {
            CAPTURE(depth);
            Forest forest(1);
            for (int level = 0; level < depth; ++level)
                for (int index : forest.leaves()) forest.split(index);
            CHECK(adjust_neighbour_scales(forest, Forest::Region::All) == 0);
            CHECK(adjust_neighbour_scales(forest, Forest::Region::Domain) == 0);
        }
    }
    SECTION("a graded tree: one corner refined three times, its neighbours once less") {
        // Domain split to level 1; quadrant (0,0) to level 2; its corner cell (0,0) to level 3.
        // Every touching pair differs by at most one level, so nothing is split.
        Forest forest(0);
        const int q = forest.split(forest.domain_root());
        const int c = forest.split(q);
        forest.split(c);
        REQUIRE(unbalanced_pairs(forest, Forest::Region::Domain) == 0);
        CHECK(adjust_neighbour_scales(forest, Forest::Region::Domain) == 0);
    }
    SECTION("a second pass after adjustment") {
        for (unsigned seed = 1; seed <= 4; ++seed) {
            CAPTURE(seed);
            std::mt19937 rng(1000 + seed);
            Forest forest(1);
            split_at_random(forest, rng, 40, 6);
            adjust_neighbour_scales(forest, Forest::Region::All);
            CHECK(adjust_neighbour_scales(forest, Forest::Region::All) == 0);
        }
    }
    SECTION("a leaf next to a cell two levels finer is split exactly once") {
        // Domain split to level 2 in its lower-left quadrant only, then one level-2 cell split:
        // the level-1 quadrants touching that level-3 block must split, nothing else.
        Forest forest(0);
        const int q = forest.split(forest.domain_root());  // level 1
        const int c = forest.split(q);                     // quadrant (0,0) -> level 2
        forest.split(c + 3);                               // cell (1,1) of level 2 -> level 3
        // (1,1) at level 2 spans [0.25, 0.5]^2: its level-3 children touch quadrants (1,0),
        // (0,1) and (1,1) of level 1 (edges and a corner), which are two levels coarser.
        // Before: those three are unbalanced w.r.t. the level-3 cells.
        CHECK(unbalanced_pairs(forest, Forest::Region::Domain) > 0);
        const int splits = adjust_neighbour_scales(forest, Forest::Region::Domain);
        CHECK(splits == 3);
        CHECK(unbalanced_pairs(forest, Forest::Region::Domain) == 0);
    }
}
