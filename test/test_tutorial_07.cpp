// test/test_tutorial_07.cpp - tutorial chapter 7 (examples/tutorial/tutorial_07_shadows.cpp,
// docs/tutorial/07-shadows.md) run small: shadow depths 2 and 3 on a 64 x 64 error grid. The
// chapter's story must hold (rea of the paper's fractions (28) falls with the shadow depth while
// the rays grow; visibility inside (21) beats both), and its key numbers must stay what the
// chapter's page says they are at these settings.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "test/run_program.h"

using mbr::test::number_after;

namespace {

/// The text from the first occurrence of `anchor` on, so that number_after reads the labels of
/// one line ("rays =" of the line that starts "shadow depth 3:").
std::string from(const std::string& text, const std::string& anchor) {
    const size_t at = text.find(anchor);
    INFO("looking for \"" << anchor << "\" in:\n" << text);
    REQUIRE(at != std::string::npos);
    return text.substr(at);
}

}  // namespace

TEST_CASE("tutorial 07: the fractions (28) against the exact shadow", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const std::string dir = tmp / "images";  // not there yet: the program makes it
    const mbr::test::ProgramRun run = mbr::test::run_example(
        "tutorial_07_shadows", {"--depths", "2", "3", "--grid", "64", "-o", dir});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(dir + "/tutorial_07_shadow.png"));
    CHECK(std::filesystem::is_regular_file(dir + "/tutorial_07_depths.png"));

    // The octree finds the one occluder between the pair.
    CHECK(number_after(run.out, "occluder candidates of the pair") == 1);

    const double rea_2 = number_after(run.out, "shadow depth 2: rea");
    const double rea_3 = number_after(run.out, "shadow depth 3: rea");
    const double rays_2 = number_after(from(run.out, "shadow depth 2:"), "rays");
    const double rays_3 = number_after(from(run.out, "shadow depth 3:"), "rays");
    const double exact_method = number_after(run.out, "exact visibility in (21) at depth 3: rea");
    // The story: one more level of shadow subdivision cuts the error by more than half and
    // costs more than three times the rays; exact visibility is far better still.
    CHECK(rea_3 < 0.5 * rea_2);
    CHECK(rays_3 > 3 * rays_2);
    CHECK(exact_method < 0.2 * rea_3);
    CHECK(number_after(from(run.out, "exact visibility in (21)"), "rays") == 0);

    // The numbers of the chapter at these settings. rea is a quadrature result printed with 4
    // decimals; the margin is 1.5 units of the last printed digit, so that a last-bit difference
    // between builds that flips the rounding passes, and anything larger fails.
    CHECK(rea_2 == Approx(7.6860).margin(1.5e-4));
    CHECK(rea_3 == Approx(2.7840).margin(1.5e-4));
    CHECK(exact_method == Approx(0.3191).margin(1.5e-4));
    // Ray counts are integers fixed by the partitions of (21), the shadow subdivision and the
    // patches whose shafts meet the occluder (6400 and 20736 before the shafts were tested).
    CHECK(rays_2 == 3136);
    CHECK(rays_3 == 10816);
    // (28) at the centre from seeded rays (4 decimals printed, margin as above), and the exact
    // visible fraction there from the closed-form shadowed form factor.
    CHECK(number_after(run.out, "fraction (28) at the centre") == Approx(0.3057).margin(1.5e-4));
    CHECK(number_after(run.out, "exact fraction at the centre") == Approx(0.2978).margin(1.5e-4));
}

TEST_CASE("tutorial 07: bad options are refused with status 2", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const mbr::test::ProgramRun run =
        mbr::test::run_example("tutorial_07_shadows", {"--depths", "4", "2", "-o", tmp / "x"});
    INFO(run);
    CHECK(run.status == 2);
    CHECK(run.err.find("--depths") != std::string::npos);
}
