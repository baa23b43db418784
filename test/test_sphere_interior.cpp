// test/test_sphere_interior.cpp - the inside of a sphere, a closed form for a concave surface.
//
// From any point of a sphere, the form factor to any area A of the same sphere is A / (4 pi R^2)
// (the kernel cos cos / (pi r^2) is constant over the sphere, 1 / (4 pi R^2)). So with an emitting
// cap (emission E, area A_c, reflectance 0) and the rest of reflectance rho (area A_r), the rest's
// radiosity is uniform: B = rho (E A_c + B A_r) / (4 pi R^2), B = rho E A_c / (4 pi R^2 - rho A_r).
// Each piece of the rest also receives from itself (self_transfer, on by default): without that, a
// single surface is 46.7 % too dark (measured before the default changed).
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>

#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"

using namespace mbr;

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double cap_degrees = 30, rho = 0.5;

/// The cap and the rest in `bands` polar bands of `sectors` azimuthal pieces each, radius 1.
Scene sphere_interior(int bands, int sectors, const std::string& settings = "") {
    std::ostringstream text;
    text << "material cap emission 1 1 1\n"
            "material wall reflectance 0.5 0.5 0.5\n"
            "sphere cap cap 0 0 0  0 0 1  1 0 0  1  0 30  0 360 inward\n";
    for (int b = 0; b < bands; ++b)
        for (int a = 0; a < sectors; ++a)
            text << "sphere w" << b << '_' << a << " wall 0 0 0  0 0 1  1 0 0  1  "
                 << cap_degrees + (180 - cap_degrees) * b / bands << ' '
                 << cap_degrees + (180 - cap_degrees) * (b + 1) / bands << "  "
                 << 360.0 * a / sectors << ' ' << 360.0 * (a + 1) / sectors << " inward\n";
    text << settings;
    std::istringstream in(text.str());
    return parse_scene(in, "sphere.scene");
}

double exact_radiosity() {
    const double cap_area = 2 * pi * (1 - std::cos(cap_degrees * pi / 180));
    const double rest_area = 4 * pi - cap_area;
    return rho * cap_area / (4 * pi - rho * rest_area);
}

/// Largest relative error of the rest's radiosity over a grid of each piece's domain.
double largest_error(const Scene& scene, const Solution& solution) {
    const double exact = exact_radiosity();
    double worst = 0;
    for (size_t i = 1; i < scene.surfaces.size(); ++i)
        for (int a = 0; a <= 8; ++a)
            for (int b = 0; b <= 8; ++b) {
                const double B = solution.radiosity[i].evaluate(a / 8.0, b / 8.0)[0];
                worst = std::max(worst, std::abs(B - exact) / exact);
            }
    return worst;
}

}  // namespace

TEST_CASE("sphere interior: one surface receives its own light by default", "[solver][sphere]") {
    const Scene scene = sphere_interior(1, 1);
    REQUIRE(scene.settings.self_transfer);
    const Octree octree = build_octree(scene);
    SolverOptions options = solver_options(scene.settings);
    const Solution solution = solve(scene, octree, options);
    CHECK(solution.stats.converged);
    CHECK(largest_error(scene, solution) <= 1e-3);

    // Off on request: the surface then misses its own light (the error the default removed).
    options.self_transfer = false;
    const Solution without = solve(scene, octree, options);
    CHECK(largest_error(scene, without) > 0.3);
}
