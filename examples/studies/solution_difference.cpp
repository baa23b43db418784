// examples/studies/solution_difference.cpp - how far one solution of a scene is from another, at
// random points of every surface: what an approximation (a cheaper rule, a coarser setting)
// costs in accuracy, measured against the solution without it. Both files come from
// `mbr render|probe SCENE --save-solution F` on the same scene.
//
// Per surface, K points uniform in its parameters (seeded), B at each from both solutions
// (radiosity_view: B = E + rho H where a field holds H). Emitters are left out (their emission
// dominates). The error at a point is |B_a - B_b| / max(B_b, floor), channel sums, relative to
// the reference as the paper's rea is; the floor, 1 % of the area-weighted mean of B_b, keeps
// points in the dark from dominating. Every surface has K points, so the mean weighs the many
// small surfaces of a cluttered scene (a chair's legs) as much as its floor.
//
// Run:    solution_difference SCENE A.solution B.solution [--points K] [--seed S] [--csv]
// Expect: 0 and 0 for a solution against itself; mean and max relative difference in percent,
//         and the difference of the area-weighted mean B (the reflected power per area),
//         B taken as the reference.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/solver/solution_file.h"
#include "radiosity/solver/solver.h"
#include "radiosity/visibility/occlusion.h"

namespace {

const char* usage =
    "usage: solution_difference SCENE A.solution B.solution [--points K] [--seed S] [--csv]\n"
    "  The relative difference of solution A from solution B (the reference) at K random\n"
    "  points of every surface that does not emit: mean and max of |B_a - B_b| / max(B_b,\n"
    "  floor), channel sums, the floor 1 % of the area-weighted mean of B_b; and the\n"
    "  difference of the area-weighted means.\n"
    "  SCENE      the scene both solutions solve (a scene file, .obj or .mgf)\n"
    "  --points K points per surface, 1..10000 (default 4)\n"
    "  --seed S   seed of the points (default 1)\n"
    "  --worst N  also list the N points that differ most (surface, u, v, B_a, B_b)\n"
    "  --csv      one CSV row\n";

int run(mbr::Args& args) {
    const int k_points = args.integer("--points", 4, 1, 10000);
    const int seed = args.integer("--seed", 1, 0, 1000000000);
    const int worst = args.integer("--worst", 0, 0, 1000000);
    const bool csv = args.flag("--csv");
    std::vector<std::string> files = args.positional();
    args.finish();
    if (files.size() != 3) throw mbr::UsageError("expected SCENE A.solution B.solution");
    const mbr::Scene scene = mbr::load_scene_file(files[0]);
    const mbr::Solution a = mbr::load_solution(files[1], scene);
    const mbr::Solution b = mbr::load_solution(files[2], scene);
    const mbr::RadiosityView view_a = mbr::radiosity_view(scene, a);
    const mbr::RadiosityView view_b = mbr::radiosity_view(scene, b);

    struct Point {
        double a, b, area;  // channel sums of B, and the area the point stands for
        int surface;
        double u, v;
    };
    std::vector<Point> points;
    for (int i = 0; i < int(scene.surfaces.size()); ++i) {
        if (max_abs(scene.material_of(i).emission.maximum()) > 0) continue;
        const mbr::Surface& s = scene.surfaces[size_t(i)].surface;
        const double share = s.area() / k_points;
        // The solver's own seeded hash (occlusion.h): surface i's points from key (seed, i).
        const std::uint64_t key = mbr::hash_seed(std::uint64_t(seed), std::uint64_t(i));
        for (int k = 0; k < k_points; ++k) {
            const double u = mbr::uniform01(key, 2 * std::uint64_t(k));
            const double v = mbr::uniform01(key, 2 * std::uint64_t(k) + 1);
            points.push_back({mbr::channel_sum(view_a.at(i, u, v)),
                              mbr::channel_sum(view_b.at(i, u, v)), share, i, u, v});
        }
    }
    if (points.empty()) throw mbr::UsageError("the scene has no surface that does not emit");
    double area = 0, power_a = 0, power_b = 0;  // the area-weighted sums
    for (const Point& p : points) {
        area += p.area;
        power_a += p.a * p.area;
        power_b += p.b * p.area;
    }
    const double floor = 0.01 * std::fabs(power_b) / area;
    auto error = [floor](const Point& p) {
        return std::fabs(p.a - p.b) / std::max(std::fabs(p.b), floor);
    };
    double sum = 0, largest = 0;
    for (const Point& p : points) {
        sum += error(p);
        largest = std::max(largest, error(p));
    }
    const double mean = sum / double(points.size());
    const double power = power_b != 0 ? (power_a - power_b) / power_b : 0.0;
    if (csv) {
        mbr::Table table({"scene", "points", "mean_rel_pct", "max_rel_pct", "mean_b_diff_pct"});
        table.add_row({files[0], std::to_string(points.size()), mbr::cell_g(100 * mean, 4),
                       mbr::cell_g(100 * largest, 4), mbr::cell_g(100 * power, 4)});
        table.write_csv(std::cout);
    } else {
        std::cout << "scene                " << files[0] << "\n"
                  << "points               " << points.size() << " (" << k_points
                  << " on each surface that does not emit)\n"
                  << "relative difference  mean " << mbr::cell_g(100 * mean, 4) << " %, max "
                  << mbr::cell_g(100 * largest, 4) << " % (floor 1 % of the area-weighted mean B)\n"
                  << "area-weighted mean B " << mbr::cell_g(power_a / area, 6) << " against "
                  << mbr::cell_g(power_b / area, 6) << " (" << mbr::cell_g(100 * power, 4)
                  << " %)\n";
    }
    if (worst > 0) {
        std::vector<Point> sorted = points;
        std::sort(sorted.begin(), sorted.end(),
                  [&](const Point& x, const Point& y) { return error(x) > error(y); });
        sorted.resize(std::min(sorted.size(), size_t(worst)));
        std::cout << "surface,u,v,B_a,B_b,rel_pct\n";
        for (const Point& p : sorted)
            std::cout << scene.surfaces[size_t(p.surface)].name << ',' << p.u << ',' << p.v << ','
                      << p.a << ',' << p.b << ',' << 100 * error(p) << '\n';
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, run);
}
