// test/test_cost.cpp - bounded cost, said before it is spent: the memory estimate of
// radiosity/solver/cost.h grows with every setting and refuses a run over the budget; an image
// named by several materials is counted (and decoded) once; a failure inside a parallel loop
// reaches the caller as an exception; coarsening a deep shooter by every number of levels works.
#include <algorithm>
#include <catch2/catch.hpp>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "examples/common/cli.h"
#include "examples/common/transfer_cli.h"
#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/solver/cost.h"
#include "radiosity/solver/solver.h"
#include "radiosity/transfer/transfer.h"

using namespace mbr;

namespace {

const std::string scenes_dir = std::string(MBR_SOURCE_DIR) + "/examples/scenes/";

Scene four_materials_one_image() {
    std::istringstream in("material a reflectance image " + scenes_dir + "picture.png\n" +
                          "material b reflectance image " + scenes_dir +
                          "picture.png scale 0.3 0.6 0.45\n" + "material c emission image " +
                          scenes_dir + "picture.png scale 20 20 20\n" +
                          "material d reflectance 0.5 0.5 0.5 emission image " + scenes_dir +
                          "picture.png\n" + "rectangle r a 0 0 0  1 0 0  0 1 0\n");
    return parse_scene(in, "four.scene");
}

}  // namespace

TEST_CASE("cost: the estimate grows with depth, order and tessellation", "[cost]") {
    for (int m = 2; m <= 5; ++m)
        for (int d = 1; d <= 12; ++d) {
            CAPTURE(m, d);
            CHECK(transfer_bytes(m, d) > transfer_bytes(m, d - 1));
            CHECK(transfer_bytes(m + 1, d) > transfer_bytes(m, d));
            CHECK(field_bytes(m, d) > field_bytes(m, d - 1));
            CHECK(transfer_seconds(m, d) > transfer_seconds(m, d - 1));
        }
    // The calibration (cost.cpp): depth 8 at m = 4 measured ~54.5 MB above the program's base;
    // the estimate may err high but not by more than a factor 2 either way.
    CHECK(transfer_bytes(4, 8) > 27e6);
    CHECK(transfer_bytes(4, 8) < 110e6);

    Scene scene = load_scene(scenes_dir + "room.scene");
    SolverOptions o = solver_options(scene.settings);
    double last = 0;
    for (int d = 1; d <= 12; ++d) {
        o.receiver.max_depth = d;
        const double bytes = scene_cost(scene, o, 2).bytes;
        CHECK(bytes > last);
        last = bytes;
    }
    o.receiver.max_depth = 6;
    const double at_24 = scene_cost(scene, o, 2).bytes;
    scene.settings.tessellation = 1024;
    // 1024^2 / 24^2 more curved facets: the polygons (2.3 MiB at 24) outgrow the rest (the
    // program, fields, hidden regions, quadrature caches and the ambient gathers' kept hits:
    // about 110 MiB in all).
    CHECK(scene_cost(scene, o, 2).bytes > 40 * at_24);
}

TEST_CASE("cost: a run over the memory budget is refused before it starts", "[cost]") {
    ReceiverOptions o;
    o.min_depth = o.max_depth = 12;
    // 4^12 leaves of 16 samples: gigabytes, against a budget of one mebibyte.
    CHECK_THROWS_AS(check_cost(transfer_cost(o), 1 << 20, "a transfer", false), UsageError);
    o.min_depth = o.max_depth = 3;
    CHECK_NOTHROW(check_cost(transfer_cost(o), 1 << 20, "a transfer", false));

    // Through the command line, as single_transfer reads it.
    std::vector<std::string> words{"prog", "--depth", "10", "--memory-budget", "64M"};
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    Args args(int(argv.size()), argv.data(), "usage");
    try {
        read_tree_options(args, ReceiverOptions{});
        FAIL("depth 10 within 64 MiB was accepted");
    } catch (const UsageError& e) {
        CHECK_THAT(e.what(), Catch::Contains("more than the memory budget of 64.0 MiB"));
    }

    // Valid but slow: one warning line on stderr with the memory and the time.
    {
        std::ostringstream err;
        std::streambuf* old = std::cerr.rdbuf(err.rdbuf());
        o.min_depth = o.max_depth = slow_receiver_depth;
        check_cost(transfer_cost(o), 1e12, "a transfer at depth 9", true);
        std::cerr.rdbuf(old);
        CHECK_THAT(err.str(),
                   Catch::StartsWith("warning: a transfer at depth 9 is slow: expect about"));
        const std::string line = err.str();
        CHECK(std::count(line.begin(), line.end(), '\n') == 1);
    }

    CHECK(parse_memory_size("4G", "x") == 4.0 * (1L << 30));
    CHECK(parse_memory_size("512MiB", "x") == 512.0 * (1L << 20));
    CHECK(parse_memory_size("1000", "x") == 1000);
    CHECK_THROWS_AS(parse_memory_size("4x", "x"), UsageError);
    CHECK_THROWS_AS(parse_memory_size("-1G", "x"), UsageError);
    CHECK_THROWS_AS(parse_memory_size("G", "x"), UsageError);
}

TEST_CASE("cost: four materials sharing one image hold it once", "[cost]") {
    const Scene scene = four_materials_one_image();
    REQUIRE(scene.materials.size() == 4);
    const Texture& first = scene.materials[0].reflectance;
    REQUIRE(first.texel_bytes() > 0);
    for (int i = 1; i < 4; ++i) {
        const Material& mat = scene.materials[i];
        CHECK(first.shares_texels(mat.reflectance.kind() == Texture::Kind::Image ? mat.reflectance
                                                                                 : mat.emission));
    }
    // The estimate counts the texels once, not four times.
    SolverOptions o = solver_options(scene.settings);
    const CostEstimate c = scene_cost(scene, o, 1);
    CHECK_THAT(c.detail, Catch::EndsWith("textures " + format_bytes(double(first.texel_bytes()))));
}

TEST_CASE("cost: a check failing inside a parallel loop reaches the caller", "[cost]") {
    // The lowest failing index is the one reported, whatever the schedule.
    try {
        parallel_for(100L, [](long i) { MBR_CHECK_MSG(i % 7 != 3, "item " << i); });
        FAIL("no exception");
    } catch (const CheckFailure& e) {
        CHECK_THAT(e.what(), Catch::Contains("item 3)"));
    }
    CHECK_THROWS_AS(parallel_for(
                        8, [](int) { throw std::runtime_error("x"); }, 2),
                    std::runtime_error);
}

TEST_CASE("cost: a depth-7 shooter coarsened by every number of levels", "[cost]") {
    // What shooter_coarsening --depth 7 does before each transfer: the floor's level-7 field
    // coarsened by c = 0..7 levels, and its power at each level.
    const int m = 4, depth = 7;
    const Surface floor = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    SplineField field(m, depth);
    for (int k = 1 - m; k < (1 << depth); ++k)
        for (int l = 1 - m; l < (1 << depth); ++l)
            field.set_coefficient(k, l, Rgb{1, 1, 1} * (1.0 + (k * l + 100) % 5));
    for (int c = 0; c <= depth; ++c) {
        CAPTURE(c);
        const Shooter s = make_shooter(floor, field, c);
        CHECK(s.unshot.level() == depth - c);
        CHECK(field.coarsened_to(depth - c).level() == depth - c);
    }
}
