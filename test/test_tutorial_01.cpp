// test/test_tutorial_01.cpp - tutorial chapter 1 (docs/tutorial/01-bsplines.md): the program
// runs, writes its image, and tells the chapter's story: the mask of (14) in closed form, the
// two-scale relation and the refinement (17) hold to rounding, and the dyadic values of (18) are
// whole multiples of 1 / ((m-1)! 2^(J(m-1))).
#include <catch2/catch.hpp>
#include <filesystem>

#include "test/run_program.h"

using mbr::test::number_after;

TEST_CASE("tutorial 01: mask, refinement and dyadic values tell the chapter's story",
          "[tutorial]") {
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example("tutorial_01_bsplines", {"-o", tmp / "images"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(tmp / "images/tutorial_01_bsplines.png"));
    const std::string& out = run.out;
    // Closed forms printed with six decimals: p_{4,k} = binom(4, k) / 8, N_4(2) = 2/3.
    CHECK(number_after(out, "p_{4,0} =") == Approx(0.125).margin(1e-12));
    CHECK(number_after(out, "p_{4,2} =") == Approx(0.75).margin(1e-12));
    CHECK(number_after(out, "omega_{4,2} = N_4(2) =") == Approx(0.666667).margin(1e-12));
    CHECK(number_after(out, "D = (m-1)! 2^(J(m-1)) =") == 384);
    // The identities hold up to rounding: a few units of 1e-16 on values of order one (the
    // partition of unity and (14) sum at most m + 1 terms; the refined f sums up to m terms of
    // coefficients up to 4, the dyadic values times D reach 256).
    CHECK(number_after(out, "partition of unity: max |sum_k N_4(x - k) - 1| =") < 1e-14);
    CHECK(number_after(out, "two-scale relation: max |N_m(x) - sum_k p_{m,k} N_m(2x - k)| =") <
          1e-14);
    CHECK(number_after(out, "refinement: max |f_coarse(s) - f_fine(s)| =") < 1e-13);
    CHECK(number_after(out, "max distance of N_m(x) D from a whole number =") < 1e-12);
    CHECK(number_after(out, "dyadic values: max |(18) - Cox-de Boor| =") < 1e-14);
}

TEST_CASE("tutorial 01: other orders and levels", "[tutorial]") {
    // m = 3, J = 3: D = 2! 2^6 = 128, p_{3,1} = 3/4; (18) still exact.
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example("tutorial_01_bsplines",
                                            {"--order", "3", "--level", "3", "-o", tmp / "i"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(number_after(run.out, "D = (m-1)! 2^(J(m-1)) =") == 128);
    CHECK(number_after(run.out, "p_{3,1} =") == Approx(0.75).margin(1e-12));
    CHECK(number_after(run.out, "max distance of N_m(x) D from a whole number =") < 1e-12);
    // A bad option is a usage error (status 2), with one line on stderr.
    const auto bad = mbr::test::run_example("tutorial_01_bsplines", {"--order", "1"});
    CHECK(bad.status == 2);
}
