// radiosity/reference.cpp - the paper's test configurations and the error metric (29).
#include "radiosity/reference.h"

#include <cmath>

#include "math/check.h"
#include "radiosity/kernel.h"

namespace mbr {

std::vector<Vec3> TransferSetup::shooter_polygon() const {
    MBR_CHECK(shooter.kind() == Surface::Kind::PlanarQuad);
    const Vec3* c = shooter.corners();
    return {c[0], c[1], c[2], c[3]};
}

TransferSetup parallel_squares(double h) {
    MBR_CHECK(h > 0);
    // The shooter's front (x_u x x_v) faces -z, towards the receiver; the receiver faces +z.
    return {Surface::planar_quad({0, 0, h}, {0, 1, h}, {1, 1, h}, {1, 0, h}),
            Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0})};
}

TransferSetup perpendicular_squares() {
    // The shooter stands on the receiver's edge t = 0 and faces +y, over the receiver.
    return {Surface::planar_quad({0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}),
            Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0})};
}

std::vector<double> exact_grid(const TransferSetup& setup, int n, double scale) {
    const std::vector<Vec3> polygon = setup.shooter_polygon();
    std::vector<double> out(size_t(n) * n);
#pragma omp parallel for schedule(static)
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const SurfacePoint p = setup.receiver.evaluate((i + 0.5) / n, (j + 0.5) / n);
            out[size_t(j) * n + i] = scale * point_polygon_form_factor(p.position, p.normal, polygon);
        }
    return out;
}

std::vector<double> field_grid(const SplineField& field, int n) {
    std::vector<double> out(size_t(n) * n);
#pragma omp parallel for schedule(static)
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) out[size_t(j) * n + i] = field.evaluate((i + 0.5) / n, (j + 0.5) / n).r;
    return out;
}

ErrorStats compare_with_exact(const SplineField& field, const TransferSetup& setup,
                              double shooter_radiosity, double reflectance, int n) {
    const std::vector<double> exact = exact_grid(setup, n, shooter_radiosity * reflectance);
    const std::vector<double> approx = field_grid(field, n);
    ErrorStats e;
    double sum_rel = 0, sum_exact = 0;
    for (size_t i = 0; i < exact.size(); ++i) {
        sum_exact += exact[i];
        if (!(exact[i] > 0)) continue;
        const double rel = std::fabs(approx[i] - exact[i]) / exact[i];  // eq. (29)
        sum_rel += rel;
        e.max_rel = std::max(e.max_rel, rel);
        ++e.n_points;
    }
    e.rea = e.n_points ? sum_rel / e.n_points : 0;
    e.mean_exact = sum_exact / double(exact.size());
    return e;
}

}  // namespace mbr
