// radiosity/transfer/form_factor.h - the kernel of the radiosity equation (paper section 2,
// eqs. (2)-(4)) and the analytic point-to-polygon form factor used as the exact reference
// (section 7: "an analytic formula advocated in [7]", Baum, Rushmeier and Winget 1989).
#pragma once

#include <vector>

#include "math/vec3.h"

namespace mbr {

/// F(p, x) of eq. (3) for a receiving point p (normal n_p) and a shooting point x (normal n_x):
/// [l . n_p][-l . n_x] / (pi |l|^4) with l = x - p, each cosine clamped at zero, so that a point
/// behind either surface receives nothing (surfaces are one-sided).
inline double form_factor_kernel(Vec3 p, Vec3 n_p, Vec3 x, Vec3 n_x) {
    const Vec3 l = x - p;
    const double cos_p = dot(l, n_p);   // |l| cos(theta_p)
    const double cos_x = -dot(l, n_x);  // |l| cos(theta_x)
    if (cos_p <= 0 || cos_x <= 0) return 0;
    const double l2 = dot(l, l);
    return cos_p * cos_x / (Pi * l2 * l2);
}

/// Shooting points given component by component (structure of arrays): the i-th point is
/// (x[i], y[i], z[i]) with unit normal (nx[i], ny[i], nz[i]).
struct ShootingNodes {
    const double *x, *y, *z, *nx, *ny, *nz;
};

/// The six arrays of `count` nodes stored one after the other in `block` (x first, then y, z,
/// nx, ny, nz), from node `start` on.
inline ShootingNodes shooting_nodes(const double* block, int count, int start = 0) {
    return {block + start,
            block + count + start,
            block + 2 * count + start,
            block + 3 * count + start,
            block + 4 * count + start,
            block + 5 * count + start};
}

/// Appends the positions and normals of `count` points to `block` in shooting_nodes' layout.
template <class Point>
void append_shooting_nodes(std::vector<double>& block, const Point* first, int count) {
    const size_t base = block.size();
    block.resize(base + 6 * size_t(count));
    double* out = block.data() + base;
    for (int i = 0; i < count; ++i) {
        out[i] = first[i].x.x;
        out[count + i] = first[i].x.y;
        out[2 * count + i] = first[i].x.z;
        out[3 * count + i] = first[i].n.x;
        out[4 * count + i] = first[i].n.y;
        out[5 * count + i] = first[i].n.z;
    }
}

/// Eq. (3) at `count` shooting points: F[i] = form_factor_kernel(p, n_p, x_i, n_i), the same
/// values to the bit (the same operations in the same order, no fused multiply-add), written so
/// that the compiler evaluates several points in one vector instruction.
/// DESIGN: the "vectorised kernel where the tensor loop is hot": the points are stored
/// as arrays (ShootingNodes), the clamps are selects instead of branches, and on x86-64 the
/// function is compiled twice, for AVX2 and for the baseline (function multi-versioning,
/// chosen once at load time), so the default build runs on any x86-64 processor and gives the
/// same bits on both (docs/method.md, "A vectorised kernel").
void form_factor_kernels(Vec3 p, Vec3 n_p, const ShootingNodes& nodes, int count, double* F);

/// The form factor from a differential area at p (unit normal n_p) to a planar polygon, by
/// Lambert's contour integral: F = |sum_i angle(R_i, R_{i+1}) n_p . unit(R_i x R_{i+1})| / (2 pi)
/// with R_i = v_i - p. The polygon is one-sided like the surfaces: its front (counter-clockwise
/// side) must face p, else F = 0. Parts behind p's tangent plane are clipped away first.
/// Relative rounding error about eps r / s for a polygon of size s at distance r (the edge
/// terms of order s / r cancel down to F), so a polygon 1e-9 of its distance keeps 7 digits.
double point_polygon_form_factor(Vec3 p, Vec3 n_p, const std::vector<Vec3>& polygon);

}  // namespace mbr
