// test/test_probe.cpp - probe points (radiosity/reference/probe.h): world points on every surface
// kind are located at the (u, v) that maps to them, a normal decides between surfaces that meet, a
// point far from every surface is refused by name, each malformed CSV gets an InputError at its
// line, and results are written with the exact headers.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "math/check.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene_octree.h"

using namespace mbr;
using Catch::Matchers::Contains;

namespace {

double deg(double d) {
    return d * Pi / 180;
}

Scene scene_of(const std::vector<Surface>& surfaces) {
    Scene scene;
    scene.materials.push_back({"grey", Texture::constant({0.5, 0.5, 0.5}), Texture()});
    for (size_t i = 0; i < surfaces.size(); ++i)
        scene.surfaces.push_back({"s" + std::to_string(i), surfaces[i], 0});
    return scene;
}

struct Case {
    std::string name;
    Surface surface;
};

// Every kind, curved ones also whole (with a seam) and inward.
std::vector<Case> cases() {
    const double r = 0.7, h = 1.3;
    return {
        // A convex quad that is no parallelogram: the inverse bilinear map is a true quadratic.
        {"general quad",
         Surface::planar_quad({0, 0, 0}, {2, 0, 0.4}, {1.5, 1.2, 0.3}, {0.2, 1, 0.04})},
        // A "planar" quad 1e-3 of its size off planar, like the Cornell box's red wall.
        {"slightly skew quad",
         Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0.002}, {0, 1, 0})},
        {"bilinear z = xy", Surface::bilinear_patch({0, 0, 0}, {1, 0, 0}, {1, 1, 1}, {0, 1, 0})},
        {"cylinder patch",
         Surface::cylinder({0.1, 0.2, 0.3}, {0, 0, 2}, {1, 0, 0}, r, h, deg(30), deg(200))},
        {"whole cylinder inward",
         Surface::cylinder({0, 0, 0}, {1, 1, 0}, {0, 0, 1}, r, h, 0, 2 * Pi, true)},
        {"sphere patch", Surface::sphere({1, 2, 3}, {0, 0, 1}, {1, 0, 0}, r, deg(20), deg(150),
                                         deg(-40), deg(100))},
        {"whole sphere", Surface::sphere({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, r, 0, Pi, 0, 2 * Pi)},
        {"sphere inward",
         Surface::sphere({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, r, deg(10), deg(80), 0, deg(90), true)},
        {"disk", Surface::disk({0, 0, 1}, {0, 0, 1}, {1, 0, 0}, 0, r, 0, 2 * Pi)},
        {"annulus sector",
         Surface::disk({0, 0, 0}, {1, 2, 3}, {1, 0, 0}, 0.3, 1.1, deg(10), deg(250))},
    };
}

// A probe file's text parsed under a fixed name.
const std::string csv_name = "points.csv";

std::vector<ProbePoint> parse(const std::string& text) {
    std::istringstream in(text);
    return parse_probe_points(in, csv_name);
}

InputError error_of(const std::string& text) {
    try {
        parse(text);
    } catch (const InputError& e) {
        return e;
    }
    FAIL("no InputError for:\n" << text);
    return InputError("");
}

void check_error(const std::string& text, int line, const std::string& part) {
    const InputError e = error_of(text);
    CAPTURE(text, e.what());
    CHECK(e.file() == csv_name);
    CHECK(e.line() == line);
    CHECK_THAT(e.message(), Contains(part));
}

}  // namespace

TEST_CASE("probe: points on every surface kind are located at their (u, v)", "[probe]") {
    for (const Case& c : cases()) {
        const Scene scene = scene_of({c.surface});
        const std::vector<Polygon> polygons = scene_polygons(scene, scene.settings.tessellation);
        const double tolerance = probe_tolerance(scene);
        // Interior parameters only: on a seam, at a pole or at a disk's centre (u, v) is not
        // unique. Points off the surface along its normal, by up to 0.9 of the tolerance, have
        // the same nearest point (the normal line through it is a critical line of the distance).
        for (double u : {0.1, 0.37, 0.5, 0.83, 0.9})
            for (double v : {0.1, 0.26, 0.5, 0.71, 0.9})
                for (double offset : {0.0, 0.9, -0.9}) {
                    const SurfacePoint sp = c.surface.evaluate(u, v);
                    const Vec3 p = sp.position + offset * tolerance * sp.normal;
                    CAPTURE(c.name, u, v, offset, p);
                    const std::optional<SurfaceLocation> loc =
                        locate_on_surface(scene, polygons, p, tolerance);
                    REQUIRE(loc);
                    CHECK(loc->surface == 0);
                    // Gauss-Newton converges quadratically on a point of the surface and fast
                    // near it: 1e-9 leaves room for rounding of the angles only.
                    CHECK(loc->u == Approx(u).margin(1e-9));
                    CHECK(loc->v == Approx(v).margin(1e-9));
                    CHECK(length(loc->position - sp.position) < 1e-9);
                    CHECK(loc->distance == Approx(std::fabs(offset) * tolerance).margin(1e-9));
                }
    }
}

TEST_CASE("probe: a point beside a quad's edge is located at the nearest edge point", "[probe]") {
    // A quad whose edge v = 0 runs from (0,0,0) to (2,0,0.4); a point just beyond it, inside the
    // tolerance, belongs at the foot of its perpendicular on that edge (the exact nearest point of
    // the closed quad, as the corners' angles there are below 90 degrees).
    const Surface quad =
        Surface::planar_quad({0, 0, 0}, {2, 0, 0.4}, {1.5, 1.2, 0.3}, {0.2, 1, 0.04});
    const Scene scene = scene_of({quad});
    const double tolerance = probe_tolerance(scene);
    const Vec3 a{0, 0, 0}, b{2, 0, 0.4};
    const Vec3 n = quad.normal(0.5, 0.5);
    const Vec3 out = normalize(cross(b - a, n));  // in the plane, away from the quad
    REQUIRE(dot(out, Vec3{0, -1, 0}) > 0);
    for (double s : {0.2, 0.5, 0.8}) {
        const Vec3 foot = a + s * (b - a);
        const Vec3 p = foot + 0.5 * tolerance * out + 0.3 * tolerance * n;
        CAPTURE(s, p);
        const auto loc = locate_on_surface(scene, {}, p, tolerance);
        REQUIRE(loc);
        CHECK(loc->v == 0);
        CHECK(loc->u == Approx(s).margin(1e-9));  // the edge v = 0 is x(u, 0) = a + u (b - a)
        CHECK(loc->distance == Approx(std::hypot(0.5, 0.3) * tolerance).epsilon(1e-9));
    }
}

TEST_CASE("probe: a given normal chooses between surfaces that meet at the point", "[probe]") {
    // A floor (y = 0, facing up), a wall (x = 0, facing +x) sharing its edge x = y = 0, a
    // ceiling (y = 1, facing down) and a small light 1e-3 below it, also facing down.
    const Scene scene = scene_of({
        Surface::planar_quad({0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}),  // floor
        Surface::planar_quad({0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}),  // wall
        Surface::planar_quad({0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}),  // ceiling
        Surface::planar_quad({0.4, 0.999, 0.4}, {0.6, 0.999, 0.4}, {0.6, 0.999, 0.6},
                             {0.4, 0.999, 0.6}),  // light
    });
    REQUIRE(scene.surfaces[0].surface.normal(0.5, 0.5).y == Approx(1));
    REQUIRE(scene.surfaces[1].surface.normal(0.5, 0.5).x == Approx(1));
    REQUIRE(scene.surfaces[2].surface.normal(0.5, 0.5).y == Approx(-1));
    REQUIRE(scene.surfaces[3].surface.normal(0.5, 0.5).y == Approx(-1));
    const double tolerance = 0.01;  // wider than the light's gap to the ceiling
    const Vec3 edge{0, 0, 0.5};
    auto surface_for = [&](Vec3 p, Vec3 n) {
        const auto loc = locate_on_surface(scene, {}, p, tolerance, n);
        return loc ? loc->surface : -1;
    };
    CHECK(surface_for(edge, {0, 1, 0}) == 0);
    CHECK(surface_for(edge, {1, 0, 0}) == 1);
    CHECK(surface_for(edge, {1, 3, 0}) == 0);                 // closer to the floor's normal
    CHECK(surface_for(edge, {3, 1, 0}) == 1);                 // closer to the wall's
    CHECK(surface_for(edge, {-1, 0, 0}) == -1);               // both face away from it
    CHECK(surface_for({0.5, 1, 0.5}, {0, -1, 0}) == 2);       // on the ceiling above the light
    CHECK(surface_for({0.5, 0.999, 0.5}, {0, -1, 0}) == 3);   // on the light
    CHECK(surface_for({0.5, 0.9996, 0.5}, {0, -1, 0}) == 2);  // nearer the ceiling

    // Through the list interface, the refusal names the point, the surface and its facing.
    ProbePoint p{"corner", edge, true, {-1, 0, 0}, 4};
    try {
        locate_probe_points(scene, {}, {p}, csv_name, tolerance);
        FAIL("no InputError");
    } catch (const InputError& e) {
        CAPTURE(e.what());
        CHECK(e.line() == 4);
        CHECK_THAT(e.message(), Contains("'corner'") && Contains("faces"));
    }
}

TEST_CASE("probe: a point far from every surface is refused with its name", "[probe]") {
    const Scene scene =
        scene_of({Surface::sphere({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, 1, 0, Pi, 0, 2 * Pi),
                  Surface::planar_quad({-2, -1, -2}, {-2, -1, 2}, {2, -1, 2}, {2, -1, -2})});
    const std::vector<Polygon> polygons = scene_polygons(scene, scene.settings.tessellation);
    const double tolerance = probe_tolerance(scene);
    // 0.5 above the sphere's top, about 80 tolerances (0.006) from any surface.
    const Vec3 far{0, 1.5, 0};
    CHECK_FALSE(locate_on_surface(scene, polygons, far, tolerance));
    const std::vector<ProbePoint> points = {
        {"top", {0, 1, 0}, false, {}, 2},
        {"above", far, false, {}, 3},
    };
    try {
        locate_probe_points(scene, polygons, points, csv_name, tolerance);
        FAIL("no InputError");
    } catch (const InputError& e) {
        CAPTURE(e.what());
        CHECK(e.file() == csv_name);
        CHECK(e.line() == 3);
        CHECK_THAT(e.message(), Contains("point 'above' (0, 1.5, 0) is not on any surface") &&
                                    Contains("'s0', 0.5 away") && Contains("tolerance"));
    }
    // The point that is on a surface alone passes.
    CHECK(locate_probe_points(scene, polygons, {points[0]}, csv_name, tolerance).size() == 1);
}

TEST_CASE("probe: CSV files with any column order, extra columns, CRLF and a BOM", "[probe]") {
    const std::vector<ProbePoint> points = parse(
        "\xEF\xBB\xBFnote, Z ,name,x,y,NX,ny,nz\r\n"
        "a,3,p1,1,2,0,0,2\r\n"
        "\r\n"
        "b c,-1e-3,p 2,4.5,5,1,1,0\r\n");
    REQUIRE(points.size() == 2);
    CHECK(points[0].name == "p1");
    CHECK(points[0].position == Vec3{1, 2, 3});
    CHECK(points[0].has_normal);
    CHECK(points[0].normal == Vec3{0, 0, 1});  // normalised
    CHECK(points[0].line == 2);
    CHECK(points[1].name == "p 2");
    CHECK(points[1].position == Vec3{4.5, 5, -1e-3});
    CHECK(points[1].normal.x == Approx(std::sqrt(0.5)));
    CHECK(points[1].line == 4);  // the blank line counts
    const std::vector<ProbePoint> plain = parse("name,x,y,z\nq,0,0,0");
    REQUIRE(plain.size() == 1);
    CHECK_FALSE(plain[0].has_normal);
}

TEST_CASE("probe: every malformed CSV gives an InputError at its line", "[probe]") {
    check_error("", 0, "empty");
    check_error("\n  \n", 0, "empty");
    check_error("name,x,y,z\n", 1, "no points");
    check_error("name,x,y\np,1,2\n", 1, "missing column 'z'");
    check_error("x,y,z\n1,2,3\n", 1, "missing column 'name'");
    check_error("name,x,y,z,X\np,1,2,3,4\n", 1, "'X' appears twice");
    check_error("name,x,y,z,nx,ny\np,1,2,3,0,1\n", 1, "all three or none");
    check_error("name,x,y,z\np,1,2,3\nq,1,2\n", 3, "expected 4 fields as in the header, found 3");
    check_error("name,x,y,z\np,1,2,3,4\n", 2, "found 5");
    check_error("name,x,y,z\np,1,two,3\n", 2, "column 'y': 'two' is not a number");
    check_error("name,x,y,z\np,1,2,3x\n", 2, "'3x' is not a number");
    check_error("name,x,y,z\np,1,,3\n", 2, "column 'y' is empty");
    check_error("name,x,y,z\np,nan,2,3\n", 2, "column 'x' is NaN");
    check_error("name,x,y,z\np,1,2,inf\n", 2, "not finite");
    check_error("name,x,y,z\np,1,2,1e999\n", 2, "not finite");
    check_error("name,x,y,z\n,1,2,3\n", 2, "no name");
    check_error("name,x,y,z\np,1,2,3\n\np,4,5,6\n", 4, "'p' is used before, on line 2");
    check_error("name,x,y,z,nx,ny,nz\np,1,2,3,0,0,0\n", 2, "normal");
    check_error("name,x,y,z\r\np,1,2,3\r\nq,1;2;3\r\n", 3, "found 2");

    // A missing file names the file.
    const std::string missing = "/nonexistent/points.csv";
    try {
        read_probe_points(missing);
        FAIL("no InputError");
    } catch (const InputError& e) {
        CHECK(e.file() == missing);
        CHECK(e.line() == 0);
        CHECK_THAT(e.message(), Contains("cannot open"));
    }
}

TEST_CASE("probe: results are written with the exact headers at full precision", "[probe]") {
    std::ostringstream plain, with_se;
    write_radiosity_csv(plain, {"a", "b"}, {{1, 0.5, 1.0 / 3}, {0, 1e-12, 123456789.0}});
    CHECK(plain.str() ==
          "name,B_r,B_g,B_b\n"
          "a,1,0.5,0.333333333\n"
          "b,0,1e-12,123456789\n");
    write_radiosity_csv(with_se, {"a"}, {{1, 2, 3}}, {{0.25, 0.125, 2.0 / 3}});
    CHECK(with_se.str() ==
          "name,B_r,B_g,B_b,se_r,se_g,se_b\n"
          "a,1,2,3,0.25,0.125,0.666666667\n");
}

TEST_CASE("probe: B at a disk's centre or a sphere's pole is the mean along the collapsed edge",
          "[probe]") {
    // A field that changes along every parameter direction, so that its values at a centre or
    // pole differ with the direction they are approached from.
    const int m = 4, level = 2;
    SplineField field(m, level);
    for (int k = -(m - 1); k < (1 << level); ++k)
        for (int l = -(m - 1); l < (1 << level); ++l)
            field.set_coefficient(k, l, Rgb{1.0 + 0.3 * k + 0.7 * l, 2.0 - 0.2 * l, 0.5 + 0.1 * k});
    const std::vector<SplineField> fields{field};
    const RadiosityView view(fields);
    // The mean along an edge by a plain midpoint sum, independent of the Gauss rule used.
    auto edge_mean = [&](int axis, double at) {
        const int n = 20000;
        Rgb sum;
        for (int i = 0; i < n; ++i) {
            const double t = (i + 0.5) / n;
            sum += axis == 0 ? view.at(0, at, t) : view.at(0, t, at);
        }
        return (1.0 / n) * sum;
    };
    struct Pole {
        std::string name;
        Surface surface;
        int axis;  // the collapsed edge: u = at (axis 0) or v = at (axis 1)
        double at;
    };
    const std::vector<Pole> poles{
        {"disk centre", Surface::disk({0, 0, 1}, {0, 0, 1}, {1, 0, 0}, 0, 0.7, 0, 2 * Pi), 0, 0},
        // v = 1 is the pole theta = 0 (an outward sphere's v runs from theta1 down to theta0).
        {"sphere pole", Surface::sphere({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, 0.7, 0, Pi, 0, 2 * Pi), 1,
         1},
    };
    for (const Pole& pole : poles) {
        CAPTURE(pole.name);
        const Scene scene = scene_of({pole.surface});
        const std::vector<Polygon> polygons = scene_polygons(scene, scene.settings.tessellation);
        const Vec3 p =
            pole.axis == 0 ? pole.surface.point(pole.at, 0.3) : pole.surface.point(0.3, pole.at);
        const std::optional<SurfaceLocation> loc =
            locate_on_surface(scene, polygons, p, probe_tolerance(scene));
        REQUIRE(loc);
        const Rgb mean = edge_mean(pole.axis, pole.at);
        // The located direction is arbitrary: any (u, v) of the edge gives the same value.
        for (double t : {0.0, 0.2, 0.55, 1.0}) {
            SurfaceLocation at = *loc;
            (pole.axis == 0 ? at.v : at.u) = t;
            (pole.axis == 0 ? at.u : at.v) = pole.at;
            const Rgb b = radiosity_at(view, scene, at);
            CAPTURE(t, b, mean);
            CHECK(max_abs(b - mean) < 1e-6);
        }
        // The field does differ along the edge, so the mean is not any one direction's value.
        const Rgb one_way = pole.axis == 0 ? view.at(0, pole.at, 0.2) : view.at(0, 0.2, pole.at);
        CHECK(max_abs(one_way - mean) > 0.05);
        // Away from the pole the value is the field's own.
        const std::optional<SurfaceLocation> off = locate_on_surface(
            scene, polygons, pole.surface.point(0.4, 0.3), probe_tolerance(scene));
        REQUIRE(off);
        CHECK(max_abs(radiosity_at(view, scene, *off) - view.at(0, off->u, off->v)) == 0);
    }
}
