// examples/tutorial/tutorial_04_sample_values.cpp - tutorial chapter 4
// (docs/tutorial/04-sample-values.md): one transfer, part 1. The receiver learns about the shooter
// only through sample values, eq. (21): dB(s0, t0) = rho * int int F(p, x(u,v)) B_h(u,v) A_h(u,v)
// du dv, with the kernel F of eq. (3). This program takes the Table 1 configuration (parallel unit
// squares at distance h, shooter radiosity B_h = 1, reflectance rho = 1, so dB is the
// point-to-square form factor) and
//   1. evaluates the kernel (3) at two shooter points (form_factor_kernel,
//   radiosity/transfer/form_factor.h);
//   2. evaluates (21) by adaptive Gauss-Legendre quadrature (section 6) at two receiving points
//      for a ladder of tolerances, and compares with the analytic form factor
//      (point_polygon_form_factor): kernel evaluations against error, plain rule
//      (adaptive_integrate_2d, math/gauss_legendre.h) beside the library's IncrementIntegrator;
//   3. runs the oracle of section 6 (subdivide_by_oracle, radiosity/transfer/oracle.h), which
//   decides
//      where the receiver needs small cells, and draws its tree over dB.
// Run: tutorial_04_sample_values [-o DIR] [--h H] [--min-depth a] [--max-depth b]
//                                [--oracle-tolerance T]
// Writes DIR/tutorial_04_quadrature.png and DIR/tutorial_04_oracle_tree.png.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_04_sample_values [-o DIR] [options]\n"
    "  Chapter 4 of the tutorial: the kernel (3), the sample values (21) by adaptive\n"
    "  Gauss-Legendre quadrature, and the oracle that builds the receiver's tree.\n"
    "  -o DIR                folder for the images (default out; created if missing)\n"
    "  --h H                 distance of the parallel unit squares, (0, 10] (default 0.1)\n"
    "  --min-depth a         oracle tree bounds, 0..7 (default 1 and 5)\n"
    "  --max-depth b\n"
    "  --oracle-tolerance T  oracle threshold (default 1e-3)\n";

// One row of the quadrature study: evaluations and relative error of both rules.
struct QuadratureRow {
    double tolerance;
    long plain_evals, library_evals;
    double plain_error, library_error;
};

// Eq. (21) at receiving point (s, t) for each tolerance, by two rules: the paper's plain
// adaptive rule (n = 6 against 7 points per cell, a quarter of the tolerance per child) on the
// integrand F A_h, and IncrementIntegrator, which adds a near-field guard. Tolerances are
// relative to the exact value, so that both rules are asked the same.
std::vector<QuadratureRow> quadrature_study(const TransferSetup& setup, double s, double t,
                                            const std::vector<double>& tolerances) {
    const SurfacePoint p = setup.receiver.evaluate(s, t);
    const double exact = point_polygon_form_factor(p.position, p.normal, setup.shooter_polygon());
    const Shooter shooter{&setup.shooter, SplineField::constant(4, 0, {1, 1, 1}), nullptr};
    std::vector<QuadratureRow> rows;
    for (double tol : tolerances) {
        // The integrand of (21) over the shooter's (u, v): F(p, x) A_h, with B_h = rho = 1.
        auto integrand = [&](double u, double v) {
            const SurfacePoint x = setup.shooter.evaluate(u, v);
            return form_factor_kernel(p.position, p.normal, x.position, x.normal) * x.area_factor;
        };
        AdaptiveOptions plain;
        plain.n = 6;
        plain.tolerance = tol * exact;
        plain.max_depth = 24;
        const auto a = adaptive_integrate_2d(integrand, Rect{0, 1, 0, 1}, plain);
        QuadratureOptions q;  // the library's rule of (21)...
        q.analytic = false;   // ...without its closed form for a constant planar shooter
        q.rel_tolerance = tol;
        IncrementIntegrator integrator(shooter, q);
        const IncrementIntegrator::Result b = integrator.integrate(p);
        rows.push_back({tol, a.n_evaluations, b.n_evaluations, std::fabs(a.value / exact - 1),
                        std::fabs(b.value[0] / exact - 1)});
    }
    return rows;
}

// What the oracle compares on one cell: the means of dB by ceil(m/2)^2 and m^2 Gauss-Legendre
// points (section 6, "Oracle"), here computed directly so that the numbers can be printed.
void print_oracle_test(IncrementSampler& sampler, const DyadicCell& cell, int m) {
    long evals = 0;
    auto mean = [&](int n) {
        const Rect r = cell.rect();
        return integrate_2d([&](double s, double t) { return sampler.sample(s, t, 0, &evals)[0]; },
                            r, gauss_legendre(n)) /
               r.area();
    };
    const double coarse = mean((m + 1) / 2), fine = mean(m);
    std::cout << "  " << cell << ": mean by " << (m + 1) / 2 << "x" << (m + 1) / 2 << " points "
              << cell_g(coarse, 7) << ", by " << m << "x" << m << " points " << cell_g(fine, 7)
              << ", relative difference " << cell_g(std::fabs(coarse / fine - 1), 3) << "\n";
}

// The tree over a map of the exact dB: each leaf outlined, the domain [0,1]^2 filling the panel.
Image draw_tree(const Forest& forest, const TransferSetup& setup, const std::string& title) {
    const int n = 256, s = 2, margin = axes_margin(s, 4), size = 560;
    Image image(margin + size + 150, 50 + size + margin, {1, 1, 1});
    const PixelRect area{margin, 50, size, size};
    const std::vector<double> exact = exact_grid(setup, n);
    double lo = exact[0], hi = exact[0];
    for (double v : exact) lo = std::min(lo, v), hi = std::max(hi, v);
    // exact_grid rows go up in t; draw_scalar_field's row 0 is the top: flip the rows.
    std::vector<double> flipped(exact.size());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) flipped[size_t(n - 1 - j) * n + i] = exact[size_t(j) * n + i];
    draw_scalar_field(image, area, flipped, n, n, lo, hi);
    const PlotLayout L = map_layout(area, 0, 1, 0, 1, s);
    Canvas canvas(image);
    for (int index : forest.leaves(Forest::Region::Domain)) {
        const Rect r = forest.node(index).cell.rect();
        const Vec2 a = L.to_pixel(r.x0, r.y0), b = L.to_pixel(r.x1, r.y1);
        canvas.polyline({a, {b.x, a.y}, b, {a.x, b.y}, a}, {{1, 1, 1}, 1});
    }
    draw_axes(image, L, "s", "t", {0, 0, 0}, s);
    draw_colour_scale(image, {margin + size + 30, 80, 22, size - 60}, lo, hi, "dB", colour_map, s);
    canvas.text(margin, 12, title, {0, 0, 0}, s);
    return image;
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const double h = args.number("--h", 0.1);
    ReceiverOptions options;  // m = 4 and the library's defaults, as in Table 1
    options.min_depth = args.integer("--min-depth", 1, 0, 7);
    options.max_depth = args.integer("--max-depth", 5, 0, 7);
    options.oracle_tolerance = args.number("--oracle-tolerance", 1e-3);
    args.finish();
    if (!(h > 0 && h <= 10)) throw UsageError("--h must be in (0, 10]");
    if (options.min_depth > options.max_depth)
        throw UsageError("--min-depth must not exceed --max-depth");
    if (!(options.oracle_tolerance > 0)) throw UsageError("--oracle-tolerance must be positive");
    make_output_folder(dir);
    const TransferSetup setup = parallel_squares(h);
    std::cout << "Chapter 4: the sample values of one transfer, parallel unit squares at h = " << h
              << "\n\n";

    // 1. The kernel (3) from the receiving point p = (0.5, 0.5, 0), normal +z, to a shooter point
    // x with normal -z: F = cos(theta_p) cos(theta_x) / (pi |x - p|^2).
    const SurfacePoint centre = setup.receiver.evaluate(0.5, 0.5);
    const Vec3 down{0, 0, -1};
    const double F_above = form_factor_kernel(centre.position, centre.normal, {0.5, 0.5, h}, down);
    const double F_corner = form_factor_kernel(centre.position, centre.normal, {0, 0, h}, down);
    std::cout << "1. The kernel F of eq. (3) from p = (0.5, 0.5, 0)\n"
              << "  F to x straight above p: " << cell_g(F_above, 8)
              << " (1 / (pi h^2) = " << cell_g(1 / (Pi * h * h), 8) << ")\n"
              << "  F to the shooter's corner (0, 0, h): " << cell_g(F_corner, 8)
              << " (h^2 / (pi (h^2 + 0.5)^2) = "
              << cell_g(h * h / (Pi * std::pow(h * h + 0.5, 2)), 8) << ")\n\n";

    // 2. Eq. (21) by adaptive quadrature, against the analytic form factor.
    const std::vector<double> tolerances = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
    Plot plot;
    plot.title = "Eq. (21) by adaptive quadrature, h = " + cell_g(h, 3);
    plot.x_label = "kernel evaluations";
    plot.y_label = "relative error";
    plot.log_x = plot.log_y = true;
    const Rgb colours[2] = {{0.0, 0.45, 0.70}, {0.84, 0.37, 0.0}};
    const double points[2][2] = {{0.5, 0.5}, {0.0, 0.0}};
    std::cout << "2. The sample value dB(s, t) of eq. (21) (B_h = rho = 1: the form factor)\n";
    for (int which = 0; which < 2; ++which) {
        const double s = points[which][0], t = points[which][1];
        const SurfacePoint p = setup.receiver.evaluate(s, t);
        const double exact =
            point_polygon_form_factor(p.position, p.normal, setup.shooter_polygon());
        const std::string name = which == 0 ? "centre" : "corner";
        std::cout << "  at the " << name << " (" << s << ", " << t
                  << "): analytic dB = " << cell_g(exact, 10) << "\n";
        Table table(
            {"tolerance", "plain evals", "plain rel error", "library evals", "library rel error"});
        std::vector<double> xs[2], ys[2];
        const std::vector<QuadratureRow> rows = quadrature_study(setup, s, t, tolerances);
        for (const QuadratureRow& r : rows) {
            table.add_row({cell_g(r.tolerance, 1), std::to_string(r.plain_evals),
                           cell_g(r.plain_error, 3), std::to_string(r.library_evals),
                           cell_g(r.library_error, 3)});
            xs[0].push_back(double(r.plain_evals));
            ys[0].push_back(std::max(r.plain_error, 1e-16));
            xs[1].push_back(double(r.library_evals));
            ys[1].push_back(std::max(r.library_error, 1e-16));
        }
        table.write_text(std::cout);
        std::cout << "  " << name << ", library rule at tolerance 1e-4: kernel evaluations "
                  << rows[2].library_evals << ", relative error "
                  << cell_g(rows[2].library_error, 3) << "\n";
        for (int rule = 0; rule < 2; ++rule)
            plot.add({xs[rule],
                      ys[rule],
                      {colours[which], 2.5, rule == 0 ? 8.0 : 0.0, 5},
                      true,
                      rule == 0 ? Marker::square : Marker::disc,
                      4,
                      name + (rule == 0 ? ", plain rule" : ", IncrementIntegrator")});
        std::cout << "\n";
    }
    Image quadrature(900, 620, {1, 1, 1});
    plot.draw(quadrature, {0, 0, 900, 620});
    write_png((std::filesystem::path(dir) / "tutorial_04_quadrature.png").string(), quadrature);

    // 3. The oracle (section 6): on each cell compare the means of dB by ceil(m/2)^2 and m^2
    // points; where they agree the cell is split once more and stopped. The samples come from
    // IncrementSampler, which evaluates (21) for the transfer (here by the closed form the
    // library uses for a constant planar shooter, QuadratureOptions::analytic).
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    IncrementSampler sampler(shooter, receiver, options.quadrature);
    std::cout << "3. The oracle, m = " << options.m << ", tolerance "
              << cell_g(options.oracle_tolerance, 3) << ", depths " << options.min_depth << ".."
              << options.max_depth << "\n";
    for (const DyadicCell& c : {DyadicCell{0, 0, 0}, DyadicCell{3, 3, 3}, DyadicCell{3, 0, 0}})
        print_oracle_test(sampler, c, options.m);

    ReceiverState state(options);         // stages 1-2 only: no rhombus radius
    subdivide_by_oracle(state, sampler);  // stage 1
    std::map<int, int> per_level;
    for (int index : state.forest.leaves(Forest::Region::Domain))
        ++per_level[state.forest.node(index).cell.level];
    for (const auto& [level, count] : per_level)
        std::cout << "  oracle leaves at level " << level << ": " << count << "\n";
    std::cout << "  oracle sample values: " << state.stats.n_oracle_increments << "\n";
    const int splits = adjust_neighbour_scales(state.forest, Forest::Region::Domain);  // stage 2
    sample_leaves(state, sampler);
    const int n_leaves = int(state.forest.leaves(Forest::Region::Domain).size());
    std::cout << "  NeighAdjust splits: " << splits << "\n"
              << "  leaves after NeighAdjust: " << n_leaves << "\n"
              << "  sample values (21) in all: " << state.stats.n_increments << " ("
              << options.m * options.m << " per leaf)\n"
              << "  largest sample: " << cell_g(state.max_sample, 8) << "\n";
    const Image tree = draw_tree(state.forest, setup,
                                 "Oracle tree, h = " + cell_g(h, 3) + ", tolerance " +
                                     cell_g(options.oracle_tolerance, 3) + ": " +
                                     std::to_string(n_leaves) + " leaves over dB");
    write_png((std::filesystem::path(dir) / "tutorial_04_oracle_tree.png").string(), tree);
    std::cout << "\nwrote " << dir << "/tutorial_04_quadrature.png and " << dir
              << "/tutorial_04_oracle_tree.png\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
