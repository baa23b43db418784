// examples/studies/shadow_transfer.cpp - one shadowed energy transfer against its exact answer
// (paper section 5 "Adaptive Subdivision in Shadow Computation", section 6 "Shadow", eq. (28)).
//
// Parallel unit squares at h = 1: the receiver [0,1]^2 in z = 0 (reflectance 1), the shooter
// [0,1]^2 in z = 1 facing down (radiosity 1), and an opaque occluder between them:
//   square   a square of side 0.4 centred at (0.5, 0.5, 0.5), parallel to both;
//   tilted   the same square rotated by +30 degrees about the x axis through its centre;
//   umbra    the square occluder under a shooter of side 0.3 (its shadow has an umbra).
// The exact shadowed value at a receiving point p is F(p, shooter) - F(p, shooter clipped to
// the occluder's central projection from p onto the shooter's plane), both by the analytic
// contour formula (radiosity/reference/configurations.h): machine precision.
//
// Run:  shadow_transfer [--config square|tilted|umbra|all] [--method fractions|exact]
//                       [--max-shadow-depth d] [--rays R] [--threshold T] [--csv]
//                       [--grid FILE] [-o DIR] [--show-splits]
//                       [--shooter 12 numbers --receiver 12 numbers --occluder 12 numbers]
// For each configuration and depth d (3 to 6 unless --max-shadow-depth gives one) it prints
// rea (29) over the points where the exact value is at least 1 % of its largest, the L1 error
// relative to the exact values' mean over all 256 x 256 points, rays cast and seconds. "depth"
// is the maximum shadow depth of the paper's method (the receiver's oracle tree is bounded by
// it too), and the receiver's maximum depth for the exact method.
// --csv prints `config,depth,rea_percent,l1_rel_percent,rays,seconds`. --grid FILE writes the
// last run's 256 x 256 values at the cell centres, one per line, s slowest. -o DIR writes
// DIR/shadow_<config>.png for the deepest run of each configuration: exact | approximation |
// error, as in Figure 7; --show-splits marks the fulcrums whose fractions split leaves.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "examples/common/transfer_cli.h"
#include "radiosity/output/output_file.h"
#include "radiosity/scene/scene_io.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: shadow_transfer [--config square|tilted|umbra|all] [options]\n"
               "  One shadowed transfer between parallel unit squares at h = 1 against the exact\n"
               "  shadowed form factor, on the receiver's 256 x 256 grid of cell centres.\n"
               "  --config C                square, tilted, umbra or all (default all)\n"
               "  --method M                fractions (the paper's masking, default) or exact\n"
               "                            (visibility inside (21))\n"
               "  --max-shadow-depth d      one depth, 1..10 (default: 3, 4, 5 and 6)\n"
               "  --rays R                  rays per shooter patch for (28), 1..4096 (default 4)\n"
               "  --threshold T             fraction difference that splits, (0, 1] (default "
               "0.05)\n"
               "  --shooter/--receiver/--occluder x0 y0 z0 ... x3 y3 z3\n"
               "                            a custom configuration (all three; parallel planes,\n"
               "                            the occluder strictly between them)\n"
               "  --csv                     header config,depth,rea_percent,l1_rel_percent,rays,"
               "seconds\n"
               "  --grid FILE               the last run's values, one per line, s slowest\n"
               "  -o DIR                    PNG panels exact | approximation | error per config\n"
               "  --show-splits             mark the fulcrums whose fractions split leaves\n"
               "  --oracle-tolerance T      the receiver's oracle threshold (default 1e-3)\n"
               "  --oracle means|interpolation   the oracle's test: the paper's two means\n"
               "                            (default), or the m x m polynomial predicting the\n"
               "                            ceil(m/2)^2 samples point by point\n") +
           receiver_options_usage;
}

struct Config {
    std::string name;
    ShadowSetup setup;
};

struct Run {
    std::string config;
    int depth = 0;
    double rea = 0, l1 = 0, seconds = 0;
    long rays = 0;
    TransferStats stats;
    std::vector<double> values;  // row-major, s fastest
    std::vector<Vec2> splits;
};

Surface read_quad(Args& args, const std::string& name) {
    const std::vector<double> v = args.numbers(name, 12);
    std::array<Vec3, 4> c;
    for (int i = 0; i < 4; ++i) c[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    const std::string problem = planar_quad_problem(c);
    if (!problem.empty()) throw UsageError(name + ": " + problem);
    return Surface::planar_quad(c[0], c[1], c[2], c[3]);
}

/// The octree over the shooter (surface 0), the receiver (1) and the occluders (2, 3, ...).
Octree make_octree(const ShadowSetup& setup) {
    std::vector<Polygon> polygons;
    auto add = [&](const std::vector<Vec3>& v, int id) {
        std::vector<Vec2> uv(v.size());
        polygons.emplace_back(v, uv, id);
    };
    for (const Surface* s : {&setup.shooter, &setup.receiver}) {
        const Vec3* c = s->corners();
        add({c[0], c[1], c[2], c[3]}, s == &setup.shooter ? 0 : 1);
    }
    for (size_t i = 0; i < setup.occluders.size(); ++i) add(setup.occluders[i], int(2 + i));
    return Octree(std::move(polygons));
}

Run measure(const Config& config, const std::vector<double>& exact, int n, int depth,
            ReceiverOptions options) {
    options.min_depth = std::min(options.min_depth, depth);
    options.max_depth = depth;
    options.shadows.max_depth = depth;
    const Octree octree = make_octree(config.setup);
    const OcclusionContext occlusion =
        make_occlusion_context(octree, config.setup.shooter, 0, config.setup.receiver, 1, 0);
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(config.setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&config.setup.receiver, [](double, double) {
                                       return Rgb{1, 1, 1};
                                   }};
    Run run;
    run.config = config.name;
    run.depth = depth;
    ReceiverState state;
    const double start = now_seconds();
    const SplineField field = transfer(shooter, receiver, options, &run.stats, &state, &occlusion);
    run.seconds = now_seconds() - start;
    run.rays = run.stats.n_rays;
    run.values = field_grid(field, n);
    run.splits = state.split_fulcrums;

    const double largest = *std::max_element(exact.begin(), exact.end());
    double sum_rel = 0, sum_abs = 0, sum_exact = 0;
    int n_rel = 0;
    for (size_t i = 0; i < exact.size(); ++i) {
        sum_abs += std::fabs(run.values[i] - exact[i]);
        sum_exact += exact[i];
        // eq. (29) where the exact value is at least 1 % of its largest.
        if (exact[i] >= 0.01 * largest) {
            sum_rel += std::fabs(run.values[i] - exact[i]) / exact[i];
            ++n_rel;
        }
    }
    run.rea = n_rel ? sum_rel / n_rel : 0;
    run.l1 = sum_exact > 0 ? sum_abs / sum_exact : 0;
    return run;
}

// Grid rows run upwards in t; images run downwards.
std::vector<double> flipped(const std::vector<double>& v, int n) {
    std::vector<double> out(v.size());
    for (int j = 0; j < n; ++j)
        std::copy_n(v.begin() + size_t(j) * n, n, out.begin() + size_t(n - 1 - j) * n);
    return out;
}

Image compose(const Run& run, const std::vector<double>& exact, int n, const std::string& method,
              bool show_splits) {
    const int s = 2, area = 2 * n, margin = axes_margin(s, 4), pad = 24;
    const int title_h = 2 * glyph_line_height * s, header_h = 3 * glyph_line_height * s + pad;
    const int panel_w = margin + area + pad;
    Image image(3 * panel_w + pad, header_h + title_h + area + margin + pad, {1, 1, 1});
    Canvas canvas(image);
    const Rgb ink{0, 0, 0};
    std::ostringstream head;
    head << "shadow_transfer: " << run.config << ", " << method << ", depth " << run.depth
         << ": rea " << cell_g(100 * run.rea, 3) << " %, L1 " << cell_g(100 * run.l1, 3) << " %, "
         << run.rays << " rays, " << cell(run.seconds, 2) << " s";
    canvas.text(pad, pad / 2, head.str(), ink, s);
    double lo = HUGE_VAL, hi = -HUGE_VAL, err_max = 0;
    std::vector<double> error(exact.size());
    for (size_t i = 0; i < exact.size(); ++i) {
        lo = std::min({lo, exact[i], run.values[i]});
        hi = std::max({hi, exact[i], run.values[i]});
        error[i] = std::fabs(run.values[i] - exact[i]);
        err_max = std::max(err_max, error[i]);
    }
    const std::string err_text = "|error|, full colour at " + cell_g(err_max, 3);
    const char* titles[3] = {"exact", "approximation", "|approx - exact|"};
    const std::vector<double>* grids[3] = {&exact, &run.values, &error};
    for (int k = 0; k < 3; ++k) {
        const PixelRect r{k * panel_w + pad + margin, header_h + title_h, area, area};
        if (k < 2)
            draw_scalar_field(image, r, flipped(*grids[k], n), n, n, lo, hi);
        else
            draw_scalar_field(image, r, flipped(*grids[k], n), n, n, 0, std::max(err_max, 1e-300));
        draw_axes(image, map_layout(r, 0, 1, 0, 1, s), "s", "t", ink, s);
        canvas.text(r.x + r.w / 2, r.y - glyph_line_height * s + 2, titles[k], ink, s,
                    Align::centre, Align::end);
        if (k == 1 && show_splits)
            for (Vec2 q : run.splits)
                canvas.disc({r.x + q.x * r.w, r.y + (1 - q.y) * r.h}, 2.5, {1, 0.2, 0.2});
    }
    canvas.text(pad, pad / 2 + glyph_line_height * s,
                "colour range of the first two panels: " + cell_g(lo, 4) + " .. " + cell_g(hi, 4) +
                    "; " + err_text,
                ink, s);
    return image;
}

int run(Args& args) {
    const std::string which = args.text("--config", "all");
    const std::string method = args.text("--method", "fractions");
    const int one_depth = args.integer("--max-shadow-depth", 0, 1, 10);
    const bool csv = args.flag("--csv");
    const std::string grid_path = args.text("--grid", "");
    const std::string dir = args.text("-o", "");
    const bool show_splits = args.flag("--show-splits");
    const bool custom = args.has("--shooter") || args.has("--receiver") || args.has("--occluder");
    std::vector<Config> configs;
    if (custom) {
        if (!(args.has("--shooter") && args.has("--receiver") && args.has("--occluder")))
            throw UsageError("a custom configuration needs --shooter, --receiver and --occluder");
        ShadowSetup setup{read_quad(args, "--shooter"), read_quad(args, "--receiver"), {}};
        const std::vector<double> o = args.numbers("--occluder", 12);
        std::vector<Vec3> occluder;
        for (int i = 0; i < 4; ++i) occluder.push_back({o[3 * i], o[3 * i + 1], o[3 * i + 2]});
        setup.occluders.push_back(occluder);
        configs.push_back({"custom", setup});
    }
    ReceiverOptions options = read_receiver_options(args);
    options.shadows.rays_per_patch =
        args.integer("--rays", options.shadows.rays_per_patch, 1, 4096);
    options.shadows.threshold = args.number("--threshold", options.shadows.threshold);
    options.oracle_tolerance = args.number("--oracle-tolerance", options.oracle_tolerance);
    const std::string oracle = args.text("--oracle", "means");
    args.finish();
    if (!(options.oracle_tolerance > 0 && options.oracle_tolerance < 1))
        throw UsageError("--oracle-tolerance must be in (0, 1)");
    if (oracle != "means" && oracle != "interpolation")
        throw UsageError("--oracle must be means or interpolation");
    options.oracle_test = oracle == "means" ? OracleTest::Means : OracleTest::Interpolation;
    if (method == "fractions")
        options.shadows.method = ShadowMethod::Fractions;
    else if (method == "exact")
        options.shadows.method = ShadowMethod::Exact;
    else
        throw UsageError("--method must be fractions or exact");
    if (!(options.shadows.threshold > 0 && options.shadows.threshold <= 1))
        throw UsageError("--threshold must be in (0, 1]");
    if (!custom) {
        if (which != "all" && which != "square" && which != "tilted" && which != "umbra")
            throw UsageError("--config must be square, tilted, umbra or all");
        if (which == "all" || which == "square") configs.push_back({"square", occluded_squares(0)});
        if (which == "all" || which == "tilted")
            configs.push_back({"tilted", occluded_squares(30)});
        if (which == "all" || which == "umbra")
            configs.push_back({"umbra", occluded_squares(0, 0.3)});
    }
    if (!dir.empty() && !std::filesystem::is_directory(dir))
        throw OutputError(dir, "the output directory does not exist");
    if (!grid_path.empty()) check_output_path(grid_path);
    std::vector<int> depths;
    if (one_depth > 0)
        depths = {one_depth};
    else
        depths = {3, 4, 5, 6};

    const int n = 256;
    Table table({"config", "depth", "rea_percent", "l1_rel_percent", "rays", "seconds"});
    if (!csv)
        std::cout << "shadow_transfer: "
                  << (method == "exact" ? "exact visibility in (21)" : "the paper's fractions (28)")
                  << ", " << describe(options) << ", " << options.shadows.rays_per_patch
                  << " rays per patch, threshold " << options.shadows.threshold << "\n";
    Run last;
    for (const Config& config : configs) {
        std::vector<double> exact;
        try {
            exact = exact_shadowed_grid(config.setup, n);
        } catch (const CheckFailure&) {
            throw UsageError(
                "the exact reference needs the occluder strictly between the planes "
                "of the shooter and the receiver");
        }
        if (!csv) {
            double mean = 0;
            for (double v : exact) mean += v;
            std::cout << config.name << ": exact mean over the grid "
                      << cell(mean / exact.size(), 6) << ", B(0.5, 0.5) = "
                      << cell(shadowed_form_factor({0.5, 0.5, 0}, {0, 0, 1},
                                                   {config.setup.shooter.corners()[0],
                                                    config.setup.shooter.corners()[1],
                                                    config.setup.shooter.corners()[2],
                                                    config.setup.shooter.corners()[3]},
                                                   config.setup.occluders[0]),
                              6)
                      << "\n";
        }
        for (int depth : depths) {
            last = measure(config, exact, n, depth, options);
            table.add_row({config.name, std::to_string(depth), cell(100 * last.rea, 4),
                           cell(100 * last.l1, 4), std::to_string(last.rays),
                           cell(last.seconds, 3)});
        }
        if (!dir.empty()) {
            const std::string path =
                (std::filesystem::path(dir) / ("shadow_" + config.name + ".png")).string();
            write_png(path, compose(last, exact, n, method, show_splits));
            if (!csv) std::cout << "wrote " << path << "\n";
        }
    }
    if (csv)
        table.write_csv(std::cout);
    else
        table.write_text(std::cout);
    if (!grid_path.empty()) {
        std::ostringstream os;
        os.precision(17);
        for (int i = 0; i < n; ++i)  // s slowest
            for (int j = 0; j < n; ++j) os << last.values[size_t(j) * n + i] << "\n";
        write_file(grid_path, os.str());
        if (!csv)
            std::cout << "wrote " << grid_path << " (" << last.config << ", depth " << last.depth
                      << ")\n";
    }
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
