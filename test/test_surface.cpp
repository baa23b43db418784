// test/test_surface.cpp - the parametric surfaces of radiosity/geometry/surface.h (paper section 2,
// eq. (4)): the area factor integrates to each kind's closed-form area, tangents agree with
// finite differences of x(u,v), normals are unit and equal to x_u x x_v normalised, and
// tessellation facets are planar, lie on (or, for curved kinds, near) the surface and cover it.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "math/gauss_legendre.h"
#include "radiosity/geometry/surface.h"

using namespace mbr;

namespace {

double deg(double d) {
    return d * Pi / 180;
}

/// A surface with its closed-form area and a label for messages.
struct Case {
    std::string name;
    Surface surface;
    double area;
};

/// Every kind, with closed-form areas (planar quads by the shoelace formula; the bilinear
/// patch z = xy over the unit square has area sqrt(3)/3 + (2/3) ln(2 + sqrt(3)) - pi/18).
std::vector<Case> cases() {
    const double r = 0.7, h = 1.3;
    return {
        {"unit square", Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}), 1.0},
        // Trapezoid with parallel sides 3 and 1, height 2, tilted out of the axis planes.
        {"trapezoid",
         Surface::planar_quad({0, 0, 0}, {3, 0, 0}, {2, 2 * 0.6, 2 * 0.8}, {1, 2 * 0.6, 2 * 0.8}),
         4.0},
        {"bilinear z = xy", Surface::bilinear_patch({0, 0, 0}, {1, 0, 0}, {1, 1, 1}, {0, 1, 0}),
         std::sqrt(3.0) / 3 + 2.0 / 3 * std::log(2 + std::sqrt(3.0)) - Pi / 18},
        {"cylinder patch",
         Surface::cylinder({0.1, 0.2, 0.3}, {0, 0, 2}, {1, 0, 0}, r, h, deg(30), deg(200)),
         r * h * deg(170)},
        {"cylinder inward",
         Surface::cylinder({0, 0, 0}, {1, 1, 0}, {0, 0, 1}, r, h, 0, 2 * Pi, true), r * h * 2 * Pi},
        {"cylinder reversed phi",
         Surface::cylinder({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, r, h, deg(90), deg(-45)),
         r * h * deg(135)},
        {"sphere patch",
         Surface::sphere({1, 2, 3}, {0, 0, 1}, {1, 0, 0}, r, deg(20), deg(150), deg(-40), deg(100)),
         r * r * deg(140) * (std::cos(deg(20)) - std::cos(deg(150)))},
        {"whole sphere", Surface::sphere({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, r, 0, Pi, 0, 2 * Pi),
         4 * Pi * r * r},
        {"sphere inward",
         Surface::sphere({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, r, deg(10), deg(80), 0, deg(90), true),
         r * r * deg(90) * (std::cos(deg(10)) - std::cos(deg(80)))},
        {"disk", Surface::disk({0, 0, 1}, {0, 0, 1}, {1, 0, 0}, 0, r, 0, 2 * Pi), Pi * r * r},
        {"annulus sector",
         Surface::disk({0, 0, 0}, {1, 2, 3}, {1, 0, 0}, 0.3, 1.1, deg(10), deg(250)),
         0.5 * deg(240) * (1.1 * 1.1 - 0.3 * 0.3)},
    };
}

/// Integral of A(u,v) over [0,1]^2: 8-point Gauss-Legendre on 16 x 16 cells (A is smooth on
/// each surface, so this is accurate to rounding).
double integrate_area_factor(const Surface& s) {
    GaussLegendre rule = gauss_legendre(8);
    const int cells = 16;
    double sum = 0;
    for (int i = 0; i < cells; ++i)
        for (int j = 0; j < cells; ++j) {
            Rect r{double(i) / cells, double(i + 1) / cells, double(j) / cells,
                   double(j + 1) / cells};
            sum += integrate_2d([&](double u, double v) { return s.area_factor(u, v); }, r, rule);
        }
    return sum;
}

/// Area of a planar polygon by Newell's formula.
double polygon_area(const std::vector<Vec3>& p) {
    Vec3 n;
    for (size_t i = 0; i < p.size(); ++i) n += cross(p[i], p[(i + 1) % p.size()]);
    return 0.5 * length(n);
}

}  // namespace

TEST_CASE("surface: integral of the area factor equals the closed-form area", "[surface]") {
    for (const Case& c : cases()) {
        CAPTURE(c.name);
        // Quadrature error is at rounding level; 1e-12 relative leaves room for the sums.
        CHECK(integrate_area_factor(c.surface) == Approx(c.area).epsilon(1e-12));
        // Surface::area() uses closed forms (quadrature for the bilinear patch).
        CHECK(c.surface.area() == Approx(c.area).epsilon(1e-12));
    }
}

TEST_CASE("surface: tangents agree with finite differences of x(u,v)", "[surface]") {
    const double h = 1e-6;
    for (const Case& c : cases())
        for (double u : {0.1, 0.37, 0.5, 0.92})
            for (double v : {0.05, 0.44, 0.71, 0.9}) {
                CAPTURE(c.name, u, v);
                Vec3 x_u, x_v;
                c.surface.tangents(u, v, x_u, x_v);
                Vec3 d_u = (c.surface.point(u + h, v) - c.surface.point(u - h, v)) / (2 * h);
                Vec3 d_v = (c.surface.point(u, v + h) - c.surface.point(u, v - h)) / (2 * h);
                // Central differences: O(h^2) truncation plus O(eps / h) rounding, about 1e-9.
                double scale = 1 + length(x_u) + length(x_v);
                CHECK(length(x_u - d_u) < 1e-7 * scale);
                CHECK(length(x_v - d_v) < 1e-7 * scale);
            }
}

TEST_CASE("surface: normals are unit and equal to x_u x x_v normalised", "[surface]") {
    for (const Case& c : cases())
        for (double u : {0.0, 0.2, 0.5, 0.8, 1.0})
            for (double v : {0.0, 0.3, 0.6, 1.0}) {
                CAPTURE(c.name, u, v);
                Vec3 n = c.surface.normal(u, v);
                CHECK(length(n) == Approx(1).margin(1e-12));
                Vec3 x_u, x_v;
                c.surface.tangents(u, v, x_u, x_v);
                Vec3 m = cross(x_u, x_v);
                double a = c.surface.area_factor(u, v);
                CHECK(a == Approx(length(m)).margin(1e-14));
                if (a > 1e-9) CHECK(length(n - m / a) < 1e-9);  // poles and centres have A = 0
                SurfacePoint sp = c.surface.evaluate(u, v);
                CHECK(length(sp.normal - n) < 1e-12);
                CHECK(length(sp.position - c.surface.point(u, v)) < 1e-12);
                CHECK(sp.area_factor == Approx(a).margin(1e-14));
            }
}

TEST_CASE("surface: curved kinds face outward unless inward, disks face their normal",
          "[surface]") {
    Vec3 o{0, 0, 0};
    Surface cyl_out = Surface::cylinder(o, {0, 0, 1}, {1, 0, 0}, 1, 1, 0, 2 * Pi);
    Surface cyl_in = Surface::cylinder(o, {0, 0, 1}, {1, 0, 0}, 1, 1, 0, 2 * Pi, true);
    Surface sph_out = Surface::sphere(o, {0, 0, 1}, {1, 0, 0}, 1, 0, Pi, 0, 2 * Pi);
    Surface sph_in = Surface::sphere(o, {0, 0, 1}, {1, 0, 0}, 1, 0, Pi, 0, 2 * Pi, true);
    Surface disk = Surface::disk(o, {0, 1, 0}, {1, 0, 0}, 0, 1, 0, 2 * Pi);
    for (double u : {0.1, 0.5, 0.9})
        for (double v : {0.0, 0.5, 1.0}) {
            CAPTURE(u, v);
            Vec3 p = cyl_out.point(u, v);
            Vec3 radial = normalize(Vec3{p.x, p.y, 0});
            CHECK(dot(cyl_out.normal(u, v), radial) == Approx(1));
            p = cyl_in.point(u, v);
            radial = normalize(Vec3{p.x, p.y, 0});
            CHECK(dot(cyl_in.normal(u, v), radial) == Approx(-1));
            CHECK(dot(sph_out.normal(u, v), normalize(sph_out.point(u, v))) == Approx(1));
            CHECK(dot(sph_in.normal(u, v), normalize(sph_in.point(u, v))) == Approx(-1));
            CHECK(length(disk.normal(u, v) - Vec3{0, 1, 0}) < 1e-15);
        }
    // A planar quad faces (p10 - p00) x (p01 - p00).
    Surface q = Surface::planar_quad({0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0});
    CHECK(length(q.normal(0.3, 0.6) - Vec3{0, 0, -1}) < 1e-15);
}

TEST_CASE("surface: tessellation facets are planar, lie on the surface and cover it", "[surface]") {
    for (const Case& c : cases()) {
        double error[2] = {0, 0};
        int ni = 0;
        for (int n : {1, 4, 16}) {
            CAPTURE(c.name, n);
            std::vector<Facet> facets = c.surface.tessellate(n);
            REQUIRE(!facets.empty());
            double sum = 0;
            for (const Facet& f : facets) {
                REQUIRE(f.vertices.size() == f.uv.size());
                REQUIRE(f.vertices.size() >= 3);
                REQUIRE(f.vertices.size() <= 4);
                // Corners are surface points at their (u,v).
                for (size_t k = 0; k < f.vertices.size(); ++k)
                    CHECK(length(f.vertices[k] - c.surface.point(f.uv[k].x, f.uv[k].y)) < 1e-12);
                // Planar: the fourth corner lies in the plane of the first three.
                Vec3 nf =
                    normalize(cross(f.vertices[1] - f.vertices[0], f.vertices[2] - f.vertices[0]));
                double size = length(f.vertices[2] - f.vertices[0]);
                if (f.vertices.size() == 4)
                    CHECK(std::fabs(dot(f.vertices[3] - f.vertices[0], nf)) < 1e-12 * (1 + size));
                // Counter-clockwise seen from the front: the facet faces like the surface.
                Vec2 uv_c;
                for (const Vec2& q : f.uv) uv_c = uv_c + (1.0 / f.uv.size()) * q;
                CHECK(dot(nf, c.surface.normal(uv_c.x, uv_c.y)) > 0.5);
                sum += polygon_area(f.vertices);
            }
            if (c.surface.kind() == Surface::Kind::PlanarQuad) {
                CHECK(sum == Approx(c.area).epsilon(1e-12));  // one exact facet
            } else if (n > 1) {
                // Chords cut corners: a facet spanning angle a keeps sin(a)/a of the arc's share,
                // so the relative shortfall is about a^2 / 6: 2.6% for a whole turn in 16.
                // (Triangles across the bilinear saddle may exceed its area; arcs' chords never.)
                if (c.surface.kind() != Surface::Kind::BilinearPatch)
                    CHECK(sum <= c.area * (1 + 1e-12));
                if (n == 16) CHECK(sum >= c.area * (1 - 0.03));
                error[ni++] = std::fabs(sum - c.area);
            }
        }
        // Second-order convergence: from 4 to 16 facets the error falls by about 16.
        CAPTURE(c.name, error[0], error[1]);
        if (error[0] > 1e-12 * c.area) CHECK(error[1] < error[0] / 8);
    }
}

TEST_CASE("surface: curved facets stay within the chord height of the surface", "[surface]") {
    const double r = 0.7;
    Surface sph = Surface::sphere({1, 2, 3}, {0, 0, 1}, {1, 0, 0}, r, 0, Pi, 0, 2 * Pi);
    Surface cyl = Surface::cylinder({1, 2, 3}, {0, 0, 1}, {1, 0, 0}, r, 1.0, 0, 2 * Pi);
    for (int n : {4, 16}) {
        CAPTURE(n);
        // The centroid of a facet is inside the surface by at most the sagitta of its arcs.
        double sagitta = r * (1 - std::cos(Pi / n)) + r * (1 - std::cos(Pi / (2 * n)));
        for (const Facet& f : sph.tessellate(n)) {
            Vec3 c;
            for (const Vec3& p : f.vertices) c += p / double(f.vertices.size());
            double d = r - length(c - Vec3{1, 2, 3});
            CHECK(d >= -1e-12);
            CHECK(d <= sagitta);
        }
        double chord = r * (1 - std::cos(Pi / n));
        for (const Facet& f : cyl.tessellate(n)) {
            Vec3 c;
            for (const Vec3& p : f.vertices) c += p / double(f.vertices.size());
            double d = r - std::hypot(c.x - 1, c.y - 2);
            CHECK(d >= -1e-12);
            CHECK(d <= chord + 1e-12);
        }
    }
}

TEST_CASE("surface: bounds contain the surface", "[surface]") {
    for (const Case& c : cases()) {
        CAPTURE(c.name);
        Box3 b = c.surface.bounds();
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; j <= 20; ++j) {
                Vec3 p = c.surface.point(i / 20.0, j / 20.0);
                for (int k = 0; k < 3; ++k) {
                    CHECK(p[k] >= b.lo[k] - 1e-12);
                    CHECK(p[k] <= b.hi[k] + 1e-12);
                }
            }
    }
}
