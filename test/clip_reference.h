// test/clip_reference.h - the exact reference of "does a polygon meet a box", shared by the
// octree's node-polygon tests (test_octree.cpp) and the occluder lists (test_occlusion.cpp).
#pragma once

#include <vector>

#include "math/vec3.h"

namespace mbr {

/// Whether the polygon meets the closed box: Sutherland-Hodgman clipping of the polygon by the
/// box's six closed half-spaces; it meets the box iff something is left. Clipping by an axis
/// plane sets that coordinate of a new vertex exactly to the bound, so the only rounding is in
/// the other two coordinates of interpolated vertices (O(1e-16) relative).
inline bool polygon_meets_box(const std::vector<Vec3>& polygon, const Box3& box) {
    std::vector<Vec3> poly = polygon, out;
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const double bound = side == 0 ? box.lo[axis] : box.hi[axis];
            auto in = [&](Vec3 p) { return side == 0 ? p[axis] >= bound : p[axis] <= bound; };
            out.clear();
            const int n = static_cast<int>(poly.size());
            for (int i = 0; i < n; ++i) {
                const Vec3 p = poly[i], q = poly[(i + 1) % n];
                if (in(p)) out.push_back(p);
                if (in(p) != in(q)) {
                    Vec3 x = p + ((bound - p[axis]) / (q[axis] - p[axis])) * (q - p);
                    x[axis] = bound;
                    out.push_back(x);
                }
            }
            poly.swap(out);
            if (poly.empty()) return false;
        }
    return true;
}

}  // namespace mbr
