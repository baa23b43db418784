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
#include "radiosity/solver/cost.h"
#include "radiosity/output/image.h"
#include "radiosity/output/output_file.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"

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
    "                            (scene's `set tolerance`, default 2e-3): sets every\n"
    "                            transfer's absolute tolerance\n"
    "  --shadows M               exact (visibility inside (21), default), paper\n"
    "                            (fractions (28) and masking) or none (`set shadows`)\n"
    "  --rays R                  paper shadows: rays per shooter patch, 1..4096\n"
    "  --shooter-level L         a shooter's unshot field is coarsened to at most level L,\n"
    "                            0..12 (scene's `set shooter_level`, default 3)\n"
    "  --contact-depth D         receiver cells touching a planar shooter split to at least\n"
    "                            level D, 0..12 (scene's `set contact_depth`, default 2)\n"
    "  --contact-oracle T        the oracle's test in cells touching a planar shooter:\n"
    "                            means (the paper's, default) or interpolation\n"
    "                            (`set contact_oracle`)\n"
    "  --unify projection|paper  every finest coefficient projected on the fine grid\n"
    "                            (default), or the paper's (17) from selected fulcrums\n"
    "                            (`set unify`)\n"
    "  --ambient on|off          the ambient correction of the unshot power (`set ambient`,\n"
    "                            default on)\n"
    "  --hidden on|off           hidden regions take their visible neighbours' values\n"
    "                            (`set hidden`, default on)\n"
    "  --threads n               OpenMP threads, 1..256 (default: all cores)\n"
    "  --quiet                   no progress bar\n"
    "  --memory-budget X         refuse a run estimated to need more memory (bytes, or K, M,\n"
    "                            G, T: 4G; default half the physical memory)\n";

namespace {

/// The solver options of the command line, read before the scene is known.
struct SolverArgs {
    int order = -1, min_depth = -1, max_depth = -1, shots = -1, rays = -1, shooter_level = -1,
        contact_depth = -1;
    double convergence = -1, tolerance = -1;
    double memory_budget = 0;
    std::string shadows, unify, ambient, hidden, contact_oracle;
    // Which options the command line gave: only those override the scene's `set` lines.
    bool has_min_depth = false, has_max_depth = false, has_tolerance = false,
         has_shadows = false, has_unify = false, has_ambient = false, has_hidden = false,
         has_contact_oracle = false;
};

SolverArgs read_solver_args(Args& args, SceneRun& run) {
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
    SolverArgs a;
    a.order = args.integer("--order", -1);
    a.min_depth = args.integer("--min-depth", -1);
    a.max_depth = args.integer("--max-depth", -1);
    a.shots = args.integer("--shots", -1);
    a.convergence = args.number("--convergence", -1);
    a.tolerance = args.number("--tolerance", -1);
    a.shadows = args.text("--shadows", "exact");
    a.rays = args.integer("--rays", -1);
    a.shooter_level = args.integer("--shooter-level", -1);
    a.contact_depth = args.integer("--contact-depth", -1);
    a.unify = args.text("--unify", "projection");
    a.contact_oracle = args.text("--contact-oracle", "means");
    a.ambient = args.text("--ambient", "on");
    a.hidden = args.text("--hidden", "on");
    run.threads = args.integer("--threads", 0);
    run.quiet = args.flag("--quiet");
    a.memory_budget = read_memory_budget(args);
    a.has_min_depth = args.has("--min-depth");
    a.has_max_depth = args.has("--max-depth");
    a.has_tolerance = args.has("--tolerance");
    a.has_shadows = args.has("--shadows");
    a.has_unify = args.has("--unify");
    a.has_ambient = args.has("--ambient");
    a.has_hidden = args.has("--hidden");
    a.has_contact_oracle = args.has("--contact-oracle");

    if (args.has("--order")) in_range("--order", a.order, 2, 8);
    if (a.has_min_depth) in_range("--min-depth", a.min_depth, 0, 12);
    if (a.has_max_depth) in_range("--max-depth", a.max_depth, 0, 12);
    if (args.has("--shots")) in_range("--shots", a.shots, 0, 1e7);
    if (args.has("--convergence")) in_range("--convergence", a.convergence, 0, 1, false, true);
    if (a.has_tolerance) in_range("--tolerance", a.tolerance, 0, 1, true, true);
    if (args.has("--rays")) in_range("--rays", a.rays, 1, 4096);
    if (args.has("--shooter-level")) in_range("--shooter-level", a.shooter_level, 0, 12);
    if (args.has("--contact-depth")) in_range("--contact-depth", a.contact_depth, 0, 12);
    if (args.has("--threads")) in_range("--threads", run.threads, 1, 256);
    if (a.shadows != "exact" && a.shadows != "paper" && a.shadows != "none")
        throw UsageError("--shadows must be exact, paper or none");
    if (a.unify != "projection" && a.unify != "paper")
        throw UsageError("--unify must be projection or paper");
    if (a.contact_oracle != "interpolation" && a.contact_oracle != "means")
        throw UsageError("--contact-oracle must be interpolation or means");
    for (const auto& [name, value] :
         {std::pair{"--ambient", a.ambient}, std::pair{"--hidden", a.hidden}})
        if (value != "on" && value != "off")
            throw UsageError(std::string(name) + " must be on or off");
    return a;
}

/// The scene's settings, then the command line over them; threads; the octree.
void finish_scene_run(const SolverArgs& a, SceneRun& run) {
    SolverOptions& o = run.options;
    o = solver_options(run.scene.settings);
    if (a.order > 0) o.receiver.m = a.order;
    if (a.min_depth >= 0) o.receiver.min_depth = a.min_depth;
    if (a.max_depth >= 0) o.receiver.max_depth = a.max_depth;
    if (o.receiver.min_depth > o.receiver.max_depth) {
        if (a.has_min_depth && a.has_max_depth)
            throw UsageError("--min-depth must not exceed --max-depth");
        // One bound given on the command line moves the other along.
        if (a.has_max_depth)
            o.receiver.min_depth = o.receiver.max_depth;
        else
            o.receiver.max_depth = o.receiver.min_depth;
    }
    if (a.shots >= 0) o.max_shots = a.shots;
    if (a.convergence >= 0) o.convergence = a.convergence;
    if (a.has_tolerance) o.tolerance = a.tolerance;
    if (a.has_shadows)
        o.receiver.shadows.method = a.shadows == "exact"   ? ShadowMethod::Exact
                                    : a.shadows == "paper" ? ShadowMethod::Fractions
                                                           : ShadowMethod::None;
    if (a.rays > 0) o.receiver.shadows.rays_per_patch = a.rays;
    if (a.shooter_level >= 0) o.shooter_level = a.shooter_level;
    if (a.contact_depth >= 0) o.receiver.contact_depth = a.contact_depth;
    if (a.has_contact_oracle)
        o.receiver.contact_oracle_test = a.contact_oracle == "means" ? OracleTest::Means
                                                                     : OracleTest::Interpolation;
    if (a.has_ambient) o.ambient = a.ambient == "on";
    if (a.has_unify) o.receiver.unify_by_projection = a.unify == "projection";
    if (a.has_hidden) o.hidden_regions = a.hidden == "on";
#ifdef _OPENMP
    if (run.threads > 0) omp_set_num_threads(run.threads);
#endif
    // The cost is said before it is spent: before the octree and the solve allocate.
    const int d = o.receiver.max_depth;
    check_cost(scene_cost(run.scene, o, thread_count()), a.memory_budget,
               run.path + " (" + std::to_string(run.scene.surfaces.size()) +
                   " surfaces, max depth " + std::to_string(d) + ", tessellation " +
                   std::to_string(run.scene.settings.tessellation) + ")",
               d >= slow_receiver_depth);
    // A light a hair's breadth from a surface is taken as lying on it: say so, once.
    const std::vector<NearContact> near = near_contacts(run.scene);
    if (!near.empty()) {
        const NearContact& c = near.front();
        std::ostringstream os;
        os << "warning: " << run.path << ": '" << run.scene.surfaces[size_t(c.b)].name
           << "' lies " << c.gap << " in front of the plane of '"
           << run.scene.surfaces[size_t(c.a)].name
           << "', within the solver's plane tolerance: it is taken as lying on it, and no light "
              "passes between them";
        if (near.size() > 1) os << " (and " << near.size() - 1 << " more such pairs)";
        std::cerr << os.str() << "\n";
    }
    run.octree = std::make_unique<Octree>(build_octree(run.scene));
}

}  // namespace

SceneRun read_scene_run(Args& args, const std::string& default_scene) {
    SceneRun run;
    // Read every option first: the scene path is what is left.
    const SolverArgs a = read_solver_args(args, run);
    const std::vector<std::string> pos = args.positional();
    if (pos.size() > 1)
        throw UsageError("one scene file, please (got " + std::to_string(pos.size()) + ")");
    if (pos.empty() && default_scene.empty()) throw UsageError("a scene file is required");
    run.path = pos.empty() ? default_scene : pos[0];
    const bool obj = run.path.size() > 4 && run.path.compare(run.path.size() - 4, 4, ".obj") == 0;
    run.scene = obj ? load_obj(run.path) : load_scene(run.path);
    finish_scene_run(a, run);
    return run;
}

SceneRun read_scene_run(Args& args, Scene scene, const std::string& name) {
    SceneRun run;
    const SolverArgs a = read_solver_args(args, run);
    const std::vector<std::string> pos = args.positional();
    if (!pos.empty()) throw UsageError("unexpected argument '" + pos[0] + "'");
    run.path = name;
    run.scene = std::move(scene);
    finish_scene_run(a, run);
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

void write_summary_csv(std::ostream& os, const SolveStats& st) {
    Table t({"shots", "unshot_percent", "seconds", "peak_mib", "coefficients"});
    t.add_row(summary_cells(st));
    t.write_csv(os);
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

double write_render(const SceneRun& run, const Solution& solution, const std::string& path,
                    const RenderOptions& options) {
    if (!run.scene.has_camera)
        throw InputError(run.path, 0, "the scene has no camera statement: nothing to render from");
    const double start = now_seconds();
    const Image radiance = render_radiance(run.scene, *run.octree, solution.radiosity, options);
    write_files({{path, encode_png(tone_map(radiance, options.exposure))}});
    return now_seconds() - start;
}

}  // namespace mbr
