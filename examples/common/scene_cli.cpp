// examples/common/scene_cli.cpp - scenes, solver options, progress and statistics for the
// whole-scene programs.
#include "examples/common/scene_cli.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/scene_io.h"
#include "radiosity/scene_octree.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbr {

const char* solver_options_usage =
    "  SCENE                     a scene file (docs/scene-format.md)\n"
    "  --order m                 B-spline order, 2..8 (scene's `set order`, default 4)\n"
    "  --min-depth d --max-depth d   receiver quadtree bounds, 0..12\n"
    "  --shots n                 at most n shots, 0..10000000 (scene's max_shots, default 100)\n"
    "  --convergence c           stop when the largest unshot power is below c x emitted, [0, 1)\n"
    "  --tolerance x             accuracy relative to the scene's radiosity scale, (0, 1)\n"
    "                            (scene's `set tolerance`, default 1e-3): sets every\n"
    "                            transfer's absolute tolerance\n"
    "  --shadows M               exact (visibility inside (21), default), paper\n"
    "                            (fractions (28) and masking) or none (`set shadows`)\n"
    "  --rays R                  paper shadows: rays per shooter patch, 1..4096\n"
    "  --unify projection|paper  every finest coefficient projected on the fine grid\n"
    "                            (default), or the paper's (17) from selected fulcrums\n"
    "                            (`set unify`)\n"
    "  --ambient on|off          the ambient correction of the unshot power (`set ambient`,\n"
    "                            default on)\n"
    "  --hidden on|off           hidden regions take their visible neighbours' values\n"
    "                            (`set hidden`, default on)\n"
    "  --threads n               OpenMP threads, 1..256 (default: all cores)\n"
    "  --quiet                   no progress bar\n";

SceneRun read_scene_run(Args& args, const std::string& default_scene) {
    SceneRun run;
    auto in_range = [](const std::string& name, double v, double lo, double hi,
                       bool open_lo = false, bool open_hi = false) {
        const bool ok = (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
        if (!ok) {
            std::ostringstream os;
            os << name << " must be in " << (open_lo ? "(" : "[") << lo << ", " << hi
               << (open_hi ? ")" : "]") << ", got " << v;
            throw UsageError(os.str());
        }
    };
    // Read every option first: the scene path is what is left.
    const int order = args.integer("--order", -1);
    const int min_depth = args.integer("--min-depth", -1);
    const int max_depth = args.integer("--max-depth", -1);
    const int shots = args.integer("--shots", -1);
    const double convergence = args.number("--convergence", -1);
    const double tolerance = args.number("--tolerance", -1);
    const std::string shadows = args.text("--shadows", "exact");
    const int rays = args.integer("--rays", -1);
    const std::string unify = args.text("--unify", "projection");
    const std::string ambient = args.text("--ambient", "on");
    const std::string hidden = args.text("--hidden", "on");
    run.threads = args.integer("--threads", 0);
    run.quiet = args.flag("--quiet");
    const std::vector<std::string> pos = args.positional();
    if (pos.size() > 1)
        throw UsageError("one scene file, please (got " + std::to_string(pos.size()) + ")");
    if (pos.empty() && default_scene.empty()) throw UsageError("a scene file is required");
    run.path = pos.empty() ? default_scene : pos[0];

    if (args.has("--order")) in_range("--order", order, 2, 8);
    if (args.has("--min-depth")) in_range("--min-depth", min_depth, 0, 12);
    if (args.has("--max-depth")) in_range("--max-depth", max_depth, 0, 12);
    if (args.has("--shots")) in_range("--shots", shots, 0, 1e7);
    if (args.has("--convergence")) in_range("--convergence", convergence, 0, 1, false, true);
    if (args.has("--tolerance")) in_range("--tolerance", tolerance, 0, 1, true, true);
    if (args.has("--rays")) in_range("--rays", rays, 1, 4096);
    if (args.has("--threads")) in_range("--threads", run.threads, 1, 256);
    if (shadows != "exact" && shadows != "paper" && shadows != "none")
        throw UsageError("--shadows must be exact, paper or none");
    if (unify != "projection" && unify != "paper") throw UsageError("--unify must be projection or paper");
    for (const auto& [name, value] : {std::pair{"--ambient", ambient}, std::pair{"--hidden", hidden}})
        if (value != "on" && value != "off") throw UsageError(std::string(name) + " must be on or off");

    const bool obj = run.path.size() > 4 && run.path.compare(run.path.size() - 4, 4, ".obj") == 0;
    run.scene = obj ? load_obj(run.path) : load_scene(run.path);
    SolverOptions& o = run.options;
    o = solver_options(run.scene.settings);
    if (order > 0) o.receiver.m = order;
    if (min_depth >= 0) o.receiver.min_depth = min_depth;
    if (max_depth >= 0) o.receiver.max_depth = max_depth;
    if (o.receiver.min_depth > o.receiver.max_depth) {
        if (args.has("--min-depth") && args.has("--max-depth"))
            throw UsageError("--min-depth must not exceed --max-depth");
        // One bound given on the command line moves the other along.
        if (args.has("--max-depth"))
            o.receiver.min_depth = o.receiver.max_depth;
        else
            o.receiver.max_depth = o.receiver.min_depth;
    }
    if (shots >= 0) o.max_shots = shots;
    if (convergence >= 0) o.convergence = convergence;
    if (args.has("--tolerance")) o.tolerance = tolerance;
    if (args.has("--shadows"))
        o.receiver.shadows.method = shadows == "exact"   ? ShadowMethod::Exact
                                    : shadows == "paper" ? ShadowMethod::Fractions
                                                         : ShadowMethod::None;
    if (rays > 0) o.receiver.shadows.rays_per_patch = rays;
    if (args.has("--ambient")) o.ambient = ambient == "on";
    if (args.has("--unify")) o.receiver.unify_by_projection = unify == "projection";
    if (args.has("--hidden")) o.hidden_regions = hidden == "on";
#ifdef _OPENMP
    if (run.threads > 0) omp_set_num_threads(run.threads);
#endif
    run.octree = std::make_unique<Octree>(build_octree(run.scene));
    return run;
}

namespace {

/// A one-line progress bar on stderr, redrawn in place.
class ProgressBar {
public:
    explicit ProgressBar(bool on) : on_(on && isatty(2)) {}
    ~ProgressBar() {
        if (drawn_) std::fprintf(stderr, "\r%*s\r", 100, "");
    }
    void update(const ShotStats& shot, const ProgressiveSolver& solver, int max_shots,
                double target) {
        if (!on_) return;
        const SolveStats& st = solver.solution().stats;
        const double elapsed = st.per_shot.empty() ? 0 : [&] {
            double s = 0;
            for (const ShotStats& x : st.per_shot) s += x.seconds;
            return s;
        }();
        const double left = st.emitted_power > 0 ? shot.unshot_after / st.emitted_power : 0;
        // Estimate of the rest: the unshot power has fallen from 1 to `left` in `elapsed`;
        // assume it keeps falling geometrically to the target (or the shot limit).
        double rest = 0;
        if (left > target && left < 1 && target > 0)
            rest = elapsed * std::log(left / target) / std::log(1 / left);
        const int width = 24;
        const double done =
            std::clamp(left > 0 && target > 0 ? std::log(left) / std::log(target) : 1.0, 0.0, 1.0);
        const int filled = static_cast<int>(done * width);
        std::string bar(filled, '#');
        bar += std::string(width - filled, '.');
        std::fprintf(stderr, "\r[%s] shot %d/%d, unshot %.3g%%, %.1f s, about %.0f s left   ",
                     bar.c_str(), shot.shot, max_shots, 100 * left, elapsed, rest);
        std::fflush(stderr);
        drawn_ = true;
    }

private:
    bool on_ = false;
    bool drawn_ = false;
};

}  // namespace

Solution solve_scene(SceneRun& run, bool progress) {
    ProgressBar bar(progress && !run.quiet);
    return solve(run.scene, *run.octree, run.options,
                 [&](const ShotStats& shot, const ProgressiveSolver& solver) {
                     bar.update(shot, solver, run.options.max_shots, run.options.convergence);
                 });
}

void print_shots(std::ostream& os, const Scene& scene, const SolveStats& stats) {
    Table t({"shot", "shooter", "shooter_power", "unshot_before_percent", "unshot_after_percent",
             "receivers", "kernel_evals", "rays", "level", "seconds"});
    for (const ShotStats& s : stats.per_shot)
        t.add_row({std::to_string(s.shot), scene.surfaces[s.shooter].name,
                   cell_g(s.shooter_power, 4),
                   cell_g(100 * s.unshot_before / stats.emitted_power, 4),
                   cell_g(100 * s.unshot_after / stats.emitted_power, 4),
                   std::to_string(s.receivers), std::to_string(s.kernel_evals),
                   std::to_string(s.rays), std::to_string(s.finest_level), cell(s.seconds, 3)});
    t.write_text(os);
}

std::vector<std::string> summary_cells(const SolveStats& st) {
    return {std::to_string(st.shots), cell_g(100 * st.unshot_power / st.emitted_power, 4),
            cell(st.seconds, 3), cell(double(st.peak_memory_bytes) / (1024.0 * 1024.0), 1),
            std::to_string(st.coefficients)};
}

void print_summary(std::ostream& os, const SceneRun& run, const SolveStats& st) {
    os << run.path << ": " << run.scene.surfaces.size() << " surfaces, "
       << run.octree->polygon_count() << " polygons\n"
       << "shots " << st.shots << (st.converged ? " (converged)" : " (shot limit)")
       << ", unshot power left " << cell_g(100 * st.unshot_power / st.emitted_power, 4)
       << " % of emitted\n"
       << "seconds " << cell(st.seconds, 3) << " (" << thread_count() << " threads), peak memory "
       << cell(double(st.peak_memory_bytes) / (1024.0 * 1024.0), 1) << " MiB, coefficients "
       << st.coefficients << " per channel\n"
       << "kernel evaluations " << st.kernel_evals << ", shadow rays " << st.rays << "\n";
}

}  // namespace mbr
