// radiosity/reference/configurations.cpp - the paper's test configurations and the error metric
// (29).
#include "radiosity/reference/configurations.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"
#include "math/convex2d.h"
#include "math/parallel.h"
#include "radiosity/transfer/form_factor.h"

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
    parallel_for(n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            const SurfacePoint p = setup.receiver.evaluate((i + 0.5) / n, (j + 0.5) / n);
            out[size_t(j) * n + i] =
                scale * point_polygon_form_factor(p.position, p.normal, polygon);
        }
    });
    return out;
}

ShadowSetup occluded_squares(double tilt_degrees, double shooter_side) {
    MBR_CHECK(shooter_side > 0 && shooter_side <= 1);
    ShadowSetup setup;
    const double a = 0.5 - 0.5 * shooter_side, b = 0.5 + 0.5 * shooter_side;
    setup.shooter = Surface::planar_quad({a, a, 1}, {a, b, 1}, {b, b, 1}, {b, a, 1});
    setup.receiver = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    const double angle = tilt_degrees * Pi / 180, c = std::cos(angle), s = std::sin(angle);
    std::vector<Vec3> occluder;
    for (Vec2 q : {Vec2{-0.2, -0.2}, Vec2{0.2, -0.2}, Vec2{0.2, 0.2}, Vec2{-0.2, 0.2}})
        occluder.push_back({0.5 + q.x, 0.5 + c * q.y, 0.5 + s * q.y});  // rotation about x
    setup.occluders.push_back(occluder);
    return setup;
}

double shadowed_form_factor(Vec3 p, Vec3 n_p, const std::vector<Vec3>& shooter,
                            const std::vector<Vec3>& occluder) {
    MBR_CHECK(shooter.size() >= 3 && occluder.size() >= 3);
    const double full = point_polygon_form_factor(p, n_p, shooter);
    // The shooter's plane, oriented so that p is in front.
    // Newell's normal from vectors relative to the first vertex: over absolute positions its
    // terms cancel down to the area and lose every digit for a tiny shooter far from the origin.
    Vec3 normal{};
    for (size_t i = 1; i + 1 < shooter.size(); ++i)
        normal += cross(shooter[i] - shooter[0], shooter[i + 1] - shooter[0]);
    normal = normalize(normal);
    const double h_p = dot(normal, p - shooter[0]);
    if (h_p == 0) return full;
    const Vec3 e1 = normalize(shooter[1] - shooter[0]);
    const Vec3 e2 = cross(normal, e1);
    auto to_plane = [&](Vec3 x) { return Vec2{dot(x - shooter[0], e1), dot(x - shooter[0], e2)}; };
    // Central projection from p of each occluder vertex onto the plane: x -> p + t (x - p),
    // t = h_p / (h_p - h(x)), with h(x) the height above the plane (strictly between 0 and h_p).
    ConvexPolygon shadow;
    for (const Vec3& x : occluder) {
        const double h = dot(normal, x - shooter[0]);
        MBR_CHECK_MSG(h / h_p > 0 && h / h_p < 1, "occluder vertex " << x << " is not between");
        shadow.push_back(to_plane(p + (h_p / (h_p - h)) * (x - p)));
    }
    if (signed_area(shadow) < 0) std::reverse(shadow.begin(), shadow.end());
    ConvexPolygon outline;
    for (const Vec3& x : shooter) outline.push_back(to_plane(x));
    const bool reversed = signed_area(outline) < 0;
    if (reversed) std::reverse(outline.begin(), outline.end());
    ConvexPolygon hidden = intersect(outline, shadow);
    if (hidden.empty()) return full;
    // Back to space, in the shooter's own orientation (the contour formula is one-sided).
    if (reversed) std::reverse(hidden.begin(), hidden.end());
    std::vector<Vec3> hidden3;
    for (Vec2 q : hidden) hidden3.push_back(shooter[0] + q.x * e1 + q.y * e2);
    return full - point_polygon_form_factor(p, n_p, hidden3);
}

std::vector<double> exact_shadowed_grid(const ShadowSetup& setup, int n) {
    MBR_CHECK(setup.shooter.kind() == Surface::Kind::PlanarQuad);
    const Vec3* c = setup.shooter.corners();
    const std::vector<Vec3> shooter{c[0], c[1], c[2], c[3]};
    std::vector<double> out(size_t(n) * n);
    parallel_for(n, [&](int j) {
        for (int i = 0; i < n; ++i) {
            const SurfacePoint p = setup.receiver.evaluate((i + 0.5) / n, (j + 0.5) / n);
            double f = point_polygon_form_factor(p.position, p.normal, shooter);
            for (const std::vector<Vec3>& o : setup.occluders)
                f -= point_polygon_form_factor(p.position, p.normal, shooter) -
                     shadowed_form_factor(p.position, p.normal, shooter, o);
            out[size_t(j) * n + i] = f;
        }
    });
    return out;
}

std::vector<double> field_grid(const SplineField& field, int n) {
    std::vector<double> out(size_t(n) * n);
    parallel_for(n, [&](int j) {
        for (int i = 0; i < n; ++i)
            out[size_t(j) * n + i] = field.evaluate((i + 0.5) / n, (j + 0.5) / n).r;
    });
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
