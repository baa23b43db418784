// examples/common/reference_command.cpp - `mbr reference` (reference_command.h).
#include "examples/common/reference_command.h"

#include <cerrno>
#include <cstdlib>
#include <iostream>
#include <string>

#include "examples/common/scene_cli.h"
#include "radiosity/reference/path_tracer.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"

namespace mbr {

const char* reference_usage =
    "usage: mbr reference SCENE --points FILE.csv --paths N [--seed S] [--threads n]\n"
    "  Estimates the radiosity B at the points of FILE.csv by path tracing, independently of\n"
    "  mbr's solver, and prints name,B_r,B_g,B_b,se_r,se_g,se_b (se: standard errors).\n"
    "  SCENE      a .scene file, an .obj with its .mtl, or an .mgf file\n"
    "  --points   CSV with a header naming columns name,x,y,z and optionally nx,ny,nz (the\n"
    "             normal of the face meant, where surfaces meet); each point must lie within\n"
    "             1e-3 of the scene's bounding-box diagonal of a surface\n"
    "  --paths    paths per point, at least 2 (the standard error falls as 1/sqrt(N))\n"
    "  --seed     random seed, a non-negative integer (default 1); equal seeds give equal\n"
    "             numbers for any --threads\n"
    "  --threads  OpenMP threads (default: OpenMP's choice)\n";

namespace {

std::uint64_t parse_seed(const std::string& text) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
    if (text.empty() || text[0] == '-' || text[0] == '+' || end != text.c_str() + text.size() ||
        errno == ERANGE)
        throw UsageError("--seed expects a non-negative integer below 2^64, got '" + text + "'");
    return static_cast<std::uint64_t>(v);
}

}  // namespace

int reference_command(Args& args) {
    const std::string points_path = args.text("--points", "");
    const int paths = args.integer("--paths", 0);
    const std::string seed_text = args.text("--seed", "1");
    const int threads = args.integer("--threads", 0);
    const std::vector<std::string> positional = args.positional();
    args.finish();
    if (positional.size() != 1)
        throw UsageError("expected one scene file, got " + std::to_string(positional.size()));
    if (points_path.empty()) throw UsageError("--points FILE.csv is required");
    if (!args.has("--paths")) throw UsageError("--paths N is required");
    if (paths < 2) throw UsageError("--paths must be at least 2, got " + std::to_string(paths));
    if (args.has("--threads") && threads < 1)
        throw UsageError("--threads must be at least 1, got " + std::to_string(threads));

    PathTracerOptions options;
    options.paths = paths;
    options.seed = parse_seed(seed_text);
    options.threads = threads;

    const std::string& scene_path = positional[0];
    const Scene scene = load_scene_file(scene_path);
    print_scene_warnings(std::cerr, scene);
    const std::vector<ProbePoint> points = read_probe_points(points_path);
    const Octree octree = build_octree(scene);
    const std::vector<SurfaceLocation> locations =
        locate_probe_points(scene, octree.polygons(), points, points_path, probe_tolerance(scene));
    const std::vector<RadiosityEstimate> estimates =
        estimate_radiosity(scene, octree, locations, options);

    std::vector<std::string> names;
    std::vector<Rgb> mean, standard_error;
    for (size_t i = 0; i < points.size(); ++i) {
        names.push_back(points[i].name);
        mean.push_back(estimates[i].mean);
        standard_error.push_back(estimates[i].standard_error);
    }
    write_radiosity_csv(std::cout, names, mean, standard_error);
    return 0;
}

}  // namespace mbr
