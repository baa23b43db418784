// test/test_scene_fuzz.cpp - the scene and OBJ/MTL readers never crash or hang: thousands
// of randomly mutated inputs (byte flips, insertions, deletions, duplicated and swapped lines,
// numbers replaced by huge, tiny, NaN or negative values, truncation), seeded and reproducible.
// Every outcome must be a valid Scene or an InputError; anything else, or one input taking
// more than a second, fails with the seed and the iteration so the case can be replayed.
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "math/check.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/solver/solver.h"
#include "test/file_bytes.h"
#include "test/fuzz_mutate.h"

using namespace mbr;

namespace {

const std::string scenes_dir = std::string(MBR_SOURCE_DIR) + "/examples/scenes/";

using test::read_bytes;

/// A scene that uses every statement, so mutations reach every branch of the reader.
const std::string every_statement =
    "material plain reflectance 0.2 0.3 0.4\n"
    "material chk reflectance checker 3 0.1 0.1 0.1 0.7 0.7 0.7 emission 0 0 0\n"
    "material img reflectance image picture.png emission image picture.png scale 2 2 2\n"
    "material lamp emission 5 5 5   # a comment\n"
    "quad q plain 0 0 0  1 0 0  1 1 0  0 1 0\n"
    "bilinear b plain 0 0 0  1 0 0  1 1 1  0 1 0\n"
    "rectangle r chk 0 0 2  1 0 0  0 1 0\n"
    "box x img 0 0 3  1 1 4\n"
    "cylinder c plain 0 0 0  0 0 1  1 0 0  0.5 2  0 180 inward\n"
    "sphere s lamp 3 3 3  0 0 1  1 0 0  0.5  0 180  0 360\n"
    "disk d plain 0 0 0  0 0 1  1 0 0  0 1  0 360\n"
    "include parallel_squares.scene\n"
    "camera eye 0 -10 0 look_at 0 0 0 up 0 0 1 fov 60 size 320 200\n"
    "set order 3\nset min_depth 2\nset max_depth 5\nset oracle_tolerance 1e-4\n"
    "set truncation_eps 1e-7\nset rhombus_radius 20\nset extrapolation higher\n"
    "set shadow_rays 8\nset convergence 0.01\nset self_transfer true\n"
    "set tessellation 8\n";

using fuzz_input::obj_sample;

using fuzz_input::mutate;

/// What the readers promise about every scene they return.
void check_scene(const Scene& s) {
    REQUIRE(!s.surfaces.empty());
    std::set<std::string> names;
    for (const SceneSurface& x : s.surfaces) {
        INFO("surface " << x.name);
        REQUIRE(names.insert(x.name).second);  // names are unique, OBJ group numbering included
        REQUIRE(x.material >= 0);
        REQUIRE(size_t(x.material) < s.materials.size());
        double a = x.surface.area();
        REQUIRE(std::isfinite(a));
        REQUIRE(a > 0);
    }
    for (const Material& m : s.materials) {
        for (int c = 0; c < 3; ++c) {
            REQUIRE(m.reflectance.minimum()[c] >= 0);
            REQUIRE(m.reflectance.maximum()[c] < 1);
            REQUIRE(m.emission.minimum()[c] >= 0);
        }
    }
    REQUIRE(s.settings.min_depth <= s.settings.max_depth);
}

/// Longer or different runs for hunting bugs by hand: MBR_FUZZ_ROUNDS multiplies the number of
/// inputs, MBR_FUZZ_SEED is added to every seed. The defaults are what CTest runs.
long env_number(const char* name, long def) {
    const char* text = std::getenv(name);
    return text ? std::strtol(text, nullptr, 10) : def;
}

/// Runs `parse` on `n` mutations of each seed text; counts accepted and refused inputs.
template <class Parse>
void fuzz(const std::vector<std::string>& seeds, int n, uint64_t seed, Parse parse, int& n_accepted,
          int& n_refused) {
    seed += uint64_t(env_number("MBR_FUZZ_SEED", 0));
    long rounds = std::max(1L, env_number("MBR_FUZZ_ROUNDS", 1));
    n = int(std::min(long(n) * rounds, 100000000L));
    std::mt19937_64 rng(seed);
    for (int i = 0; i < n; ++i) {
        const std::string& base = seeds[size_t(i) % seeds.size()];
        std::string text = mutate(base, rng);
        auto start = std::chrono::steady_clock::now();
        try {
            Scene s = parse(text);
            check_scene(s);
            ++n_accepted;
        } catch (const InputError& e) {
            CHECK(!e.message().empty());
            ++n_refused;
        } catch (const std::exception& e) {
            FAIL("seed " << seed << ", iteration " << i << ": not an InputError: " << e.what()
                         << "\n--- input ---\n"
                         << text);
        }
        double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (seconds > 1.0)
            FAIL("seed " << seed << ", iteration " << i << " took " << seconds
                         << " s\n--- input ---\n"
                         << text);
    }
}

}  // namespace

TEST_CASE("scene_fuzz: mutated scene files give a Scene or an InputError", "[scene_fuzz]") {
    std::vector<std::string> seeds = {every_statement};
    for (const char* f : {"parallel_squares.scene", "perpendicular_squares.scene",
                          "three_strips.scene", "room.scene", "cornell_box.scene"})
        seeds.push_back(read_bytes(scenes_dir + f));
    for (const std::string& s : seeds) REQUIRE(!s.empty());
    int n_accepted = 0, n_refused = 0;
    const uint64_t seed = 20240601;
    fuzz(
        seeds, 6000, seed,
        [](const std::string& text) {
            std::istringstream in(text);
            return parse_scene(in, scenes_dir + "fuzz.scene");
        },
        n_accepted, n_refused);
    CAPTURE(n_accepted, n_refused);
    // Both outcomes must be common, or the mutations are too mild or too wild to test much.
    CHECK(n_accepted > 300);
    CHECK(n_refused > 3000);
}

TEST_CASE("scene_fuzz: mutated OBJ files give a Scene or an InputError", "[scene_fuzz][obj]") {
    std::vector<std::string> seeds = {obj_sample, read_bytes(scenes_dir + "cornell_box.obj")};
    // Strictly read, and forgiving: the same mutations (the same seed), which the forgiving
    // import must accept more often, never crashing.
    int n_accepted = 0, n_refused = 0, n_forgiven = 0, n_refused_forgiving = 0;
    for (const bool strict : {true, false})
        fuzz(
            seeds, 3000, 77,
            [strict](const std::string& text) {
                std::istringstream in(text);
                return parse_obj(in, scenes_dir + "fuzz.obj", ImportOptions{strict});
            },
            strict ? n_accepted : n_forgiven, strict ? n_refused : n_refused_forgiving);
    CAPTURE(n_accepted, n_refused, n_forgiven, n_refused_forgiving);
    CHECK(n_accepted > 300);
    CHECK(n_refused > 1000);
    CHECK(n_forgiven > n_accepted + 500);
}

TEST_CASE("scene_fuzz: mutated MTL files give a Scene or an InputError", "[scene_fuzz][obj]") {
    // MTL files are read from disk only: mutations go to a scratch folder with a copy of the
    // texture they may name.
    std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                ("mbr_test_scene_fuzz_" + std::to_string(long(getpid())));
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(scenes_dir + "picture.png", dir / "picture.png",
                               std::filesystem::copy_options::overwrite_existing);
    const std::string mtl_seed = read_bytes(scenes_dir + "cornell_box.mtl") +
                                 "newmtl tex\nKa 0.1 0.1 0.1\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1 "
                                 "picture.png\nKe 0.1 0.1 0.1\nmap_Ke picture.png\nNs 10\nd 1\n"
                                 "illum 2\n";
    const std::string obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl white\n"
        "f 1 2 3 4\nusemtl light\nf 4 3 2 1\n";
    const std::string obj_path = (dir / "m.obj").string();
    std::ofstream(obj_path, std::ios::binary) << obj;
    int n_accepted = 0, n_refused = 0;
    fuzz(
        {mtl_seed}, 800, 99,
        [&](const std::string& text) {
            std::ofstream((dir / "m.mtl").string(), std::ios::binary | std::ios::trunc) << text;
            return load_obj(obj_path, ImportOptions{true});
        },
        n_accepted, n_refused);
    // Forgiving, every mutation of the library gives a scene (the faces are always there).
    int n_forgiven = 0, n_refused_forgiving = 0;
    fuzz(
        {mtl_seed}, 800, 99,
        [&](const std::string& text) {
            std::ofstream((dir / "m.mtl").string(), std::ios::binary | std::ios::trunc) << text;
            return load_obj(obj_path);
        },
        n_forgiven, n_refused_forgiving);
    CAPTURE(n_forgiven, n_refused_forgiving);
    CHECK(n_refused_forgiving == 0);
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    CAPTURE(n_accepted, n_refused);
    CHECK(n_accepted > 50);
    CHECK(n_refused > 200);
}

TEST_CASE("scene_fuzz: a solution header naming a huge field is refused before allocating it",
          "[scene_fuzz][solution]") {
    // Found by mbr_fuzz_readers (test/data/fuzz_finds/): 'radiosity level 14' at
    // order 8 made load_solution allocate 3 x 2.7e8 coefficients (6 GiB) before it read the
    // coefficient line that could never hold them. The reproducer is saved for
    // examples/scenes/parallel_squares.scene, whose fingerprint it carries.
    const Scene scene = load_scene(scenes_dir + "parallel_squares.scene");
    const std::string path =
        std::string(MBR_SOURCE_DIR) + "/test/data/fuzz_finds/solution_level14.solution";
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in);
    try {
        load_solution(in, path, scene);
        FAIL("the damaged solution loaded");
    } catch (const InputError& e) {
        CHECK(e.line() == 6);  // the first coefficient line
        CHECK(std::string(e.message()).find("coefficients") != std::string::npos);
    }
}
