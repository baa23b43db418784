// examples/mbr/mbr.cpp - the mbr command-line tool: solve a scene by multiresolution B-spline
// radiosity (paper sections 4-6) and render it or export it for viewers, print the paper's
// tables, or read the solved radiosity (or an independent path-traced estimate) at chosen points.
//
//   mbr render SCENE -o OUT.png [options]     solve (or load) and render to PNG (and HDR)
//   mbr probe SCENE --points FILE.csv         solve (or load), then B at the points, as CSV
//     both with --light-group NAME=WEIGHT ... [--group-solutions PREFIX]: relighting, the
//     weighted sum of each light group's solution (radiosity/solver/superposition.h)
//   mbr export SCENE -o OUT.glb|OUT.ply       solve (or load), then the lit surfaces as a mesh
//                                             (glTF 2.0 binary or PLY) for viewers
//   mbr reference SCENE --points FILE.csv --paths N   path-traced B at the points
//   mbr tables                                Tables 1, 2 and 3 beside the paper's values
//   mbr --help | mbr COMMAND --help | mbr --version
//
// Exit status: 0 on success, 2 for bad usage or bad input (an output path that cannot be written,
// or that names an input or another output, is bad usage: refused before any work), 1 for a
// failure while running; one line on stderr. The outputs of a run are written all or none
// (write_files, radiosity/output/output_file.h).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/paper_tables.h"
#include "examples/common/reference_command.h"
#include "examples/common/scene_cli.h"
#include "examples/common/transfer_cli.h"
#include "math/check.h"
#include "radiosity/output/export.h"
#include "radiosity/output/output_file.h"
#include "radiosity/output/render.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/solver/superposition.h"

#ifndef MBR_VERSION
#define MBR_VERSION "unknown"
#endif

namespace mbr {
namespace {

const char* main_usage =
    "usage: mbr COMMAND [options]\n"
    "  Multiresolution B-spline radiosity (Yu and Peng): radiosity as tensor B-splines of\n"
    "  several scales, solved by progressive refinement with shadows.\n"
    "commands:\n"
    "  render SCENE -o OUT.png     solve the scene (or load a solution) and render it;\n"
    "    --light-group NAME=WEIGHT ... [--group-solutions PREFIX]: relight, a weighted sum\n"
    "    of the light groups' solutions, without solving again (mbr render --help)\n"
    "  probe SCENE --points F.csv  solve (or load), then print B at the given world points\n"
    "  export SCENE -o OUT.glb|OUT.ply\n"
    "                              solve (or load), then write the lit surfaces as a glTF 2.0\n"
    "                              binary or PLY mesh for viewers (Blender, three.js)\n"
    "  reference SCENE --points F.csv --paths N\n"
    "                              an independent path-traced estimate at those points\n"
    "  tables                      the paper's Tables 1, 2 and 3, computed now, beside its values\n"
    "  --help, COMMAND --help      usage; --version: the version\n"
    "Scene files: docs/scene-format.md. Exit status 0 ok, 2 bad usage or input, 1 failure.\n";

/// Usage lines of the light-group options (render and, without saving, probe).
std::string light_group_usage(bool render) {
    std::string u =
        "light groups (relighting by superposition; docs/solution-format.md, \"Light groups\"):\n"
        "  A light group is an emitting material and every surface made of it. A group's\n"
        "  solution is the scene solved with every other group's emission off (reflectance\n"
        "  kept). The result is the weighted sum of the groups' solutions: the solve of the\n"
        "  scene with each group's emission times its weight, to the solves' tolerance.\n"
        "  --light-group NAME=WEIGHT group NAME's weight, finite and >= 0 (0 turns it off, 2\n"
        "                            doubles it); repeat it for several groups (or give\n"
        "                            several, blank-separated, in one argument); a group not\n"
        "                            named keeps weight 1\n"
        "  --group-solutions PREFIX  read group NAME's solution from the file PREFIX + NAME +\n"
        "                            .solution instead of solving (no solve at all)\n";
    if (render)
        u += "  --save-group-solutions PREFIX\n"
             "                            solve each group and write its solution to PREFIX +\n"
             "                            NAME + .solution, with the image (all or none)\n";
    u += render ? "  Without --group-solutions, every group is solved now, one after the other.\n"
                : "  Without --group-solutions, every group is solved now, one after the other\n"
                  "  (mbr render --save-group-solutions keeps them).\n";
    u += "  In file names, bytes of NAME other than letters, digits, . _ - + = , @ and\n"
         "  non-ASCII bytes are written %XX.\n";
    return u;
}

std::string render_usage() {
    return std::string(
               "usage: mbr render SCENE -o OUT.png [options]\n"
               "  Solves SCENE by progressive refinement (or loads a solution) and renders it\n"
               "  with its camera: radiance B/pi at each pixel, sRGB tone mapping. Without a\n"
               "  camera statement (an OBJ file), a camera that frames the scene's bounds\n"
               "  (docs/scene-format.md, \"camera\").\n"
               "  -o OUT.png                the image (required)\n"
               "  --spp n                   samples per pixel, 1..4096 (default 4)\n"
               "  --exposure x|auto         radiance multiplier before tone mapping (default 1);\n"
               "                            auto: the lit pixels' log-average luminance shows\n"
               "                            at middle grey 0.18 (for lights in any unit)\n"
               "  --hdr OUT.hdr             also the linear radiance as Radiance HDR\n"
               "  --quadtree                draw each surface's final quadtree over the image\n"
               "  --save-solution F         write the solved fields to F\n"
               "  --load-solution F         render F's fields instead of solving\n"
               "  --seed n                  seed of the pixel jitter (default 1)\n"
               "  --camera EX EY EZ LX LY LZ UX UY UZ\n"
               "                            the camera's eye, look_at point and up direction\n"
               "                            (replacing the scene's or the framing camera's)\n"
               "  --fov F                   vertical field of view, degrees in (0, 180)\n"
               "  --size W H                image size in pixels, 1..16384 each\n"
               "  --back-faces cull|black   a ray meeting a surface's back sees what lies\n"
               "                            beyond (default) or black\n") +
           light_group_usage(true) + solver_options_usage();
}

std::string probe_usage() {
    return std::string(
               "usage: mbr probe SCENE --points FILE.csv [--load-solution F | --save-solution F]\n"
               "                 [options]\n"
               "  Solves SCENE (or loads a solution) and prints the radiosity at each point of\n"
               "  FILE.csv as CSV: name,B_r,B_g,B_b, one row per point in the file's order; the\n"
               "  solve's summary (shots, unshot power, seconds, counts) goes to stderr unless\n"
               "  --quiet.\n"
               "  --points FILE.csv         header row; columns name, x, y, z required (any\n"
               "                            order), nx, ny, nz optional (picks the surface facing\n"
               "                            that way where several are close), others ignored.\n"
               "                            Each point goes to the nearest surface point within\n"
               "                            1e-3 of the scene's bounding-box diagonal.\n"
               "  --load-solution F         use F's fields instead of solving\n"
               "  --save-solution F         write the solved fields to F (for render or probe\n"
               "                            --load-solution)\n") +
           light_group_usage(false) + solver_options_usage();
}

std::string export_usage() {
    return std::string(
               "usage: mbr export SCENE -o OUT.glb|OUT.ply [--lightmaps SIZE] [--exposure x]\n"
               "                  [--load-solution F | --save-solution F] [options]\n"
               "  Solves SCENE (or loads a solution) and writes every surface as a triangle mesh\n"
               "  with its radiosity at the vertices, for viewers: radiosity does not depend on\n"
               "  the view, so the lit scene can be looked at from anywhere (docs/export.md).\n"
               "  Each surface is a regular grid of its (u, v) domain, twice as fine as its\n"
               "  field's knots (curved ones at least the scene's tessellation; at most 256).\n"
               "  -o OUT.glb|OUT.ply        the file (required); its extension, in any case, says\n"
               "                            the format: glTF 2.0 binary (one unlit mesh per\n"
               "                            surface, COLOR_0 = min(1, exposure B/pi), the exact B\n"
               "                            as _RADIOSITY) or binary PLY (8-bit sRGB colours as\n"
               "                            mbr render's pixels, and float radiosity_r/g/b = B)\n"
               "  --exposure x              radiance multiplier of the colours, as render's\n"
               "                            (default 1); B itself is written unscaled\n"
               "  --lightmaps SIZE          .glb only: also bake every surface's B into one\n"
               "                            SIZE x SIZE sRGB PNG atlas (a power of two,\n"
               "                            16..4096; a square tile per surface), textured\n"
               "                            through TEXCOORD_0 instead of COLOR_0\n"
               "  --save-solution F         write the solved fields to F\n"
               "  --load-solution F         export F's fields instead of solving\n") +
           solver_options_usage();
}

/// The solution as the file `path` to write (save_solution's format), with "wrote PATH" in the
/// summary when reporting.
OutputFile solution_file(const std::string& path, const Scene& scene, const Solution& solution,
                         bool report, std::ostream& summary) {
    std::ostringstream os;
    save_solution(os, scene, solution);
    MBR_CHECK_MSG(!os.fail(), "the solution of " << path << " could not be formatted");
    if (report) summary << "wrote " << path << "\n";
    return {path, os.str()};
}

/// A solution: solved now (printing the summary unless quiet), or loaded.
Solution obtain_solution(SceneRun& run, const std::string& load, bool report,
                         std::ostream& summary) {
    Solution solution;
    if (!load.empty()) {
        solution = load_solution(load, run.scene);  // refuses folders, devices and FIFOs
        if (report) summary << "loaded " << load << "\n";
    } else {
        solution = solve_scene(run, true);
        if (report) print_summary(summary, run, solution.stats);
    }
    return solution;
}

/// Every file the run reads: the scene with what it includes (OBJ, MTL, textures) and the
/// loaded solution, for refuse_bad_outputs.
std::vector<std::string> run_inputs(const SceneRun& run, const std::string& load) {
    std::vector<std::string> inputs = run.scene.input_files;
    inputs.push_back(run.path);
    inputs.push_back(load);
    return inputs;
}

// ---- Light groups: relighting by superposition (radiosity/solver/superposition.h) ----------

/// The light-group options as given on the command line.
struct GroupArgs {
    std::vector<std::string> weights;  // the NAME=WEIGHT words of --light-group
    bool load = false;                 // --group-solutions PREFIX
    std::string load_prefix;
    bool save = false;  // --save-group-solutions PREFIX (render only)
    std::string save_prefix;
    bool on() const { return !weights.empty() || load || save; }
};

GroupArgs read_group_args(Args& args, bool render) {
    GroupArgs a;
    if (args.has("--light-group")) {
        // main() has joined every --light-group of the line into one, blank-separated.
        std::istringstream words(args.text("--light-group", ""));
        for (std::string w; words >> w;) a.weights.push_back(w);
        if (a.weights.empty()) throw UsageError("--light-group expects NAME=WEIGHT");
    }
    a.load = args.has("--group-solutions");
    a.load_prefix = args.text("--group-solutions", "");
    if (render) {
        a.save = args.has("--save-group-solutions");
        a.save_prefix = args.text("--save-group-solutions", "");
    }
    if (a.load && a.save)
        throw UsageError(
            "--group-solutions and --save-group-solutions exclude each other (the first reads "
            "the groups' solutions, the second solves the groups and writes them)");
    return a;
}

/// A group's name as part of a file name: letters, digits, . _ - + = , @ and non-ASCII bytes as
/// they are, every other byte (a '/', a '%', a control byte) as %XX.
std::string file_name_part(const std::string& name) {
    std::string out;
    for (unsigned char c : name) {
        if (std::isalnum(c) || c >= 0x80 || (c != 0 && std::strchr("._-+=,@", c) != nullptr)) {
            out += char(c);
        } else {
            char hex[4];
            std::snprintf(hex, sizeof hex, "%%%02X", unsigned(c));
            out += hex;
        }
    }
    return out;
}

/// What the light-group options ask of the scene: its groups with their weights and files.
struct GroupPlan {
    std::vector<LightGroup> groups;
    std::vector<double> weights;    // per group: its --light-group weight, else 1
    std::vector<std::string> load;  // per group: the solution file to read, or empty: solve
    std::vector<std::string> save;  // per group: the solution file to write, or empty
};

/// Why `name` is no light group of the scene, with the names of those it has.
std::string no_such_group(const SceneRun& run, const std::string& name,
                          const std::vector<LightGroup>& groups) {
    const int m = run.scene.find_material(name);
    std::string why =
        m < 0 ? "unknown light group '" + name + "'"
        : !run.scene.materials[size_t(m)].emits()
            ? "material '" + name + "' emits nothing, so it is no light group"
            : "material '" + name + "' is used by no surface, so it is no light group";
    std::string list;
    const size_t shown = std::min<size_t>(groups.size(), 20);
    for (size_t g = 0; g < shown; ++g) list += (g ? ", " : "") + groups[g].name;
    if (groups.size() > shown) list += " and " + std::to_string(groups.size() - shown) + " more";
    return why + ": the light groups of " + run.path + " (its emitting materials) are " + list;
}

GroupPlan plan_groups(const GroupArgs& a, const SceneRun& run) {
    GroupPlan p;
    p.groups = light_groups(run.scene);
    if (p.groups.empty())
        throw UsageError(
            run.path + " has no light group: no surface is made of an emitting material", false);
    const size_t n = p.groups.size();
    p.weights.assign(n, 1.0);
    std::vector<std::string> given(n);
    for (const std::string& word : a.weights) {
        const size_t eq = word.rfind('=');  // a name may hold '=', a number never does
        if (eq == std::string::npos || eq == 0 || eq + 1 == word.size())
            throw UsageError("--light-group expects NAME=WEIGHT, got '" + word + "'");
        const std::string name = word.substr(0, eq), value = word.substr(eq + 1);
        size_t g = 0;
        while (g < n && p.groups[g].name != name) ++g;
        if (g == n) throw UsageError(no_such_group(run, name, p.groups), false);
        if (!given[g].empty())
            throw UsageError("light group '" + name + "' is given twice (" + given[g] + " and " +
                             word + ")");
        given[g] = word;
        const double w = parse_number(value, "--light-group " + name);
        if (!(w >= 0))
            throw UsageError("--light-group " + name + ": the weight must be >= 0, got '" + value +
                             "'");
        const Material& mat = run.scene.materials[size_t(p.groups[g].material)];
        if (w * max_abs(mat.emission.maximum()) > max_emission)
            throw UsageError("--light-group " + word + " makes the emission " +
                             cell_g(w * max_abs(mat.emission.maximum()), 6) +
                             ", beyond the scene format's limit of 1e30");
        p.weights[g] = w;
    }
    p.load.resize(n);
    p.save.resize(n);
    for (size_t g = 0; g < n; ++g) {
        const std::string file = file_name_part(p.groups[g].name) + ".solution";
        if (a.load) p.load[g] = a.load_prefix + file;
        if (a.save) p.save[g] = a.save_prefix + file;
    }
    return p;
}

/// The fingerprint of `scene` as a solution file's second line writes it.
std::string fingerprint_text(const Scene& scene) {
    char fp[32];
    std::snprintf(fp, sizeof fp, "%016" PRIx64, scene_fingerprint(scene));
    return fp;
}

/// Group g's solution from plan.load[g], for the group's scene. A file that is another group's
/// solution, or the whole scene's, is refused by that name rather than as another scene's.
Solution load_group_solution(const SceneRun& run, const GroupPlan& plan, size_t g,
                             const Scene& group_scene) {
    const std::string& path = plan.load[g];
    try {
        return load_solution(path, group_scene);  // refuses folders, devices and FIFOs
    } catch (const InputError& e) {
        if (e.line() != 2 || e.message().rfind("the solution was made for another scene", 0) != 0)
            throw;
        // The first two lines have been read and checked: "mbr-solution 1", "fingerprint H".
        std::ifstream in(path);
        std::string header, word, fp;
        std::getline(in, header);
        in >> word >> fp;
        for (size_t h = 0; h < plan.groups.size(); ++h)
            if (h != g && fp == fingerprint_text(light_group_scene(run.scene, plan.groups, int(h))))
                throw InputError(path, 2,
                                 "this is the solution of light group '" + plan.groups[h].name +
                                     "', not of light group '" + plan.groups[g].name + "'");
        if (fp == fingerprint_text(run.scene))
            throw InputError(path, 2,
                             "this is the solution of the whole scene (every light, as "
                             "--save-solution writes it), not of light group '" +
                                 plan.groups[g].name + "'");
        throw;
    }
}

/// Each group's solution, read (plan.load) or solved now, and their weighted sum
/// (radiosity/solver/superposition.h). The group solutions to save are added to `files`.
Solution relight(SceneRun& run, const GroupPlan& plan, bool report, std::ostream& summary,
                 std::vector<OutputFile>& files) {
    std::vector<Solution> solutions;
    solutions.reserve(plan.groups.size());
    for (size_t g = 0; g < plan.groups.size(); ++g) {
        const std::string& name = plan.groups[g].name;
        Scene group_scene = light_group_scene(run.scene, plan.groups, int(g));
        if (!plan.load[g].empty()) {
            solutions.push_back(load_group_solution(run, plan, g, group_scene));
            // The fields of one surface must share the order in every sum (the levels may
            // differ; the surfaces' orders may differ too, SceneSurface::order).
            for (size_t i = 0; i < run.scene.surfaces.size(); ++i) {
                const int m = solutions.back().radiosity[i].order();
                const int m0 = solutions[0].radiosity[i].order();
                if (m != m0)
                    throw InputError(plan.load[g], 0,
                                     "surface '" + run.scene.surfaces[i].name +
                                         "' has fields of order " + std::to_string(m) +
                                         " here and of order " + std::to_string(m0) + " in " +
                                         plan.load[0] +
                                         ": solve every light group with the same orders");
            }
            // And each surface's field must hold the same quantity (B, or H: `set texture_field`).
            for (size_t i = 0; i < run.scene.surfaces.size(); ++i) {
                const auto holds = [i](const Solution& s) {
                    const bool h =
                        i < s.quantity.size() && s.quantity[i] == FieldQuantity::irradiance;
                    return std::string(h ? "the irradiance H" : "the radiosity B");
                };
                if (holds(solutions.back()) != holds(solutions[0]))
                    throw InputError(plan.load[g], 0,
                                     "surface '" + run.scene.surfaces[i].name + "' holds " +
                                         holds(solutions.back()) + " here and " +
                                         holds(solutions[0]) + " in " + plan.load[0] +
                                         ": solve every light group with the same texture_field");
            }
            if (report) summary << "loaded " << plan.load[g] << " (light group " << name << ")\n";
        } else {
            // The group's solve: the run's scene is the group's while it runs (the surfaces are
            // the same, so the octree and the options hold).
            std::swap(run.scene, group_scene);
            solutions.push_back(solve_scene(run, true));
            std::swap(run.scene, group_scene);
            if (report) {
                summary << "light group " << name << " alone:\n";
                print_summary(summary, run, solutions.back().stats);
            }
        }
        if (!plan.save[g].empty()) {
            // Written with the images, all or none (radiosity/output/output_file.h).
            std::ostringstream os;
            save_solution(os, group_scene, solutions.back());
            MBR_CHECK_MSG(!os.fail(),
                          "the solution of " << plan.save[g] << " could not be formatted");
            files.push_back({plan.save[g], os.str()});
            if (report) summary << "wrote " << plan.save[g] << "\n";
        }
    }
    std::vector<const Solution*> terms;
    for (const Solution& s : solutions) terms.push_back(&s);
    Solution sum = combine(terms, plan.weights);
    if (report) {
        summary << "relit:";
        for (size_t g = 0; g < plan.groups.size(); ++g)
            summary << (g ? ", " : " ") << plan.groups[g].name << " x "
                    << cell_g(plan.weights[g], 6);
        summary << "\n";
    }
    return sum;
}

/// The camera options of render, as given (empty vectors when absent).
struct CameraArgs {
    std::vector<double> view;  // --camera: eye, look_at, up (9 numbers)
    double fov = 0;            // --fov (0: absent)
    std::vector<double> size;  // --size W H
};

CameraArgs read_camera_args(Args& args) {
    CameraArgs c;
    c.view = args.numbers("--camera", 9);
    c.fov = args.number("--fov", 0);
    if (args.has("--fov") && !(c.fov > 0 && c.fov < 180))
        throw UsageError("--fov must be in (0, 180) degrees");
    c.size = args.numbers("--size", 2);
    for (double v : c.size)
        if (!(v >= 1 && v <= 16384 && v == std::floor(v)))
            throw UsageError("--size takes two integers in 1..16384");
    return c;
}

/// The scene's camera, or the framing camera when it has none (framing_camera), with the
/// options' changes; UsageError when the result cannot look anywhere.
Camera chosen_camera(const Scene& scene, const CameraArgs& c) {
    Camera cam = scene.has_camera ? scene.camera : framing_camera(scene);
    if (!c.view.empty()) {
        cam.eye = {c.view[0], c.view[1], c.view[2]};
        cam.look_at = {c.view[3], c.view[4], c.view[5]};
        cam.up = {c.view[6], c.view[7], c.view[8]};
        const Vec3 dir = cam.look_at - cam.eye;
        if (!(length(dir) > 0)) throw UsageError("--camera: eye and look_at coincide");
        if (!(length(cam.up) > 0) || length(cross(normalize(dir), normalize(cam.up))) < 1e-6)
            throw UsageError("--camera: up is zero or parallel to the viewing direction");
    }
    if (c.fov > 0) cam.fov_degrees = c.fov;
    if (!c.size.empty()) {
        cam.width = int(c.size[0]);
        cam.height = int(c.size[1]);
    }
    return cam;
}

int render_command(Args& args) {
    const std::string out = args.text("-o", "");
    const int spp = args.integer("--spp", 4, 1, 4096);
    // --exposure x, or auto (auto_exposure, render.h): chosen from the picture once rendered.
    const std::string exposure_text = args.text("--exposure", "1");
    const bool auto_exposed = exposure_text == "auto";
    const double exposure = auto_exposed ? 1 : parse_number(exposure_text, "--exposure");
    const std::string hdr = args.text("--hdr", "");
    const bool quadtree = args.flag("--quadtree");
    const std::string save = args.text("--save-solution", "");
    const std::string load = args.text("--load-solution", "");
    const int seed = args.integer("--seed", 1, 0, 2147483647);
    const CameraArgs camera_args = read_camera_args(args);
    const std::string faces = args.text("--back-faces", "cull");
    if (faces != "cull" && faces != "black")
        throw UsageError("--back-faces must be cull or black (got '" + faces + "')");
    const BackFaces back_faces = faces == "cull" ? BackFaces::Cull : BackFaces::Black;
    const GroupArgs group_args = read_group_args(args, true);
    if (out.empty()) throw UsageError("-o OUT.png is required");
    if (!save.empty() && !load.empty())
        throw UsageError("--save-solution and --load-solution exclude each other");
    if (group_args.on() && (args.has("--save-solution") || args.has("--load-solution")))
        throw UsageError(
            "--save-solution and --load-solution hold the whole scene's solution; with light "
            "groups use --save-group-solutions and --group-solutions");
    if (!(exposure > 0)) throw UsageError("--exposure must be positive");
    // Refuse outputs that cannot be written, or that clash, before any work; the scene's own
    // files, and the light groups' files, are known once it is read (and before it is solved).
    std::vector<std::string> outputs{out, hdr, save};
    refuse_bad_outputs(outputs, {load});
    SceneRun run = read_scene_run(args, "");
    args.finish();
    std::vector<std::string> inputs = run_inputs(run, load);
    GroupPlan plan;
    if (group_args.on()) {
        plan = plan_groups(group_args, run);
        outputs.insert(outputs.end(), plan.save.begin(), plan.save.end());
        inputs.insert(inputs.end(), plan.load.begin(), plan.load.end());
    }
    refuse_bad_outputs(outputs, inputs);
    run.scene.camera = chosen_camera(run.scene, camera_args);
    run.scene.has_camera = true;
    RenderOptions ro;
    ro.back_faces = back_faces;
    ro.samples_per_pixel = spp;
    ro.seed = static_cast<std::uint64_t>(seed);
    ro.exposure = exposure;
    ro.quadtree_overlay = quadtree;
    check_render_cost(run, ro);  // the picture's memory too, before the solve

    const bool report = !is_standard_output(out) && !is_standard_output(hdr);
    std::ostringstream summary;
    std::vector<OutputFile> files;
    const Solution solution = group_args.on() ? relight(run, plan, report, summary, files)
                                              : obtain_solution(run, load, report, summary);
    // DESIGN: a relit image is drawn with the scene whose groups' emissions are multiplied by
    // their weights: the scene the weighted sum solves. A field that holds B has the weighted
    // emission in it already; for one that holds H, radiosity_view adds E from this scene.
    const Scene lit =
        group_args.on() ? weighted_scene(run.scene, plan.groups, plan.weights) : Scene{};
    const Scene& shown = group_args.on() ? lit : run.scene;
    // Written with the images, all or none (radiosity/output/output_file.h).
    if (!save.empty()) files.push_back(solution_file(save, run.scene, solution, report, summary));
    const double start = now_seconds();
    const Image radiance = render_radiance(shown, *run.octree, radiosity_view(shown, solution), ro);
    const double shown_exposure = auto_exposed ? auto_exposure(radiance) : exposure;
    Image display = tone_map(radiance, shown_exposure);
    if (quadtree)
        draw_quadtree_overlay(display, shown, *run.octree, &solution.leaves, ro.overlay_colour,
                              nullptr, back_faces);
    files.push_back({out, encode_png(display)});
    if (!hdr.empty()) {
        std::ostringstream os;
        write_hdr(os, radiance);
        files.push_back({hdr, os.str()});
    }
    write_files(files);
    if (report) {
        summary << "rendered " << radiance.width << " x " << radiance.height << ", " << spp
                << " samples per pixel, in " << cell(now_seconds() - start, 2) << " s"
                << (auto_exposed ? ", exposure " + detail::fmt_approx(shown_exposure) + " (auto)"
                                 : "")
                << "\n"
                << "wrote " << out << (hdr.empty() ? "" : " and " + hdr) << "\n";
        std::cout << summary.str();
    }
    return 0;
}

int probe_command(Args& args) {
    const std::string points_path = args.text("--points", "");
    const std::string load = args.text("--load-solution", "");
    const std::string save = args.text("--save-solution", "");
    const GroupArgs group_args = read_group_args(args, false);
    if (points_path.empty()) throw UsageError("--points FILE.csv is required");
    if (!save.empty() && !load.empty())
        throw UsageError("--save-solution and --load-solution exclude each other");
    if (group_args.on() && (args.has("--load-solution") || args.has("--save-solution")))
        throw UsageError(
            "--save-solution and --load-solution hold the whole scene's solution; with light "
            "groups use --group-solutions");
    // As render does: an output that cannot be written, or that is an input, before any work.
    const std::vector<std::string> outputs{save};
    refuse_bad_outputs(outputs, {load, points_path});
    SceneRun run = read_scene_run(args, "");
    args.finish();
    std::vector<std::string> inputs = run_inputs(run, load);
    inputs.push_back(points_path);
    refuse_bad_outputs(outputs, inputs);
    const GroupPlan plan = group_args.on() ? plan_groups(group_args, run) : GroupPlan{};
    // Read and place the points before solving: a bad file fails at once.
    const std::vector<ProbePoint> points = read_probe_points(points_path);
    const std::vector<SurfaceLocation> at = locate_probe_points(
        run.scene, run.octree->polygons(), points, points_path, probe_tolerance(run.scene));
    // The summary goes to stderr (stdout is the CSV), unless --quiet.
    const bool report = !run.quiet;
    std::ostringstream summary;
    std::vector<OutputFile> none;  // probe saves no group solutions
    const Solution solution = group_args.on() ? relight(run, plan, report, summary, none)
                                              : obtain_solution(run, load, report, summary);
    if (!save.empty())  // a temporary name, then renamed
        write_files({solution_file(save, run.scene, solution, report, summary)});
    std::cerr << summary.str();
    // Relit: B is formed with the groups' emissions times their weights (see render_command).
    const Scene lit =
        group_args.on() ? weighted_scene(run.scene, plan.groups, plan.weights) : Scene{};
    const Scene& shown = group_args.on() ? lit : run.scene;
    std::vector<std::string> names;
    std::vector<Rgb> values;
    const RadiosityView view = radiosity_view(shown, solution);  // B = E + rho H for H fields
    for (size_t i = 0; i < points.size(); ++i) {
        names.push_back(points[i].name);
        values.push_back(radiosity_at(view, shown, at[i]));
    }
    write_radiosity_csv(std::cout, names, values);
    return 0;
}

/// The format of `mbr export`, from the extension of its output, in any case.
enum class ExportFormat { Glb, Ply };

ExportFormat export_format(const std::string& path) {
    const std::string ext = detail::lowercase_extension(path);
    if (ext == ".glb") return ExportFormat::Glb;
    if (ext == ".ply") return ExportFormat::Ply;
    throw UsageError("-o " + path +
                     ": the export format is chosen by the extension, .glb (glTF 2.0 binary) or "
                     ".ply");
}

int export_command(Args& args) {
    const std::string out = args.text("-o", "");
    const double exposure = args.number("--exposure", 1);
    const bool lightmaps = args.has("--lightmaps");
    const int lightmap_size = args.integer("--lightmaps", 0, min_lightmap_size, max_lightmap_size);
    const std::string save = args.text("--save-solution", "");
    const std::string load = args.text("--load-solution", "");
    if (out.empty()) throw UsageError("-o OUT.glb or -o OUT.ply is required");
    const ExportFormat format = export_format(out);
    if (lightmaps && !valid_lightmap_size(lightmap_size))
        throw UsageError(
            "--lightmaps must be a power of two in " + std::to_string(min_lightmap_size) + ".." +
            std::to_string(max_lightmap_size) + " (got " + std::to_string(lightmap_size) + ")");
    if (lightmaps && format != ExportFormat::Glb)
        throw UsageError("--lightmaps needs a .glb output (a PLY file holds no textures)");
    if (!save.empty() && !load.empty())
        throw UsageError("--save-solution and --load-solution exclude each other");
    if (!(exposure > 0)) throw UsageError("--exposure must be positive");
    // As render does: outputs that cannot be written, or that clash, before any work.
    const std::vector<std::string> outputs{out, save};
    refuse_bad_outputs(outputs, {load});
    SceneRun run = read_scene_run(args, "");
    args.finish();
    refuse_bad_outputs(outputs, run_inputs(run, load));
    const int n_surfaces = int(run.scene.surfaces.size());
    if (lightmaps && n_surfaces > 0 && smallest_lightmap_size(n_surfaces) > lightmap_size) {
        const int least = smallest_lightmap_size(n_surfaces);
        throw UsageError("--lightmaps " + std::to_string(lightmap_size) + " is too small for the " +
                             std::to_string(n_surfaces) + " surfaces of " + run.path + ": " +
                             (least ? "give at least " + std::to_string(least)
                                    : std::string("even 4096 gives no 2 x 2 texels each")),
                         false);
    }

    // The export's memory too, before the solve (as render's picture: check_render_cost).
    check_output_cost(run, export_bytes(run.scene, lightmaps ? lightmap_size : 0), "export",
                      " exported", "the depth" + std::string(lightmaps ? " or --lightmaps" : ""));

    const bool report = !run.quiet && !is_standard_output(out) && !is_standard_output(save);
    std::ostringstream summary;
    const Solution solution = obtain_solution(run, load, report, summary);
    std::vector<OutputFile> files;
    // Written with the export, all or none (radiosity/output/output_file.h).
    if (!save.empty()) files.push_back(solution_file(save, run.scene, solution, report, summary));
    const double start = now_seconds();
    const RadiosityView view = radiosity_view(run.scene, solution);
    const ExportMesh mesh = tessellate_for_export(run.scene, view);
    std::string bytes;
    if (format == ExportFormat::Glb) {
        GlbOptions go;
        go.exposure = exposure;
        go.scene_name = run.path;
        Lightmap lightmap;
        if (lightmaps && n_surfaces > 0) {
            lightmap = make_lightmap(view, lightmap_size, exposure);
            go.lightmap = &lightmap;
        }
        bytes = encode_glb(mesh, go);
    } else {
        bytes = encode_ply(mesh, exposure);
    }
    const size_t n_bytes = bytes.size();
    files.push_back({out, std::move(bytes)});
    write_files(files);
    if (report) {
        summary << "exported " << mesh.surfaces.size() << " surfaces: " << mesh.vertex_count()
                << " vertices, " << mesh.triangle_count() << " triangles"
                << (lightmaps ? ", a " + std::to_string(lightmap_size) + " x " +
                                    std::to_string(lightmap_size) + " lightmap"
                              : std::string())
                << ", " << n_bytes << " bytes, in " << cell(now_seconds() - start, 2) << " s\n"
                << "wrote " << out << "\n";
        std::cout << summary.str();
    }
    return 0;
}

int tables_command(Args& args) {
    std::cout << "== Table 1: parallel squares ==\n";
    int status = run_paper_table(args, paper_table1, 6, true);
    std::cout << "\n== Table 2: perpendicular squares ==\n";
    status = std::max(status, run_paper_table(args, paper_table2, 2, false));
    std::cout << "\n== Table 3: dual coefficients mu_{3;0,l} ==\n";
    status = std::max(status, run_table3(args));
    return status;
}

/// Args reads each option once, but --light-group may be given many times: its values are
/// joined into one "--light-group" value, blank-separated (names hold no blanks), before Args
/// reads the line. One without a value (the last word, or before --help) is left for Args.
std::vector<std::string> join_light_groups(const std::vector<std::string>& words) {
    const std::string option = "--light-group";
    std::vector<std::string> kept;
    std::string joined;
    bool any = false;
    for (size_t i = 0; i < words.size(); ++i) {
        const std::string& w = words[i];
        const bool with_value =
            w == option && i + 1 < words.size() && words[i + 1] != "--help" && words[i + 1] != "-h";
        if (with_value || w.rfind(option + "=", 0) == 0) {
            joined += (any ? " " : "") + (with_value ? words[++i] : w.substr(option.size() + 1));
            any = true;
        } else {
            kept.push_back(w);
        }
    }
    if (any) {
        kept.push_back(option);
        kept.push_back(joined);
    }
    return kept;
}

struct Command {
    const char* name;
    std::string usage;
    int (*body)(Args&);
};

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    using namespace mbr;
    wait_passively(argv);  // before the commands' run_main, whose argv is made up
    const std::string first = argc > 1 ? argv[1] : "";
    if (first == "--version") {
        std::cout << "mbr " << MBR_VERSION
                  << " (multiresolution B-spline radiosity, Yu and Peng)\n";
        return 0;
    }
    const Command commands[] = {
        {"render", render_usage(), render_command},
        {"probe", probe_usage(), probe_command},
        {"export", export_usage(), export_command},
        {"reference", reference_usage, reference_command},
        {"tables",
         std::string("usage: mbr tables [--csv] [receiver options]\n"
                     "  The paper's Tables 1 and 2 (rea of one transfer) and Table 3 (dual\n"
                     "  coefficients), computed now, each beside the paper's values.\n") +
             receiver_options_usage,
         tables_command},
    };
    for (const Command& c : commands)
        if (first == c.name) {
            // The command's own arguments, with "mbr COMMAND" as the program name in messages.
            std::string program = std::string("mbr ") + c.name;
            std::vector<std::string> words =
                join_light_groups(std::vector<std::string>(argv + 2, argv + argc));
            std::vector<char*> sub{program.data()};
            for (std::string& w : words) sub.push_back(w.data());
            return run_main(static_cast<int>(sub.size()), sub.data(), c.usage, c.body);
        }
    if (first.empty()) {
        std::cerr << "mbr: a command is required: render, probe, export, reference or tables "
                     "(mbr --help)\n";
        return 2;
    }
    if (first == "--help" || first == "-h" || first == "help") {
        std::cout << main_usage;
        return 0;
    }
    std::cerr << "mbr: unknown command '" << first << "' (mbr --help lists the commands)\n";
    return 2;
}
