// test/test_tutorial_03.cpp - tutorial chapter 3 (docs/tutorial/03-projection.md): the program
// runs at small levels, writes its two images, and tells the chapter's story: the projection of a
// smooth function converges fast, that of a step does not in the max norm, and the truncation at
// the rhombus radius costs accuracy below about ten cells and nothing beyond.
#include <catch2/catch.hpp>
#include <filesystem>

#include "test/run_program.h"

using mbr::test::number_after;

TEST_CASE("tutorial 03: projection error against scale and truncation radius", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example(
        "tutorial_03_projection", {"--levels", "2", "3", "--level", "3", "-o", tmp / "images"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(tmp / "images/tutorial_03_projection.png"));
    CHECK(std::filesystem::is_regular_file(tmp / "images/tutorial_03_truncation.png"));
    const std::string& out = run.out;
    // The rhombus radius is a multiple of 1/16 (dual_basis.h): exact.
    CHECK(number_after(out, "eps = 1e-09 gives rhombus radius") == 32.875);
    // Errors of (19)-(20), printed with six significant digits: stored values, relative 1e-5
    // (the printing rounds at 5e-6; Release and sanitizer builds differ far below that).
    const double smooth_2 = number_after(out, "smooth level 2: max error =");
    const double smooth_3 = number_after(out, "smooth level 3: max error =");
    CHECK(smooth_2 == Approx(0.0406058).epsilon(1e-5));
    CHECK(smooth_3 == Approx(0.00325718).epsilon(1e-5));
    CHECK(number_after(out, "kink level 3: max error =") == Approx(0.0966942).epsilon(1e-5));
    const double step_2 = number_after(out, "step level 2: max error =");
    const double step_3 = number_after(out, "step level 3: max error =");
    CHECK(step_3 == Approx(0.631486).epsilon(1e-5));
    CHECK(number_after(out, "step level 3: max error = 0.631486, rms error =") ==
          Approx(0.147429).epsilon(1e-5));
    // The story: halving the scale divides the smooth error by more than 2^3 (order m = 4), and
    // leaves the step's max error where it was (within 10 %).
    CHECK(smooth_2 / smooth_3 > 8);
    CHECK(step_3 / step_2 == Approx(1).margin(0.1));
    // Truncation: the cell count is exact; r = 4 spoils the result (stored), from r = 12 on the
    // error is the projection's own (equal to the untruncated level-3 error to 1e-5).
    CHECK(number_after(out, "r = 4: cells per coefficient =") == 60);
    CHECK(number_after(out, "r = 4: cells per coefficient = 60, max error =") ==
          Approx(0.072707).epsilon(1e-5));
    CHECK(number_after(out, "r = 12: cells per coefficient = 364, max error =") ==
          Approx(smooth_3).epsilon(1e-5));
}
