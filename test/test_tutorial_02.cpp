// test/test_tutorial_02.cpp - tutorial chapter 2 (docs/tutorial/02-dual-basis.md): the program
// runs, writes Figure 1, and tells the chapter's story: the appendix reproduces all of the
// paper's Table 3, the duals are biorthogonal to the B-splines, and they give a spline's
// coefficients back (13).
#include <catch2/catch.hpp>
#include <filesystem>

#include "test/run_program.h"

using mbr::test::number_after;

TEST_CASE("tutorial 02: Table 3, biorthogonality and Figure 1 tell the chapter's story",
          "[tutorial]") {
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example("tutorial_02_dual_basis", {"-o", tmp / "images"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(tmp / "images/tutorial_02_dual_basis.png"));
    const std::string& out = run.out;
    // The Gram sequence in closed form: N_6(3) = 11/20, N_6(4) = 13/60 (nine decimals printed).
    CHECK(number_after(out, "gamma_0 =") == Approx(0.55).margin(1e-9));
    CHECK(number_after(out, "gamma_1 =") == Approx(13.0 / 60).margin(1e-9));
    // The appendix: how many sections M_{3;K} it inverts is a count, the same in every build
    // unless the method changes; and every printed value of Table 3 is matched.
    CHECK(number_after(out, "eps 1e-12: matrices inverted =") == 9);
    CHECK(number_after(out, "Table 3:") == 19);
    // Biorthogonality and (13) hold to rounding: exact quadrature of piecewise polynomials of
    // order one, summed over fewer than a hundred unit intervals.
    CHECK(number_after(out, "biorthogonality: max |<N_m(. - k), DN_m> - delta_k0| =") < 1e-14);
    CHECK(number_after(out, "<f, DN_3(. - 2)> =") == Approx(2).margin(1e-9));
    CHECK(number_after(out, "<f, DN_3(. + 1)> =") == Approx(0).margin(1e-9));
    // Figure 1's peaks, printed with six decimals: DN_3(1.5) = 3/4 mu_0 + 1/4 mu_1.
    CHECK(number_after(out, "DN_3(1.5) =") == Approx(1.801196).margin(1e-6));
    CHECK(number_after(out, "DN_4(2) =") == Approx(2.279474).margin(1e-6));
}
