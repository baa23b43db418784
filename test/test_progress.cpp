// test/test_progress.cpp - the run's progress off a terminal (examples/common/progress.h): a
// line every interval while a stage runs, even with no event inside it, the stage's end said
// at once, and nothing at all for a run shorter than the interval or when turned off.
#include <fcntl.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <string>
#include <thread>

#include "examples/common/progress.h"
#include "examples/common/scene_cli.h"
#include "test/run_program.h"

using Catch::Matchers::Contains;

namespace {

/// What `body` writes to stderr (file descriptor 2), captured in an anonymous file.
template <class Body>
std::string stderr_of(Body body) {
    const int file = mbr::test::capture_file();
    const int saved = ::dup(2);
    REQUIRE(saved >= 0);
    REQUIRE(::dup2(file, 2) == 2);
    body();
    ::fflush(stderr);
    ::dup2(saved, 2);
    ::close(saved);
    const std::string text = mbr::test::read_fd(file);
    ::close(file);
    return text;
}

void sleep_for(double seconds) {
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
}

}  // namespace

TEST_CASE("progress: off a terminal, a line every interval, the end of a stage at once",
          "[progress]") {
    const std::string log = stderr_of([] {
        mbr::ProgressReporter progress(true, 0.2);
        progress.stage("building the octree of 9 surfaces");  // no event inside it
        sleep_for(0.5);
        progress.stage("hidden regions");
        sleep_for(0.2);
        progress.update("1/4 surfaces", 0.25);  // about 0.6 s left
        sleep_for(0.3);
        progress.update("4/4 surfaces", 1.0);
        progress.stage("");  // idle: nothing more is shown
        sleep_for(0.3);
    });
    CAPTURE(log);
    CHECK(log.find('\r') == std::string::npos);
    CHECK_THAT(log, Contains("building the octree of 9 surfaces, 0."));
    CHECK_THAT(log, Contains("hidden regions: 1/4 surfaces, "));
    CHECK_THAT(log, Contains("hidden regions: 4/4 surfaces, "));
    CHECK_THAT(log, Contains("s left"));
    // Idle at the end: the last line is the stage's end.
    CHECK(log.rfind("4/4 surfaces") > log.rfind("1/4 surfaces"));
    CHECK(log.substr(log.rfind('\n', log.size() - 2) + 1).find("4/4") != std::string::npos);
}

TEST_CASE("progress: an estimate counts down between events and is dropped once run out",
          "[progress]") {
    const std::string log = stderr_of([] {
        mbr::ProgressReporter progress(true, 0.2);
        progress.stage("shot 2/3");
        progress.update("0/5 transfers", 0.5, 1.0);  // one second left, then no event
        sleep_for(2.2);
        progress.stage("");
    });
    CAPTURE(log);
    // The lines before the second ends carry the estimate; the last ones, after it, do not.
    CHECK_THAT(log, Contains("0/5 transfers, 0.") && Contains("s, about 1 s left"));
    const std::string last = log.substr(log.rfind('\n', log.size() - 2) + 1);
    CHECK_THAT(last, Contains("shot 2/3: 0/5 transfers, "));
    CHECK(last.find("left") == std::string::npos);
}

TEST_CASE("progress: a run shorter than the interval, or turned off, says nothing", "[progress]") {
    CHECK(stderr_of([] {
              mbr::ProgressReporter progress(true, 5);
              progress.stage("reading x.scene");
              progress.update("half", 0.5);
              sleep_for(0.2);
          }).empty());
    CHECK(stderr_of([] {
              mbr::ProgressReporter progress(false, 0.05);
              progress.stage("reading x.scene");
              sleep_for(0.3);
          }).empty());
}

TEST_CASE("progress: the time left in seconds, minutes or hours", "[progress]") {
    CHECK(mbr::format_duration(0.4) == "0 s");
    CHECK(mbr::format_duration(42) == "42 s");
    CHECK(mbr::format_duration(99) == "99 s");
    CHECK(mbr::format_duration(2322) == "39 min");
    CHECK(mbr::format_duration(7199) == "120 min");
    CHECK(mbr::format_duration(12600) == "3.5 h");
}

TEST_CASE("progress: the shots' fraction reaches 1 only when the run ends", "[progress]") {
    using mbr::shot_progress_fraction;
    // With a convergence threshold: the unshot share's way down to it, on a log scale.
    CHECK(shot_progress_fraction(1.0, 1e-3, 0, 100) == 0.0);
    CHECK(shot_progress_fraction(0.1, 1e-3, 5, 100) == Approx(1.0 / 3));
    CHECK(shot_progress_fraction(1e-4, 1e-3, 50, 100) == 1.0);
    CHECK(shot_progress_fraction(0.0, 1e-3, 50, 100) == 1.0);
    CHECK(shot_progress_fraction(1.3, 1e-3, 1, 100) == 0.0);  // more unshot than emitted
    // Without one (--convergence 0) only the shot limit ends the run: before, every update of
    // every shot read 1 and was printed at once, a line per receiver off a terminal.
    CHECK(shot_progress_fraction(0.5, 0.0, 0, 4) == 0.0);
    CHECK(shot_progress_fraction(0.5, 0.0, 3, 4) == 0.75);
    CHECK(shot_progress_fraction(0.5, 0.0, 4, 4) == 1.0);
    CHECK(shot_progress_fraction(0.5, 0.0, 0, 0) == 1.0);
}
