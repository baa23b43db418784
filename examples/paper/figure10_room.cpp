// examples/paper/figure10_room.cpp - Figure 10 of the paper (section 7): "an image of a room with a
// table and a stool", solved by progressive refinement (section 4) with shadows.
//
// Run:  figure10_room [SCENE] [--per-shot] [--csv] [-o FILE.png] [--spp n] [solver options]
//
// Solves examples/scenes/room.scene (or SCENE): 27 surfaces of every kind (quads, a bilinear
// cloth, boxes, cylinders, spheres, disks), 2558 tessellation polygons for the rays. Prints the
// shots, the unshot power left in percent of the emitted, seconds, peak memory and the
// coefficients stored, then where the time went: the seconds of the shots by shooter. With
// --per-shot one line per shot as it finishes (the shooter, its power, the unshot power before
// and after, receivers, kernel evaluations, rays, level, seconds). --csv prints
// `shots,unshot_percent,seconds,peak_mib,coefficients`. -o FILE.png renders the solution with
// the scene's camera (--spp samples per pixel, default 4).
//
// Default shots: the scene's `set max_shots` (60) as for every scene program, or --shots. The
// scene sets the paper's shadows (fractions (28)); every shot costs a few seconds, and the ambient
// correction (on by default) stands in for what a shorter run leaves unshot.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/scene_cli.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: figure10_room [SCENE] [--per-shot] [--csv] [-o FILE.png] [--spp n]\n"
               "                     [options]\n"
               "  Figure 10: the room with a table and a stool (default\n"
               "  examples/scenes/room.scene), solved with shadows; prints shots, unshot power\n"
               "  left (% of emitted), seconds, peak memory, coefficients, and the seconds by\n"
               "  shooter.\n"
               "  --per-shot                one line per shot, as it finishes\n"
               "  --csv                     header shots,unshot_percent,seconds,peak_mib,"
               "coefficients\n"
               "  -o FILE.png               a picture of the solution (the scene's camera)\n"
               "  --spp n                   samples per pixel of the picture, 1..4096 (4)\n") +
           solver_options_usage();
}

/// One shot's line, printed as soon as it is done (a room's shot can take minutes).
void print_shot(std::ostream& os, const Scene& scene, const ShotStats& s, double emitted) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "%5d  %-14s  %10.4g  %12.4g%%  %11.4g%%  %4d  %12ld  %10ld  %2d  %9.3f  %7d\n",
                  s.shot, scene.surfaces[s.shooter].name.c_str(), s.shooter_power,
                  100 * s.unshot_before / emitted, 100 * s.unshot_after / emitted, s.receivers,
                  s.kernel_evals, s.rays, s.finest_level, s.seconds, s.members);
    os << line << std::flush;
}

/// Where the time went: seconds and shots per shooter, the most expensive first.
void print_time_by_shooter(std::ostream& os, const Scene& scene, const SolveStats& stats) {
    struct Sum {
        int shots = 0;
        double seconds = 0;
        long kernel_evals = 0, rays = 0;
    };
    std::map<int, Sum> by_shooter;
    double total = 0;
    for (const ShotStats& s : stats.per_shot) {
        Sum& sum = by_shooter[s.shooter];
        ++sum.shots;
        sum.seconds += s.seconds;
        sum.kernel_evals += s.kernel_evals;
        sum.rays += s.rays;
        total += s.seconds;
    }
    std::vector<std::pair<int, Sum>> rows(by_shooter.begin(), by_shooter.end());
    std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
        return a.second.seconds > b.second.seconds;
    });
    Table t({"shooter", "shots", "seconds", "share_percent", "kernel_evals", "rays"});
    for (const auto& [shooter, sum] : rows)
        t.add_row({scene.surfaces[shooter].name, std::to_string(sum.shots), cell(sum.seconds, 2),
                   cell(total > 0 ? 100 * sum.seconds / total : 0, 1),
                   std::to_string(sum.kernel_evals), std::to_string(sum.rays)});
    os << "seconds by shooter:\n";
    t.write_text(os);
}

int run(Args& args) {
    const bool per_shot = args.flag("--per-shot");
    const bool csv = args.flag("--csv");
    const std::string out = args.text("-o", "");
    const int spp = args.integer("--spp", 4, 1, 4096);
    if (!out.empty()) check_output_path(out);  // refuse an unwritable path before solving
    SceneRun run =
        read_scene_run(args, std::string(MBR_SOURCE_DIR) + "/examples/scenes/room.scene");
    args.finish();

    if (!csv) {
        std::cout << run.path << ": " << run.scene.surfaces.size() << " surfaces, "
                  << run.octree->polygon_count() << " polygons; at most " << run.options.max_shots
                  << " shots, convergence " << run.options.convergence << "\n";
        if (per_shot)
            std::cout << " shot  shooter         shooter_pw  unshot_before  unshot_after  recv  "
                         "kernel_evals        rays  lv    seconds  members\n";
        std::cout << std::flush;
    }
    const Solution solution =
        solve(run.scene, *run.octree, run.options,
              [&](const ShotStats& shot, const ProgressiveSolver& solver) {
                  if (per_shot && !csv)
                      print_shot(std::cout, run.scene, shot, solver.solution().stats.emitted_power);
              });
    if (csv) {
        write_summary_csv(std::cout, solution.stats);
    } else {
        print_summary(std::cout, run, solution.stats);
        print_time_by_shooter(std::cout, run.scene, solution.stats);
    }
    if (!out.empty()) {
        RenderOptions ro;
        ro.samples_per_pixel = spp;
        const double seconds = write_render(run, solution, out, ro);
        (csv ? std::cerr : std::cout)
            << "wrote " << out << " (rendered in " << cell(seconds, 2) << " s)\n";
    }
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
