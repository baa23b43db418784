// radiosity/geometry/quadtree.cpp - dyadic cells and the forest of quadtrees over the parameter
// plane.
#include "radiosity/geometry/quadtree.h"

#include <cmath>

#include "math/check.h"

namespace mbr {

namespace {
int floor_div_pow2(int i, int levels) {
    // floor(i / 2^levels) for negative i as well.
    return i >= 0 ? (i >> levels) : -((-i - 1) >> levels) - 1;
}
}  // namespace

double DyadicCell::size() const {
    return std::ldexp(1.0, -level);
}

Rect DyadicCell::rect() const {
    const double h = size();
    return {i * h, (i + 1) * h, j * h, (j + 1) * h};
}

bool DyadicCell::in_domain() const {
    const int n = 1 << level;
    return i >= 0 && i < n && j >= 0 && j < n;
}

int DyadicCell::patch() const {
    const int n = 1 << level;
    const int si = i < 0 ? -1 : (i >= n ? 1 : 0);
    const int sj = j < 0 ? -1 : (j >= n ? 1 : 0);
    if (si == 0 && sj == 0) return -1;
    // Counter-clockwise from below-left: (-1,-1) (0,-1) (1,-1) (1,0) (1,1) (0,1) (-1,1) (-1,0).
    static const int table[3][3] = {{0, 7, 6}, {1, -1, 5}, {2, 3, 4}};  // [si+1][sj+1]
    return table[si + 1][sj + 1];
}

DyadicCell DyadicCell::parent() const {
    MBR_CHECK(level > 0);
    return {level - 1, floor_div_pow2(i, 1), floor_div_pow2(j, 1)};
}

bool operator==(const DyadicCell& a, const DyadicCell& b) {
    return a.level == b.level && a.i == b.i && a.j == b.j;
}

std::ostream& operator<<(std::ostream& os, const DyadicCell& c) {
    return os << "cell(L" << c.level << ", " << c.i << ", " << c.j << ')';
}

Forest::Forest(int K) {
    Node domain;
    domain.cell = {0, 0, 0};
    nodes_.push_back(domain);
    roots_ = {0};
    grow(K);
}

void Forest::grow(int K) {
    MBR_CHECK(K >= 0 && K <= 4096);
    if (K <= K_ && !roots_.empty()) return;
    const int side = 2 * K + 1;
    std::vector<int> roots(size_t(side) * side, -1);
    for (int J = -K; J <= K; ++J)
        for (int I = -K; I <= K; ++I) {
            int index = root(I, J);  // existing root, if any
            if (index < 0) {
                Node n;
                n.cell = {0, I, J};
                index = static_cast<int>(nodes_.size());
                nodes_.push_back(n);
            }
            roots[size_t(J + K) * side + (I + K)] = index;
        }
    roots_ = std::move(roots);
    K_ = K;
}

int Forest::root(int I, int J) const {
    if (I < -K_ || I > K_ || J < -K_ || J > K_ || roots_.empty()) return -1;
    const int side = 2 * K_ + 1;
    return roots_[size_t(J + K_) * side + (I + K_)];
}

int Forest::split(int index) {
    MBR_CHECK(nodes_[index].is_leaf());
    const int first = static_cast<int>(nodes_.size());
    const DyadicCell c = nodes_[index].cell;
    for (int ch = 0; ch < 4; ++ch) {
        Node n;
        n.cell = c.child(ch & 1, ch >> 1);
        n.parent = index;
        nodes_.push_back(n);
    }
    nodes_[index].first_child = first;  // after push_back: nodes_ may have moved
    return first;
}

int Forest::find(const DyadicCell& cell) const {
    const int I = floor_div_pow2(cell.i, cell.level), J = floor_div_pow2(cell.j, cell.level);
    int index = root(I, J);
    if (index < 0) return -1;
    for (int L = 1; L <= cell.level; ++L) {
        const Node& n = nodes_[index];
        if (n.is_leaf()) return index;
        // Which child at level L contains the cell: bit (cell.level - L) of its indices.
        const int shift = cell.level - L;
        const int di = floor_div_pow2(cell.i, shift) & 1, dj = floor_div_pow2(cell.j, shift) & 1;
        index = n.first_child + di + 2 * dj;
    }
    return index;
}

int Forest::leaf_at(double s, double t) const {
    double fs = std::floor(s), ft = std::floor(t);
    if (s == K_ + 1.0) fs = K_;
    if (t == K_ + 1.0) ft = K_;
    int index = root(static_cast<int>(fs), static_cast<int>(ft));
    if (index < 0) return -1;
    double x = s - fs, y = t - ft;  // position inside the current cell, in its units
    while (!nodes_[index].is_leaf()) {
        int di = x >= 0.5 ? 1 : 0, dj = y >= 0.5 ? 1 : 0;
        x = std::min(2 * x - di, 1.0);
        y = std::min(2 * y - dj, 1.0);
        index = nodes_[index].first_child + di + 2 * dj;
    }
    return index;
}

std::vector<int> Forest::leaves(Region region) const {
    std::vector<int> out;
    for (int index = 0; index < n_nodes(); ++index) {
        const Node& n = nodes_[index];
        if (!n.is_leaf()) continue;
        const bool inside = n.cell.in_domain();
        if (region == Region::Domain && !inside) continue;
        if (region == Region::Expanded && inside) continue;
        out.push_back(index);
    }
    return out;
}

}  // namespace mbr
