// examples/mbr/mbr.cpp - the mbr command-line tool: solve a scene by multiresolution B-spline
// radiosity (paper sections 4-6) and render it, print the paper's tables, or read the solved
// radiosity (or an independent path-traced estimate) at chosen points.
//
//   mbr render SCENE -o OUT.png [options]     solve (or load) and render to PNG (and HDR)
//   mbr probe SCENE --points FILE.csv         solve (or load), then B at the points, as CSV
//   mbr reference SCENE --points FILE.csv --paths N   path-traced B at the points
//   mbr tables                                Tables 1, 2 and 3 beside the paper's values
//   mbr --help | mbr COMMAND --help | mbr --version
//
// Exit status: 0 on success, 2 for bad usage or bad input (an output path that cannot be written,
// or that names an input or another output, is bad usage: refused before any work), 1 for a
// failure while running; one line on stderr. The outputs of a run are written all or none
// (write_files, radiosity/output/output_file.h).
#include <algorithm>
#include <cerrno>
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
#include "radiosity/output/output_file.h"
#include "radiosity/output/render.h"
#include "radiosity/reference/probe.h"

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
    "  render SCENE -o OUT.png     solve the scene (or load a solution) and render it\n"
    "  probe SCENE --points F.csv  solve (or load), then print B at the given world points\n"
    "  reference SCENE --points F.csv --paths N\n"
    "                              an independent path-traced estimate at those points\n"
    "  tables                      the paper's Tables 1, 2 and 3, computed now, beside its values\n"
    "  --help, COMMAND --help      usage; --version: the version\n"
    "Scene files: docs/scene-format.md. Exit status 0 ok, 2 bad usage or input, 1 failure.\n";

std::string render_usage() {
    return std::string(
               "usage: mbr render SCENE -o OUT.png [options]\n"
               "  Solves SCENE by progressive refinement (or loads a solution) and renders it\n"
               "  with its camera: radiance B/pi at each pixel, sRGB tone mapping.\n"
               "  -o OUT.png                the image (required)\n"
               "  --spp n                   samples per pixel, 1..4096 (default 4)\n"
               "  --exposure x              radiance multiplier before tone mapping (default 1)\n"
               "  --hdr OUT.hdr             also the linear radiance as Radiance HDR\n"
               "  --quadtree                draw each surface's final quadtree over the image\n"
               "  --save-solution F         write the solved fields to F\n"
               "  --load-solution F         render F's fields instead of solving\n"
               "  --seed n                  seed of the pixel jitter (default 1)\n") +
           solver_options_usage();
}

std::string probe_usage() {
    return std::string(
               "usage: mbr probe SCENE --points FILE.csv [--load-solution F] [options]\n"
               "  Solves SCENE (or loads a solution) and prints the radiosity at each point of\n"
               "  FILE.csv as CSV: name,B_r,B_g,B_b, one row per point in the file's order.\n"
               "  --points FILE.csv         header row; columns name, x, y, z required (any\n"
               "                            order), nx, ny, nz optional (picks the surface facing\n"
               "                            that way where several are close), others ignored.\n"
               "                            Each point goes to the nearest surface point within\n"
               "                            1e-3 of the scene's bounding-box diagonal.\n"
               "  --load-solution F         use F's fields instead of solving\n") +
           solver_options_usage();
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

int render_command(Args& args) {
    const std::string out = args.text("-o", "");
    const int spp = args.integer("--spp", 4, 1, 4096);
    const double exposure = args.number("--exposure", 1);
    const std::string hdr = args.text("--hdr", "");
    const bool quadtree = args.flag("--quadtree");
    const std::string save = args.text("--save-solution", "");
    const std::string load = args.text("--load-solution", "");
    const int seed = args.integer("--seed", 1, 0, 2147483647);
    if (out.empty()) throw UsageError("-o OUT.png is required");
    if (!save.empty() && !load.empty())
        throw UsageError("--save-solution and --load-solution exclude each other");
    if (!(exposure > 0)) throw UsageError("--exposure must be positive");
    // Refuse outputs that cannot be written, or that clash, before any work; the scene's own
    // files are known once it is read (and before it is solved).
    const std::vector<std::string> outputs{out, hdr, save};
    refuse_bad_outputs(outputs, {load});
    SceneRun run = read_scene_run(args, "");
    args.finish();
    refuse_bad_outputs(outputs, run_inputs(run, load));
    if (!run.scene.has_camera)
        throw InputError(run.path, 0, "the scene has no camera statement: nothing to render from");
    RenderOptions ro;
    ro.samples_per_pixel = spp;
    ro.seed = static_cast<std::uint64_t>(seed);
    ro.exposure = exposure;
    ro.quadtree_overlay = quadtree;
    check_render_cost(run, ro);  // the picture's memory too, before the solve

    const bool report = !is_standard_output(out) && !is_standard_output(hdr);
    std::ostringstream summary;
    const Solution solution = obtain_solution(run, load, report, summary);
    std::vector<OutputFile> files;
    if (!save.empty()) {
        // Written with the images, all or none (radiosity/output/output_file.h).
        std::ostringstream os;
        save_solution(os, run.scene, solution);
        MBR_CHECK_MSG(!os.fail(), "the solution of " << save << " could not be formatted");
        files.push_back({save, os.str()});
        if (report) summary << "wrote " << save << "\n";
    }
    const double start = now_seconds();
    const Image radiance = render_radiance(run.scene, *run.octree, radiosity_view(run.scene, solution), ro);
    Image display = tone_map(radiance, exposure);
    if (quadtree)
        draw_quadtree_overlay(display, run.scene, *run.octree, &solution.leaves, ro.overlay_colour);
    files.push_back({out, encode_png(display)});
    if (!hdr.empty()) {
        std::ostringstream os;
        write_hdr(os, radiance);
        files.push_back({hdr, os.str()});
    }
    write_files(files);
    if (report) {
        summary << "rendered " << radiance.width << " x " << radiance.height << ", " << spp
                << " samples per pixel, in " << cell(now_seconds() - start, 2) << " s\n"
                << "wrote " << out << (hdr.empty() ? "" : " and " + hdr) << "\n";
        std::cout << summary.str();
    }
    return 0;
}

int probe_command(Args& args) {
    const std::string points_path = args.text("--points", "");
    const std::string load = args.text("--load-solution", "");
    if (points_path.empty()) throw UsageError("--points FILE.csv is required");
    SceneRun run = read_scene_run(args, "");
    args.finish();
    // Read and place the points before solving: a bad file fails at once.
    const std::vector<ProbePoint> points = read_probe_points(points_path);
    const std::vector<SurfaceLocation> at = locate_probe_points(
        run.scene, run.octree->polygons(), points, points_path, probe_tolerance(run.scene));
    std::ostringstream ignored;
    const Solution solution = obtain_solution(run, load, false, ignored);
    std::vector<std::string> names;
    std::vector<Rgb> values;
    const RadiosityView view = radiosity_view(run.scene, solution);  // B = E + rho H for H fields
    for (size_t i = 0; i < points.size(); ++i) {
        names.push_back(points[i].name);
        values.push_back(view.at(at[i].surface, at[i].u, at[i].v));
    }
    write_radiosity_csv(std::cout, names, values);
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
            std::vector<char*> sub{program.data()};
            for (int i = 2; i < argc; ++i) sub.push_back(argv[i]);
            return run_main(static_cast<int>(sub.size()), sub.data(), c.usage, c.body);
        }
    if (first.empty()) {
        std::cerr << "mbr: a command is required: render, probe, reference or tables "
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
