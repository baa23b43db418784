// test/test_tutorial_09.cpp - tutorial chapter 9 (examples/tutorial/tutorial_09_rendering.cpp,
// docs/tutorial/09-rendering.md) run small: receiver depth 3, ten shots, a 64 x 64 render with
// one sample per pixel.
// Checked: the render and the comparison image are written, all 16 reference points are read
// and compared, the reference values are printed as the file holds them, the errors at these
// settings stay what they are, and a missing reference file is a clear input error (status 2).
#include <catch2/catch.hpp>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "test/run_program.h"

using mbr::test::number_after;

using mbr::test::row_fields;

TEST_CASE("tutorial 09: the render and the path-traced points", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const std::string dir = tmp / "images";
    const mbr::test::ProgramRun run = mbr::test::run_example(
        "tutorial_09_rendering",
        {"--max-depth", "3", "--shots", "10", "--spp", "1", "--size", "64", "-o", dir});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(dir + "/tutorial_09_render.png"));
    CHECK(std::filesystem::is_regular_file(dir + "/tutorial_09_comparison.png"));
    CHECK(number_after(run.out, "camera rays") == 64 * 64);

    // Every point of the file has its row: name, surface, shadow, 3 + 3 values, Y_ref, Y_mbr,
    // error. stop1's Y_ref is the file's B (1.010713, 0.703816, 0.207595) weighted by the
    // luminance coefficients: 0.733240 (printed with 4 decimals).
    for (const char* name :
         {"floor1", "floor2", "floor_pen1", "floor_pen3", "back1", "back3", "back_pen1", "red1",
          "red3", "green1", "green3", "ceil1", "stop1", "sfront1", "tfront1", "tside1"})
        CHECK(row_fields(run.out, name).size() == 12);
    const std::vector<std::string> stop1 = row_fields(run.out, "stop1");
    CHECK(stop1[1] == "short_top");
    CHECK(std::stod(stop1[9]) == Approx(0.7332).margin(6e-5));

    // The errors at these settings (quadrature results printed with 3 decimals; the margin is
    // 1.5 units of the last digit). Ten shots at depth 3 leave 13 % of the power unshot for the
    // gathered ambient correction and its final gather (2.370 / 18.455 % at floor_pen1 without
    // the final gather; 11.221 / 93.212 % at sfront1 with the constant correction); the
    // chapter's page shows the defaults'.
    CHECK(number_after(run.out, "mean relative error") == Approx(2.380).margin(1.5e-3));
    CHECK(number_after(run.out, "max relative error") == Approx(22.389).margin(1.5e-3));
    CHECK(run.out.find("(floor_pen1)") != std::string::npos);
}

TEST_CASE("tutorial 09: a missing reference file is an input error", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const std::string missing = tmp / "no such points.csv";
    const mbr::test::ProgramRun run =
        mbr::test::run_example("tutorial_09_rendering", {"--points", missing, "-o", tmp / "x"});
    INFO(run);
    CHECK(run.status == 2);
    CHECK(run.err.find(missing) != std::string::npos);
    CHECK(run.err.find("missing") != std::string::npos);
    CHECK(run.out.empty());  // refused before the solve
}
