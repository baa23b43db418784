// examples/studies/cornell_accuracy.cpp - how close to a path-traced reference mbr's radiosity of
// the Cornell box is, and what it costs, at a ladder of accuracy settings (each solved from
// scratch).
//
// The reference: examples/data/cornell_reference_points.csv, path-traced radiosity at 16
// points of examples/scenes/cornell_box.scene (pbrt-v3, 4096 samples per pixel; provenance and
// noise in cornell_reference_points.md: about 0.3-0.45 % rms). The error at a point is the
// relative error of luminance Y = 0.2126 R + 0.7152 G + 0.0722 B, |Y / Y_ref - 1|.
//
// Run:  cornell_accuracy [--setting NAME] [--points FILE] [--per-point] [--csv] [-o DIR]
//                        [solver options]
// For each setting: solve seconds; mean and max luminance error over the points, and the mean
// over the lit and the shadowed points (`in_shadow` column) apart; shots, coefficients, kernel
// evaluations and rays; the lowest value of B on a 129 x 129 (u, v) grid of every surface
// and where. --csv prints `setting,seconds,mean_err_percent,max_err_percent,shots,
// coefficients`. --points FILE reads another points file with the same columns (name, x, y, z,
// nx, ny, nz, B_r, B_g, B_b; in_shadow optional). -o DIR writes DIR/cornell_<setting>.png (the
// render) and DIR/cornell_<setting>_error.png (the error against the reference image
// examples/data/cornell_reference_pbrt.png where that is below 1, and at the points).
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "examples/common/scene_cli.h"
#include "math/check.h"
#include "radiosity/output/output_file.h"
#include "radiosity/output/render.h"
#include "radiosity/reference/probe.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: cornell_accuracy [--setting NAME] [--points FILE] [--per-point] [--csv]\n"
               "                        [-o DIR] [solver options]\n"
               "  Solves the Cornell box at a ladder of accuracy settings and compares the\n"
               "  radiosity at reference points with a path-traced reference.\n"
               "  --setting NAME            one of the ladder (coarse, medium, default, fine,\n"
               "                            finer) or 'given' (just the solver options); default\n"
               "                            all of the ladder\n"
               "  --points FILE             reference points (default\n"
               "                            examples/data/cornell_reference_points.csv)\n"
               "  --per-point               every point's error per setting\n"
               "  --csv                     header setting,seconds,mean_err_percent,"
               "max_err_percent,shots,coefficients\n"
               "  -o DIR                    renders and error maps per setting\n") +
           solver_options_usage();
}

/// One rung of the ladder: what it changes from the command line's options.
struct Setting {
    std::string name;
    double tolerance;       // SolverOptions::tolerance
    int max_depth;          // receiver quadtree depth
    double convergence;     // stop at this unshot fraction
    int order = 0;          // B-spline order m (0: as given)
    int min_depth = -1;     // receiver quadtree's minimum depth (-1: as given)
    int ambient_rays = -1;  // rays a point of the ambient gather (-1: as given)
};
// DESIGN: the two fast rungs stop early (medium at the finest depth): the gathered ambient
// correction and its final gather (docs/method.md) place the power left unshot about as well as
// further shots would, and a coarse tree costs more in the shadows than the shots it saves.
// Measured 2026-12-06 (2 threads): coarse (1e-2, 3, 1e-2) 2.81 / 23.52 % in 0.78 s became
// (5e-2, 6, 5e-2) 1.18 / 3.40 % in 0.32 s; medium (3e-3, 4, 3e-3) 0.87 / 4.65 % in 1.26 s became
// (3e-2, 6, 3e-2) 0.87 / 2.15 % in 0.48 s; tolerances 2e-2 to 4e-2 and stops at 2 or 3 % read
// 0.87-1.17 / 2.06-2.75 % (docs/method.md, "The Cornell box's time").
// DESIGN: coarse is the paper's other order, m = 3, at depths 2..5 with 64 gather rays a point
// (tolerance and stop 3e-2). Its quadratic pieces need one level more at the top than m = 4's
// cubic ones (at min_depth 1 the green wall's level-1 cells follow the lamp's fall-off within
// 3.9 %; at 2 within 0.4 %), and take 9 samples a leaf instead of 16. Measured 2026-12-07:
// 0.83 / 2.45 % at the 16 points in 0.224 s a process (farm-bench, 11 pairs, against 0.391 s
// for (3e-2, 6, 3e-2) with 96 rays and m = 4, which reads 0.84 / 1.88 %); at 63 random points
// against 1M-path estimates 1.26 % mean against that setting's 1.42 % (docs/method.md). The
// previous coarse, (5e-2, 6, 5e-2) at m = 4, read 1.29 / 6.83 %.
const Setting ladder[] = {
    {"coarse", 3e-2, 5, 3e-2, 3, 2, 64},
    {"medium", 3e-2, 6, 3e-2},
    {"default", 0, 0, 0},  // the options as given (mbr render's defaults)
    {"fine", 1e-3, 6, 1e-4},
    {"finer", 3e-4, 7, 1e-4},
};

/// A reference point: where, and its radiosity.
struct RefPoint {
    ProbePoint point;
    Rgb B;
    bool in_shadow = false;
};

std::vector<RefPoint> read_reference(const std::string& path) {
    // The location columns through probe.h (checked, located later); the values here.
    const std::vector<ProbePoint> points = read_probe_points(path);
    std::ifstream in(path);
    if (!in) throw InputError(path, 0, "cannot open the file");
    std::string line;
    std::getline(in, line);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind("\xEF\xBB\xBF", 0) == 0) line = line.substr(3);
    std::vector<std::string> head;
    {
        std::stringstream ss(line);
        for (std::string w; std::getline(ss, w, ',');) head.push_back(w);
    }
    auto column = [&](const std::string& name, bool required) {
        auto it = std::find(head.begin(), head.end(), name);
        if (it == head.end() && required)
            throw InputError(path, 1, "missing column '" + name + "'");
        return it == head.end() ? -1 : int(it - head.begin());
    };
    const int cr = column("B_r", true), cg = column("B_g", true), cb = column("B_b", true);
    const int cs = column("in_shadow", false);
    std::vector<RefPoint> out;
    for (const ProbePoint& p : points) {
        // probe.h kept the line of each point: find it.
        while (std::getline(in, line)) {
            if (!line.empty() && line.back() == '\r') line.pop_back();
            std::vector<std::string> f;
            std::stringstream ss(line);
            for (std::string w; std::getline(ss, w, ',');) f.push_back(w);
            if (f.empty() || f[0] != p.name) continue;
            RefPoint r;
            r.point = p;
            for (int c = 0; c < 3; ++c) {
                const int col = c == 0 ? cr : (c == 1 ? cg : cb);
                if (col >= int(f.size())) throw InputError(path, p.line, "missing value");
                r.B[c] = parse_number(f[col], "B");
            }
            r.in_shadow = cs >= 0 && cs < int(f.size()) && f[cs] == "1";
            if (!(luminance(r.B) > 0))
                throw InputError(path, p.line, "the reference luminance must be positive");
            out.push_back(r);
            break;
        }
    }
    if (out.size() != points.size())
        throw InputError(path, 0, "could not read every point's values");
    return out;
}

struct Result {
    std::string setting;
    double seconds = 0, mean = 0, max = 0, mean_lit = 0, mean_shadow = 0;
    std::string worst;
    double lowest = 0;   // lowest channel value on a 129 x 129 (u, v) grid of every surface
    std::string lowest_at;
    SolveStats stats;
    std::vector<double> errors;  // signed, per point
};

/// The lowest value of any channel of B over a 129 x 129 grid of (u, v) on every surface (the
/// corners included), and where: radiosity is never negative (issue 19's target).
void lowest_value(const Scene& scene, const RadiosityView& view, Result& r) {
    const int n = 129;
    r.lowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < view.size(); ++i) {
        if (view.empty(i)) continue;
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) {
                const Rgb B = view.at(i, double(a) / (n - 1), double(b) / (n - 1));
                const double v = std::min({B[0], B[1], B[2]});
                if (v < r.lowest) {
                    r.lowest = v;
                    std::ostringstream where;
                    where << scene.surfaces[i].name << "(" << a << "/128," << b << "/128)";
                    r.lowest_at = where.str();
                }
            }
    }
}

/// The reference image (256 x 256, linear radiance clipped at 1 and raised to 1/2.2).
std::vector<double> reference_image(const std::string& path, int& w, int& h) {
    int n = 0;
    unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 3);
    if (!data) throw InputError(path, 0, "cannot read the reference image");
    std::vector<double> Y(size_t(w) * h);
    for (size_t i = 0; i < Y.size(); ++i) {
        Rgb c;
        for (int k = 0; k < 3; ++k) c[k] = std::pow(data[3 * i + k] / 255.0, 2.2);
        Y[i] = luminance(c);
    }
    stbi_image_free(data);
    return Y;
}

int run(Args& args) {
    const std::string which = args.text("--setting", "");
    const std::string points_path = args.text(
        "--points", std::string(MBR_SOURCE_DIR) + "/examples/data/cornell_reference_points.csv");
    const bool per_point = args.flag("--per-point");
    const bool csv = args.flag("--csv");
    const std::string dir = args.text("-o", "");
    SceneRun run =
        read_scene_run(args, std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    args.finish();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
        throw OutputError(dir, "the output directory does not exist");
    const std::vector<RefPoint> ref = read_reference(points_path);
    std::vector<ProbePoint> probes;
    for (const RefPoint& r : ref) probes.push_back(r.point);
    const std::vector<SurfaceLocation> at = locate_probe_points(
        run.scene, run.octree->polygons(), probes, points_path, probe_tolerance(run.scene));

    std::vector<Setting> settings;
    for (const Setting& s : ladder)
        if (which.empty() || which == s.name) settings.push_back(s);
    if (which == "given") settings.push_back({"given", 0, 0, 0});
    if (settings.empty())
        throw UsageError("--setting must be coarse, medium, default, fine, finer or given");

    const SolverOptions given = run.options;
    std::vector<Result> results;
    for (const Setting& s : settings) {
        run.options = given;
        if (s.tolerance > 0) run.options.tolerance = s.tolerance;
        if (s.max_depth > 0) run.options.receiver.max_depth = s.max_depth;
        if (s.convergence > 0) run.options.convergence = s.convergence;
        if (s.order > 0) run.options.receiver.m = s.order;
        if (s.min_depth >= 0) run.options.receiver.min_depth = s.min_depth;
        if (s.ambient_rays >= 0) run.options.ambient_rays = s.ambient_rays;
        run.options.receiver.min_depth =
            std::min(run.options.receiver.min_depth, run.options.receiver.max_depth);
        const double start = now_seconds();
        const Solution solution = solve_scene(run, !csv);
        Result r;
        r.setting = s.name;
        r.seconds = now_seconds() - start;
        r.stats = solution.stats;
        int n_lit = 0, n_shadow = 0;
        const RadiosityView view = radiosity_view(run.scene, solution);
        for (size_t i = 0; i < ref.size(); ++i) {
            const Rgb B = radiosity_at(view, run.scene, at[i]);
            const double e = luminance(B) / luminance(ref[i].B) - 1;
            r.errors.push_back(e);
            r.mean += std::fabs(e);
            if (std::fabs(e) > r.max) {
                r.max = std::fabs(e);
                r.worst = ref[i].point.name;
            }
            (ref[i].in_shadow ? r.mean_shadow : r.mean_lit) += std::fabs(e);
            ++(ref[i].in_shadow ? n_shadow : n_lit);
        }
        r.mean /= double(ref.size());
        lowest_value(run.scene, view, r);
        if (n_lit) r.mean_lit /= n_lit;
        if (n_shadow) r.mean_shadow /= n_shadow;
        results.push_back(r);
        if (!dir.empty()) {
            // The render at the reference image's size, and the error against it.
            RenderOptions ro;
            Scene& scene = run.scene;
            int w = 0, h = 0;
            const std::vector<double> Yref = reference_image(
                std::string(MBR_SOURCE_DIR) + "/examples/data/cornell_reference_pbrt.png", w, h);
            const Camera full = scene.camera;
            scene.camera.width = w;
            scene.camera.height = h;
            const Image radiance =
                render_radiance(scene, *run.octree, radiosity_view(scene, solution), ro);
            scene.camera = full;
            Image error(w, h, {0.5, 0.5, 0.5});
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const double yr = Yref[size_t(y) * w + x];
                    const double ym = std::min(1.0, luminance(radiance.at(x, y)));
                    if (yr <= 0.01 || yr >= 0.99) continue;  // black or clipped in the reference
                    // Diverging: blue too dark, red too bright, full colour at 10 %.
                    error.at(x, y) =
                        diverging_map(0.5 + 0.5 * std::clamp((ym / yr - 1) / 0.1, -1.0, 1.0));
                }
            write_files(
                {{(std::filesystem::path(dir) / ("cornell_" + s.name + ".png")).string(),
                  encode_png(tone_map(radiance, 1))},
                 {(std::filesystem::path(dir) / ("cornell_" + s.name + "_error.png")).string(),
                  encode_png(error)}});
        }
    }

    if (csv) {
        Table t(
            {"setting", "seconds", "mean_err_percent", "max_err_percent", "shots", "coefficients"});
        for (const Result& r : results)
            t.add_row({r.setting, cell(r.seconds, 3), cell(100 * r.mean, 3), cell(100 * r.max, 3),
                       std::to_string(r.stats.shots), std::to_string(r.stats.coefficients)});
        t.write_csv(std::cout);
        return 0;
    }
    std::cout << "Cornell box against " << points_path << " (" << ref.size()
              << " points; luminance error |Y / Y_ref - 1|)\n\n";
    Table t({"setting", "seconds", "mean_%", "max_%", "worst", "lit_%", "shadow_%", "shots",
             "unshot_%", "coefficients", "kernel_evals", "rays", "lowest", "lowest_at"});
    for (const Result& r : results)
        t.add_row({r.setting, cell(r.seconds, 2), cell(100 * r.mean, 2), cell(100 * r.max, 2),
                   r.worst, cell(100 * r.mean_lit, 2), cell(100 * r.mean_shadow, 2),
                   std::to_string(r.stats.shots),
                   cell_g(100 * r.stats.unshot_power / r.stats.emitted_power, 3),
                   std::to_string(r.stats.coefficients), std::to_string(r.stats.kernel_evals),
                   std::to_string(r.stats.rays), cell_g(r.lowest, 3), r.lowest_at});
    t.write_text(std::cout);
    if (per_point) {
        std::vector<std::string> cols{"point", "in_shadow", "Y_ref"};
        for (const Result& r : results) cols.push_back(r.setting + "_%");
        Table p(cols);
        for (size_t i = 0; i < ref.size(); ++i) {
            std::vector<std::string> row{ref[i].point.name, ref[i].in_shadow ? "1" : "0",
                                         cell(luminance(ref[i].B), 5)};
            for (const Result& r : results) row.push_back(cell(100 * r.errors[i], 2));
            p.add_row(row);
        }
        std::cout << "\n";
        p.write_text(std::cout);
    }
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
