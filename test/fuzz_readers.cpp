// test/fuzz_readers.cpp - the long-running fuzz driver for every reader of outside
// data: scene files, OBJ, MTL, solution files and probe CSVs (docs/fuzzing.md). g++ has no
// libFuzzer, so this is a deterministic mutation loop: seed corpora, seeded mutations
// (test/fuzz_mutate.h plus extreme numbers), each input written to a file and read the way the
// programs read it; first, each reader is also given what is not a file of lines (a folder,
// /dev/zero, a FIFO) and a line one byte over its limit. The
// only accepted failure is an InputError; any other exception, a broken promise of the readers,
// an input slower than --slow seconds, or (in the MBR_SANITIZE build) a sanitizer report is a
// find. Not part of mbr_tests and not a CTest test: it runs for minutes.
//
//   mbr_fuzz_readers [--inputs N] [--seed S] [--reader scene|obj|mtl|solution|probe|all]
//                    [--finds DIR] [--slow SECONDS]
//
// Input i of reader r is made by its own generator, seeded from (S, r, i), so one input can be
// replayed alone: --reader r --first i --inputs 1.
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "math/check.h"
#include "octree/octree.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"
#include "test/file_bytes.h"
#include "test/fuzz_mutate.h"

namespace fs = std::filesystem;
using namespace mbr;

namespace {

const std::string scenes_dir = std::string(MBR_SOURCE_DIR) + "/examples/scenes/";

std::string read_text(const fs::path& path) { return test::read_bytes(path.string()); }

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

/// Numbers at the edges of what text can say, beyond the test's list: the readers must refuse
/// or clamp every one of them without overflow, huge allocations or hangs.
const char* const extreme[] = {"1e308",
                               "-1e308",
                               "1e-308",
                               "-0",
                               "nan",
                               "-nan",
                               "inf",
                               "-inf",
                               "1e400",
                               "4.9e-324",
                               "2147483647",
                               "-2147483648",
                               "2147483648",
                               "9223372036854775807",
                               "18446744073709551616",
                               "14",
                               "15",
                               "30",
                               "31",
                               "1024",
                               "1025",
                               "0x10",
                               "1e8",
                               "100000001",
                               "1073741824",
                               "8",
                               "9"};

/// Replaces one whitespace-separated numeric token by an extreme value.
std::string replace_number(std::string text, std::mt19937_64& rng) {
    std::vector<size_t> starts;
    for (size_t i = 0; i < text.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        if ((std::isdigit(c) || c == '-' || c == '.') &&
            (i == 0 || std::isspace(static_cast<unsigned char>(text[i - 1]))))
            starts.push_back(i);
    }
    if (starts.empty()) return text;
    const size_t s = starts[rng() % starts.size()];
    size_t end = s;
    while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
    text.replace(s, end - s, extreme[rng() % std::size(extreme)]);
    return text;
}

/// One input: the test's mutations, sometimes followed by extreme numbers.
std::string make_input(const std::string& base, std::mt19937_64& rng) {
    std::string text = rng() % 4 == 0 ? base : fuzz_input::mutate(base, rng);
    for (int n = int(rng() % 3); n > 0; --n) text = replace_number(text, rng);
    return text;
}

/// What the readers promise about every scene they return; an empty string when it holds.
std::string scene_problem(const Scene& s) {
    if (s.surfaces.empty()) return "a scene without surfaces";
    std::set<std::string> names;
    for (const SceneSurface& x : s.surfaces) {
        if (!names.insert(x.name).second) return "two surfaces named " + x.name;
        if (x.material < 0 || size_t(x.material) >= s.materials.size())
            return "surface " + x.name + " has material index " + std::to_string(x.material);
        const double a = x.surface.area();
        if (!std::isfinite(a) || a <= 0)
            return "surface " + x.name + " has area " + std::to_string(a);
    }
    for (const Material& m : s.materials)
        for (int c = 0; c < 3; ++c)
            if (!(m.reflectance.minimum()[c] >= 0 && m.reflectance.maximum()[c] < 1 &&
                  m.emission.minimum()[c] >= 0))
                return "a material out of range";
    if (s.settings.min_depth > s.settings.max_depth) return "min_depth > max_depth";
    return "";
}

using fuzz_input::obj_sample;

/// A reader under test: its seed corpus and how one input file is read. `read` returns a
/// problem (empty when the result keeps the reader's promises) or throws.
struct Target {
    std::string name;
    std::vector<std::string> corpus;
    fs::path file;  // where each input is written
    std::function<std::string(const fs::path&)> read;
    size_t max_line = 65536;  // the reader's line limit, for the over-long line
};

/// Inputs that are not files of lines, put where the target reads its input, each refused with
/// an InputError (without reading /dev/zero to its end or waiting on the FIFO), and a first
/// line one byte over the limit before the seed. Returns the finds as "what: problem".
std::vector<std::string> special_inputs(const Target& t, double slow) {
    std::vector<std::string> finds;
    const auto check = [&](const std::string& what) {
        const auto t0 = std::chrono::steady_clock::now();
        std::string find;
        try {
            find = t.read(t.file);
            if (find.empty()) find = "accepted";
        } catch (const InputError& e) {
            if (e.message().empty()) find = "an InputError without a message";
        } catch (const std::exception& e) {
            find = std::string("not an InputError: ") + e.what();
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (find.empty() && seconds > slow) find = "slow: " + std::to_string(seconds) + " s";
        if (!find.empty()) finds.push_back(what + ": " + find);
    };
    std::error_code ec;
    fs::remove_all(t.file, ec);
    fs::create_directory(t.file, ec);
    check("a folder");
    fs::remove_all(t.file, ec);
    fs::create_symlink("/dev/zero", t.file, ec);
    if (!ec) check("/dev/zero");
    fs::remove_all(t.file, ec);
    if (::mkfifo(t.file.c_str(), 0600) == 0) check("a FIFO");
    fs::remove_all(t.file, ec);
    write_text(t.file, std::string(t.max_line + 1, '7') + "\n" + t.corpus[0]);
    check("a line of " + std::to_string(t.max_line + 1) + " bytes");
    fs::remove_all(t.file, ec);
    return finds;
}

struct Counts {
    long inputs = 0, accepted = 0, refused = 0, finds = 0;
};

long number_arg(int argc, char** argv, const std::string& flag, long def) {
    for (int i = 1; i + 1 < argc; ++i)
        if (argv[i] == flag) return std::stol(argv[i + 1]);
    return def;
}
std::string text_arg(int argc, char** argv, const std::string& flag, const std::string& def) {
    for (int i = 1; i + 1 < argc; ++i)
        if (argv[i] == flag) return argv[i + 1];
    return def;
}

}  // namespace

int main(int argc, char** argv) {
    const long n_inputs = number_arg(argc, argv, "--inputs", 100000);
    const long first = number_arg(argc, argv, "--first", 0);
    const std::uint64_t seed = std::uint64_t(number_arg(argc, argv, "--seed", 1));
    const std::string only = text_arg(argc, argv, "--reader", "all");
    const double slow = double(number_arg(argc, argv, "--slow", 2));

    // A scratch folder with the files the seeds name (texture, MTL library, included scene).
    const fs::path dir =
        fs::temp_directory_path() / ("mbr_fuzz_readers_" + std::to_string(long(getpid())));
    const fs::path finds = text_arg(argc, argv, "--finds", (dir / "finds").string());
    fs::create_directories(dir);
    fs::create_directories(finds);
    for (const char* f : {"picture.png", "cornell_box.mtl", "parallel_squares.scene"})
        fs::copy_file(scenes_dir + f, dir / f, fs::copy_options::overwrite_existing);

    // The solution seed: a tiny solve of the parallel squares, saved.
    Scene squares = load_scene(scenes_dir + "parallel_squares.scene");
    SolverOptions so = solver_options(squares.settings);
    so.receiver.min_depth = 1;
    so.receiver.max_depth = 2;
    so.max_shots = 1;
    const Solution solution = solve(squares, build_octree(squares), so);
    std::ostringstream saved;
    save_solution(saved, squares, solution);

    std::vector<Target> targets;
    {
        Target t{"scene", {}, dir / "fuzz.scene", nullptr};
        for (const fs::path& p : fs::directory_iterator(scenes_dir))
            if (p.extension() == ".scene") t.corpus.push_back(read_text(p));
        t.read = [](const fs::path& f) { return scene_problem(load_scene(f.string())); };
        targets.push_back(t);
    }
    targets.push_back({"obj",
                       {obj_sample, read_text(scenes_dir + "cornell_box.obj")},
                       dir / "fuzz.obj",
                       [](const fs::path& f) { return scene_problem(load_obj(f.string())); }});
    {
        // MTL libraries are read through the OBJ that names them.
        const fs::path obj = dir / "m.obj";
        write_text(obj,
                   "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl white\n"
                   "f 1 2 3 4\nusemtl light\nf 4 3 2 1\n");
        targets.push_back(
            {"mtl",
             {read_text(scenes_dir + "cornell_box.mtl") +
              "newmtl tex\nKa 0.1 0.1 0.1\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1 picture.png\n"
              "Ke 0.1 0.1 0.1\nmap_Ke picture.png\nNs 10\nd 1\nillum 2\n"},
             dir / "m.mtl",
             [obj](const fs::path&) { return scene_problem(load_obj(obj.string())); }});
    }
    targets.push_back({"solution",
                       {saved.str()},
                       dir / "fuzz.solution",
                       [&squares](const fs::path& f) -> std::string {
                           const Solution s = load_solution(f.string(), squares);
                           if (s.radiosity.size() != squares.surfaces.size() ||
                               s.unshot.size() != squares.surfaces.size())
                               return "a solution of the wrong size";
                           return "";
                       },
                       size_t(1) << 26});
    targets.push_back({"probe",
                       {"name,x,y,z\na,0.5,0.5,0\nb,0.25,0.75,1\n",
                        "\xEF\xBB\xBFName , X,y,Z,nx,ny,nz,note\r\np,0.5,0.5,0,0,0,1,x\r\n"},
                       dir / "fuzz.csv",
                       [](const fs::path& f) -> std::string {
                           const std::vector<ProbePoint> points = read_probe_points(f.string());
                           for (const ProbePoint& p : points)
                               if (!(std::fabs(p.position.x) <= max_coordinate &&
                                     std::fabs(p.position.y) <= max_coordinate &&
                                     std::fabs(p.position.z) <= max_coordinate))
                                   return "a point beyond the coordinate limit";
                           return points.empty() ? "no points" : "";
                       }});

    std::cout << "mbr_fuzz_readers: seed " << seed << ", scratch folder " << dir
              << " (a crash leaves its input there), finds in " << finds << std::endl;
    int n_selected = 0;
    for (const Target& t : targets) n_selected += (only == "all" || only == t.name);
    if (n_selected == 0) {
        std::cerr << "unknown --reader " << only << "\n";
        return 2;
    }
    Counts total;
    const auto start_all = std::chrono::steady_clock::now();
    for (size_t r = 0; r < targets.size(); ++r) {
        const Target& t = targets[r];
        if (only != "all" && only != t.name) continue;
        Counts c;
        const long n = n_inputs / n_selected;
        const auto start = std::chrono::steady_clock::now();
        if (first == 0)
            for (const std::string& find : special_inputs(t, slow)) {
                ++c.finds;
                std::cout << "FIND " << t.name << " " << find << std::endl;
            }
        for (long i = first; i < first + n; ++i) {
            std::seed_seq ss{std::uint32_t(seed), std::uint32_t(seed >> 32), std::uint32_t(r),
                             std::uint32_t(i), std::uint32_t(i >> 32)};
            std::mt19937_64 rng(ss);
            const std::string text = make_input(t.corpus[size_t(i) % t.corpus.size()], rng);
            write_text(t.file, text);
            ++c.inputs;
            std::string find;
            const auto t0 = std::chrono::steady_clock::now();
            try {
                find = t.read(t.file);
                if (find.empty()) ++c.accepted;
            } catch (const InputError& e) {
                if (e.message().empty()) find = "an InputError without a message";
                ++c.refused;
            } catch (const std::exception& e) {
                find = std::string("not an InputError: ") + e.what();
            }
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (find.empty() && seconds > slow) find = "slow: " + std::to_string(seconds) + " s";
            if (!find.empty()) {
                ++c.finds;
                const fs::path keep =
                    finds / (t.name + "_" + std::to_string(i) + t.file.extension().string());
                write_text(keep, text);
                std::cout << "FIND " << t.name << " input " << i << ": " << find << " (saved to "
                          << keep << ")" << std::endl;
            }
        }
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%-9s inputs %ld  accepted %ld  refused %ld  finds %ld  (%.1f s)\n",
                    t.name.c_str(), c.inputs, c.accepted, c.refused, c.finds, seconds);
        total.inputs += c.inputs;
        total.accepted += c.accepted;
        total.refused += c.refused;
        total.finds += c.finds;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_all).count();
    std::printf("%-9s inputs %ld  accepted %ld  refused %ld  finds %ld  (%.1f s)\n", "total",
                total.inputs, total.accepted, total.refused, total.finds, seconds);
    std::error_code ec;
    for (const fs::path& p : fs::directory_iterator(dir))
        if (p != finds) fs::remove(p, ec);
    if (fs::is_empty(finds, ec)) fs::remove_all(dir, ec);
    return total.finds == 0 ? 0 : 1;
}
