// examples/studies/octree_stats.cpp - the paper's octree (section 6, "Octree") over a scene: its
// size, and the work it saves ray queries against a loop over every polygon.
//
// The scene's surfaces are tessellated at its `tessellation` setting
// (radiosity/scene/scene_octree.h) and the octree is built over the polygons. Two kinds of seeded
// random rays are cast, each through the octree and through a brute-force loop over all polygons
// (Polygon::intersect on every one; any_hit stops at the first hit), and the answers are compared:
// - closest_hit (rendering): origins uniform in the scene's bounding box, directions uniform on
//   the sphere; they probe the tree everywhere, from inside and between the objects.
// - any_hit (shadow rays, eq. (28)): a segment between two points drawn uniformly by area on the
//   polygons of two different surfaces whose fronts face each other (the only pairs the kernel
//   (2) lets exchange energy, so the only ones the solver tests); the ends are excluded by 1e-6
//   of the segment, as a shadow ray leaving a surface must. If 1000 draws find no facing pair,
//   the last pair is used and counted as "unfacing".
// A disagreement is a different polygon or t (closest_hit) or a different yes/no (any_hit).
//
// The octree's pass can be timed several times (--repeat, the median is reported, for a shared
// machine) and only the first rays checked against the loop (--check, for scenes so large that
// the loop would take hours).
//
// Run:    octree_stats SCENE [--rays N] [--check N] [--repeat R] [--seed S] [--max-depth D]
//                            [--leaf-polygons P] [--tessellation T] [--csv]
//         e.g. build/examples/octree_stats examples/scenes/room.scene
// Expect: zero disagreements (exit status 1 otherwise). On the room (2558 polygons at
//         tessellation 24, 3819 nodes) 5.18 nodes and 4.85 polygon tests per closest-hit ray and
//         8.41 nodes and 6.71 tests per shadow segment instead of 2558 and 2345; on two shared
//         cores about 3.5 million rays per second of each kind with --repeat 5 (1.1 and 0.85
//         million before the flat layout of octree.h: 3.0 and 4.3 times fewer), a speed-up of
//         55-80 over the loop, which takes about 4 of the 4.5 seconds. On a 200,000-quad room
//         (33,333 boxes 0.07-0.13 wide and up to 3 tall, turned about the vertical, on the floor
//         of a 40 x 6 x 40 room) about 350,000 and 320,000 rays per second with --check 200, 2.1
//         and 2.4 times the pointer layout's (there the queries wait on memory). On the other
//         examples (2 to 17 polygons) the octree gains little: the loop over all polygons is as
//         fast (17 polygons) or twice as fast (2 and 4).
#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "math/check.h"
#include "octree/octree.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"

namespace {

const char* usage =
    "usage: octree_stats SCENE [--rays N] [--check N] [--repeat R] [--seed S] [--max-depth D]\n"
    "                          [--leaf-polygons P] [--tessellation T] [--csv]\n"
    "  Builds the paper's octree over the scene's polygons and times N random closest-hit rays\n"
    "  and N shadow-ray segments through it and through a loop over all polygons.\n"
    "  SCENE             a scene file (or an .obj file, imported)\n"
    "  --rays N          rays per query kind, 1..10000000 (default 100000)\n"
    "  --check N         the first N rays of each kind are also cast through the loop over\n"
    "                    all polygons and compared, 0..10000000 (default: all)\n"
    "  --repeat R        the octree's queries are timed R times, the median kept; 1..100\n"
    "                    (default 1)\n"
    "  --seed S          seed of the random rays, 0..2147483647 (default 1)\n"
    "  --max-depth D     deepest octree node, the root at 0; 0..24 (default 10)\n"
    "  --leaf-polygons P a node listing more polygons is split; 1..1000000 (default 8)\n"
    "  --tessellation T  facets per parameter direction of curved surfaces, 1..1024\n"
    "                    (default: the scene's)\n"
    "  --csv             one row per query kind, with the build numbers on every row\n";

using mbr::Vec3;

// Point sampling uniform by area over the polygons.
class AreaSampler {
public:
    explicit AreaSampler(const std::vector<mbr::Polygon>& polygons) : polygons_(polygons) {
        double sum = 0;
        for (const mbr::Polygon& p : polygons) cumulative_.push_back(sum += p.area());
    }
    /// A polygon index with probability proportional to its area.
    int pick(std::mt19937_64& rng) const {
        double a = std::uniform_real_distribution<double>(0, cumulative_.back())(rng);
        auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), a);
        return std::min(static_cast<int>(it - cumulative_.begin()),
                        static_cast<int>(cumulative_.size()) - 1);
    }
    /// A point uniform on polygon i: a fan triangle by area, then uniform in the triangle.
    Vec3 point(int i, std::mt19937_64& rng) const {
        std::uniform_real_distribution<double> u01(0, 1);
        const std::vector<Vec3>& v = polygons_[i].vertices();
        const int n = static_cast<int>(v.size());
        double total = 0;
        for (int k = 1; k + 1 < n; ++k) total += length(cross(v[k] - v[0], v[k + 1] - v[0]));
        double a = u01(rng) * total;
        int k = 1;
        for (; k + 2 < n; ++k) {
            double t = length(cross(v[k] - v[0], v[k + 1] - v[0]));
            if (a < t) break;
            a -= t;
        }
        double r1 = std::sqrt(u01(rng)), r2 = u01(rng);
        return (1 - r1) * v[0] + (r1 * (1 - r2)) * v[k] + (r1 * r2) * v[k + 1];
    }

private:
    const std::vector<mbr::Polygon>& polygons_;
    std::vector<double> cumulative_;
};

Vec3 random_direction(std::mt19937_64& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-6) return normalize(v);
    }
}

std::vector<mbr::Ray> closest_hit_rays(const mbr::Box3& box, int n, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<mbr::Ray> rays;
    rays.reserve(n);
    const Vec3 e = box.extent();
    for (int i = 0; i < n; ++i) {
        Vec3 o = box.lo + Vec3{u01(rng) * e.x, u01(rng) * e.y, u01(rng) * e.z};
        rays.push_back(mbr::Ray{o, random_direction(rng)});
    }
    return rays;
}

std::vector<mbr::Ray> shadow_segments(const std::vector<mbr::Polygon>& polygons, int n_surfaces,
                                      int n, std::mt19937_64& rng, int& n_unfacing) {
    const AreaSampler sampler(polygons);
    std::vector<mbr::Ray> rays;
    rays.reserve(n);
    n_unfacing = 0;
    for (int i = 0; i < n; ++i) {
        Vec3 p, q;
        bool facing = false;
        for (int attempt = 0; attempt < 1000 && !facing; ++attempt) {
            int a = sampler.pick(rng), b = sampler.pick(rng);
            p = sampler.point(a, rng);
            q = sampler.point(b, rng);
            facing = (n_surfaces == 1 || polygons[a].surface() != polygons[b].surface()) &&
                     dot(polygons[a].normal(), q - p) > 0 && dot(polygons[b].normal(), p - q) > 0;
        }
        if (!facing) ++n_unfacing;
        rays.push_back(mbr::Ray{p, q - p, 1e-6, 1 - 1e-6});
    }
    return rays;
}

// Brute force: every polygon tested; the smallest t wins, the lower index at equal t (the
// octree's rule).
std::optional<mbr::Hit> brute_closest(const std::vector<mbr::Polygon>& polygons,
                                      const mbr::Ray& ray) {
    std::optional<mbr::Hit> best;
    for (int i = 0; i < static_cast<int>(polygons.size()); ++i)
        if (std::optional<double> t = polygons[i].intersect(ray))
            if (!best || *t < best->t) {
                best = mbr::Hit{};
                best->polygon = i;
                best->t = *t;
            }
    return best;
}

bool brute_any(const std::vector<mbr::Polygon>& polygons, const mbr::Ray& ray, long& n_tests) {
    for (const mbr::Polygon& p : polygons) {
        ++n_tests;
        if (p.intersect(ray)) return true;
    }
    return false;
}

// One query kind's measurements.
struct QueryRow {
    std::string query;
    long n_rays = 0;
    long n_hits = 0;
    mbr::RayStats stats;
    long n_checked = 0;      // rays also cast through the brute-force loop
    long n_brute_tests = 0;  // over the checked rays
    double octree_seconds = 0, brute_seconds = 0;
    long n_disagreements = 0;
};

// How the queries are timed and checked.
struct Timing {
    int n_repeats = 1;   // the octree's pass is timed this many times, the median kept
    long n_checked = 0;  // rays (the first ones) also cast through the brute-force loop
};

// The median of `n_repeats` timings of pass(), which also counts its work into `stats` (the
// counts of the first pass only: every pass does the same work).
template <class Pass>
double median_seconds(int n_repeats, mbr::RayStats& stats, Pass pass) {
    std::vector<double> seconds;
    for (int r = 0; r < n_repeats; ++r) {
        mbr::RayStats s;
        double t0 = mbr::now_seconds();
        pass(s);
        seconds.push_back(mbr::now_seconds() - t0);
        if (r == 0) stats = s;
    }
    std::sort(seconds.begin(), seconds.end());
    return seconds[seconds.size() / 2];
}

QueryRow measure_closest(const mbr::Octree& octree, const std::vector<mbr::Ray>& rays,
                         const Timing& timing) {
    QueryRow row;
    row.query = "closest_hit";
    row.n_rays = static_cast<long>(rays.size());
    const std::vector<mbr::Polygon>& polygons = octree.polygons();
    const size_t n_checked = std::min(rays.size(), static_cast<size_t>(timing.n_checked));
    std::vector<std::optional<mbr::Hit>> fast(rays.size()), slow(n_checked);
    row.octree_seconds = median_seconds(timing.n_repeats, row.stats, [&](mbr::RayStats& s) {
        for (size_t i = 0; i < rays.size(); ++i) fast[i] = octree.closest_hit(rays[i], &s);
    });
    double t1 = mbr::now_seconds();
    for (size_t i = 0; i < n_checked; ++i) slow[i] = brute_closest(polygons, rays[i]);
    row.brute_seconds = mbr::now_seconds() - t1;
    row.n_checked = static_cast<long>(n_checked);
    row.n_brute_tests = row.n_checked * static_cast<long>(polygons.size());
    for (size_t i = 0; i < rays.size(); ++i) row.n_hits += fast[i].has_value();
    for (size_t i = 0; i < n_checked; ++i) {
        const bool same =
            fast[i].has_value() == slow[i].has_value() &&
            (!fast[i] || (fast[i]->polygon == slow[i]->polygon && fast[i]->t == slow[i]->t));
        if (!same && row.n_disagreements++ == 0)
            std::cerr << "octree_stats: closest_hit disagrees on " << rays[i] << "\n";
    }
    return row;
}

QueryRow measure_any(const mbr::Octree& octree, const std::vector<mbr::Ray>& rays,
                     const Timing& timing) {
    QueryRow row;
    row.query = "any_hit";
    row.n_rays = static_cast<long>(rays.size());
    const std::vector<mbr::Polygon>& polygons = octree.polygons();
    const size_t n_checked = std::min(rays.size(), static_cast<size_t>(timing.n_checked));
    std::vector<char> fast(rays.size()), slow(n_checked);
    row.octree_seconds = median_seconds(timing.n_repeats, row.stats, [&](mbr::RayStats& s) {
        for (size_t i = 0; i < rays.size(); ++i) fast[i] = octree.any_hit(rays[i], &s);
    });
    double t1 = mbr::now_seconds();
    for (size_t i = 0; i < n_checked; ++i)
        slow[i] = brute_any(polygons, rays[i], row.n_brute_tests);
    row.brute_seconds = mbr::now_seconds() - t1;
    row.n_checked = static_cast<long>(n_checked);
    for (size_t i = 0; i < rays.size(); ++i) row.n_hits += fast[i];
    for (size_t i = 0; i < n_checked; ++i) {
        if (fast[i] != slow[i] && row.n_disagreements++ == 0)
            std::cerr << "octree_stats: any_hit disagrees on " << rays[i] << "\n";
    }
    return row;
}

// The rows of the text table and of the CSV table (which leads with the scene and the octree).
// Returns the number of disagreements over both queries.
long fill_tables(const std::string& path, const mbr::Scene& scene, const mbr::Octree& octree,
                 const QueryRow (&rows)[2], mbr::Table& table, mbr::Table& csv_table) {
    const int n_polygons = octree.polygon_count();
    const std::vector<std::string> build_cells = {std::to_string(scene.settings.tessellation),
                                                  std::to_string(n_polygons),
                                                  std::to_string(octree.node_count()),
                                                  std::to_string(octree.leaf_count()),
                                                  std::to_string(octree.depth()),
                                                  std::to_string(octree.reference_count())};
    long n_disagreements = 0;
    for (const QueryRow& r : rows) {
        const double n = static_cast<double>(r.n_rays),
                     n_checked = static_cast<double>(r.n_checked);
        const bool checked = r.n_checked > 0;
        // The speed-up compares seconds per ray: the brute-force loop may see fewer rays.
        const double speedup = (r.brute_seconds / n_checked) / (r.octree_seconds / n);
        std::vector<std::string> cells = {r.query,
                                          std::to_string(r.n_rays),
                                          mbr::cell(r.n_hits / n, 4),
                                          mbr::cell(r.stats.n_nodes_visited / n, 2),
                                          mbr::cell(r.stats.n_polygons_tested / n, 2),
                                          mbr::cell_g(r.octree_seconds, 4),
                                          mbr::cell_g(n / r.octree_seconds, 4),
                                          std::to_string(r.n_checked),
                                          checked ? mbr::cell(r.n_brute_tests / n_checked, 2) : "-",
                                          mbr::cell_g(r.brute_seconds, 4),
                                          checked ? mbr::cell(speedup, 1) : "-",
                                          std::to_string(r.n_disagreements)};
        n_disagreements += r.n_disagreements;
        std::vector<std::string> csv_cells = {path};
        csv_cells.insert(csv_cells.end(), build_cells.begin(), build_cells.end());
        csv_cells.insert(csv_cells.end(), cells.begin(), cells.end());
        table.add_row(cells);
        csv_table.add_row(csv_cells);
    }

    return n_disagreements;
}

int run(mbr::Args& args) {
    const bool csv = args.flag("--csv");
    // 10^7 rays: two ray arrays of 0.6 GB each, and hours of brute force on a large scene.
    const int n_rays = args.integer("--rays", 100000, 1, 10000000);
    const int seed = args.integer("--seed", 1, 0, INT_MAX);
    Timing timing;
    timing.n_checked = args.integer("--check", n_rays, 0, 10000000);
    timing.n_repeats = args.integer("--repeat", 1, 1, 100);
    mbr::OctreeOptions options;
    options.max_depth = args.integer("--max-depth", options.max_depth, 0, 24);
    options.max_polygons_per_leaf =
        args.integer("--leaf-polygons", options.max_polygons_per_leaf, 1, 1000000);
    const bool has_tessellation = args.has("--tessellation");
    const int tessellation_option = args.integer("--tessellation", 16, 1, 1024);
    std::vector<std::string> files = args.positional();
    args.finish();
    if (files.size() != 1) throw mbr::UsageError("expected one SCENE file");

    const std::string& path = files[0];
    mbr::Scene scene = mbr::load_scene_file(path);
    if (has_tessellation) scene.settings.tessellation = tessellation_option;

    mbr::ScenePolygonStats polygon_stats;
    double t0 = mbr::now_seconds();
    const mbr::Octree octree = mbr::build_octree(scene, options, &polygon_stats);
    const double build_seconds = mbr::now_seconds() - t0;
    if (octree.polygon_count() == 0) throw mbr::InputError(path, 0, "the scene has no polygons");

    std::mt19937_64 rng(static_cast<unsigned long>(seed));
    const std::vector<mbr::Ray> probes = closest_hit_rays(scene.bounds(), n_rays, rng);
    int n_unfacing = 0;
    const std::vector<mbr::Ray> segments = shadow_segments(
        octree.polygons(), static_cast<int>(scene.surfaces.size()), n_rays, rng, n_unfacing);
    const QueryRow rows[] = {measure_closest(octree, probes, timing),
                             measure_any(octree, segments, timing)};

    mbr::Table table({"query", "rays", "hit_fraction", "nodes_per_ray", "tests_per_ray",
                      "octree_seconds", "rays_per_s", "checked", "brute_tests_per_ray",
                      "brute_seconds", "speedup", "disagreements"});
    mbr::Table csv_table({"scene", "tessellation", "polygons", "nodes", "leaves", "depth",
                          "references", "query", "rays", "hit_fraction", "nodes_per_ray",
                          "tests_per_ray", "octree_seconds", "rays_per_s", "checked",
                          "brute_tests_per_ray", "brute_seconds", "speedup", "disagreements"});
    const long n_disagreements = fill_tables(path, scene, octree, rows, table, csv_table);
    const int n_polygons = octree.polygon_count();

    if (csv) {
        csv_table.write_csv(std::cout);
        return n_disagreements == 0 ? 0 : 1;
    }
    const mbr::ScenePolygonStats& ps = polygon_stats;
    std::cout << "scene       " << path << ": " << scene.surfaces.size()
              << " surfaces, tessellation " << scene.settings.tessellation << "\n"
              << "polygons    " << n_polygons << " from " << ps.n_facets << " facets ("
              << ps.n_split << " split into triangles, " << ps.n_dropped << " degenerate dropped, "
              << ps.n_empty_surfaces << " surfaces left empty)\n"
              << "octree      " << octree.node_count() << " nodes, " << octree.leaf_count()
              << " leaves, depth " << octree.depth() << ", " << octree.reference_count()
              << " references (" << mbr::cell(double(octree.reference_count()) / n_polygons, 2)
              << " per polygon); max depth " << options.max_depth << ", split above "
              << options.max_polygons_per_leaf << " polygons; built in "
              << mbr::cell_g(build_seconds, 3) << " s\n"
              << "rays        " << n_rays << " per query, seed " << seed << "; octree timed "
              << timing.n_repeats << (timing.n_repeats == 1 ? " time" : " times (median)")
              << ", the first " << std::min<long>(timing.n_checked, n_rays)
              << " checked against brute force\n"
              << "  closest_hit  origins uniform in the scene's box, directions uniform\n"
              << "  any_hit      segments between area-uniform points of two facing surfaces";
    if (n_unfacing) std::cout << " (" << n_unfacing << " unfacing)";
    std::cout << "\n\n";
    table.write_text(std::cout);
    std::cout << "\n"
              << (n_disagreements > 0 ? "DISAGREEMENTS between octree and brute force\n"
                  : std::min<long>(timing.n_checked, n_rays) == n_rays
                      ? "octree and brute force agree on every ray\n"
                      : "octree and brute force agree on every ray checked\n");
    return n_disagreements == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, run);
}
