// examples/common/scene_cli.cpp - scenes, solver options, progress and statistics for the
// whole-scene programs.
#include "examples/common/scene_cli.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/output/image.h"
#include "radiosity/output/output_file.h"
#include "radiosity/scene/light_sides.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/cost.h"
#include "radiosity/solver/resolution.h"
#include "radiosity/visibility/occlusion.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbr {

std::string solver_options_usage() {
    return "  SCENE                     a scene file (docs/scene-format.md), a Wavefront OBJ file\n"
           "                            (.obj, with its MTL libraries) or an MGF file (.mgf)\n" +
           option_usage() +
           "  --strict                  refuse every fault of an imported OBJ, MTL, MGF or "
           "texture\n"
           "                            (default: repair it where the intent is clear, warn)\n"
           "  --keep-triangles          every imported triangle stays three quads (default: two\n"
           "                            triangles that make a planar quad join into one surface)\n"
           "  --light NAME[=E]          make material NAME, or the surfaces NAME and NAME.K,\n"
           "                            emit E (one number, or R,G,B; default: a mean radiosity\n"
           "                            of about 1 in the scene): for files without Ke\n"
           "  --two-sided-lights        every light emits from both sides (as the material\n"
           "                            clause two_sided makes it)\n"
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
    ImportOptions import;
    std::string light;  // --light NAME[=E], or empty
    bool two_sided_lights = false;
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
    run.progress = std::make_shared<ProgressReporter>(!run.quiet);
    a.memory_budget = read_memory_budget(args);
    a.import.strict = args.flag("--strict");
    a.import.join_triangles = !args.flag("--keep-triangles");
    a.light = args.text("--light", "");
    a.two_sided_lights = args.flag("--two-sided-lights");
    if (args.has("--light") && a.light.empty())
        throw UsageError("--light needs a material or surface name (--light NAME[=E])");
    return a;
}

/// The emission of --light NAME=E: one number (grey) or R,G,B, each finite, >= 0 and at most
/// the scene format's limit, not all zero.
Rgb light_emission(const std::string& text) {
    std::vector<std::string> parts(1);
    for (char c : text) {
        if (c == ',')
            parts.emplace_back();
        else
            parts.back() += c;
    }
    if (parts.size() != 1 && parts.size() != 3)
        throw UsageError("--light NAME=E: E is one number or R,G,B, found '" + text + "'");
    Rgb e;
    for (int i = 0; i < 3; ++i) {
        const double x = parse_number(parts[parts.size() == 1 ? 0 : size_t(i)], "--light's E");
        if (!(x >= 0 && x <= max_emission))
            throw UsageError("--light NAME=E: E must lie in [0, " + detail::fmt(max_emission) +
                             "], found " + detail::fmt(x));
        e[i] = x;
    }
    if (max_abs(e) == 0) throw UsageError("--light NAME=E: E is zero, which lights nothing");
    return e;
}

/// --light NAME[=E] (docs/scene-format.md, "Lights for files without them"): the surfaces of
/// material NAME (and of its copies for texture coordinates, NAME@LINE.K), or else the surfaces
/// called NAME or NAME.K, emit E. Without E, the lights get the emission that gives an
/// enclosure of the scene's area and mean reflectance rho a mean radiosity of 1: E = A (1 - rho)
/// / A_lights. Says on stderr what it did.
void apply_light(Scene& scene, const std::string& value, const std::string& path) {
    const size_t eq = value.find('=');
    const std::string name = value.substr(0, eq);
    if (name.empty()) throw UsageError("--light needs a material or surface name before '='");
    std::vector<int> lit;  // the surfaces that will emit
    const auto family = [](const std::string& m) { return m.substr(0, m.rfind('@')); };
    for (size_t i = 0; i < scene.surfaces.size(); ++i)
        if (family(scene.material_of(int(i)).name) == name) lit.push_back(int(i));
    const bool by_material = !lit.empty();
    if (!by_material)
        for (size_t i = 0; i < scene.surfaces.size(); ++i) {
            const std::string& s = scene.surfaces[i].name;
            if (s == name ||
                (s.size() > name.size() && s.compare(0, name.size(), name) == 0 &&
                 s[name.size()] == '.' &&
                 s.find_first_not_of("0123456789", name.size() + 1) == std::string::npos))
                lit.push_back(int(i));
        }
    if (lit.empty())
        throw UsageError("--light " + name + ": " + path +
                         " has no material and no surface of that name");
    double area = 0, lit_area = 0, rho_area = 0;
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        const double a = scene.surfaces[i].surface.area();
        area += a;
        rho_area += a * max_abs(scene.material_of(int(i)).reflectance.mean());
    }
    for (int i : lit) lit_area += scene.surfaces[size_t(i)].surface.area();
    Rgb e;
    if (eq != std::string::npos) {
        e = light_emission(value.substr(eq + 1));
    } else {
        const double rho = area > 0 ? rho_area / area : 0;
        const double x = lit_area > 0 ? std::min(area * (1 - rho) / lit_area, max_emission) : 1.0;
        e = {x, x, x};
    }
    // Each lit surface's material, copied once with the emission (a material is shared by
    // surfaces that do not all emit when the light is named by surface).
    std::vector<int> copy(scene.materials.size(), -1);
    for (int i : lit) {
        int& m = copy[size_t(scene.surfaces[size_t(i)].material)];
        if (m < 0) {
            Material light = scene.materials[size_t(scene.surfaces[size_t(i)].material)];
            if (!by_material) light.name += ":light";
            light.emission = Texture::constant(e);
            if (by_material) {
                m = scene.surfaces[size_t(i)].material;
                scene.materials[size_t(m)] = std::move(light);
            } else {
                scene.materials.push_back(std::move(light));
                m = int(scene.materials.size()) - 1;
            }
        }
        scene.surfaces[size_t(i)].material = m;
    }
    std::cerr << "--light " << name << ": " << lit.size()
              << (lit.size() == 1 ? " surface" : " surfaces") << " ("
              << (by_material ? "material" : "surface name")
              << ") emit E = " << detail::fmt_approx(e.r)
              << (e.r == e.g && e.g == e.b
                      ? std::string()
                      : " " + detail::fmt_approx(e.g) + " " + detail::fmt_approx(e.b))
              << "\n";
}

/// Loads the scene, OBJ or MGF file at `path` (load_scene_file: by its extension), applies
/// --light, and warns when nothing in it emits.
Scene load_any_scene(const std::string& path, const SolverArgs& a) {
    Scene scene = load_scene_file(path, a.import);
    if (!a.light.empty()) apply_light(scene, a.light, path);
    if (a.two_sided_lights) {
        std::vector<int> lights;
        for (size_t m = 0; m < scene.materials.size(); ++m)
            if (scene.materials[m].emits() && !scene.materials[m].two_sided)
                lights.push_back(int(m));
        add_back_sides(scene, lights);
    }
    if (scene.emitters().empty()) {
        SceneWarning w;
        w.kind = "no light";
        w.file = path;
        w.message =
            "nothing in the scene emits light (no emission, no Ke), so every picture is "
            "black; name a light with --light NAME (a material or surface name)";
        scene.warn(w);
    }
    return scene;
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
    run.progress->stage("building the octree of " + std::to_string(run.scene.surfaces.size()) +
                        " surfaces");
    run.octree = std::make_unique<Octree>(build_octree(run.scene));
    run.progress->stage("");
}

}  // namespace

void print_scene_warnings(std::ostream& os, const Scene& scene) {
    for (const SceneWarning& w : scene.warnings) os << "warning: " << w.text() << "\n";
}

void check_output_cost(const SceneRun& run, double bytes, const std::string& item,
                       const std::string& doing, const std::string& lower) {
    CostEstimate c = run.cost;
    c.bytes += bytes;
    c.detail += ", " + item + " " + format_bytes(bytes);
    check_cost(c, run.memory_budget, describe_run(run) + doing, false, lower);
}

void check_render_cost(const SceneRun& run, const RenderOptions& options) {
    const Camera& camera = run.scene.camera;
    check_output_cost(
        run, render_bytes(camera.width, camera.height, options), "image",
        " rendered at " + std::to_string(camera.width) + " x " + std::to_string(camera.height),
        "the depth or the camera's size");
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
    run.progress->stage("reading " + run.path);
    run.scene = load_any_scene(run.path, a);
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
    if (!a.light.empty()) apply_light(run.scene, a.light, name);
    finish_scene_run(a, run);
    return run;
}

namespace {

/// The shots' progress (ProgressReporter::update): the unshot share so far and, from its fall
/// over the shots so far, an estimate of the time left to the target; the receivers of the shot
/// under way when `done` and `total` are given.
struct ShotProgress {
    int shot = 0, max_shots = 0;
    double left = 1;          // unshot share after the last shot
    double target = 0;        // the convergence threshold
    double elapsed = 0;       // seconds of the shots so far
    double shot_start = 0;    // now_seconds() when the shot under way began
    int done = 0, total = 0;  // its receivers done, of
    double fraction() const { return shot_progress_fraction(left, target, shot, max_shots); }
    /// Assumes the unshot power keeps falling geometrically to the target, and no more shots
    /// than the limit, at the mean time a shot has taken; the shot under way counts with the
    /// time its receivers so far say it will take (one slow shot among fast ones, a wall
    /// shooting at hundreds of boxes, is not "about 1 s left" while it runs).
    double seconds_left(double now) const {
        double current = 0, projected = 0;
        if (done > 0 && total > 0) {
            current = std::max(0.0, now - shot_start);
            projected = current * total / done;
        }
        const int counted = shot + (projected > 0 ? 1 : 0);
        if (counted < 1) return -1;
        const double mean = (elapsed + projected) / counted;
        double rest = (max_shots - counted) * mean;
        if (left > target && left < 1 && target > 0)
            rest = std::min(rest, mean * shot * std::log(left / target) / std::log(1 / left));
        return std::max(0.0, rest) + (projected - current);
    }
};

}  // namespace

double shot_progress_fraction(double left, double target, int shots, int max_shots) {
    if (!(target > 0)) return max_shots > 0 ? std::clamp(double(shots) / max_shots, 0.0, 1.0) : 1.0;
    return std::clamp(left > 0 ? std::log(left) / std::log(target) : 1.0, 0.0, 1.0);
}

Solution solve_scene(SceneRun& run, bool progress) {
    // A receiver too coarse for a light's peak is an error before the first shot, not a dark
    // picture after it (radiosity/solver/resolution.h).
    check_resolution(run.scene, run.options.receiver.max_depth);
    ProgressReporter* reporter = progress && run.progress ? run.progress.get() : nullptr;
    ShotProgress sp;
    sp.max_shots = run.options.max_shots;
    sp.target = run.options.convergence;
    char text[160];
    bool in_shot = false;  // the stage shown is a shot's (else the solver's setup)
    if (reporter) reporter->stage("setting up the solver");
    const auto shot_stage = [&] {
        in_shot = true;
        sp.shot_start = now_seconds();
        sp.done = sp.total = 0;
        std::snprintf(text, sizeof text, "shot %d/%d, unshot %.3g%%", sp.shot + 1, sp.max_shots,
                      100 * sp.left);
        reporter->stage(text);
        reporter->update("", sp.fraction(), sp.seconds_left(sp.shot_start));
    };
    Solution solution = solve(
        run.scene, *run.octree, run.options,
        [&](const ShotStats& shot, const ProgressiveSolver& solver) {
            if (!reporter) return;
            const SolveStats& st = solver.solution().stats;
            sp.shot = shot.shot;
            sp.elapsed = 0;
            for (const ShotStats& x : st.per_shot) sp.elapsed += x.seconds;
            sp.left = st.emitted_power > 0 ? shot.unshot_after / st.emitted_power : 0;
            // After the last shot the ambient correction may follow, not a "shot 4/3".
            if (sp.shot < sp.max_shots)
                shot_stage();
            else
                reporter->stage("finishing the solve (the ambient correction when on)");
        },
        [&](int done, int total) {
            if (!reporter) return;
            if (done == 1) reporter->stage("hidden regions");
            std::snprintf(text, sizeof text, "%d/%d surfaces", done, total);
            reporter->update(text, double(done) / total);
            if (done == total) shot_stage();
        },
        [&](int done, int total) {
            if (!reporter) return;
            if (!in_shot) shot_stage();
            sp.done = done;
            sp.total = total;
            std::snprintf(text, sizeof text, "%d/%d transfers", done, total);
            reporter->update(text, sp.fraction(), sp.seconds_left(now_seconds()));
        });
    if (reporter) reporter->stage("");
    return solution;
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
             "receivers", "kernel_evals", "analytic_evals", "rays", "level", "seconds", "members"});
    for (const ShotStats& s : stats.per_shot)
        t.add_row({std::to_string(s.shot), scene.surfaces[s.shooter].name,
                   cell_g(s.shooter_power, 4),
                   cell_g(percent_of_emitted(s.unshot_before, stats), 4),
                   cell_g(percent_of_emitted(s.unshot_after, stats), 4),
                   std::to_string(s.receivers), std::to_string(s.kernel_evals),
                   std::to_string(s.analytic_evals), std::to_string(s.rays),
                   std::to_string(s.finest_level), cell(s.seconds, 3), std::to_string(s.members)});
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
       << "kernel evaluations " << st.kernel_evals << ", analytic form factors "
       << st.analytic_evals << ", shadow rays " << st.rays << "\n";
    if (st.paper_transfers > 0)
        os << "shadows auto: the paper's fractions for " << st.paper_transfers << " of "
           << st.transfers << " transfers (more than " << run.options.exact_shadow_casters
           << " shadow casters between the pair, and more than " << exact_limit / 2
           << " toward one of 3 x 3 points of the receiver or at most " << exact_limit
           << " in all), exact visibility for the rest\n";
    if (st.weak_transfers > 0)
        os << "weak transfers: " << st.weak_transfers << " of " << st.transfers
           << " (every root sample below " << cell_g(run.options.receiver.weak_transfer, 3)
           << " tolerances) took the polynomial through their root's samples\n";
    if (st.clustered_shots > 0)
        os << "planar clusters: " << st.clustered_shots << " of " << st.shots
           << " shots were of coplanar surfaces together (" << st.clustered_surfaces
           << " surfaces in them)\n";
    if (run.options.ambient && st.ambient_power > 0)
        os << "ambient correction: " << cell_g(percent_of_emitted(st.ambient_power, st), 4)
           << " % of the emitted power added"
           << (st.ambient_rays > 0 ? ", gathered by " + std::to_string(st.ambient_rays) +
                                         " rays in " + cell(st.ambient_seconds, 2) + " s"
                                   : std::string(", a constant per surface"))
           << "\n";
    // DESIGN: the constant ambient correction restores the unshot power's total but not where
    // it falls; beyond about 1 % unshot single points go wrong by several per cent (cube.mgf:
    // 1.4 % unshot, 2.9 % mean error at 196 random points; 5.9 %, 15.4 %). The gather places
    // it, but as coarse fields (level 1, up to level 4 on large bright surfaces by the final
    // gather): at 5.9 % unshot cube.mgf reads 0.68 % mean and 7.1 % at its worst point
    // (docs/method.md, "Ambient correction, gathered" and "The final gather").
    const double unshot = percent_of_emitted(st.unshot_power, st);
    const bool gathered = run.options.ambient_rays > 0;
    if (run.options.ambient && unshot > (gathered ? 5 : 1))
        os << "warning: " << cell_g(unshot, 3) << " % of the power is still unshot; "
           << (gathered ? "the ambient gather places it with coarse fields (finer on large "
                          "bright surfaces), so its shadows are soft and dark points may be off "
                          "by more than that"
                        : "the ambient correction restores its total, not where it falls, so "
                          "single points may be off by more than that")
           << " (raise --max-shots or lower --convergence for the right light)\n";
}

double write_render(const SceneRun& run, const Solution& solution, const std::string& path,
                    const RenderOptions& options) {
    // Without a camera statement, the camera that frames the scene (framing_camera).
    Scene framed;
    if (!run.scene.has_camera) {
        framed = run.scene;
        framed.camera = framing_camera(run.scene);
        framed.has_camera = true;
    }
    const Scene& shown = run.scene.has_camera ? run.scene : framed;
    const double start = now_seconds();
    if (run.progress)
        run.progress->stage("rendering " + std::to_string(shown.camera.width) + " x " +
                            std::to_string(shown.camera.height));
    const Image radiance =
        render_radiance(shown, *run.octree, radiosity_view(run.scene, solution), options);
    if (run.progress) run.progress->stage("");
    write_files({{path, encode_png(tone_map(radiance, options.exposure))}});
    return now_seconds() - start;
}

}  // namespace mbr
