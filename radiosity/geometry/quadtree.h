// radiosity/geometry/quadtree.h - the hierarchical structures of a receiver's parameter plane
// (paper section 5: "Upon the domain R[a,b;c,d] and each patch of the expanded domain, there is a
// hierarchical structure constructed during subdivision").
//
// Every cell is a dyadic square (level L, index i, j) = [i 2^-L, (i+1) 2^-L] x [j 2^-L, (j+1) 2^-L]
// of the (s,t) plane. The roots are the unit squares (I, J) with |I|, |J| <= K: the root (0,0)
// is the domain [0,1]^2, the others tile the expanded domain, grouped into the eight patches of
// Figure 5 by the signs of I and J. One lattice for all of them keeps neighbour look-ups and
// fulcrum positions consistent across the domain's boundary.
#pragma once

#include <ostream>
#include <vector>

#include "math/vec3.h"

namespace mbr {

/// A dyadic square of the parameter plane.
struct DyadicCell {
    int level = 0, i = 0, j = 0;
    double size() const;
    Rect rect() const;
    /// True when the cell lies inside the domain [0,1]^2.
    bool in_domain() const;
    /// The patch of Figure 5 holding the cell: -1 for the domain, else 0..7 counter-clockwise
    /// from the patch below-left of the domain (0: s<0,t<0; 1: below; 2: s>1,t<0; 3: right;
    /// 4: s>1,t>1; 5: above; 6: s<0,t>1; 7: left).
    int patch() const;
    /// The child (di, dj) in {0,1}^2, one level finer.
    DyadicCell child(int di, int dj) const { return {level + 1, 2 * i + di, 2 * j + dj}; }
    DyadicCell parent() const;
};
bool operator==(const DyadicCell& a, const DyadicCell& b);
std::ostream& operator<<(std::ostream& os, const DyadicCell& c);

/// A forest of pointer-free quadtrees (nodes in one array, children contiguous).
class Forest {
public:
    struct Node {
        DyadicCell cell;
        int first_child = -1;  // index of child (0,0); children (1,0), (0,1), (1,1) follow
        int parent = -1;
        int samples = -1;        // index of the leaf's m x m samples, -1 when not computed
        bool resampled = false;  // its samples were resampled from its parent's polynomial (a
                                 //   leaf made by shadow subdivision), not computed by (21)
        bool is_leaf() const { return first_child < 0; }
    };

    /// Roots (I, J) for |I|, |J| <= K; K = 0 is the domain alone.
    explicit Forest(int K);
    Forest() : Forest(0) {}
    int extent() const { return K_; }
    /// Adds roots so that |I|, |J| <= K (existing nodes keep their indices).
    void grow(int K);
    /// The node index of root (I, J), or -1 outside the forest.
    int root(int I, int J) const;
    int domain_root() const { return root(0, 0); }
    const Node& node(int index) const { return nodes_[index]; }
    Node& node(int index) { return nodes_[index]; }
    int n_nodes() const { return static_cast<int>(nodes_.size()); }
    /// Splits a leaf into four children; returns the index of child (0,0).
    int split(int index);
    /// Index of the node for `cell` if it exists; otherwise the leaf that contains it (a
    /// coarser cell), or -1 when the cell lies outside the forest.
    int find(const DyadicCell& cell) const;
    /// The leaf containing the point (s, t) (half-open cells, the upper edge of the forest
    /// belongs to the last cell); -1 outside.
    int leaf_at(double s, double t) const;
    /// All leaves, optionally only those of the domain (in_domain) or only expanded ones.
    enum class Region { All, Domain, Expanded };
    std::vector<int> leaves(Region region = Region::All) const;
    /// Child c (0..3, order (0,0), (1,0), (0,1), (1,1)) of a split node.
    int child(int index, int c) const { return nodes_[index].first_child + c; }

private:
    int K_ = 0;
    std::vector<Node> nodes_;
    std::vector<int> roots_;  // node index of root (I, J) at (J + K) (2K + 1) + (I + K)
};

}  // namespace mbr
