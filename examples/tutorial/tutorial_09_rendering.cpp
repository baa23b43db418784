// examples/tutorial/tutorial_09_rendering.cpp - tutorial chapter 9 (docs/tutorial/09-rendering.md):
// from the solved coefficients to a picture, and how true the picture is.
//
// Chapter 8 left every surface with a SplineField: the coefficients of eq. (20). Rendering is
// what the paper calls trivial and leaves out; mbr does it in radiosity/output/render.h: a camera
// ray per sample finds the first surface (the octree of section 6 again), eq. (20) gives B_i(u, v)
// there, and a Lambertian surface sends radiance L = B / pi toward the eye. tone_map turns
// radiance into sRGB display values, write_png stores them (the `mbr render` tool does the same).
//
// Is the solution right? A path tracer solves eq. (1) by an independent method. The file
// cornell_reference_points.csv holds pbrt-v3's radiosity at 16 named points of the box (and
// cornell_reference_points.md beside it what other programs reach there). We locate each point
// on its surface (radiosity/reference/probe.h), evaluate our B there, and compare luminances.
//
// Run:  tutorial_09_rendering [-o DIR] [--points FILE] [--max-depth d] [--tolerance x]
//                             [--shots n] [--spp n]
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "radiosity/output/render.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_09_rendering [-o DIR] [options]\n"
    "  Tutorial chapter 9: the Cornell box solved, rendered to PNG, and compared with a\n"
    "  path tracer (pbrt-v3) at 16 reference points.\n"
    "  -o DIR              folder for the images (default out; created if missing)\n"
    "  --points FILE       the reference points (default\n"
    "                      examples/data/cornell_reference_points.csv)\n"
    "  --max-depth d       receiver quadtree depth, 1..8 (default 6, the scene's)\n"
    "  --tolerance x       accuracy relative to the radiosity scale, (0, 1) (default 2e-3)\n"
    "  --shots n           at most n shots, 1..1000 (default 100)\n"
    "  --spp n             camera samples per pixel, 1..64 (default 4)\n"
    "  --size n            the render's width and height, 16..2048 (default 512, the scene's)\n";

/// The reference file: --points when given, else the repository's copy in examples/data (the
/// one cornell_accuracy reads). InputError (exit status 2) naming what was tried when there is
/// none.
std::string find_reference(const std::string& given) {
    if (!given.empty()) {
        if (!std::filesystem::is_regular_file(given))
            throw InputError(given, 0, "the reference points file is missing");
        return given;
    }
    const std::string path =
        std::string(MBR_SOURCE_DIR) + "/examples/data/cornell_reference_points.csv";
    if (std::filesystem::is_regular_file(path)) return path;
    throw InputError(path, 0, "the path-traced reference is missing; give one with --points FILE");
}

/// The reference values of a points file, by point name: B (columns B_r, B_g, B_b) and whether
/// the light is partly hidden there (column in_shadow, optional). The positions are read by
/// read_probe_points, which checks them.
struct Reference {
    Rgb B;
    bool in_shadow = false;
};
std::map<std::string, Reference> read_reference_values(const std::string& path) {
    std::ifstream in(path);
    std::string line;
    std::vector<std::string> head;
    auto split = [](const std::string& s) {
        std::vector<std::string> fields;
        std::stringstream ss(s);
        for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
        return fields;
    };
    if (!std::getline(in, line)) throw InputError(path, 1, "the file is empty");
    head = split(line);
    auto column = [&](const std::string& name) {
        return int(std::find(head.begin(), head.end(), name) - head.begin());
    };
    const int cr = column("B_r"), cg = column("B_g"), cb = column("B_b");
    const int cs = column("in_shadow");
    if (std::max({cr, cg, cb}) >= int(head.size()))
        throw InputError(path, 1, "the columns B_r, B_g and B_b are required");
    std::map<std::string, Reference> values;
    for (int n = 2; std::getline(in, line); ++n) {
        const std::vector<std::string> f = split(line);
        if (f.empty()) continue;
        if (std::max({cr, cg, cb}) >= int(f.size())) throw InputError(path, n, "missing values");
        Reference r;
        r.B = {parse_number(f[cr], "B_r"), parse_number(f[cg], "B_g"), parse_number(f[cb], "B_b")};
        r.in_shadow = cs < int(f.size()) && f[cs] == "1";
        if (!(luminance(r.B) > 0))
            throw InputError(path, n, "the reference luminance must be positive");
        values[f[0]] = r;
    }
    return values;
}

/// The pixel (x, y) where world point p appears: camera_ray's direction is affine in (x, y),
/// d = d0 + x dx + y dy, so p - eye = lambda d is a 3 x 3 linear system (Cramer's rule).
Vec2 pixel_of(const Camera& camera, Vec3 p) {
    const Vec3 d0 = camera_ray(camera, 0, 0).dir;
    const Vec3 dx = camera_ray(camera, 1, 0).dir - d0, dy = camera_ray(camera, 0, 1).dir - d0;
    const Vec3 q = p - camera.eye;
    const double det = dot(d0, cross(dx, dy));
    const double lambda = dot(q, cross(dx, dy)) / det;
    return {dot(d0, cross(q, dy)) / det / lambda, dot(d0, cross(dx, q)) / det / lambda};
}

/// Three panels: ours with the reference's tone curve (clipped at 1, power 1/2.2), the
/// reference image, and the ratio of their luminances averaged over 3 x 3 pixels (the
/// reference's 8 bits make single pixels speckle), blue where ours is darker, red where
/// brighter, full colour at 10 %; grey where the reference is black or clipped. The reference
/// points are drawn at `marks`, coloured by their own error.
Image comparison(const Image& ours, const Image& reference, const std::vector<Vec2>& marks,
                 const std::vector<double>& errors) {
    const int w = reference.width, h = reference.height;
    Image a(w, h), c(w, h, {0.5, 0.5, 0.5});
    std::vector<double> y_ours(size_t(w) * h), y_ref(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Rgb linear_ref;
            for (int k = 0; k < 3; ++k) {
                a.at(x, y)[k] = std::pow(std::clamp(ours.at(x, y)[k], 0.0, 1.0), 1 / 2.2);
                linear_ref[k] = std::pow(reference.at(x, y)[k], 2.2);
            }
            y_ours[size_t(y) * w + x] = std::min(1.0, luminance(ours.at(x, y)));
            y_ref[size_t(y) * w + x] = luminance(linear_ref);
        }
    for (int y = 1; y + 1 < h; ++y)
        for (int x = 1; x + 1 < w; ++x) {
            double sum_ours = 0, sum_ref = 0;
            bool usable = true;
            for (int j = y - 1; j <= y + 1; ++j)
                for (int i = x - 1; i <= x + 1; ++i) {
                    const double r = y_ref[size_t(j) * w + i];
                    usable = usable && r > 0.01 && r < 0.99;
                    sum_ours += y_ours[size_t(j) * w + i];
                    sum_ref += r;
                }
            if (usable)
                c.at(x, y) = diverging_map(
                    0.5 + 0.5 * std::clamp((sum_ours / sum_ref - 1) / 0.1, -1.0, 1.0));
        }
    Canvas canvas(c);
    for (size_t i = 0; i < marks.size(); ++i) {
        canvas.disc(marks[i], 3.5,
                    diverging_map(0.5 + 0.5 * std::clamp(errors[i] / 0.1, -1.0, 1.0)));
        canvas.circle(marks[i], 4, {{0, 0, 0}, 1});
    }
    Image panels(3 * w + 40, h + 60, {1, 1, 1});
    blit(panels, a, 10, 40);
    blit(panels, reference, 20 + w, 40);
    blit(panels, c, 30 + 2 * w, 40);
    Canvas top(panels);
    const char* titles[3] = {"mbr", "pbrt-v3 path tracer", "Y ratio: blue -10%, red +10%"};
    for (int k = 0; k < 3; ++k)
        top.text(10 + k * (w + 10) + w / 2, 30, titles[k], {0, 0, 0}, 1, Align::centre, Align::end);
    return panels;
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const std::string points_arg = args.text("--points", "");
    const int max_depth = args.integer("--max-depth", 6, 1, 8);
    const double tolerance = args.number("--tolerance", 2e-3);
    const int shots = args.integer("--shots", 100, 1, 1000);
    RenderOptions render;
    render.samples_per_pixel = args.integer("--spp", render.samples_per_pixel, 1, 64);
    const int size = args.integer("--size", 512, 16, 2048);
    args.finish();
    if (!(tolerance > 0 && tolerance < 1)) throw UsageError("--tolerance must be in (0, 1)");
    // The reference is checked before the solve, so a missing file costs no time.
    const std::string points_path = find_reference(points_arg);
    make_output_folder(dir);

    // Solve as chapter 8 did, here to the scene's convergence test (or the shot limit).
    Scene scene = load_scene(std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    SolverOptions options = solver_options(scene.settings);
    options.receiver.max_depth = max_depth;
    options.receiver.min_depth = std::min(options.receiver.min_depth, max_depth);
    options.tolerance = tolerance;
    options.max_shots = shots;
    scene.camera.width = scene.camera.height = size;
    const Octree octree = build_octree(scene);
    const Solution solution = solve(scene, octree, options);
    std::cout << "tutorial_09_rendering: Cornell box, max depth " << max_depth << ", tolerance "
              << tolerance << "\n"
              << "shots: " << solution.stats.shots << ", unshot left "
              << cell_g(100 * solution.stats.unshot_power / solution.stats.emitted_power, 3)
              << " % of emitted, coefficients " << solution.stats.coefficients << " per channel\n";

    // 1. The picture, as `mbr render` makes it: render_display = render_radiance (one octree
    // closest_hit per sample, B / pi by eq. (20) at the hit) + tone_map (sRGB).
    const std::string render_png = (std::filesystem::path(dir) / "tutorial_09_render.png").string();
    RenderStats render_stats;
    write_png(render_png, render_display(scene, octree, radiosity_view(scene, solution), render,
                                         nullptr, &render_stats));
    std::cout << "camera rays: " << render_stats.n_camera_rays << " (" << scene.camera.width
              << " x " << scene.camera.height << " pixels, " << render.samples_per_pixel
              << " per pixel)\n";

    // 2. The truth at points. locate_probe_points finds each point's (surface, u, v); our value
    // there is the field of eq. (20) evaluated at (u, v).
    const std::vector<ProbePoint> points = read_probe_points(points_path);
    const std::map<std::string, Reference> ref = read_reference_values(points_path);
    const std::vector<SurfaceLocation> at =
        locate_probe_points(scene, octree.polygons(), points, points_path, probe_tolerance(scene));
    std::cout << "\nreference: " << std::filesystem::path(points_path).filename().string() << ", "
              << points.size() << " points\n"
              << "luminance Y = 0.2126 R + 0.7152 G + 0.0722 B; error = Y_mbr / Y_ref - 1\n\n";
    Table table({"point", "surface", "shadow", "B_ref (r g b)", "B_mbr (r g b)", "Y_ref", "Y_mbr",
                 "error_%"});
    double sum = 0, worst = 0, sum_lit = 0, sum_shadow = 0;
    int n_lit = 0, n_shadow = 0;
    std::string worst_name;
    std::vector<double> errors;
    const RadiosityView view = radiosity_view(scene, solution);  // B = E + rho H where it holds H
    for (size_t i = 0; i < points.size(); ++i) {
        const Reference& r = ref.at(points[i].name);
        const Rgb B = radiosity_at(view, scene, at[i]);
        const double e = luminance(B) / luminance(r.B) - 1;
        errors.push_back(e);
        sum += std::fabs(e);
        (r.in_shadow ? sum_shadow : sum_lit) += std::fabs(e);
        ++(r.in_shadow ? n_shadow : n_lit);
        if (std::fabs(e) > worst) {
            worst = std::fabs(e);
            worst_name = points[i].name;
        }
        auto rgb = [](Rgb c) { return cell(c.r, 3) + " " + cell(c.g, 3) + " " + cell(c.b, 3); };
        table.add_row({points[i].name, scene.surfaces[at[i].surface].name,
                       r.in_shadow ? "yes" : "no", rgb(r.B), rgb(B), cell(luminance(r.B), 4),
                       cell(luminance(B), 4), cell(100 * e, 2)});
    }
    table.write_text(std::cout);
    std::cout << "\nmean relative error: " << cell(100 * sum / points.size(), 3) << " %\n"
              << "max relative error: " << cell(100 * worst, 3) << " % (" << worst_name << ")\n"
              << "mean over lit points: " << cell(100 * sum_lit / std::max(n_lit, 1), 3) << " %\n"
              << "mean over penumbra points: " << cell(100 * sum_shadow / std::max(n_shadow, 1), 3)
              << " %\n";

    // 3. Side by side with the path tracer's image (in the points' folder, when there), rendered
    // again at its size with render_radiance (linear radiance, no tone curve yet).
    const std::string ref_png =
        (std::filesystem::path(points_path).parent_path() / "cornell_reference_pbrt.png").string();
    int w = 0, h = 0, channels = 0;
    unsigned char* data = stbi_load(ref_png.c_str(), &w, &h, &channels, 3);
    if (!data) {
        std::cout << "no reference image at " << ref_png << ": comparison image skipped\n";
    } else {
        Camera camera = scene.camera;
        camera.width = w;
        camera.height = h;
        Scene small = scene;
        small.camera = camera;
        const Image ours = render_radiance(small, octree, radiosity_view(scene, solution), render);
        Image reference(w, h);
        for (size_t i = 0; i < reference.pixels.size(); ++i)
            for (int k = 0; k < 3; ++k) reference.pixels[i][k] = data[3 * i + k] / 255.0;
        stbi_image_free(data);
        std::vector<Vec2> marks;
        for (const SurfaceLocation& l : at) marks.push_back(pixel_of(camera, l.position));
        const Image panels = comparison(ours, reference, marks, errors);
        const std::string cmp_png =
            (std::filesystem::path(dir) / "tutorial_09_comparison.png").string();
        write_png(cmp_png, panels);
        std::cout << "wrote " << cmp_png << "\n";
    }
    std::cout << "wrote " << render_png << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
