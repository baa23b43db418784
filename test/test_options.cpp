// test/test_options.cpp - the option table (radiosity/scene/settings.h) drives everything that
// spells a solver option: a scene's `set` line and the command-line flag of every row reach the
// same field, the older flag spellings are aliases, the usage text lists every flag with its
// range and default, docs/scene-format.md holds exactly the table, and a bad value names the
// option and its range the same way in a scene and on a command line.
#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/scene_cli.h"
#include "math/check.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/settings.h"
#include "radiosity/solver/solver.h"

#ifndef MBR_SOURCE_DIR
#error "MBR_SOURCE_DIR must name the repository (test/CMakeLists.txt defines it)"
#endif

using namespace mbr;

namespace {

const char* two_squares =
    "material white reflectance 0.5 0.5 0.5\n"
    "material light reflectance 0 0 0 emission 1 1 1\n"
    "quad floor white  0 0 0  1 0 0  1 1 0  0 1 0\n"
    "quad lamp  light  0 0 1  0 1 1  1 1 1  1 0 1\n";

/// A valid value of the option other than its default, as text.
std::string other_value(const OptionSpec& o) {
    const SolverSettings defaults;
    const double d = o.get(defaults);
    switch (o.kind) {
        case OptionSpec::Kind::Integer:
            return std::to_string(int(d == o.hi ? o.lo : o.hi));
        case OptionSpec::Kind::Real: {
            const double mid = 0.5 * (o.lo + o.hi);
            std::ostringstream os;
            os.precision(17);
            os << (mid == d ? 0.25 * o.lo + 0.75 * o.hi : mid);
            return os.str();
        }
        case OptionSpec::Kind::Choice:
            return o.choices[d == 0 ? 1 : 0];
        case OptionSpec::Kind::Switch:
            return d != 0 ? "false" : "true";
    }
    return "";
}

/// The settings after read_scene_run with the given command line over `scene`.
SolverSettings settings_from_flags(const Scene& scene, std::vector<std::string> words) {
    std::vector<std::string> storage{"prog"};
    storage.insert(storage.end(), words.begin(), words.end());
    std::vector<char*> argv;
    for (std::string& w : storage) argv.push_back(w.data());
    Args args(int(argv.size()), argv.data(), "usage");
    SceneRun run = read_scene_run(args, scene, "test");
    args.finish();
    return run.scene.settings;
}

/// The message of the UsageError that read_scene_run throws for this command line ("" if none).
std::string flag_error(const Scene& scene, std::vector<std::string> words) {
    try {
        settings_from_flags(scene, std::move(words));
    } catch (const UsageError& e) {
        return e.what();
    }
    return "";
}

/// The message (without file and line) of the InputError a scene with this line throws.
std::string set_error(const std::string& line) {
    std::istringstream in(std::string(two_squares) + line + "\n");
    try {
        parse_scene(in, "test.scene");
    } catch (const InputError& e) {
        return e.message();
    }
    return "";
}

}  // namespace

TEST_CASE("options: a set line and its flag reach the same field, for every option", "[options]") {
    for (const OptionSpec& o : option_table()) {
        if (o.name == "min_depth" || o.name == "max_depth") continue;  // a pair: below
        const std::string value = other_value(o);
        CAPTURE(o.name, value);
        std::istringstream in(std::string(two_squares) + "set " + o.name + " " + value + "\n");
        const Scene from_set = parse_scene(in, "test.scene");
        const SolverSettings defaults;
        CHECK(o.get(from_set.settings) != o.get(defaults));

        std::istringstream plain(two_squares);
        const Scene scene = parse_scene(plain, "test.scene");
        const SolverSettings from_flag = settings_from_flags(scene, {o.flag(), value});
        CHECK(o.get(from_flag) == o.get(from_set.settings));
        for (const std::string& alias : o.aliases) {
            CAPTURE(alias);
            CHECK(o.get(settings_from_flags(scene, {alias, value})) == o.get(from_set.settings));
        }
    }
}

TEST_CASE("options: the older flags are aliases of the table's", "[options]") {
    std::istringstream in(two_squares);
    const Scene scene = parse_scene(in, "test.scene");
    CHECK(settings_from_flags(scene, {"--shots", "7"}).max_shots == 7);
    CHECK(settings_from_flags(scene, {"--max-shots", "7"}).max_shots == 7);
    CHECK(settings_from_flags(scene, {"--rays", "9"}).shadow_rays == 9);
    CHECK(settings_from_flags(scene, {"--shadow-rays", "9"}).shadow_rays == 9);
    // A switch: on|off on the command line as before, true|false as in scene files.
    CHECK_FALSE(settings_from_flags(scene, {"--ambient", "off"}).ambient);
    CHECK_FALSE(settings_from_flags(scene, {"--hidden", "false"}).hidden);
    CHECK(settings_from_flags(scene, {"--self-transfer", "on"}).self_transfer);
    // The depth pair: one bound moves the other along; both crossed is an error.
    CHECK(settings_from_flags(scene, {"--min-depth", "8"}).max_depth == 8);
    CHECK(settings_from_flags(scene, {"--max-depth", "0"}).min_depth == 0);
    CHECK(flag_error(scene, {"--min-depth", "5", "--max-depth", "3"}) ==
          "--min-depth must not exceed --max-depth");
}

TEST_CASE("options: a bad value names the option and its range, in a scene and on a line",
          "[options]") {
    std::istringstream in(two_squares);
    const Scene scene = parse_scene(in, "test.scene");
    CHECK(set_error("set order 9") == "order '9' is outside [2, 8]");
    CHECK(flag_error(scene, {"--order", "9"}) == "--order '9' is outside [2, 8]");
    CHECK(set_error("set tolerance 1") == "tolerance 1 is outside (0, 1)");
    CHECK(flag_error(scene, {"--tolerance", "1"}) == "--tolerance 1 is outside (0, 1)");
    CHECK(set_error("set shadows soft") == "shadows 'soft' is not 'exact', 'paper', 'none' or 'auto'");
    CHECK(flag_error(scene, {"--shadows", "soft"}) ==
          "--shadows 'soft' is not 'exact', 'paper', 'none' or 'auto'");
    CHECK(flag_error(scene, {"--shots", "x"}) == "expected an integer for --shots, found 'x'");
    CHECK_THAT(flag_error(scene, {"--ambient", "maybe"}),
               Catch::Contains("--ambient 'maybe' is neither 'true' nor 'false'"));
}

TEST_CASE("options: the usage text lists every flag with its range and default", "[options]") {
    // The text is wrapped: compare with its blanks and line breaks folded to single spaces.
    std::string usage;
    for (char c : solver_options_usage()) {
        const bool blank = c == ' ' || c == '\n';
        if (!(blank && !usage.empty() && usage.back() == ' ')) usage += blank ? ' ' : c;
    }
    const SolverSettings defaults;
    for (const OptionSpec& o : option_table()) {
        CAPTURE(o.name);
        CHECK_THAT(usage, Catch::Contains(" " + o.flag() + " " + o.unit));
        for (const std::string& alias : o.aliases) CHECK_THAT(usage, Catch::Contains(alias));
        CHECK_THAT(usage, Catch::Contains(o.doc + "; " + o.range_text() + ", default " +
                                          o.value_text(defaults) + " (`set " + o.name + "`)"));
    }
}

TEST_CASE("options: docs/scene-format.md holds the option table", "[options]") {
    std::ifstream in(std::string(MBR_SOURCE_DIR) + "/docs/scene-format.md");
    REQUIRE(in);
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string doc = ss.str();
    const std::string begin = "<!-- option table: begin", end = "<!-- option table: end -->";
    const size_t a = doc.find(begin), b = doc.find(end);
    REQUIRE(a != std::string::npos);
    REQUIRE(b != std::string::npos);
    const size_t first = doc.find('\n', a) + 1;
    const std::string table = doc.substr(first, b - first);
    CHECK(table == option_table_markdown());
}

TEST_CASE("options: solver_options turns each choice into the solver's own", "[options]") {
    SolverSettings s;
    s.shadows = ShadowSetting::Paper;
    s.extrapolation = ExtrapolationSetting::Higher;
    s.unify = UnifySetting::Paper;
    s.contact_oracle = OracleSetting::Means;  // neither default, and not each other
    s.oracle = OracleSetting::Interpolation;
    s.shadow_rays = 9;
    const SolverOptions o = solver_options(s);
    CHECK(o.receiver.shadows.method == ShadowMethod::Fractions);
    CHECK(o.receiver.extrapolation == Extrapolation::Quadratic);
    CHECK_FALSE(o.receiver.unify_by_projection);
    CHECK(o.receiver.contact_oracle_test == OracleTest::Means);
    CHECK(o.receiver.oracle_test == OracleTest::Interpolation);
    CHECK(o.receiver.shadows.rays_per_patch == 9);
    s.shadows = ShadowSetting::None;
    CHECK(solver_options(s).receiver.shadows.method == ShadowMethod::None);
    const SolverOptions d = solver_options(SolverSettings{});
    CHECK(d.receiver.shadows.method == ShadowMethod::Exact);
    CHECK(d.receiver.unify_by_projection);
    CHECK(d.receiver.extrapolation == Extrapolation::Linear);
    CHECK(d.receiver.oracle_test == OracleTest::Hybrid);
    CHECK(d.receiver.contact_oracle_test == OracleTest::Interpolation);
    CHECK(d.receiver.shadows.kernel_weighted);  // `set fraction_rays kernel`, the default
    s.fraction_rays = FractionRaysSetting::Area;
    CHECK_FALSE(solver_options(s).receiver.shadows.kernel_weighted);
    CHECK_FALSE(ShadowOptions{}.kernel_weighted);  // a transfer of its own keeps the paper's
}
