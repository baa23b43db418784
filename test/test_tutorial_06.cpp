// test/test_tutorial_06.cpp - tutorial chapter 6 (docs/tutorial/06-fulcrums-and-projection.md):
// the program runs at its default tree with one row of Table 1, writes its images, and tells
// the chapter's story: fulcrums of two scales, the rhombus radii, the coefficient converging as
// the rhombus grows, unification by (17) against projection, and Table 1's first row.
#include <catch2/catch.hpp>
#include <filesystem>

#include "test/run_program.h"

using mbr::test::number_after;

TEST_CASE("tutorial 06: fulcrums, truncation, unification and Table 1", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example("tutorial_06_fulcrums_and_projection",
                                            {"--table-rows", "1", "-o", tmp / "images"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::exists(tmp / "images/tutorial_06_fulcrums.png"));
    CHECK(std::filesystem::exists(tmp / "images/tutorial_06_truncation.png"));
    const std::string& out = run.out;
    // Stage 5 counts are exact.
    CHECK(number_after(out, "fulcrums at level 3:") == 65);
    CHECK(number_after(out, "fulcrums at level 4:") == 200);
    CHECK(number_after(out, "corners carrying fulcrums of two scales:") == 32);
    // Rhombus radii come from DN on a 1/16 grid: printed to 4 digits.
    CHECK(number_after(out, "eps 0.0001: r =") == Approx(14.69).epsilon(1e-4));
    CHECK(number_after(out, "eps 1e-07: r =") == Approx(25.69).epsilon(1e-4));
    // The chosen coefficient by (19) at two truncations (quadrature over stored samples:
    // 1e-6 relative absorbs rounding between builds).
    CHECK(number_after(out, "eps 0.0001: r = 14.69 cells, coefficient") ==
          Approx(0.492180181).epsilon(1e-6));
    CHECK(number_after(out, "eps 1e-06: r = 21.81 cells, coefficient") ==
          Approx(0.493154505).epsilon(1e-6));
    // The coefficient moves less as the rhombus grows (stored 0.00094 at eps 1e-4, 3.3e-05 at
    // 1e-6): the truncation error falls by more than a factor 10 over two decades of eps.
    const double change_4 =
        number_after(out, "cells, coefficient 0.492180181, change against eps 1e-7");
    const double change_6 =
        number_after(out, "cells, coefficient 0.493154505, change against eps 1e-7");
    CHECK(change_6 < 0.1 * change_4);
    // rea in %, printed with 4 decimals; 1e-3 relative absorbs rounding between builds.
    CHECK(number_after(out, "rea with unification by (17):") == Approx(0.9574).epsilon(1e-3));
    CHECK(number_after(out, "rea with unification by projection:") == Approx(0.0990).epsilon(1e-3));
    CHECK(number_after(out, "eps 0.001, r = 10.81: rea by (17)") == Approx(1.9478).epsilon(1e-3));
    // Table 1, h = 1, d = 2: ours against the paper's 0.880 %.
    CHECK(number_after(out, "h = 1.0, d = 2: rea") == Approx(0.0586).epsilon(1e-3));
    CHECK(number_after(out, "(paper") == Approx(0.880));
    CHECK(number_after(out, "samples (21)") == 1192);
}
