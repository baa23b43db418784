// examples/studies/scene_scaling.cpp - how the cost of reading a scene, building the paper's octree
// (section 6, "Octree") and casting rays grows with the number of surfaces. The paper claims that
// the method's cost grows linearly with the scene; this program measures the stages around the
// solver, and leaves a column for the solver itself (see "SOLVE HOOK" below).
//
// For each size N it generates a deterministic scene of about N planar quads: a room (a box seen
// from inside, 6 quads), a lamp under its ceiling, and a square grid of small boxes of varying
// height on the floor, each written as six `quad` statements. The same boxes are also written as
// an OBJ file (one group per box, four vertices per face, negative indices) and read through a
// scene's `obj` statement. The files go to a fresh temporary folder that is removed at the end.
//
// Per N it reports:
// - parse_s        load_scene of the all-`quad` scene file (wall-clock seconds)
// - obj_parse_s    load_scene of the scene that imports the boxes with `obj`
// - octree_s       build_octree on the parsed scene, with the nodes, leaves and depth
// - closest_per_s  closest_hit rays per second (one thread): origins uniform in the room,
//                  directions uniform on the sphere
// - shadow_per_s   any_hit segments per second (one thread) between two points drawn uniformly
//                  by area over all polygons, the ends excluded by 1e-6 of the segment
// - solve_s        with --solve-shots K, for sizes up to --solve-max: the progressive solver
//                  (radiosity/solver/solver.h) at the scene's settings for exactly K shots (no
//                  convergence stop, no ambient correction, so that every size does the same
//                  number of shots), with its transfers, kernel evaluations and shadow rays;
//                  shots_s is the time in the shots, setup_s the rest (the emission's
//                  projection and the hidden-region masks of every surface,
//                  radiosity/visibility/hidden_regions.h). The lamp shoots first, then the
//                  brightest walls and block tops; each shot reaches every surface in front of its
//                  shooter, so the transfers per shot, and the cost of a linear method, grow in
//                  proportion to N.
// A cost per quad (seconds / N) that stays flat as N grows is linear behaviour.
//
// Run:    scene_scaling [--sizes 1000,10000,100000,200000] [--rays N] [--seed S] [--keep]
//                       [--solve-shots K] [--solve-max N] [--solve-shadows M] [--csv]
// Expect: parse and octree seconds close to proportional to N: about 3-8 microseconds per quad
//         to parse and 1.5-5 to build the octree (200,000 quads: parse 1-1.5 s, octree 0.5-0.8 s
//         on two shared cores; before name look-ups were hashed, parsing took 163 s). Ray rates
//         fall slowly with N (about 3x from 1,000 to 200,000 quads: deeper trees, more cache
//         misses).
//         --solve-shots 2 (no shadows, two cores): 1000, 3000, 10000 quads take 11.2, 42.8,
//         237 s in the shots (1199, 3549, 11755 transfers; 1.9, 2.7, 4.7 million kernel
//         evaluations per transfer) and a small setup (the hidden regions are found through the
//         octree's contacts: 0.02 s at 1000 quads, 0.06 s at 10000). The lamp stays 1 x 1 while
//         the room grows, so the absolute tolerance (the scene's `tolerance` times emitted power
//         over total area) falls as 1/N and each transfer works harder: at 10000 quads with
//         the absolute tolerance of 1000 (mbr probe --tolerance 0.018176 on the kept file) the
//         2 shots take 94 s, 1.8 million evaluations per transfer. --solve-shadows paper: 100,
//         300, 1000, 3000, 10000 quads take 7.6, 25.7, 72, 204, 1260 s; exact: 100 quads had
//         not finished the floor's shot after 6 minutes. (docs/method.md, "Scaling with the
//         scene".)
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "math/check.h"
#include "octree/octree.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"

namespace {

namespace fs = std::filesystem;
using mbr::Vec3;

const char* usage =
    "usage: scene_scaling [--sizes N1,N2,...] [--rays R] [--seed S] [--keep]\n"
    "                     [--solve-shots K] [--solve-max N] [--solve-shadows M] [--csv]\n"
    "  Generates scenes of about N planar quads (a room with a grid of small boxes on its\n"
    "  floor), writes each as a .scene file of `quad` statements and as a scene importing the\n"
    "  boxes from an OBJ file, and reports per N the seconds to parse both, the seconds to\n"
    "  build the octree, its nodes and depth, and closest-hit and shadow rays per second.\n"
    "  --sizes N1,N2,...  numbers of quads, each 13..2000000 (default 1000,10000,100000,200000)\n"
    "  --rays R           rays of each kind per size, 1..100000000 (default 100000)\n"
    "  --seed S           seed of the random rays, 0..2147483647 (default 1)\n"
    "  --keep             keep the generated files (their folder is printed on stderr)\n"
    "  --solve-shots K    also solve each scene for exactly K shots, 0..1000 (default 0: no\n"
    "                     solve), and report the seconds, transfers, kernel evaluations and rays\n"
    "  --solve-max N      solve only the sizes up to N quads (default 1000; solving is the slow\n"
    "                     part)\n"
    "  --solve-shadows M  none (default), paper or exact: the solve's shadow method\n"
    "  --csv              one CSV row per size\n";

// === Scene generation

/// One axis-aligned box: its corners and the number it is named by.
struct Block {
    Vec3 lo, hi;
};

/// The generated geometry: a room of side `side` (height 2) and the blocks on its floor.
struct Layout {
    double side = 0;
    std::vector<Block> blocks;
};

/// Blocks in a square grid of pitch 1, each 0.6 x 0.6 with a height in [0.2, 1.0) drawn from
/// its index by a multiplicative hash (deterministic, and independent of N for a given index).
Layout make_layout(int n_quads) {
    Layout layout;
    const int n_blocks = std::max(0, (n_quads - 7 + 5) / 6);  // room 6 + lamp 1 + 6 per block
    const int k = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(n_blocks)))));
    layout.side = k;
    for (int i = 0; i < n_blocks; ++i) {
        const int row = i / k, col = i % k;
        const std::uint32_t hash = static_cast<std::uint32_t>(i) * 2654435761u;
        const double height = 0.2 + 0.8 * double(hash % 1000u) / 1000.0;
        const Vec3 lo{col + 0.2, 0, row + 0.2};
        layout.blocks.push_back({lo, lo + Vec3{0.6, height, 0.6}});
    }
    return layout;
}

/// The six outward-facing quads of a box, corners counter-clockwise seen from outside (the
/// rule of the scene format's `box`: eb x ec points along +axis a).
std::vector<std::array<Vec3, 4>> block_quads(const Block& b) {
    std::vector<std::array<Vec3, 4>> quads;
    for (int a = 0; a < 3; ++a)
        for (int side = 0; side < 2; ++side) {
            const int ib = (a + 1) % 3, ic = (a + 2) % 3;
            Vec3 base = b.lo;
            if (side == 1) base[a] = b.hi[a];
            Vec3 eb, ec;
            eb[ib] = b.hi[ib] - b.lo[ib];
            ec[ic] = b.hi[ic] - b.lo[ic];
            const Vec3 e_u = side == 1 ? eb : ec, e_v = side == 1 ? ec : eb;
            quads.push_back({base, base + e_u, base + e_u + e_v, base + e_v});
        }
    return quads;
}

void write_point(std::ostream& os, Vec3 p) {
    os << ' ' << p.x << ' ' << p.y << ' ' << p.z;
}

/// The header both scene files share: materials, the room and the lamp.
void write_room(std::ostream& os, const Layout& layout) {
    const double s = layout.side, c = 0.5 * s;
    os << "# generated by scene_scaling\n"
       << "material wall reflectance 0.7 0.7 0.7\n"
       << "material block reflectance 0.5 0.55 0.6\n"
       << "material lamp reflectance 0.8 0.8 0.8 emission 10 10 10\n"
       << "box room wall 0 0 0 " << s << " 2 " << s << " inward\n"
       << "rectangle lamp lamp " << c - 0.5 << " 1.99 " << c - 0.5 << "  1 0 0  0 0 1\n";
}

/// Writes `writer(os)` to `path`, failing loudly on any stream error (a full disk).
template <typename Writer>
void write_file(const fs::path& path, Writer&& writer) {
    std::ofstream os(path, std::ios::binary);
    if (!os) throw std::runtime_error("cannot create " + path.string());
    os.precision(10);
    writer(os);
    os.close();
    if (!os) throw std::runtime_error("cannot write " + path.string());
}

/// The files of one size: the all-`quad` scene and the scene importing an OBJ.
struct SceneFiles {
    fs::path quads, with_obj;
    double megabytes = 0;
};

SceneFiles write_scene_files(const fs::path& dir, int n_quads, const Layout& layout) {
    SceneFiles files;
    const std::string stem = "n" + std::to_string(n_quads);
    files.quads = dir / (stem + ".scene");
    files.with_obj = dir / (stem + "_obj.scene");
    const fs::path obj = dir / (stem + ".obj");
    write_file(files.quads, [&](std::ostream& os) {
        write_room(os, layout);
        for (size_t i = 0; i < layout.blocks.size(); ++i) {
            const char* faces[] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
            int f = 0;
            for (const auto& q : block_quads(layout.blocks[i])) {
                os << "quad b" << i << '.' << faces[f++] << " block";
                for (Vec3 p : q) write_point(os, p);
                os << '\n';
            }
        }
    });
    write_file(obj, [&](std::ostream& os) {
        os << "# generated by scene_scaling: one group per block\n";
        for (size_t i = 0; i < layout.blocks.size(); ++i) {
            os << "g b" << i << '\n';
            for (const auto& q : block_quads(layout.blocks[i])) {
                for (Vec3 p : q) {
                    os << 'v';
                    write_point(os, p);
                    os << '\n';
                }
                os << "f -4 -3 -2 -1\n";
            }
        }
    });
    write_file(files.with_obj, [&](std::ostream& os) {
        write_room(os, layout);
        // OBJ faces without `usemtl` take obj_default; defining it here colours them.
        os << "material obj_default reflectance 0.5 0.55 0.6\n"
           << "obj " << obj.filename().string() << '\n';
    });
    files.megabytes = double(fs::file_size(files.quads)) / 1e6;
    return files;
}

/// A fresh folder under the system's temporary folder, removed when this goes out of scope
/// (unless kept).
class TempFolder {
public:
    TempFolder() {
        const fs::path base = fs::temp_directory_path();
        for (int attempt = 0; attempt < 100; ++attempt) {
            fs::path p = base / ("mbr_scene_scaling_" + std::to_string(::getpid()) + "_" +
                                 std::to_string(attempt));
            std::error_code ec;
            if (fs::create_directory(p, ec)) {
                path_ = p;
                return;
            }
        }
        throw std::runtime_error("cannot create a temporary folder in " + base.string());
    }
    ~TempFolder() {
        std::error_code ec;
        if (!keep_) fs::remove_all(path_, ec);
    }
    TempFolder(const TempFolder&) = delete;
    TempFolder& operator=(const TempFolder&) = delete;
    const fs::path& path() const { return path_; }
    void keep() { keep_ = true; }

private:
    fs::path path_;
    bool keep_ = false;
};

// === Rays

Vec3 random_direction(std::mt19937_64& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-6) return normalize(v);
    }
}

/// A point uniform by area on the polygons: a polygon by area, a fan triangle by area, then a
/// uniform point in it.
class AreaSampler {
public:
    explicit AreaSampler(const std::vector<mbr::Polygon>& polygons) : polygons_(polygons) {
        double sum = 0;
        for (const mbr::Polygon& p : polygons) cumulative_.push_back(sum += p.area());
    }
    Vec3 point(std::mt19937_64& rng) const {
        std::uniform_real_distribution<double> u01(0, 1);
        const double a = u01(rng) * cumulative_.back();
        const size_t i = std::min<size_t>(
            std::upper_bound(cumulative_.begin(), cumulative_.end(), a) - cumulative_.begin(),
            cumulative_.size() - 1);
        const std::vector<Vec3>& v = polygons_[i].vertices();
        const size_t n = v.size();
        double total = 0;
        for (size_t k = 1; k + 1 < n; ++k) total += length(cross(v[k] - v[0], v[k + 1] - v[0]));
        double r = u01(rng) * total;
        size_t k = 1;
        for (; k + 2 < n; ++k) {
            const double t = length(cross(v[k] - v[0], v[k + 1] - v[0]));
            if (r < t) break;
            r -= t;
        }
        const double r1 = std::sqrt(u01(rng)), r2 = u01(rng);
        return (1 - r1) * v[0] + (r1 * (1 - r2)) * v[k] + (r1 * r2) * v[k + 1];
    }

private:
    const std::vector<mbr::Polygon>& polygons_;
    std::vector<double> cumulative_;
};

// === Measurements

struct Row {
    int n_quads = 0;
    size_t n_surfaces = 0;
    double megabytes = 0;
    double parse_s = 0, obj_parse_s = 0, octree_s = 0;
    int n_polygons = 0, n_nodes = 0, n_leaves = 0, depth = 0;
    double references_per_polygon = 0;
    double closest_per_s = 0, shadow_per_s = 0;
    double closest_hit_fraction = 0, shadow_hit_fraction = 0;
    bool solved = false;
    double solve_s = 0, shots_s = 0;
    long transfers = 0, kernel_evals = 0, shadow_rays = 0;
};

/// What the solve column measures.
struct SolveSettings {
    int shots = 0;                 // 0: no solve
    int max_quads = 0;             // sizes above this are not solved
    bool progress = false;         // one line per shot on stderr
    std::string shadows = "none";  // the scene setting `shadows`: none, paper or exact
};

Row measure(const fs::path& dir, int n_quads, int n_rays, int seed, const SolveSettings& solve) {
    Row row;
    row.n_quads = n_quads;
    const Layout layout = make_layout(n_quads);
    const SceneFiles files = write_scene_files(dir, n_quads, layout);
    row.megabytes = files.megabytes;

    double t0 = mbr::now_seconds();
    const mbr::Scene scene = mbr::load_scene(files.quads.string());
    row.parse_s = mbr::now_seconds() - t0;
    row.n_surfaces = scene.surfaces.size();

    t0 = mbr::now_seconds();
    const mbr::Scene scene_obj = mbr::load_scene(files.with_obj.string());
    row.obj_parse_s = mbr::now_seconds() - t0;
    if (scene_obj.surfaces.size() != scene.surfaces.size())
        throw std::runtime_error("the OBJ scene has " + std::to_string(scene_obj.surfaces.size()) +
                                 " surfaces, the quad scene " +
                                 std::to_string(scene.surfaces.size()));

    t0 = mbr::now_seconds();
    const mbr::Octree octree = mbr::build_octree(scene);
    row.octree_s = mbr::now_seconds() - t0;
    row.n_polygons = octree.polygon_count();
    row.n_nodes = octree.node_count();
    row.n_leaves = octree.leaf_count();
    row.depth = octree.depth();
    row.references_per_polygon = double(octree.reference_count()) / row.n_polygons;

    // Rays are drawn before the clock starts, so that only the queries are timed.
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    std::uniform_real_distribution<double> u01(0, 1);
    const double s = layout.side;
    std::vector<mbr::Ray> probes, segments;
    for (int i = 0; i < n_rays; ++i)
        probes.push_back(
            mbr::Ray{{u01(rng) * s, u01(rng) * 2, u01(rng) * s}, random_direction(rng)});
    const AreaSampler sampler(octree.polygons());
    for (int i = 0; i < n_rays; ++i) {
        const Vec3 p = sampler.point(rng), q = sampler.point(rng);
        segments.push_back(mbr::Ray{p, q - p, 1e-6, 1 - 1e-6});
    }
    long n_hits = 0;
    t0 = mbr::now_seconds();
    for (const mbr::Ray& r : probes) n_hits += octree.closest_hit(r).has_value();
    row.closest_per_s = n_rays / (mbr::now_seconds() - t0);
    row.closest_hit_fraction = double(n_hits) / n_rays;
    n_hits = 0;
    t0 = mbr::now_seconds();
    for (const mbr::Ray& r : segments) n_hits += octree.any_hit(r);
    row.shadow_per_s = n_rays / (mbr::now_seconds() - t0);
    row.shadow_hit_fraction = double(n_hits) / n_rays;

    if (solve.shots > 0 && n_quads <= solve.max_quads) {
        mbr::SolverSettings settings = scene.settings;
        mbr::apply_setting(settings, *mbr::find_option("shadows"), solve.shadows,
                           "--solve-shadows");
        mbr::SolverOptions options = mbr::solver_options(settings);
        options.max_shots = solve.shots;
        options.convergence = 0;  // never stop early: the same number of shots at every size
        options.ambient = false;  // its cost is not that of the paper's method
        t0 = mbr::now_seconds();
        const mbr::Solution solution = mbr::solve(
            scene, octree, options, [&](const mbr::ShotStats& shot, const mbr::ProgressiveSolver&) {
                if (solve.progress)
                    std::cerr << "scene_scaling: " << n_quads << " quads, shot " << shot.shot
                              << " from " << scene.surfaces[shot.shooter].name << ": "
                              << shot.receivers << " transfers, " << shot.kernel_evals
                              << " kernel evaluations, " << shot.rays << " rays, " << shot.seconds
                              << " s\n";
            });
        row.solve_s = mbr::now_seconds() - t0;
        row.solved = true;
        for (const mbr::ShotStats& shot : solution.stats.per_shot) {
            row.transfers += shot.receivers;
            row.shots_s += shot.seconds;
        }
        row.kernel_evals = solution.stats.kernel_evals;
        row.shadow_rays = solution.stats.rays;
    }
    return row;
}

std::vector<int> parse_sizes(const std::string& text) {
    std::vector<int> sizes;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        const double x = mbr::parse_number(item, "--sizes");
        // 13: the room, the lamp and one block (no block would leave the OBJ file empty).
        if (x != std::floor(x) || x < 13 || x > 2000000)
            throw mbr::UsageError("--sizes: each size must be an integer in 13..2000000, got '" +
                                  item + "'");
        sizes.push_back(static_cast<int>(x));
    }
    if (sizes.empty()) throw mbr::UsageError("--sizes needs at least one size");
    return sizes;
}

int run(mbr::Args& args) {
    const bool csv = args.flag("--csv");
    const bool keep = args.flag("--keep");
    const std::vector<int> sizes = parse_sizes(args.text("--sizes", "1000,10000,100000,200000"));
    const int n_rays = args.integer("--rays", 100000, 1, 100000000);
    const int seed = args.integer("--seed", 1, 0, 2147483647);
    SolveSettings solve;
    solve.shots = args.integer("--solve-shots", 0, 0, 1000);
    solve.max_quads = args.integer("--solve-max", 1000, 13, 2000000);
    solve.progress = !csv;
    solve.shadows = args.text("--solve-shadows", "none");
    if (solve.shadows != "none" && solve.shadows != "paper" && solve.shadows != "exact")
        throw mbr::UsageError("--solve-shadows must be none, paper or exact, got '" +
                              solve.shadows + "'");
    args.finish();
    if (!args.positional().empty()) throw mbr::UsageError("scene_scaling takes no file names");

    TempFolder dir;
    if (keep) {
        dir.keep();
        std::cerr << "scene_scaling: files kept in " << dir.path().string() << "\n";
    }
    mbr::Table table({"quads",
                      "surfaces",
                      "file_MB",
                      "parse_s",
                      "parse_us_per_quad",
                      "obj_parse_s",
                      "octree_s",
                      "octree_us_per_quad",
                      "polygons",
                      "nodes",
                      "leaves",
                      "depth",
                      "refs_per_polygon",
                      "closest_per_s",
                      "closest_hits",
                      "shadow_per_s",
                      "shadow_hits",
                      "solve_s",
                      "shots_s",
                      "setup_s",
                      "transfers",
                      "kernel_evals",
                      "shadow_rays"});
    for (int n : sizes) {
        const Row r = measure(dir.path(), n, n_rays, seed, solve);
        const double quads = double(r.n_surfaces);
        table.add_row({std::to_string(r.n_quads),
                       std::to_string(r.n_surfaces),
                       mbr::cell(r.megabytes, 2),
                       mbr::cell_g(r.parse_s, 3),
                       mbr::cell(1e6 * r.parse_s / quads, 2),
                       mbr::cell_g(r.obj_parse_s, 3),
                       mbr::cell_g(r.octree_s, 3),
                       mbr::cell(1e6 * r.octree_s / quads, 2),
                       std::to_string(r.n_polygons),
                       std::to_string(r.n_nodes),
                       std::to_string(r.n_leaves),
                       std::to_string(r.depth),
                       mbr::cell(r.references_per_polygon, 2),
                       mbr::cell_g(r.closest_per_s, 3),
                       mbr::cell(r.closest_hit_fraction, 3),
                       mbr::cell_g(r.shadow_per_s, 3),
                       mbr::cell(r.shadow_hit_fraction, 3),
                       r.solved ? mbr::cell_g(r.solve_s, 3) : "",
                       r.solved ? mbr::cell_g(r.shots_s, 3) : "",
                       r.solved ? mbr::cell_g(r.solve_s - r.shots_s, 3) : "",
                       r.solved ? std::to_string(r.transfers) : "",
                       r.solved ? std::to_string(r.kernel_evals) : "",
                       r.solved ? std::to_string(r.shadow_rays) : ""});
        if (!csv) std::cerr << "scene_scaling: " << n << " quads done\n";
    }
    if (csv) {
        table.write_csv(std::cout);
        return 0;
    }
    std::cout << "Scenes of N quads: a room, a lamp and a grid of boxes; " << n_rays
              << " rays of each kind, seed " << seed << ", one thread.\n"
              << "parse_s: the scene of `quad` statements; obj_parse_s: the same boxes through "
                 "`obj`; solve_s: "
              << (solve.shots > 0 ? std::to_string(solve.shots) + " shots up to " +
                                        std::to_string(solve.max_quads) + " quads"
                                  : std::string("not measured (--solve-shots K)"))
              << ".\n\n";
    table.write_text(std::cout);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, run);
}
