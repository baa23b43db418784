// examples/paper/figure7_error_images.cpp - the paper's Figure 7: pictures of the relative error of
// one energy transfer between (a) parallel unit squares at distance h = 0.5 with the receiver
// at uniform depth d = 4 and (b) perpendicular unit squares with d = 3 (section 7; m = 4,
// linear extrapolation (23)-(25), the default truncation, as in Tables 1-2).
//
// Run:  figure7_error_images -o DIR [--grid N] [--error-max E] [receiver options]
//
// Writes DIR/figure7a_parallel.png and DIR/figure7b_perpendicular.png (DIR must exist). As in
// the paper's caption, each image has four panels over the receiver's (s,t) domain [0,1]^2:
//   upper left   the exact result, B_exact = F(p -> shooter) from the analytic point-to-polygon
//                form factor, on the N x N grid of cell centres (N = 256 as in eq. (29));
//   upper right  the approximation, the unified spline field of the transfer (eq. (20)) on
//                the same grid, in the same colour range as the exact panel;
//   lower right  the relative error |B_spline - B_exact| / B_exact at those sample points,
//                magnified: full colour at E, so the panel shows the error times 1/E;
//   lower left   the colour scales of both maps and the measured numbers.
// E is a 1-2-5 value: by default the smallest one at or above the 99th percentile of the
// errors, so that a few points at a singular corner cannot wash the picture out; points
// above E are drawn black and counted. --error-max E fixes it instead (E = 1 / magnification).
// Expect with the defaults: (a) rea about 0.0011 % (max about 0.008 %, near the corners),
// full red at 0.005 % (magnification 20000), a pattern symmetric under s <-> t as the
// configuration is; (b) rea about 0.32 % (max about 32 % at (0.998, 0.014)), the error
// concentrated along the side edges s = 0 and s = 1 below t = 0.2, worst at the ends of the
// shared edge t = 0, where the form factor's derivatives are singular; full red at 5 %
// (magnification 20), about 380 points (0.58 %) beyond, drawn black.
// stdout: per image the configuration, rea, max relative error and where, the colour ranges
// and the file written. A bad option gives one error line and exit 2; a folder that is missing,
// read-only or not a folder one line and exit 1, before anything is computed. Both images are
// rendered and both written to temporaries before either file is replaced (write_files in
// radiosity/output/output_file.h), so a full disk leaves both old files as they were.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "examples/common/transfer_cli.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: figure7_error_images -o DIR [--grid N] [--error-max E] [options]\n"
               "  The paper's Figure 7: exact result, B-spline approximation, magnified relative\n"
               "  error and colour scale for (a) parallel squares h = 0.5, d = 4 and (b)\n"
               "  perpendicular squares, d = 3. Writes DIR/figure7a_parallel.png and\n"
               "  DIR/figure7b_perpendicular.png.\n"
               "  -o DIR                    existing output directory (required)\n"
               "  --grid N                  sample grid N x N, 16..1024 (default 256, as eq. "
               "(29))\n"
               "  --error-max E             relative error at full colour, 1e-9..10 (default:\n"
               "                            the 99th percentile rounded up to 1, 2 or 5 x "
               "10^k)\n") +
           receiver_options_usage;
}

// One panel of Figure 7, measured: the three grids (row-major, s fastest, t upwards) and the
// numbers printed on the image and on stdout.
struct Measured {
    std::string label;     // "(a)" or "(b)"
    std::string geometry;  // "parallel unit squares, h = 0.5"
    int depth = 0;
    int n = 0;  // grid size
    std::vector<double> exact, approx, relative;
    TransferRun run;
    double value_min = 0, value_max = 0;  // shared range of the upper panels
    double error_max = 0;                 // E: the relative error drawn at full colour
    int n_clipped = 0;                    // sample points with relative error above E
    double argmax_s = 0, argmax_t = 0;    // where the largest relative error is
};

// The smallest 1, 2 or 5 x 10^k at or above x > 0.
double nice_ceiling(double x) {
    const double decade = std::pow(10.0, std::floor(std::log10(x)));
    for (double f : {1.0, 2.0, 5.0, 10.0})
        if (f * decade >= x * (1 - 1e-12)) return f * decade;
    return 10 * decade;
}

Measured measure(const std::string& label, const std::string& geometry, const TransferSetup& setup,
                 int depth, ReceiverOptions options, int n, double error_max) {
    Measured out;
    out.label = label;
    out.geometry = geometry;
    out.depth = depth;
    out.n = n;
    options.min_depth = options.max_depth = depth;
    out.run = run_transfer(setup, options, n);
    // Shooter radiosity 1 and reflectance 1, as run_transfer measures: B_exact is F itself.
    out.exact = exact_grid(setup, n);
    out.approx = field_grid(out.run.field, n);

    out.value_min = HUGE_VAL, out.value_max = -HUGE_VAL;
    out.relative.assign(out.exact.size(), NAN);
    std::vector<double> sorted;
    double largest = -1;
    for (size_t i = 0; i < out.exact.size(); ++i) {
        out.value_min = std::min({out.value_min, out.exact[i], out.approx[i]});
        out.value_max = std::max({out.value_max, out.exact[i], out.approx[i]});
        if (!(out.exact[i] > 0)) continue;  // no light: eq. (29) skips the point
        const double e = std::fabs(out.approx[i] - out.exact[i]) / out.exact[i];
        out.relative[i] = e;
        sorted.push_back(e);
        if (e > largest) {
            largest = e;
            out.argmax_s = (double(i % n) + 0.5) / n;
            out.argmax_t = (double(i / n) + 0.5) / n;
        }
    }
    if (sorted.empty()) throw std::runtime_error("the receiver gets no light on the grid");
    // DESIGN: the default full-colour error is the 99th percentile rounded up to a 1-2-5
    // value, so one singular corner does not leave the rest of the panel dark.
    if (!(error_max > 0)) {
        const size_t q = std::min(sorted.size() - 1, size_t(0.99 * double(sorted.size())));
        std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
        error_max = nice_ceiling(std::max(sorted[q], 1e-12));
    }
    out.error_max = error_max;
    for (double e : out.relative) out.n_clipped += e > error_max;
    return out;
}

// The error map: white (no error) to red (E); beyond E drawn black by the caller.
Rgb error_map(double t) {
    return diverging_map(0.5 + 0.5 * std::clamp(t, 0.0, 1.0));
}
const Rgb clipped_colour{0.05, 0.05, 0.05};

// Grid rows run upwards in t; images run downwards.
std::vector<double> flipped(const std::vector<double>& v, int n) {
    std::vector<double> out(v.size());
    for (int j = 0; j < n; ++j)
        std::copy_n(v.begin() + size_t(j) * n, n, out.begin() + size_t(n - 1 - j) * n);
    return out;
}

std::string percent(double fraction, int digits = 3) {
    return cell_g(100 * fraction, digits) + " %";
}

// The magnification 1/E as text ("5000", "20", "2.5").
std::string magnification(double error_max) {
    const double n = 1 / error_max;
    return std::fabs(n - std::round(n)) < 1e-6 * n && n < 1e9 ? cell(std::round(n), 0)
                                                              : cell_g(n, 4);
}

Image compose(const Measured& M, const ReceiverOptions& options) {
    const int s = 2;                                        // text scale of labels and ticks
    const int area = M.n <= 512 ? M.n * (512 / M.n) : M.n;  // whole pixels per sample
    const int margin = axes_margin(s, 4);                   // left of and below each field
    const int title_h = 2 * glyph_line_height * s;          // above each panel
    const int pad = 16 * s;
    const int panel_w = margin + area + pad, panel_h = title_h + area + margin;
    const int width = 2 * panel_w + pad;

    // Header: what is shown, under which options, wrapped to the image width.
    const std::vector<std::string> title =
        wrap_text("Figure 7" + M.label + ": " + M.geometry + ", d = " + std::to_string(M.depth),
                  width - 2 * pad, 3);
    const std::vector<std::string> subtitle = wrap_text(
        "Relative error of a single energy transfer (shooter radiosity 1, reflectance 1); " +
            describe(options) + "; sample points: the " + std::to_string(M.n) + " x " +
            std::to_string(M.n) + " cell centres of [0,1]^2.",
        width - 2 * pad, s);
    const int title_lines_h = int(title.size()) * glyph_line_height * 3;
    const int header_h =
        pad / 2 + title_lines_h + int(subtitle.size()) * glyph_line_height * s + pad;
    Image image(width, header_h + 2 * panel_h + pad / 2, {1, 1, 1});
    Canvas canvas(image);
    const Rgb ink{0, 0, 0};
    for (size_t i = 0; i < title.size(); ++i)
        canvas.text(pad, pad / 2 + int(i) * glyph_line_height * 3, title[i], ink, 3);
    for (size_t i = 0; i < subtitle.size(); ++i)
        canvas.text(pad, pad / 2 + title_lines_h + int(i) * glyph_line_height * s, subtitle[i], ink,
                    s);

    auto field_area = [&](int column, int row) {
        return PixelRect{column * panel_w + pad + margin, header_h + row * panel_h + title_h, area,
                         area};
    };
    auto panel_title = [&](const PixelRect& a, const std::string& title) {
        canvas.text(a.x + a.w / 2, a.y - glyph_line_height * s + 2, title, ink, s + 1,
                    Align::centre, Align::end);
    };
    auto frame = [&](const PixelRect& a) {
        draw_axes(image, map_layout(a, 0, 1, 0, 1, s), "s", "t", ink, s);
    };

    // Upper row: exact and approximation in one colour range.
    const PixelRect exact_area = field_area(0, 0), approx_area = field_area(1, 0);
    draw_scalar_field(image, exact_area, flipped(M.exact, M.n), M.n, M.n, M.value_min, M.value_max);
    draw_scalar_field(image, approx_area, flipped(M.approx, M.n), M.n, M.n, M.value_min,
                      M.value_max);
    frame(exact_area);
    frame(approx_area);
    panel_title(exact_area, "exact (analytic form factor)");
    panel_title(approx_area,
                "B-spline, d = " + std::to_string(M.depth) + ", m = " + std::to_string(options.m));

    // Lower right: the magnified relative error; points beyond E in black.
    const PixelRect error_area = field_area(1, 1);
    const std::vector<double> rel = flipped(M.relative, M.n);
    draw_scalar_field(image, error_area, rel, M.n, M.n, 0, M.error_max, error_map);
    if (M.n_clipped > 0)
        for (int y = 0; y < error_area.h; ++y) {
            const int sy = std::min(M.n - 1, y * M.n / error_area.h);
            for (int x = 0; x < error_area.w; ++x) {
                const int sx = std::min(M.n - 1, x * M.n / error_area.w);
                if (rel[size_t(sy) * M.n + sx] > M.error_max)
                    image.at(error_area.x + x, error_area.y + y) = clipped_colour;
            }
        }
    frame(error_area);
    panel_title(error_area, "relative error x " + magnification(M.error_max));

    // Lower left: the two colour scales and the numbers.
    const PixelRect scale_area = field_area(0, 1);
    panel_title(scale_area, "colour scales");
    const int line = glyph_line_height * s;
    const int bar_w = scale_area.w - 2 * pad, bar_h = 12 * s;
    int y = scale_area.y + line + 2 * s;
    draw_colour_scale(
        image, {scale_area.x + pad, y, bar_w, bar_h}, M.value_min, M.value_max,
        "B (both upper panels): " + cell(M.value_min, 4) + " .. " + cell(M.value_max, 4),
        colour_map, s);
    y += bar_h + 3 * line + 2 * s;
    draw_colour_scale(image, {scale_area.x + pad, y, bar_w, bar_h}, 0, 100 * M.error_max,
                      "relative error in % (lower right)", error_map, s);
    y += bar_h + 2 * line;
    const int x0 = scale_area.x + pad;
    canvas.text(x0, y,
                "magnification x " + magnification(M.error_max) + ": full red at " +
                    percent(M.error_max, 2),
                ink, s);
    y += line;
    canvas.fill_rect({x0, y, 7 * s, 7 * s}, clipped_colour);
    canvas.text(x0 + 10 * s, y,
                "above " + percent(M.error_max, 2) + ": " + std::to_string(M.n_clipped) +
                    " points (" + percent(double(M.n_clipped) / (double(M.n) * M.n), 2) + ")",
                ink, s);
    y += 2 * line;
    const ErrorStats& e = M.run.errors;
    const TransferStats& st = M.run.stats;
    for (const std::string& text :
         {"rea (eq. 29)        = " + percent(e.rea, 3),
          "max relative error  = " + percent(e.max_rel, 3),
          "  at (s, t)         = (" + cell(M.argmax_s, 3) + ", " + cell(M.argmax_t, 3) + ")",
          "mean of exact       = " + cell(e.mean_exact, 6),
          "leaves " + std::to_string(st.n_leaves) + ", fulcrums " + std::to_string(st.n_fulcrums) +
              ", level j = " + std::to_string(st.level),
          "rhombus radius " + cell(st.rhombus_radius, 2) + " cells, " + cell(st.seconds_total, 2) +
              " s"}) {
        canvas.text(x0, y, text, ink, s);
        y += line;
    }
    // How to read the panels, in the space left.
    y += line;
    for (const std::string& text :
         wrap_text("The upper panels share one colour range: equal colours are equal values. "
                   "The lower right shows |B_spline - B_exact| / B_exact at every sample point, "
                   "white where it vanishes, full red at " +
                       percent(M.error_max, 2) + ".",
                   scale_area.w - pad, s)) {
        if (y + line > scale_area.bottom()) break;
        canvas.text(x0, y, text, {0.3, 0.3, 0.3}, s);
        y += line;
    }
    return image;
}

int run(Args& args) {
    const std::string dir = args.text("-o", "");
    const int n = args.integer("--grid", 256, 16, 1024);
    const double error_max = args.number("--error-max", 0);
    ReceiverOptions options = read_receiver_options(args);
    args.finish();
    if (dir.empty()) throw UsageError("-o DIR is required");
    if (args.has("--error-max") && !(error_max >= 1e-9 && error_max <= 10))
        throw UsageError("--error-max must be in 1e-9..10");
    const std::filesystem::path base(dir);
    const std::string path_a = (base / "figure7a_parallel.png").string();
    const std::string path_b = (base / "figure7b_perpendicular.png").string();
    std::error_code ec;
    if (std::filesystem::exists(base, ec) && !std::filesystem::is_directory(base, ec))
        throw OutputError(dir, "is not a folder (-o names the folder the two images go to)");
    check_output_path(path_a);  // a missing or read-only folder fails now, not after the work
    check_output_path(path_b);

    const Measured a = measure("(a)", "parallel unit squares, h = 0.5", parallel_squares(0.5), 4,
                               options, n, error_max);
    const Measured b = measure("(b)", "perpendicular unit squares, shared edge t = 0",
                               perpendicular_squares(), 3, options, n, error_max);
    // Both images exist in memory before either file is written; both or neither replaced.
    write_files(
        {{path_a, encode_png(compose(a, options))}, {path_b, encode_png(compose(b, options))}});

    std::cout << "Figure 7: relative error of a single transfer, " << describe(options) << "\n"
              << "grid " << n << " x " << n << " of cell centres\n\n";
    Table table({"figure", "configuration", "d", "rea_percent", "max_rel_percent", "at_s", "at_t",
                 "B_range", "error_at_full_colour", "points_above", "file"});
    for (const auto& [M, path] : {std::pair{&a, path_a}, std::pair{&b, path_b}})
        table.add_row({"7" + M->label, M->geometry, std::to_string(M->depth),
                       cell(100 * M->run.errors.rea, 4), cell(100 * M->run.errors.max_rel, 4),
                       cell(M->argmax_s, 3), cell(M->argmax_t, 3),
                       cell(M->value_min, 4) + ".." + cell(M->value_max, 4),
                       percent(M->error_max, 2) + " (x" + magnification(M->error_max) + ")",
                       std::to_string(M->n_clipped), path});
    table.write_text(std::cout);
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
