// examples/common/scene_cli.h - what every whole-scene program shares: reading a scene and the
// solver options (the scene's `set` statements, overridden by the command line), solving with
// a progress line, and printing the statistics of a run.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/progress.h"
#include "octree/octree.h"
#include "radiosity/output/render.h"
#include "radiosity/scene/scene.h"
#include "radiosity/solver/cost.h"
#include "radiosity/solver/solver.h"

namespace mbr {

/// Usage lines of the options read_scene_run understands: SCENE, every option of the table
/// (radiosity/scene/settings.h), --threads, --quiet and --memory-budget.
std::string solver_options_usage();

/// A scene to solve, with its options and octree.
struct SceneRun {
    std::string path;
    Scene scene;
    SolverOptions options;
    int threads = 0;                 // 0: OpenMP's default
    bool quiet = false;              // no progress bar
    std::unique_ptr<Octree> octree;  // over scene_polygons(scene, settings.tessellation)
    CostEstimate cost;               // the solve's estimate (radiosity/solver/cost.h)
    double memory_budget = 0;        // --memory-budget (bytes)
    /// The run's progress on stderr (off with --quiet): reading, the octree, the solve.
    std::shared_ptr<ProgressReporter> progress;
};

/// Says the cost of the solve and of a picture of the scene's camera together before either is
/// spent (check_cost with render_bytes of radiosity/output/render.h added): UsageError when it
/// exceeds the run's memory budget.
void check_render_cost(const SceneRun& run, const RenderOptions& options);

/// The same for any output that needs `bytes` beside the solve: `item` names it in the
/// estimate's detail ("image", "export"), `doing` follows the run's description in the message
/// (" rendered at 640 x 480"), `lower` says what to lower ("the depth or the camera's size").
void check_output_cost(const SceneRun& run, double bytes, const std::string& item,
                       const std::string& doing, const std::string& lower);

/// The readers' warnings (Scene::warnings), one line each: "warning: " + SceneWarning::text().
/// read_scene_run prints them on stderr once, right after loading, with --quiet too: they are
/// about the input, not progress.
void print_scene_warnings(std::ostream& os, const Scene& scene);

/// Reads the solver options (every flag of the option table, radiosity/scene/settings.h, with
/// its aliases such as --shots and --rays; --threads, --quiet, --memory-budget), then the scene
/// path (the one positional argument, or `default_scene` when empty and none is given), loads
/// the scene (printing its warnings, print_scene_warnings) and builds its octree. The flags
/// override the scene's `set` lines (and are written into run.scene.settings). Call it after
/// reading the program's own options.
SceneRun read_scene_run(Args& args, const std::string& default_scene);
/// The same for a scene made by the program: the options of solver_options_usage() without SCENE
/// (a positional argument is refused), applied over the scene's settings, and the scene's
/// warnings printed; `name` stands for the path in summaries.
SceneRun read_scene_run(Args& args, Scene scene, const std::string& name);

/// Solves, with its progress on stderr (run.progress) when `progress` is set: the hidden
/// regions, each shot and the receivers inside it.
Solution solve_scene(SceneRun& run, bool progress);

/// How far the shots are, for the progress bar (0..1): the unshot share `left` on its way down
/// (geometrically) to the convergence threshold `target`; with no threshold (0: only the shot
/// limit stops the run) the shots done of `max_shots`. 1 ends the stage, so it must not come
/// before the run ends (off a terminal every update of a finished stage is printed at once).
double shot_progress_fraction(double left, double target, int shots, int max_shots);

/// One line per shot.
void print_shots(std::ostream& os, const Scene& scene, const SolveStats& stats);
/// The run's statistics as text.
void print_summary(std::ostream& os, const SceneRun& run, const SolveStats& stats);
/// shots, unshot_percent, seconds, peak_mib, coefficients.
std::vector<std::string> summary_cells(const SolveStats& stats);
/// The run's summary as one CSV table: header shots,unshot_percent,seconds,peak_mib,coefficients.
void write_summary_csv(std::ostream& os, const SolveStats& stats);

/// Renders the solution with the scene's camera, or without one the camera that frames the
/// scene (framing_camera, radiosity/output/render.h), as radiance B / pi with sRGB tone mapping
/// and options.exposure, and writes it as a PNG to `path` (all or nothing,
/// radiosity/output/output_file.h). Returns the render's seconds.
double write_render(const SceneRun& run, const Solution& solution, const std::string& path,
                    const RenderOptions& options = {});

}  // namespace mbr
