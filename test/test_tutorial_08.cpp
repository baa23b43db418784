// test/test_tutorial_08.cpp - tutorial chapter 8
// (examples/tutorial/tutorial_08_progressive_loop.cpp, docs/tutorial/08-progressive-loop.md) run
// small: three shots of the Cornell box at receiver depth 3. Checked: who shoots in which order,
// the energy bookkeeping of every shot, and the key numbers the chapter's page reports at these
// settings.
#include <catch2/catch.hpp>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "test/run_program.h"

using mbr::test::number_after;

using mbr::test::row_fields;

TEST_CASE("tutorial 08: the Cornell box shot by shot", "[tutorial]") {
    mbr::test::TempFolder tmp;
    const std::string dir = tmp / "images";
    const mbr::test::ProgramRun run = mbr::test::run_example(
        "tutorial_08_progressive_loop", {"--shots", "3", "--max-depth", "3", "-o", dir});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::is_regular_file(dir + "/tutorial_08_convergence.png"));

    // The largest unshot power shoots first: the light, then the back wall, then the floor.
    CHECK(row_fields(run.out, "1")[1] == "light");
    CHECK(row_fields(run.out, "2")[1] == "back_wall");
    CHECK(row_fields(run.out, "3")[1] == "floor");
    CHECK(number_after(run.out, "shots:") == 3);

    // Bookkeeping: unshot_after = unshot_before - shot + reflected holds to rounding (the terms
    // are sums of a few dozen products of coefficients and weights, each near 1e6: 1e-12 of the
    // emitted power is a thousand times the rounding), and emitted = unshot + absorbed + left.
    CHECK(number_after(run.out, "largest bookkeeping error per shot") < 1e-12);
    CHECK(number_after(run.out, "emitted = unshot + absorbed + left") == Approx(100).margin(0.01));

    // The chapter's numbers, printed with 4 significant digits (margins: 1.5 units of the last
    // digit, so that only a rounding flip between builds passes). The light's shot: 82.89 % of
    // the emitted power arrives, 44.31 % is reflected (the rest of what arrives is absorbed).
    const std::vector<std::string> first = row_fields(run.out, "1");
    CHECK(std::stod(first[5]) == Approx(82.89).margin(0.015));  // incident_%
    CHECK(std::stod(first[6]) == Approx(44.31).margin(0.015));  // reflected_%
    CHECK(number_after(run.out, "still unshot") == Approx(31.95).margin(0.015));
    CHECK(number_after(run.out, "left through the open front (shot - arrived)") ==
          Approx(20.91).margin(0.015));
    // Integer counts, fixed by the adaptive decisions of every transfer: a change in the
    // library's refinement changes them.
    CHECK(number_after(run.out, "kernel evaluations") == 9028471);
    CHECK(number_after(run.out, "shadow rays") == 0);  // exact visibility casts none here
}
