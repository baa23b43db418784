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
#include "radiosity/output/image.h"
#include "radiosity/output/output_file.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/cost.h"
#include "radiosity/solver/resolution.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbr {

std::string solver_options_usage() {
    return "  SCENE                     a scene file (docs/scene-format.md)\n" + option_usage() +
           "  --threads n               OpenMP threads, 1..256 (default: all cores)\n"
           "  --quiet                   no progress bar\n"
           "  --memory-budget X         refuse a run estimated to need more memory (bytes, or\n"
           "                            K, M, G, T: 4G; default half the physical memory)\n";
}

namespace {

/// One option of the table set from the command line; a bad value is a usage error naming the
/// flag as written.
void apply_flag(SolverSettings& s, const OptionSpec* option, const std::string& flag,
                const std::string& value) {
    try {
        apply_setting(s, *option, value, flag);
    } catch (const InputError& e) {
        throw UsageError(e.message());
    }
}

/// The solver options of the command line, read before the scene is known: each option of the
/// table (radiosity/scene/settings.h) the line gives, with the spelling it was given as.
struct SolverArgs {
    struct Given {
        const OptionSpec* option = nullptr;
        std::string flag;  // as written: the flag or an alias
        std::string value;
    };
    std::vector<Given> given;
    double memory_budget = 0;
    /// True when the line gives the option called `name`.
    bool has(const std::string& name) const {
        for (const Given& g : given)
            if (g.option->name == name) return true;
        return false;
    }
};

SolverArgs read_solver_args(Args& args, SceneRun& run) {
    SolverArgs a;
    for (const OptionSpec& o : option_table()) {
        std::vector<std::string> spellings{o.flag()};
        spellings.insert(spellings.end(), o.aliases.begin(), o.aliases.end());
        for (const std::string& flag : spellings)
            if (args.has(flag)) a.given.push_back({&o, flag, args.text(flag, "")});
    }
    // The values are checked here, before the scene is read, so that a bad flag is a usage
    // error whatever the scene holds.
    SolverSettings check;
    for (const SolverArgs::Given& g : a.given) apply_flag(check, g.option, g.flag, g.value);
    run.threads = args.integer("--threads", 0, 1, 256);
    run.quiet = args.flag("--quiet");
    a.memory_budget = read_memory_budget(args);
    return a;
}

/// "room.scene (27 surfaces, max depth 6, tessellation 24)": a run for messages.
std::string describe_run(const SceneRun& run) {
    return run.path + " (" + std::to_string(run.scene.surfaces.size()) + " surfaces, max depth " +
           std::to_string(run.options.receiver.max_depth) + ", tessellation " +
           std::to_string(run.scene.settings.tessellation) + ")";
}

/// The scene's warnings; the scene's settings, then the command line over them; threads; the
/// octree.
void finish_scene_run(const SolverArgs& a, SceneRun& run) {
    // Once per run, before anything else can fail: what the readers let pass is said first.
    print_scene_warnings(std::cerr, run.scene);
    SolverSettings s = run.scene.settings;
    for (const SolverArgs::Given& g : a.given) apply_flag(s, g.option, g.flag, g.value);
    if (s.min_depth > s.max_depth) {
        const bool has_min = a.has("min_depth"), has_max = a.has("max_depth");
        if (has_min && has_max) throw UsageError("--min-depth must not exceed --max-depth");
        // One bound given on the command line moves the other along.
        if (has_max)
            s.min_depth = s.max_depth;
        else
            s.max_depth = s.min_depth;
    }
    run.scene.settings = s;
    SolverOptions& o = run.options;
    o = solver_options(s);
#ifdef _OPENMP
    if (run.threads > 0) omp_set_num_threads(run.threads);
#endif
    // The cost is said before it is spent: before the octree and the solve allocate.
    const int d = o.receiver.max_depth;
    run.cost = scene_cost(run.scene, o, thread_count());
    run.memory_budget = a.memory_budget;
    // DESIGN: slow means a receiver depth that holds big grids, or a minute of one core.
    check_cost(run.cost, run.memory_budget, describe_run(run),
               d >= slow_receiver_depth || run.cost.seconds > 60);
    // A light a hair's breadth from a surface is taken as lying on it: say so, once.
    const std::vector<NearContact> near = near_contacts(run.scene);
    if (!near.empty()) {
        const NearContact& c = near.front();
        std::ostringstream os;
        os << "warning: " << run.path << ": '" << run.scene.surfaces[size_t(c.b)].name << "' lies "
           << c.gap << " in front of the plane of '" << run.scene.surfaces[size_t(c.a)].name
           << "', within the solver's plane tolerance: it is taken as lying on it, and no light "
              "passes between them";
        if (near.size() > 1) os << " (and " << near.size() - 1 << " more such pairs)";
        std::cerr << os.str() << "\n";
    }
    run.octree = std::make_unique<Octree>(build_octree(run.scene));
}

}  // namespace

void print_scene_warnings(std::ostream& os, const Scene& scene) {
    for (const SceneWarning& w : scene.warnings) os << "warning: " << w.text() << "\n";
}

void check_render_cost(const SceneRun& run, const RenderOptions& options) {
    const Camera& camera = run.scene.camera;
    const double image = render_bytes(camera.width, camera.height, options);
    CostEstimate c = run.cost;
    c.bytes += image;
    c.detail += ", image " + format_bytes(image);
    check_cost(c, run.memory_budget,
               describe_run(run) + " rendered at " + std::to_string(camera.width) + " x " +
                   std::to_string(camera.height),
               false, "the depth or the camera's size");
}

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

/// Progress on stderr: on a terminal a line redrawn in place, elsewhere (a pipe, a log file) a
/// line every `interval` seconds, the first after that long, so that short runs stay silent.
class ProgressBar {
public:
    explicit ProgressBar(bool on) : on_(on), terminal_(isatty(2)), start_(now_seconds()) {}
    ~ProgressBar() {
        if (drawn_) std::fprintf(stderr, "\r%*s\r", 100, "");
    }
    /// The hidden regions before the first shot: `done` of `total` surfaces.
    void setup(int done, int total) {
        const double elapsed = now_seconds() - start_;
        const double rest = done > 0 ? elapsed * (total - done) / done : 0;
        char line[160];
        std::snprintf(line, sizeof line,
                      "hidden regions: %d/%d surfaces, %.1f s, about %.0f s left", done, total,
                      elapsed, rest);
        show(line, done == total);
    }
    void update(const ShotStats& shot, const ProgressiveSolver& solver, int max_shots,
                double target) {
        const SolveStats& st = solver.solution().stats;
        double elapsed = 0;
        for (const ShotStats& x : st.per_shot) elapsed += x.seconds;
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
        char line[200];
        std::snprintf(line, sizeof line,
                      "[%s] shot %d/%d, unshot %.3g%%, %.1f s, about %.0f s left", bar.c_str(),
                      shot.shot, max_shots, 100 * left, elapsed, rest);
        show(line, false);
    }

private:
    static constexpr double interval = 5;  // seconds between lines off a terminal
    void show(const char* line, bool last) {
        if (!on_) return;
        if (terminal_) {
            std::fprintf(stderr, "\r%s   ", line);
            drawn_ = true;
        } else {
            // Off a terminal: every `interval` seconds, and the end of a stage that was shown.
            const double t = now_seconds() - start_;
            if (t < next_ && !(last && shown_)) return;
            std::fprintf(stderr, "%s\n", line);
            shown_ = true;
            next_ = t + interval;
        }
        std::fflush(stderr);
    }
    bool on_ = false;
    bool terminal_ = false;
    bool drawn_ = false;  // a line is on the terminal, to be cleared at the end
    bool shown_ = false;  // off a terminal, some line has been printed
    double start_ = 0;
    double next_ = interval;
};

}  // namespace

Solution solve_scene(SceneRun& run, bool progress) {
    // A receiver too coarse for a light's peak is an error before the first shot, not a dark
    // picture after it (radiosity/solver/resolution.h).
    check_resolution(run.scene, run.options.receiver.max_depth);
    ProgressBar bar(progress && !run.quiet);
    return solve(
        run.scene, *run.octree, run.options,
        [&](const ShotStats& shot, const ProgressiveSolver& solver) {
            bar.update(shot, solver, run.options.max_shots, run.options.convergence);
        },
        [&](int done, int total) { bar.setup(done, total); });
}

namespace {

// `power` as a percent of the emitted power. DESIGN: a scene that emits nothing has nothing
// left to shoot: 0 %, not 0/0 (which would print as an empty cell).
double percent_of_emitted(double power, const SolveStats& stats) {
    return stats.emitted_power > 0 ? 100 * power / stats.emitted_power : 0.0;
}

}  // namespace

void print_shots(std::ostream& os, const Scene& scene, const SolveStats& stats) {
    Table t({"shot", "shooter", "shooter_power", "unshot_before_percent", "unshot_after_percent",
             "receivers", "kernel_evals", "rays", "level", "seconds"});
    for (const ShotStats& s : stats.per_shot)
        t.add_row({std::to_string(s.shot), scene.surfaces[s.shooter].name,
                   cell_g(s.shooter_power, 4),
                   cell_g(percent_of_emitted(s.unshot_before, stats), 4),
                   cell_g(percent_of_emitted(s.unshot_after, stats), 4),
                   std::to_string(s.receivers), std::to_string(s.kernel_evals),
                   std::to_string(s.rays), std::to_string(s.finest_level), cell(s.seconds, 3)});
    t.write_text(os);
}

std::vector<std::string> summary_cells(const SolveStats& st) {
    return {std::to_string(st.shots), cell_g(percent_of_emitted(st.unshot_power, st), 4),
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
       << "shots " << st.shots
       << (st.converged ? ", stopped: largest unshot share below the convergence threshold, "
                        : ", stopped at the shot limit, ")
       << cell_g(percent_of_emitted(st.unshot_power, st), 4) << " % of the power unshot in total ("
       << (run.options.ambient ? "ambient correction applied" : "no ambient correction") << ")\n"
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
    const Image radiance =
        render_radiance(run.scene, *run.octree, radiosity_view(run.scene, solution), options);
    write_files({{path, encode_png(tone_map(radiance, options.exposure))}});
    return now_seconds() - start;
}

}  // namespace mbr
