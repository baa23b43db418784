// examples/studies/cornell_box.cpp - the Cornell box solved by progressive refinement (paper
// section 4) with shadows, its statistics, and a picture.
//
// Run:  cornell_box [SCENE] [--per-shot] [--csv] [-o FILE.png] [solver options]
// Solves examples/scenes/cornell_box.scene (or SCENE) until the unshot power is below the
// convergence fraction of the emitted power (or the shot limit), and prints shots, the unshot
// power left in percent of the emitted, seconds, peak memory and coefficients stored; with
// --per-shot one line per shot (shooter, power before and after, receivers, kernel evaluations,
// rays, seconds). --csv prints `shots,unshot_percent,seconds,peak_mib,coefficients`.
#include <iostream>

#include "examples/common/cli.h"
#include "examples/common/scene_cli.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: cornell_box [SCENE] [--per-shot] [--csv] [-o FILE.png] [options]\n"
               "  Solves the Cornell box (default examples/scenes/cornell_box.scene) and prints\n"
               "  shots, unshot power left (% of emitted), seconds, peak memory, coefficients.\n"
               "  --per-shot                one line per shot\n"
               "  --csv                     header shots,unshot_percent,seconds,peak_mib,"
               "coefficients\n"
               "  -o FILE.png               a picture of the solution\n") +
           solver_options_usage();
}

int run(Args& args) {
    const bool per_shot = args.flag("--per-shot");
    const bool csv = args.flag("--csv");
    const std::string out = args.text("-o", "");
    if (!out.empty()) check_output_path(out);  // refuse an unwritable path before solving
    SceneRun run =
        read_scene_run(args, std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    args.finish();
    const Solution solution = solve_scene(run, !csv);
    if (per_shot && !csv) print_shots(std::cout, run.scene, solution.stats);
    if (csv) {
        write_summary_csv(std::cout, solution.stats);
    } else {
        print_summary(std::cout, run, solution.stats);
    }
    if (!out.empty()) {
        const double seconds = write_render(run, solution, out);
        // The CSV stays one table; the note goes to stderr then.
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
