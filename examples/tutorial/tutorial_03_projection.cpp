// examples/tutorial/tutorial_03_projection.cpp - tutorial chapter 3
// (docs/tutorial/03-projection.md): projecting a known function onto tensor B-splines with the dual
// basis, eq. (19), then reconstructing it with (20); how the error falls with the scale 2^-j for a
// smooth function, one with a kink and one with a step; and what cutting the dual functions off at
// the rhombus radius (section 5 "Projection", Figure 3) saves and costs.
//
// Run:  tutorial_03_projection [-o DIR] [--order M] [--levels J0 J1] [--level J] [--eps E]
//
// Chapter 2 showed that c_k = <f, DN_m(. - k)> gives back the coefficients of a spline. For any
// other f the same formula gives the spline NEAREST to f (in L2), and in two dimensions at
// level j it reads (DESIGN.md section 2)
//     c_{k,l} = 4^j int int f(s,t) DN_m(2^j s - k) DN_m(2^j t - l) ds dt          (19)
//     f_hat(s,t) = sum_{k,l} c_{k,l} N_m(2^j s - k) N_m(2^j t - l)                 (20)
// The factor 4^j makes a constant f come back with every c equal to that constant.
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "math/dual_basis.h"
#include "math/parallel.h"
#include "radiosity/transfer/transfer.h"

namespace mbr {
namespace {

const char* const usage =
    "usage: tutorial_03_projection [-o DIR] [--order M] [--levels J0 J1] [--level J] [--eps E]\n"
    "  Tutorial chapter 3: projection (19) of known functions with the dual basis, the error\n"
    "  against the scale, and the cost of truncating DN at the rhombus radius. Writes\n"
    "  DIR/tutorial_03_projection.png and DIR/tutorial_03_truncation.png.\n"
    "  -o DIR          folder for the images (default out; created if missing)\n"
    "  --order M       B-spline order, 2..5 (default 4)\n"
    "  --levels J0 J1  levels of the convergence table, 1 <= J0 <= J1 <= 7 (default 2 5)\n"
    "  --level J       level of the truncation sweep, 1..6 (default 4)\n"
    "  --eps E         truncation of the convergence table, 1e-12..1e-2 (default 1e-9)\n";

// Three test functions on the (s,t) plane, all built on the circle of radius 0.3 around
// (0.45, 0.5) (off the dyadic grid on purpose) and all zero far away.
struct TestFunction {
    std::string name;
    std::function<double(double, double)> f;
};
std::vector<TestFunction> test_functions() {
    auto rho = [](double s, double t) { return std::hypot(s - 0.45, t - 0.5); };
    return {
        {"smooth", [=](double s, double t) { return std::exp(-std::pow(rho(s, t) / 0.25, 2)); }},
        {"kink",
         [=](double s, double t) { return std::max(0.0, 1 - std::pow(rho(s, t) / 0.3, 2)); }},
        {"step", [=](double s, double t) { return rho(s, t) < 0.3 ? 1.0 : 0.0; }}};
}

// Eq. (19) for every basis function of level j that touches [0,1]^2, by the library's stage 6
// (radiosity/transfer/projection.h: project). In a transfer, project() integrates the samples of
// (21) over the leaves of an adaptive quadtree; here the tree is uniform at level j, wide enough
// for every rhombus, and its samples are f at the m x m Gauss-Legendre nodes of each leaf.
SplineField project_function(const std::function<double(double, double)>& f, int m, int j,
                             double radius, const DualTable& dn) {
    ReceiverOptions options;
    options.m = m;
    ReceiverState state(options, radius);  // rhombus radius in cells of the basis scale 2^-j
    const int K = static_cast<int>(std::ceil((radius + m) * std::ldexp(1.0, -j)));
    state.forest = Forest(K);  // unit roots (I, J), |I|, |J| <= K; (0,0) is [0,1]^2
    for (int level = 0; level < j; ++level)
        for (int index : state.forest.leaves()) state.forest.split(index);
    const GaussLegendre rule = gauss_legendre(m);
    int block = 0;
    for (int index : state.forest.leaves()) {
        Forest::Node& node = state.forest.node(index);
        node.samples = block++;
        const Rect r = node.cell.rect();
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                const double v = f(r.x0 + 0.5 * (rule.x[a] + 1) * r.width(),
                                   r.y0 + 0.5 * (rule.x[b] + 1) * r.height());
                state.samples.push_back({v, v, v});
            }
    }
    const ProjectionTables tables = make_projection_tables(m, dn, radius, 0);
    SplineField field(m, j);
    const int first = first_touching_index(m), n = touching_count(m, j);
    std::vector<Rgb> c(size_t(n) * n);
    parallel_for(n * n, [&](int i) {
        c[i] = project(state, dn, tables, Fulcrum{j, first + i / n, first + i % n});
    });
    for (int i = 0; i < n * n; ++i) field.set_coefficient(first + i / n, first + i % n, c[i]);
    return field;
}

// Max and root-mean-square of f - f_hat on a 129 x 129 grid over [0,1]^2 (eq. 20, evaluated
// through radiosity/geometry/spline_field.h: PolynomialPatches, the field as one polynomial per
// cell).
struct Error {
    double max = 0, rms = 0;
};
Error error_of(const SplineField& f_hat, const std::function<double(double, double)>& f) {
    const PolynomialPatches patches(f_hat);
    const int n = 129;
    Error e;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double s = double(a) / (n - 1), t = double(b) / (n - 1);
            const double d = std::fabs(patches(s, t).r - f(s, t));
            e.max = std::max(e.max, d);
            e.rms += d * d;
        }
    e.rms = std::sqrt(e.rms / (double(n) * n));
    return e;
}

// The cells of the basis scale that meet the rhombus |x| + |y| <= r around a fulcrum (a cell
// corner for even m, a cell centre for odd m): on a uniform tree, exactly the leaves project()
// visits for one coefficient, each costing m x m products of DN DN with a sample.
long cells_in_rhombus(int m, double r) {
    const double c = (m % 2) ? 0.5 : 0.0;
    const int R = static_cast<int>(std::ceil(r)) + 1;
    long count = 0;
    for (int i = -R; i <= R; ++i)
        for (int j = -R; j <= R; ++j) {
            const double dx = std::max({0.0, i - c, c - (i + 1)});
            const double dy = std::max({0.0, j - c, c - (j + 1)});
            if (dx + dy <= r) ++count;
        }
    return count;
}

const Rgb colours[] = {{0.12, 0.40, 0.75}, {0.80, 0.20, 0.15}, {0.15, 0.55, 0.25},
                       {0.55, 0.30, 0.65}, {0.85, 0.55, 0.10}, {0.3, 0.3, 0.3}};

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const int m = args.integer("--order", 4, 2, 5);
    std::vector<double> levels = args.numbers("--levels", 2);
    const int J = args.integer("--level", 4, 1, 6);
    const double eps = args.number("--eps", 1e-9);
    args.finish();
    if (levels.empty()) levels = {2, 5};
    const int j0 = int(levels[0]), j1 = int(levels[1]);
    if (j0 != levels[0] || j1 != levels[1] || j0 < 1 || j0 > j1 || j1 > 7)
        throw UsageError("--levels J0 J1 must be integers with 1 <= J0 <= J1 <= 7");
    if (!(eps >= 1e-12 && eps <= 1e-2)) throw UsageError("--eps must be in 1e-12..1e-2");
    const std::filesystem::path folder(make_output_folder(dir));
    const std::string png_projection = (folder / "tutorial_03_projection.png").string();
    const std::string png_truncation = (folder / "tutorial_03_truncation.png").string();

    // The dual of order m as polynomial pieces, and the rhombus of Figure 3: the region where
    // |DN(x) DN(y)| exceeds eps max|DN|^2 lies inside |x| + |y| <= r (math/dual_basis.h).
    const DualTable dn(m);
    const double radius = dn.rhombus_radius(eps);
    std::cout << "order m = " << m << "; eps = " << cell_g(eps, 2) << " gives rhombus radius "
              << cell(radius, 4) << " cells\n\n";

    // === Part 1. The error against the scale. Halving the knot spacing 2^-j should divide the
    // error by 2^rate: rate m for a smooth f (the spline matches its Taylor polynomial of degree
    // m - 1 on each cell), less where f has a kink or a step.
    std::cout << "Part 1. The error against the scale 2^-j (r = " << cell(radius, 4) << " cells)\n";
    const std::vector<TestFunction> functions = test_functions();
    std::vector<std::vector<SplineField>> fields(functions.size());
    Table table({"function", "level j", "coefficients", "max error", "rate", "rms error", "rate"});
    for (size_t q = 0; q < functions.size(); ++q) {
        Error previous;
        for (int j = j0; j <= j1; ++j) {
            fields[q].push_back(project_function(functions[q].f, m, j, radius, dn));
            const Error e = error_of(fields[q].back(), functions[q].f);
            const bool first = j == j0;
            table.add_row({functions[q].name, std::to_string(j),
                           std::to_string(touching_count(m, j) * touching_count(m, j)),
                           cell_g(e.max, 3), first ? "" : cell(std::log2(previous.max / e.max), 2),
                           cell_g(e.rms, 3),
                           first ? "" : cell(std::log2(previous.rms / e.rms), 2)});
            std::cout << functions[q].name << " level " << j << ": max error = " << cell_g(e.max, 6)
                      << ", rms error = " << cell_g(e.rms, 6) << "\n";
            previous = e;
        }
    }
    std::cout << "\n";
    table.write_text(std::cout);

    // === Part 2. Truncation. DN_m never ends (chapter 2), so project() keeps only the cells
    // that meet the rhombus of radius r around each fulcrum. A smaller r visits fewer cells, and
    // drops the tail of f DN DN outside it.
    std::cout << "\nPart 2. Truncation at the rhombus radius r (smooth f, level " << J << ")\n";
    const long side = std::lround(2 * dn.half_width());  // the whole tabulated support
    std::cout << "untruncated: DN_" << m << " is tabulated to " << cell(dn.half_width(), 1)
              << " cells from its fulcrum, a square of " << side * side
              << " cells per coefficient\n";
    Table sweep({"r (cells)", "eps", "cells/coef", "products/coef", "max error", "rms error"});
    std::vector<double> rs, max_errors, rms_errors, costs;
    for (double r : {1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0, 24.0, 28.0}) {
        const Error e = error_of(project_function(functions[0].f, m, J, r, dn), functions[0].f);
        const long cells = cells_in_rhombus(m, r);
        sweep.add_row({cell(r, 0), cell_g(dn.eps_for_rhombus_radius(r), 2), std::to_string(cells),
                       std::to_string(cells * m * m), cell_g(e.max, 3), cell_g(e.rms, 3)});
        std::cout << "r = " << r << ": cells per coefficient = " << cells
                  << ", max error = " << cell_g(e.max, 6) << "\n";
        rs.push_back(r), max_errors.push_back(e.max), rms_errors.push_back(e.rms);
        costs.push_back(double(cells));
    }
    sweep.write_text(std::cout);

    // === The pictures. (1) Sections t = 0.5 of each f and its projections, and the error along
    // them on a log scale; (2) the error and the cost against r.
    Image image(1200, 800, {1, 1, 1});
    for (size_t q = 0; q < functions.size(); ++q) {
        Plot top, bottom;
        top.title = "(" + std::string(1, char('a' + q)) + ") " + functions[q].name + ", t = 0.5";
        bottom.title = "error |f - f_hat|";
        top.x_label = bottom.x_label = "s";
        bottom.log_y = true;
        bottom.y_min = 1e-9;
        bottom.y_max = 3;
        std::vector<double> s, y;
        for (int i = 0; i <= 500; ++i) s.push_back(i / 500.0);
        for (double si : s) y.push_back(functions[q].f(si, 0.5));
        top.add_line(s, y, {{0, 0, 0}, 3}, "f");
        for (size_t n = 0; n < fields[q].size(); ++n) {
            std::vector<double> v, e;
            for (size_t i = 0; i < s.size(); ++i) {
                v.push_back(fields[q][n].evaluate(s[i], 0.5).r);
                e.push_back(std::max(1e-9, std::fabs(v.back() - y[i])));
            }
            const std::string label = "j = " + std::to_string(j0 + int(n));
            top.add_line(s, v, {colours[n % 6], 2}, label);
            bottom.add_line(s, e, {colours[n % 6], 2}, label);
        }
        // One legend, at the top right of (a).
        top.legend = q == 0 ? LegendPlace::top_right : LegendPlace::none;
        if (q == 0) top.y_max = 1.8;  // room for it above the curves
        bottom.legend = LegendPlace::none;
        top.draw(image, {int(q) * 400, 0, 400, 400});
        bottom.draw(image, {int(q) * 400, 400, 400, 400});
    }
    write_png(png_projection, image);

    Image trunc(1100, 440, {1, 1, 1});
    Plot err, cost;
    err.title = "error against r (level " + std::to_string(J) + ")";
    cost.title = "cells per coefficient";
    err.x_label = cost.x_label = "rhombus radius r (cells)";
    err.log_y = true;
    err.add({rs, max_errors, {colours[0], 3}, true, Marker::disc, 4, "max error"});
    err.add({rs, rms_errors, {colours[1], 3}, true, Marker::disc, 4, "rms error"});
    cost.add({rs, costs, {colours[2], 3}, true, Marker::disc, 4, "cells"});
    err.draw(trunc, {0, 0, 550, 440});
    cost.draw(trunc, {550, 0, 550, 440});
    write_png(png_truncation, trunc);
    std::cout << "\nwrote " << png_projection << "\nwrote " << png_truncation << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
