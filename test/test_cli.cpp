// test/test_cli.cpp - the programs' shared command line and main() wrapper
// (examples/common/cli.h, transfer_cli.h): exit status 0 / 2 / 1 with one stderr line, --help
// anywhere, integer options with their ranges, options a mode would ignore refused, and a
// report that cannot be written to stdout ending in status 1.
#include <fcntl.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/transfer_cli.h"
#include "radiosity/output/output_file.h"

using namespace mbr;

namespace {

const std::string test_usage = "usage: prog [--rays N]\n";

// What run_main did: its status and what it wrote on stdout and stderr.
struct Run {
    int status = -1;
    std::string out, err;
    bool body_ran = false;
};

std::string read_fd(int fd) {
    std::string s;
    ::lseek(fd, 0, SEEK_SET);
    char buffer[4096];
    for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) s.append(buffer, n);
    return s;
}

// A file for one captured stream, unlinked at once (the descriptor keeps it).
int capture_file() {
    std::string name = (std::filesystem::temp_directory_path() / "mbr_test_cli_XXXXXX").string();
    const int fd = ::mkstemp(name.data());
    REQUIRE(fd >= 0);
    ::unlink(name.c_str());
    return fd;
}

// run_main on `words` (argv[0] = "prog") with fd 1 and 2 captured; stdout_device, when given, is
// opened as fd 1 instead (its content is then not read back). No Catch2 macro runs while the
// streams are redirected.
Run run(const std::vector<std::string>& words, const std::function<int(Args&)>& body,
        const char* stdout_device = nullptr) {
    std::vector<std::string> storage = {"prog"};
    storage.insert(storage.end(), words.begin(), words.end());
    std::vector<char*> argv;
    for (std::string& w : storage) argv.push_back(w.data());
    const int out = stdout_device ? ::open(stdout_device, O_WRONLY) : capture_file();
    const int err = capture_file();
    REQUIRE(out >= 0);
    std::cout.flush();
    std::cerr.flush();
    std::fflush(stdout);
    std::fflush(stderr);
    const int saved_out = ::dup(STDOUT_FILENO), saved_err = ::dup(STDERR_FILENO);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    Run r;
    r.status = run_main(static_cast<int>(argv.size()), argv.data(), test_usage, [&](Args& args) {
        r.body_ran = true;
        return body(args);
    });
    std::cout.flush();
    std::cerr.flush();
    std::fflush(stdout);
    std::fflush(stderr);
    ::dup2(saved_out, STDOUT_FILENO);
    ::dup2(saved_err, STDERR_FILENO);
    ::close(saved_out);
    ::close(saved_err);
    if (!stdout_device) r.out = read_fd(out);
    r.err = read_fd(err);
    ::close(out);
    ::close(err);
    return r;
}

int lines(const std::string& s) {
    int n = 0;
    for (char c : s) n += c == '\n';
    return n;
}

// The body of a small program: one ranged integer option, then finish().
int rays_body(Args& args) {
    const int rays = args.integer("--rays", 100, 1, 10000000);
    args.finish();
    std::cout << "rays " << rays << "\n";
    return 0;
}

// The UsageError message of f, or "" when it throws none.
template <class F>
std::string usage_error(F f) {
    try {
        f();
    } catch (const UsageError& e) {
        return e.what();
    }
    return "";
}

Args make_args(std::vector<std::string> words, std::vector<std::string>& storage,
               std::vector<char*>& argv) {
    storage = {"prog"};
    storage.insert(storage.end(), words.begin(), words.end());
    argv.clear();
    for (std::string& w : storage) argv.push_back(w.data());
    return Args(static_cast<int>(argv.size()), argv.data(), test_usage);
}

}  // namespace

TEST_CASE("cli: --help anywhere prints the usage and exits 0 without running", "[cli]") {
    for (const std::vector<std::string>& words : {std::vector<std::string>{"--help"},
                                                  {"--help", "--bogus"},
                                                  {"--bogus", "--help"},
                                                  {"--rays", "abc", "-h"},
                                                  {"--rays", "99999999999", "--help"}}) {
        CAPTURE(words);
        const Run r = run(words, rays_body);
        CHECK(r.status == 0);
        CHECK_FALSE(r.body_ran);
        CHECK(r.out == test_usage);
        CHECK(r.err == "");
    }
}

TEST_CASE("cli: exit status 0, 2 for usage and input, 1 for failures, one stderr line", "[cli]") {
    Run r = run({"--rays", "5"}, rays_body);
    CHECK(r.status == 0);
    CHECK(r.out == "rays 5\n");
    CHECK(r.err == "");

    r = run({"--bogus"}, rays_body);
    CHECK(r.status == 2);
    CHECK(r.out == "");
    CHECK(lines(r.err) == 1);
    CHECK_THAT(r.err, Catch::StartsWith("prog: unknown option --bogus"));

    r = run({}, [](Args&) -> int { throw InputError("room.scene", 12, "reflectance 1.2"); });
    CHECK(r.status == 2);
    CHECK(r.err == "prog: room.scene:12: reflectance 1.2\n");

    r = run({}, [](Args&) -> int {
        throw OutputError("out/x.png", std::string("cannot write: ") + std::strerror(ENOSPC));
    });
    CHECK(r.status == 1);
    CHECK(r.err == std::string("prog: out/x.png: cannot write: ") + std::strerror(ENOSPC) + "\n");

    r = run({}, [](Args&) -> int { throw std::runtime_error("the solver diverged"); });
    CHECK(r.status == 1);
    CHECK(r.err == "prog: error: the solver diverged\n");

    // A program's own non-zero status passes through.
    r = run({}, [](Args&) { return 1; });
    CHECK(r.status == 1);
}

TEST_CASE("cli: an integer out of its range names the option and the range", "[cli]") {
    Run r = run({"--rays", "99999999999"}, rays_body);
    CHECK(r.status == 2);
    CHECK(lines(r.err) == 1);
    CHECK_THAT(r.err, Catch::Contains("--rays must be in 1..10000000, got 99999999999"));
    r = run({"--rays", "-99999999999999999999999"}, rays_body);  // beyond long long too
    CHECK_THAT(r.err, Catch::Contains("--rays must be in 1..10000000"));
    r = run({"--rays=0"}, rays_body);
    CHECK_THAT(r.err, Catch::Contains("--rays must be in 1..10000000, got 0"));
    for (const char* bad : {"1e5", "12x", " 12", "", "+", "0x10"}) {
        CAPTURE(bad);
        r = run({"--rays", bad}, rays_body);
        CHECK(r.status == 2);
        CHECK_THAT(r.err, Catch::Contains(std::string("--rays expects an integer, got '") + bad));
    }
    r = run({"--rays=+42"}, rays_body);
    CHECK(r.out == "rays 42\n");

    // The receiver options: --coarsen-shooter and --order carry their ranges.
    std::vector<std::string> storage;
    std::vector<char*> argv;
    {
        Args args = make_args({"--coarsen-shooter", "1000"}, storage, argv);
        CHECK(usage_error([&] { read_receiver_options(args); }) ==
              "--coarsen-shooter must be in 0..14, got 1000");
    }
    {
        Args args = make_args({"--order", "9"}, storage, argv);
        CHECK(usage_error([&] { read_receiver_options(args); }) ==
              "--order must be in 2..8, got 9");
    }
    {
        Args args = make_args({"--coarsen-shooter", "14", "--order", "3"}, storage, argv);
        const ReceiverOptions o = read_receiver_options(args);
        CHECK(o.shooter_coarsening == 14);
        CHECK(o.m == 3);
    }
}

TEST_CASE("cli: options a mode would ignore are refused", "[cli]") {
    std::vector<std::string> storage;
    std::vector<char*> argv;
    auto tree_error = [&](std::vector<std::string> words) {
        Args args = make_args(std::move(words), storage, argv);
        return usage_error([&] { read_tree_options(args, ReceiverOptions{}); });
    };
    CHECK_THAT(tree_error({"--adaptive", "--depth", "5"}),
               Catch::StartsWith("--depth has no effect with --adaptive"));
    CHECK_THAT(tree_error({"--depth", "5", "--max-depth", "6"}),
               Catch::Contains("need --adaptive"));
    CHECK_THAT(tree_error({"--oracle-tolerance", "1e-2"}), Catch::Contains("need --adaptive"));
    CHECK(tree_error({"--adaptive", "--min-depth", "4", "--max-depth", "3"}) ==
          "--min-depth must not exceed --max-depth");
    {
        Args args =
            make_args({"--adaptive", "--min-depth", "2", "--max-depth", "5"}, storage, argv);
        const ReceiverOptions o = read_tree_options(args, ReceiverOptions{});
        CHECK(o.min_depth == 2);
        CHECK(o.max_depth == 5);
    }
    {
        Args args = make_args({"--depth", "4"}, storage, argv);
        const ReceiverOptions o = read_tree_options(args, ReceiverOptions{});
        CHECK(o.min_depth == 4);
        CHECK(o.max_depth == 4);
    }
    Args args = make_args({"--eps", "1e-6", "--rhombus-radius", "14"}, storage, argv);
    CHECK_THAT(usage_error([&] { read_receiver_options(args); }),
               Catch::StartsWith("--eps and --rhombus-radius exclude each other"));
}

TEST_CASE("cli: a transfer's quads face each other when any part does", "[cli]") {
    // The shooter: the unit square in z = 0, its front +z ((p10 - p00) x (p01 - p00)).
    const Surface shooter = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    // Facing squarely: the unit square in z = 1, its front -z.
    CHECK(fronts_face_each_other(
        shooter, Surface::planar_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1})));
    // The same square turned round faces away.
    CHECK_FALSE(fronts_face_each_other(
        shooter, Surface::planar_quad({0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1})));
    // Coplanar, side by side: neither lies in front of the other.
    CHECK_FALSE(fronts_face_each_other(
        shooter, Surface::planar_quad({2, 0, 0}, {3, 0, 0}, {3, 1, 0}, {2, 1, 0})));
    // Only in part: a quad in the plane x = 0.8, front +x, from z = -0.8 to 0.2. Its centre
    // (z = -0.3) is behind the shooter and the shooter's centre (x = 0.5) behind it, so a test of
    // the centres refused it; yet its strip z > 0 and the shooter's strip x > 0.8 face each other.
    const Surface straddling =
        Surface::planar_quad({0.8, 0, -0.8}, {0.8, 1, -0.8}, {0.8, 1, 0.2}, {0.8, 0, 0.2});
    REQUIRE(straddling.evaluate(0.5, 0.5).normal.x > 0);
    CHECK(fronts_face_each_other(shooter, straddling));
    CHECK(fronts_face_each_other(straddling, shooter));
    // Lowered to z in [-0.8, -0.1], all of it is behind the shooter: refused.
    CHECK_FALSE(fronts_face_each_other(
        shooter,
        Surface::planar_quad({0.8, 0, -0.8}, {0.8, 1, -0.8}, {0.8, 1, -0.1}, {0.8, 0, -0.1})));
}

TEST_CASE("cli: a report that cannot be written to stdout gives status 1 and the reason", "[cli]") {
    if (::access("/dev/full", W_OK) != 0) {
        WARN("skipped: no /dev/full here");
        return;
    }
    // 200 KB of report: more than any buffer holds, so the failure happens during the body.
    const Run big = run(
        {},
        [](Args&) {
            for (int i = 0; i < 20000; ++i) std::cout << "row " << i << ", some numbers\n";
            return 0;
        },
        "/dev/full");
    CHECK(big.status == 1);
    CHECK(big.err ==
          std::string("prog: standard output: cannot write: ") + std::strerror(ENOSPC) + "\n");
    // A short report fails only at the final flush, and is reported the same way.
    const Run small = run(
        {},
        [](Args&) {
            std::cout << "rea 0.73 %\n";
            return 0;
        },
        "/dev/full");
    CHECK(small.status == 1);
    CHECK(small.err == big.err);
    // And the usage text of --help too.
    const Run help = run({"--help"}, rays_body, "/dev/full");
    CHECK(help.status == 1);
    CHECK(help.err == big.err);
}

TEST_CASE("cli: a word starting with '-' that nobody asked for is an unknown option", "[cli]") {
    auto positional = [](std::vector<std::string> words) {
        std::vector<std::string> storage;
        std::vector<char*> argv;
        Args args = make_args(std::move(words), storage, argv);
        (void)args.integer("--rays", 1);
        std::string joined;
        for (const std::string& p : args.positional()) joined += "[" + p + "]";
        return joined;
    };
    CHECK(usage_error([&] { positional({"base.scene", "-x"}); }) == "unknown option -x");
    CHECK(usage_error([&] { positional({"base.scene", "--camera", "0", "1", "3"}); }) ==
          "unknown option --camera");
    // Read options, a lone "-" and numbers are not unknown options.
    CHECK(positional({"--rays", "5", "a.scene", "-", "-1", "-.5"}) == "[a.scene][-][-1][-.5]");

    // An output path that cannot be written is a usage error without the options' hint.
    const Run r = run({}, [](Args&) -> int {
        refuse_bad_outputs({"/nonexistent folder of mbr/x.png"});
        return 0;
    });
    CHECK(r.status == 2);
    CHECK(r.err == "prog: /nonexistent folder of mbr/x.png: cannot write: the folder "
                   "'/nonexistent folder of mbr' does not exist\n");
}
