// radiosity/transfer/form_factor.cpp - the kernel of eq. (3) on arrays of points (vectorised) and
// the analytic point-to-polygon form factor (paper section 7, the exact reference of "an
// analytic formula advocated in [7]").
#include "radiosity/transfer/form_factor.h"

#include <algorithm>
#include <cmath>

#include "math/simd.h"
#include "octree/polygon.h"

namespace mbr {

MBR_VECTOR_CLONES
void form_factor_kernels(Vec3 p, Vec3 n_p, const ShootingNodes& nodes, int count,
                         double* __restrict F) {
    const double* __restrict x = nodes.x;
    const double* __restrict y = nodes.y;
    const double* __restrict z = nodes.z;
    const double* __restrict nx = nodes.nx;
    const double* __restrict ny = nodes.ny;
    const double* __restrict nz = nodes.nz;
    for (int i = 0; i < count; ++i) {
        // form_factor_kernel's operations in its order; where a cosine is not positive both
        // give +0 (0 times the other clamped cosine over a positive denominator). A zero
        // denominator (p on the node, or within 1e-80 of it, where |l|^4 underflows) is
        // replaced by 1: the value is then 0 where form_factor_kernel gives 0 or infinity.
        const double lx = x[i] - p.x, ly = y[i] - p.y, lz = z[i] - p.z;
        const double cos_p = lx * n_p.x + ly * n_p.y + lz * n_p.z;
        const double cos_x = -(lx * nx[i] + ly * ny[i] + lz * nz[i]);
        const double l2 = lx * lx + ly * ly + lz * lz;
        const double a = cos_p > 0 ? cos_p : 0.0;
        const double b = cos_x > 0 ? cos_x : 0.0;
        double den = Pi * l2 * l2;
        den = den > 0 ? den : 1.0;  // a select, not a branch: the loop stays vectorisable
        F[i] = a * b / den;
    }
}

double point_polygon_form_factor(Vec3 p, Vec3 n_p, const std::vector<Vec3>& polygon) {
    if (polygon.size() < 3) return 0;
    // One-sided: the polygon's front (Newell normal of its counter-clockwise order) must face p.
    // The normal is summed from vectors relative to the first vertex: from absolute positions
    // each cross(a, b) is of order |a| |b| and they cancel down to twice the area, which loses
    // every digit for a polygon far smaller than its distance from the origin.
    Vec3 normal{};
    for (size_t i = 1; i + 1 < polygon.size(); ++i)
        normal += cross(polygon[i] - polygon[0], polygon[i + 1] - polygon[0]);
    Vec3 centroid{};
    for (const Vec3& v : polygon) centroid += v - polygon[0];
    centroid = polygon[0] + centroid / double(polygon.size());
    if (dot(p - centroid, normal) <= 0) return 0;

    // Clip against p's tangent plane: keep the part with (v - p) . n_p >= 0.
    std::vector<Vec3> clipped;
    clipped.reserve(polygon.size() + 2);
    const auto in_front = [&](Vec3 v) { return dot(v - p, n_p); };
    clip_polygon(polygon, in_front, clipped);
    if (clipped.size() < 3) return 0;

    // Lambert: F = (1 / 2 pi) sum_i gamma_i n_p . (R_i x R_{i+1}) / |R_i x R_{i+1}|.
    // R_i x R_{i+1} is taken as R_i x E_i with the edge E_i = v_{i+1} - v_i from the vertices
    // themselves: for a polygon of size s at distance r, R_i and R_{i+1} are nearly parallel,
    // and their cross product (of size s r) carries an absolute rounding error of order
    // eps r^2, so its direction is off by eps r / s; the terms (of order s / r) cancel down to
    // F (of order s^2 / r^2), and F came out with a relative error of eps r^2 / s^2 (all of it
    // at s = 1e-8 r). With E_i the cross product is accurate to eps of its size, and
    // F to about eps r / s.
    double sum = 0;
    for (size_t i = 0; i < clipped.size(); ++i) {
        const Vec3& v_next = clipped[(i + 1) % clipped.size()];
        const Vec3 r_i = clipped[i] - p;
        const Vec3 c = cross(r_i, v_next - clipped[i]);
        const double c_len = length(c);
        if (c_len <= 0) continue;  // collinear with p: the edge contributes nothing
        const double gamma = std::atan2(c_len, dot(r_i, v_next - p));  // angle between R_i, R_i+1
        sum += gamma * dot(n_p, c) / c_len;
    }
    return std::fabs(sum) / (2 * Pi);
}

}  // namespace mbr
