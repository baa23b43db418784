// test/test_resolution.cpp - a receiver too coarse for a light's peak is an error before any
// work (radiosity/solver/resolution.h; issue 19, "a large receiver loses the light").
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "math/check.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/resolution.h"
#include "radiosity/solver/solver.h"

using namespace mbr;

namespace {

/// A floor of half-width `half` (reflectance 0.5) under a 1 x 1 lamp (emission 1) at height 1
/// above (x, z) = (lamp_x, lamp_z), its corner there.
Scene lamp_over_floor(double half, double lamp_x = -0.5, double lamp_z = -0.5,
                      const std::string& more = "") {
    std::ostringstream text;
    text << "material lamp emission 1 1 1\n"
            "material floor reflectance 0.5 0.5 0.5\n"
            "rectangle floor floor  "
         << -half << " 0 " << -half << "   0 0 " << 2 * half << "   " << 2 * half
         << " 0 0\n"
            "rectangle lamp lamp  "
         << lamp_x << " 1 " << lamp_z << "   1 0 0   0 0 1\n"
         << more;
    std::istringstream in(text.str());
    return parse_scene(in, "floor.scene");
}

}  // namespace

TEST_CASE("resolution: a floor whose finest cells are wider than the lamp's spot is refused",
          "[resolution]") {
    // The spot under a 1 x 1 lamp at height 1 is about 1 wide. A floor 20 wide holds it from
    // max_depth 5 (cells 0.63 wide); 2e4 wide, from max_depth 15, beyond what may be set.
    CHECK(unresolved_lights(lamp_over_floor(10), 6).empty());
    CHECK(unresolved_lights(lamp_over_floor(10), 5).empty());
    const std::vector<UnresolvedLight> at4 = unresolved_lights(lamp_over_floor(10), 4);
    REQUIRE(at4.size() == 1);
    CHECK(at4[0].receiver == 0);
    CHECK(at4[0].emitter == 1);
    CHECK(at4[0].cell == Approx(1.25));
    CHECK(at4[0].spot == Approx(1).epsilon(0.05));
    CHECK(at4[0].needed_depth == 5);
    CHECK(at4[0].form_factor > 0.9);  // the floor takes nearly all of the lamp's light
    const Scene huge = lamp_over_floor(1e4);
    const std::vector<UnresolvedLight> u = unresolved_lights(huge, 6);
    REQUIRE(u.size() == 1);
    CHECK(u[0].needed_depth == 15);
    // The error names the floor's statement, the lamp's, and what to change.
    try {
        check_resolution(huge, 6);
        FAIL("no error");
    } catch (const InputError& e) {
        CHECK(e.file() == "floor.scene");
        CHECK(e.line() == 3);
        CHECK_THAT(e.message(), Catch::Contains("'floor' is too coarse for the light of 'lamp' "
                                                "(floor.scene:4)"));
        CHECK_THAT(e.message(), Catch::Contains("split 'floor' into surfaces about 39.1 wide"));
        CHECK_THAT(e.message(), !Catch::Contains("set max_depth"));
    }
    try {
        check_resolution(lamp_over_floor(10), 4);
        FAIL("no error");
    } catch (const InputError& e) {
        CHECK_THAT(e.message(), Catch::Contains("set max_depth 5"));
    }
    // The 1e8 floor of the coordinate limit: an error too, never a NaN or a dark floor.
    CHECK_THROWS_AS(check_resolution(lamp_over_floor(5e7), 12), InputError);
}

TEST_CASE("resolution: a strip's peak is as narrow as the strip", "[resolution]") {
    // A 1.4 x 0.08 strip lamp 4 cm under a 3.7 x 5.3 ceiling: across the strip its peak is
    // about 0.08 wide, and the ceiling's cells at max_depth 6 are 5.8 x 8.3 cm (measured: -17 %
    // at the peak's centre, from -97 to +687 % beside it; within 2 % of the centre at depth 7,
    // 0.5 % everywhere at depth 8). A square lamp of the same area (0.335 wide) is held at 6.
    auto ceiling_over = [](const std::string& lamp) {
        std::istringstream in(
            "material ceil reflectance 0.75 0.75 0.75\n"
            "material lamp emission 1 1 1\n"
            "quad ceiling ceil 0 0.2 2.8  0 5.5 2.8  3.7 5.5 2.8  3.7 0.2 2.8\n" +
            lamp);
        return parse_scene(in, "ceiling.scene");
    };
    const Scene strip = ceiling_over(
        "quad strip lamp 1.1 2.86 2.76  2.5 2.86 2.76  2.5 2.94 2.76  1.1 2.94 2.76\n");
    const std::vector<UnresolvedLight> u = unresolved_lights(strip, 6);
    REQUIRE(u.size() == 1);
    CHECK(u[0].spot == Approx(0.08).epsilon(1e-9));
    CHECK(u[0].needed_depth == 7);
    CHECK(unresolved_lights(strip, 7).empty());
    const double side = std::sqrt(1.4 * 0.08), x = 1.8 - side / 2, y = 2.9 - side / 2;
    std::ostringstream square;
    square << "quad square lamp " << x << " " << y << " 2.76  " << x + side << " " << y << " 2.76  "
           << x + side << " " << y + side << " 2.76  " << x << " " << y + side << " 2.76\n";
    CHECK(unresolved_lights(ceiling_over(square.str()), 6).empty());
}

TEST_CASE("resolution: what the check leaves alone", "[resolution]") {
    // A lamp off to the side of the floor (its spot falls beside it): the floor takes little.
    CHECK(unresolved_lights(lamp_over_floor(10, 30, 0), 2).empty());
    // A lamp below the floor's plane, or lying on it: no peak in front of it.
    CHECK(unresolved_lights(
              lamp_over_floor(1e4, -0.5, -0.5, "rectangle under lamp  0 -1 0   1 0 0   0 0 1\n"),
              6)
              .size() == 1);  // only the lamp above counts
    // A black floor reflects nothing: what it loses, nobody sees.
    std::istringstream black(
        "material lamp emission 1 1 1\n"
        "material black reflectance 0 0 0\n"
        "rectangle floor black  -1e4 0 -1e4   0 0 2e4   2e4 0 0\n"
        "rectangle lamp lamp  -0.5 1 -0.5   1 0 0   0 0 1\n");
    CHECK(unresolved_lights(parse_scene(black, "black.scene"), 6).empty());
}

TEST_CASE("resolution: the example scenes pass the check at their own settings", "[resolution]") {
    for (const char* name : {"cornell_box.scene", "room.scene", "parallel_squares.scene",
                             "perpendicular_squares.scene", "three_strips.scene"}) {
        CAPTURE(name);
        const Scene scene =
            load_scene(std::string(MBR_SOURCE_DIR) + "/examples/scenes/" + std::string(name));
        CHECK(unresolved_lights(scene, scene.settings.max_depth).empty());
    }
}

TEST_CASE("resolution: where the check passes, the light under the lamp is right",
          "[resolution][solver]") {
    // At max_depth 6 a floor 20 wide passes; under the lamp's centre it reads rho E F, F the
    // point form factor to the lamp: 0.5 x 0.23945647 (two rectangles' formula, by hand).
    const Scene scene = lamp_over_floor(10, -0.5, -0.5, "set max_depth 6\n");
    REQUIRE(unresolved_lights(scene, 6).empty());
    const Octree octree = build_octree(scene);
    const Solution solution = solve(scene, octree, solver_options(scene.settings));
    const double exact = 0.5 * 0.23945647047;
    CHECK(solution.radiosity[0].evaluate(0.5, 0.5)[0] == Approx(exact).epsilon(0.02));
}
