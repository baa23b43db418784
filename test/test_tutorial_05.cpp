// test/test_tutorial_05.cpp - tutorial chapter 5 (docs/tutorial/05-expanded-domain.md): the
// program runs at depth 2, writes its images, and tells the chapter's story: edgefill's profile
// matches the analytic derivative, the ring is built, and without a continuation outside the
// domain the transfer is two orders of magnitude worse than with linear extrapolation.
#include <catch2/catch.hpp>
#include <filesystem>

#include "test/run_program.h"

using mbr::test::number_after;

TEST_CASE("tutorial 05: extrapolation is what makes the boundary right", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const auto run = mbr::test::run_example("tutorial_05_expanded_domain",
                                            {"--depth", "2", "-o", tmp / "images"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::exists(tmp / "images/tutorial_05_expanded_domain.png"));
    CHECK(std::filesystem::exists(tmp / "images/tutorial_05_extrapolation_profiles.png"));
    const std::string& out = run.out;
    // Edgefill against the analytic profile (stored 0.000201 and 0.000351 of the maxima): the
    // edgefill tolerance is 1e-4 relative, so a few 1e-4 is the expected size; 1e-3 would mean a
    // broken divided difference (22).
    CHECK(number_after(out, "bottom edge, 201 points: largest |dB| error") < 1e-3);
    CHECK(number_after(out, "of max dB, largest |dB_t| error") < 1e-3);
    CHECK(number_after(out, "dB_t =") == Approx(0.7731073).epsilon(1e-5));
    // The ring: counts are exact (a dyadic subdivision with discrete decisions).
    CHECK(number_after(out, "ring width") == 8);
    CHECK(number_after(out, "expanded leaves:") == 1392);
    CHECK(number_after(out, "leaves in patch 1:") == 56);
    // rea (29) in % for each continuation. Stored: zero 16.5115, linear 0.1521, quadratic
    // 0.7787, cubic 1.0801, exact 0.1768; printed with 4 decimals. The quadrature and the
    // projection are deterministic, so 1e-3 relative only absorbs rounding differences between
    // builds while catching any change of the method.
    CHECK(number_after(out, "none (zero outside): rea") == Approx(16.5115).epsilon(1e-3));
    CHECK(number_after(out, "linear (23)-(25): rea") == Approx(0.1521).epsilon(1e-3));
    CHECK(number_after(out, "quadratic (26): rea") == Approx(0.7787).epsilon(1e-3));
    CHECK(number_after(out, "cubic (27): rea") == Approx(1.0801).epsilon(1e-3));
    CHECK(number_after(out, "exact continuation: rea") == Approx(0.1768).epsilon(1e-3));
}
