// examples/tutorial/tutorial_08_progressive_loop.cpp - tutorial chapter 8
// (docs/tutorial/08-progressive-loop.md): the progressive refinement loop of paper section 4 on
// the Cornell box, one shot at a time, with its energy bookkeeping.
//
// Chapters 4-7 made one transfer. A scene needs many: the paper's algorithm box projects each
// emitter's emission (B = dB_unshot = E), then repeatedly picks the surface with the largest
// unshot power int dB_unshot A, lets it shoot to every other surface (one transfer each, with
// shadows), adds each receiver's increment dB to both its radiosity B and its unshot dB_unshot,
// and sets the shooter's unshot radiosity to zero. radiosity/solver/solver.h is that loop;
// ProgressiveSolver runs it one shot() at a time, so this program can print what every shot
// did: who shot, how much power left the shooter, how much arrived, how much was reflected,
// what it cost, and how the unshot power falls.
//
// Run:  tutorial_08_progressive_loop [-o DIR] [--shots n] [--max-depth d] [--tolerance x]
//                                    [--convergence c] [--shadows exact|paper]
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "radiosity/output/image.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_08_progressive_loop [-o DIR] [options]\n"
    "  Tutorial chapter 8: the Cornell box solved by progressive refinement, shot by shot,\n"
    "  with the energy bookkeeping of every shot.\n"
    "  -o DIR              folder for the image (default out; created if missing)\n"
    "  --shots n           at most n shots, 1..1000 (default 30)\n"
    "  --max-depth d       receiver quadtree depth, 1..8 (default 5; the scene's is 6)\n"
    "  --tolerance x       accuracy relative to the radiosity scale, (0, 1) (default 2e-3)\n"
    "  --convergence c     stop when the largest unshot power < c x emitted, [0, 1)\n"
    "                      (default 1e-3)\n"
    "  --shadows M         exact (visibility inside (21), the scene default) or paper\n"
    "                      (fractions (28), chapter 7)\n";

/// Percent of the emitted power, with enough digits for small numbers.
std::string pct(double power, double emitted) {
    return cell_g(100 * power / emitted, 4);
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const int shots = args.integer("--shots", 30, 1, 1000);
    const int max_depth = args.integer("--max-depth", 5, 1, 8);
    const double tolerance = args.number("--tolerance", 2e-3);
    const double convergence = args.number("--convergence", 1e-3);
    const std::string shadows = args.text("--shadows", "exact");
    args.finish();
    if (!(tolerance > 0 && tolerance < 1)) throw UsageError("--tolerance must be in (0, 1)");
    if (!(convergence >= 0 && convergence < 1)) throw UsageError("--convergence must be in [0, 1)");
    if (shadows != "exact" && shadows != "paper")
        throw UsageError("--shadows must be exact or paper");
    make_output_folder(dir);

    // The scene and its `set` statements as solver options (radiosity/scene/scene_io.h, solver.h),
    // then this chapter's overrides. The octree is the one every shadow ray walks.
    const std::string path = std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene";
    const Scene scene = load_scene(path);
    SolverOptions options = solver_options(scene.settings);
    options.max_shots = shots;
    options.receiver.max_depth = max_depth;
    options.receiver.min_depth = std::min(options.receiver.min_depth, max_depth);
    options.tolerance = tolerance;
    options.convergence = convergence;
    options.receiver.shadows.method =
        shadows == "exact" ? ShadowMethod::Exact : ShadowMethod::Fractions;
    const Octree octree = build_octree(scene);

    // The constructor is the first loop of the algorithm box: every emitter's emission is
    // projected (project_emission) and B = dB_unshot = E.
    ProgressiveSolver solver(scene, octree, options);
    const double emitted = solver.solution().stats.emitted_power;
    std::cout << "tutorial_08_progressive_loop: " << scene.surfaces.size()
              << " surfaces of examples/scenes/cornell_box.scene, max depth " << max_depth
              << ", tolerance " << tolerance << ", " << shadows << " shadows\n"
              << "emitted power: " << cell_g(emitted, 6) << " (sum of the RGB channels, "
              << "int E A over the light)\n"
              << "radiosity scale: " << cell_g(solver.radiosity_scale(), 6)
              << " (emitted power / total area; tolerances are relative to it)\n\n";

    // The while loop of the algorithm box. shoot() picks the surface with the largest unshot
    // power, makes one transfer to every surface that can receive from it
    // (radiosity/transfer/transfer.h), adds the increments and zeroes the shooter's unshot field.
    Table table({"shot", "shooter", "shot_%", "unshot_before_%", "unshot_after_%", "incident_%",
                 "reflected_%", "receivers", "kernel_evals", "rays"});
    double sum_shot = 0, sum_incident = 0, sum_reflected = 0, worst_balance = 0;
    std::vector<double> x_shot, y_unshot, y_evals;
    while (!solver.done()) {
        const ShotStats s = solver.shoot();
        // Energy bookkeeping: the shooter's unshot power leaves the scene's unshot total, and
        // what the receivers reflect joins it, so unshot_after = unshot_before - shot +
        // reflected. Of the shot power, the part that does not arrive (shot - incident) leaves
        // through the box's open front; of what arrives, 1 - rho is absorbed.
        const double balance = s.unshot_after - (s.unshot_before - s.shooter_power + s.reflected);
        worst_balance = std::max(worst_balance, std::fabs(balance) / emitted);
        sum_shot += s.shooter_power;
        sum_incident += s.incident;
        sum_reflected += s.reflected;
        table.add_row({std::to_string(s.shot), scene.surfaces[s.shooter].name,
                       pct(s.shooter_power, emitted), pct(s.unshot_before, emitted),
                       pct(s.unshot_after, emitted), pct(s.incident, emitted),
                       pct(s.reflected, emitted), std::to_string(s.receivers),
                       std::to_string(s.kernel_evals), std::to_string(s.rays)});
        x_shot.push_back(s.shot);
        y_unshot.push_back(100 * s.unshot_after / emitted);
        y_evals.push_back(double(s.kernel_evals));
    }
    table.write_text(std::cout);

    const ShotStats& first = solver.solution().stats.per_shot.front();
    const Solution solution = solver.finish();  // adds the ambient term for what is left unshot
    const SolveStats& st = solution.stats;
    std::cout << "\nfirst shot: " << scene.surfaces[first.shooter].name << " sends "
              << pct(first.shooter_power, emitted) << " % of the emitted power, "
              << pct(first.incident, emitted) << " % arrives, " << pct(first.reflected, emitted)
              << " % is reflected\n"
              << "shots: " << st.shots << (st.converged ? " (converged)" : " (shot limit)") << "\n"
              << "energy, in % of the emitted power (sum of channels):\n"
              << "  shot in total: " << pct(sum_shot, emitted) << "\n"
              << "  arrived at receivers: " << pct(sum_incident, emitted) << "\n"
              << "  reflected (became unshot again): " << pct(sum_reflected, emitted) << "\n"
              << "  absorbed (arrived - reflected): " << pct(sum_incident - sum_reflected, emitted)
              << "\n"
              << "  left through the open front (shot - arrived): "
              << pct(sum_shot - sum_incident, emitted) << "\n"
              << "  still unshot: " << pct(st.unshot_power, emitted) << "\n"
              << "  emitted = unshot + absorbed + left: "
              << pct(st.unshot_power + sum_shot - sum_reflected, emitted) << "\n"
              << "largest bookkeeping error per shot: " << cell_g(worst_balance, 3)
              << " of emitted\n"
              << "ambient power added at the end: " << pct(st.ambient_power, emitted) << "\n"
              << "kernel evaluations: " << st.kernel_evals << "\n"
              << "shadow rays: " << st.rays << "\n"
              << "coefficients: " << st.coefficients << " per channel\n";

    // The picture: the unshot fraction and the cost of every shot, on log scales.
    Image image(960, 400, {1, 1, 1});
    Plot left;
    left.title = "unshot power";
    left.x_label = "shot";
    left.y_label = "% of emitted";
    left.log_y = true;
    left.legend = LegendPlace::none;
    Plot right = left;
    right.title = "kernel evaluations";
    right.y_label = "evaluations";
    Series unshot, target, evals;
    unshot.x = evals.x = x_shot;
    unshot.y = y_unshot;
    evals.y = y_evals;
    unshot.stroke.colour = {0.8, 0.2, 0.1};
    evals.stroke.colour = {0.1, 0.3, 0.8};
    unshot.marker = evals.marker = Marker::disc;
    unshot.marker_radius = evals.marker_radius = 3;
    left.add(unshot);
    if (convergence > 0) {  // the convergence test's threshold, dashed
        target.x = {1, double(x_shot.size())};
        target.y = {100 * convergence, 100 * convergence};
        target.stroke = {{0.4, 0.4, 0.4}, 1.5, 6, 4};
        left.add(target);
    }
    right.add(evals);
    left.draw(image, {0, 0, 480, 400});
    right.draw(image, {480, 0, 480, 400});
    const std::string png = (std::filesystem::path(dir) / "tutorial_08_convergence.png").string();
    write_png(png, image);
    std::cout << "wrote " << png << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
