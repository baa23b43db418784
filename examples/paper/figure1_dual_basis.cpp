// examples/paper/figure1_dual_basis.cpp - the paper's Figure 1: the graphs of the dual scaling
// functions (a) DN_3(x) and (b) DN_4(x) (section 3, eq. (13); computed by the appendix's
// method, eqs. (30)-(32), in math/dual_basis.h).
//
// Run:  figure1_dual_basis -o figure1.png [--width 1200 --height 500]
//
// Writes one PNG with two panels, each DN_m over its fulcrum m/2 +/- 6, sampled densely from
// the piecewise-polynomial DualTable, with the fulcrum (dashed) and the zero crossings marked.
// Expect the shapes of the paper's figure: a central peak at the fulcrum, DN_3(1.5) = 1.8012
// and DN_4(2) = 2.2795 (with Table 3's mu_0 = 2.842171 and mu_1 = -1.321729, DN_3(1.5) =
// 0.75 mu_0 + 0.25 mu_1 = 1.8012 by eq. (32)), then lobes of alternating sign whose amplitude
// shrinks geometrically (by a factor of about 0.43 per unit for m = 3 and 0.54 for m = 4),
// symmetric about the fulcrum; the first negative lobes reach -0.67 and -1.06.
// stdout gets a short table of what was measured from the tables: max |DN_m| and where, the
// first zero crossings to the right of the fulcrum (those on the left mirror them), and the
// extreme of the first negative lobe (on stderr when the image goes to stdout). A bad command
// line gives one error line and exit code 2; an output path that cannot be written one line and
// exit code 1, and never a partial file (radiosity/output/output_file.h).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "math/dual_basis.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

const char* const usage =
    "usage: figure1_dual_basis -o FILE.png [--width W --height H]\n"
    "  Draws the paper's Figure 1, the dual scaling functions DN_3 and DN_4, as one PNG.\n"
    "  -o FILE.png   output image (required)\n"
    "  --width W     image width in pixels, 400..8000 (default 1200)\n"
    "  --height H    image height in pixels, 200..8000 (default 500)\n";

constexpr double half_range = 6;  // each panel shows fulcrum +/- half_range
constexpr int n_samples = 2401;   // samples per curve: 200 per unit, finer than the pixels

// What the summary reports about one DN_m, measured from its table.
struct Measured {
    int m = 0;
    double fulcrum = 0;
    double max_abs = 0, argmax = 0;  // largest |DN_m| among the samples and where
    std::vector<double> zeros;       // sign changes right of the fulcrum, inside the range
    double first_min = 0;            // the most negative value of the first negative lobe
};

// The zero of DN_m in [a, b], where it changes sign, by bisection to double precision.
double bisect_zero(const DualTable& dn, double a, double b) {
    double fa = dn(a);
    for (int i = 0; i < 100 && b - a > 1e-15; ++i) {
        const double c = 0.5 * (a + b), fc = dn(c);
        if ((fc < 0) == (fa < 0))
            a = c, fa = fc;
        else
            b = c;
    }
    return 0.5 * (a + b);
}

Measured measure(const DualTable& dn, const std::vector<double>& x, const std::vector<double>& y) {
    Measured out;
    out.m = dn.order();
    out.fulcrum = dn.fulcrum();
    for (size_t i = 0; i < x.size(); ++i)
        if (std::fabs(y[i]) > out.max_abs) out.max_abs = std::fabs(y[i]), out.argmax = x[i];
    for (size_t i = 1; i < x.size(); ++i) {
        if (x[i - 1] < out.fulcrum) continue;
        if ((y[i - 1] < 0) != (y[i] < 0) && y[i - 1] != 0)
            out.zeros.push_back(bisect_zero(dn, x[i - 1], x[i]));
        if (out.zeros.size() == 1 && y[i] < out.first_min) out.first_min = y[i];
    }
    return out;
}

// One panel: DN_m over fulcrum +/- half_range, with the fulcrum and the zero crossings marked.
Measured draw_panel(Image& image, const PixelRect& panel, int m, const std::string& title,
                    Rgb colour, int text_scale) {
    const DualTable dn(m);
    std::vector<double> x(n_samples), y(n_samples);
    for (int i = 0; i < n_samples; ++i) {
        x[i] = dn.fulcrum() - half_range + 2 * half_range * i / (n_samples - 1);
        y[i] = dn(x[i]);
    }
    const Measured measured = measure(dn, x, y);

    Plot plot;
    plot.text_scale = text_scale;
    plot.title = title;
    plot.x_label = "x";
    plot.y_label = "DN_" + std::to_string(m) + "(x)";
    plot.x_min = x.front();
    plot.x_max = x.back();
    const double px = text_scale;  // line widths and markers grow with the text
    plot.add_vline(dn.fulcrum(), {{0.45, 0.45, 0.45}, px, 4 * px, 3 * px}, "fulcrum m/2");
    plot.add_line(x, y, {colour, 1.25 * px}, "DN_" + std::to_string(m) + "(x)");
    Series zeros;  // both sides: the function is symmetric about its fulcrum
    for (double z : measured.zeros) {
        for (double zz : {z, 2 * dn.fulcrum() - z}) {
            zeros.x.push_back(zz);
            zeros.y.push_back(0);
        }
    }
    zeros.draw_line = false;
    zeros.marker = Marker::disc;
    zeros.stroke.colour = {0, 0, 0};
    zeros.marker_radius = 2 * px;
    zeros.label = "zeros";
    plot.add(zeros);
    plot.draw(image, panel);
    return measured;
}

std::string list(const std::vector<double>& v, size_t n, int digits) {
    std::string s;
    for (size_t i = 0; i < v.size() && i < n; ++i) s += (i ? " " : "") + cell(v[i], digits);
    return s;
}

int run(Args& args) {
    const std::string path = args.text("-o", "");
    const int width = args.integer("--width", 1200, 400, 8000);
    const int height = args.integer("--height", 500, 200, 8000);
    args.finish();
    if (path.empty()) throw UsageError("-o FILE.png is required");
    check_output_path(path);

    Image image(width, height, {1, 1, 1});
    const int half = width / 2;
    // Text grows with the panels: scale 2 (10 x 14 pixel glyphs) at the default size.
    const int text_scale = std::clamp(std::min(half / 280, height / 240), 1, 4);
    const Measured dn3 =
        draw_panel(image, {0, 0, half, height}, 3, "(a) DN_3(x)", {0.12, 0.40, 0.75}, text_scale);
    const Measured dn4 = draw_panel(image, {half, 0, width - half, height}, 4, "(b) DN_4(x)",
                                    {0.80, 0.20, 0.15}, text_scale);
    write_png(path, image);

    // The report goes on stderr when the image went to stdout, so that the two do not mix.
    std::ostream& report = is_standard_output(path) ? std::cerr : std::cout;
    report << "Figure 1: dual scaling functions DN_3 and DN_4 -> " << path << " (" << width << " x "
           << height << ")\n"
           << "each panel: x in fulcrum +/- " << half_range << ", " << n_samples
           << " samples of the DualTable\n";
    Table table({"m", "fulcrum", "max|DN_m|", "at_x", "first_zeros_right_of_fulcrum",
                 "first_negative_lobe_min"});
    for (const Measured& r : {dn3, dn4})
        table.add_row({std::to_string(r.m), cell(r.fulcrum, 1), cell(r.max_abs, 6),
                       cell(r.argmax, 3), list(r.zeros, 4, 4), cell(r.first_min, 4)});
    table.write_text(report);
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
