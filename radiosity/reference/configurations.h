// radiosity/reference/configurations.h - what checks one transfer (paper section 7, DESIGN.md
// section 6): the paper's test configurations (unit squares, parallel at distance h or
// perpendicular with a shared edge) and the relative error metric rea of eq. (29) on a grid of
// receiver points, against the analytic point-to-polygon form factor.
#pragma once

#include <vector>

#include "math/vec3.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/geometry/surface.h"

namespace mbr {

/// A shooter and a receiver, both planar quads; the shooter's corners double as the polygon
/// of the analytic reference.
struct TransferSetup {
    Surface shooter;
    Surface receiver;
    std::vector<Vec3> shooter_polygon() const;
};

/// Table 1: unit squares facing each other at distance h; the receiver is [0,1]^2 in z = 0.
TransferSetup parallel_squares(double h);
/// Table 2: unit squares at a right angle sharing the edge y = z = 0 (the receiver in z = 0,
/// the shooter in y = 0).
TransferSetup perpendicular_squares();

/// The errors of eq. (29) on an n x n grid of cell centres of the receiver's (s,t) domain.
struct ErrorStats {
    double rea = 0;         // mean of |B_spline - B_exact| / B_exact, eq. (29)
    double max_rel = 0;     // largest relative error on the grid
    double mean_exact = 0;  // grid mean of B_exact (the area form factor, times B rho)
    int n_points = 0;       // grid points with B_exact > 0 (the others are skipped)
};

/// Compares the red channel of `field` with B_exact = rho * B_h * F(p -> shooter polygon);
/// the grid is evaluated in parallel.
ErrorStats compare_with_exact(const SplineField& field, const TransferSetup& setup,
                              double shooter_radiosity = 1, double reflectance = 1, int n = 256);

/// A shadowed transfer (issue "Shadows", example shadow_transfer): a shooter and a receiver,
/// both planar quads with parallel planes, and convex planar occluders strictly between them.
struct ShadowSetup {
    Surface shooter;
    Surface receiver;
    std::vector<std::vector<Vec3>> occluders;  // convex polygons
};
/// Parallel unit squares at h = 1 (the receiver [0,1]^2 in z = 0) with an opaque square of side
/// 0.4 centred at (0.5, 0.5, 0.5): parallel to both (tilt 0) or rotated by `tilt_degrees` about
/// the x axis through its centre. `shooter_side` < 1 shrinks the shooter about its centre (an
/// umbra appears below the occluder once the shooter is small enough).
ShadowSetup occluded_squares(double tilt_degrees, double shooter_side = 1);

/// The exact form factor from p (normal n_p) to a planar convex shooter polygon seen past one
/// convex occluder lying strictly between p and the shooter's plane: F(shooter) minus
/// F(shooter clipped to the occluder's central projection from p onto the shooter's plane), each
/// by the analytic contour formula (machine precision).
double shadowed_form_factor(Vec3 p, Vec3 n_p, const std::vector<Vec3>& shooter,
                            const std::vector<Vec3>& occluder);

/// The exact shadowed values (shooter radiosity 1, reflectance 1) on the n x n grid of cell
/// centres of the receiver, row-major with s fastest. Occluders must not overlap as seen from
/// any grid point (one at a time is subtracted).
std::vector<double> exact_shadowed_grid(const ShadowSetup& setup, int n);

/// The exact values on the same grid, row-major with s fastest (for pictures).
std::vector<double> exact_grid(const TransferSetup& setup, int n, double scale = 1);
/// The field's red channel on the grid.
std::vector<double> field_grid(const SplineField& field, int n);

}  // namespace mbr
