// examples/tutorial/tutorial_01_bsplines.cpp - tutorial chapter 1 (docs/tutorial/01-bsplines.md):
// the uniform B-splines N_m of the paper's section 3, their two-scale relation (14), the refinement
// of a coefficient sequence (15)-(17), and the values at dyadic points (18).
//
// Run:  tutorial_01_bsplines [-o DIR] [--order M] [--level J]
//
// Notation, once and for all (the paper's, and the library's in math/bspline.h):
//   m          the ORDER of a B-spline; its pieces are polynomials of DEGREE m - 1. The paper uses
//              m = 4 (cubic) and m = 3 (quadratic); m = 2 is the "hat" function.
//   N_m(x)     the cardinal B-spline: a bump on [0, m] made of m polynomial pieces, one per
//              unit interval [i, i + 1], joined smoothly (m - 2 continuous derivatives).
//   N_m(x - k) the same bump moved right by the integer k (a "translate").
//   N_m(2^j s - k)   the bump squeezed to width m 2^-j: the basis function k at LEVEL j. Its
//              knots (where the pieces join) are 2^-j apart on the s axis.
//   a_k^(j)    the coefficient of basis function k at level j; the sequence stands for the
//              function f(s) = sum_k a_k^(j) N_m(2^j s - k)   (eq. 15).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "math/bspline.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

const char* const usage =
    "usage: tutorial_01_bsplines [-o DIR] [--order M] [--level J]\n"
    "  Tutorial chapter 1: B-splines N_m, the two-scale relation (14), refinement (17) and the\n"
    "  values at dyadic points (18). Writes DIR/tutorial_01_bsplines.png.\n"
    "  -o DIR       folder for the image (default out; created if missing)\n"
    "  --order M    the order m of parts 2-4, 2..8 (default 4: cubic)\n"
    "  --level J    dyadic points i / 2^J of part 4, 0..6 (default 2)\n";

// The largest |g(x)| over n + 1 equally spaced points of [a, b].
template <class G>
double max_abs_on(G&& g, double a, double b, int n = 4000) {
    double worst = 0;
    for (int i = 0; i <= n; ++i) worst = std::max(worst, std::fabs(g(a + (b - a) * i / n)));
    return worst;
}

// The picture: (a) N_2, N_3, N_4; (b) N_m as the sum of its half-width pieces (14), with the
// dyadic values of part 4 marked.
void draw(const std::string& path, int m, int j1) {
    Image image(1100, 440, {1, 1, 1});
    const Rgb colours[] = {{0.12, 0.40, 0.75},
                           {0.80, 0.20, 0.15},
                           {0.15, 0.55, 0.25},
                           {0.55, 0.30, 0.65},
                           {0.85, 0.55, 0.10}};
    Plot a;
    a.title = "(a) N_2, N_3, N_4";
    a.x_label = "x";
    for (int order = 2; order <= 4; ++order) {
        std::vector<double> x, y;
        for (int i = 0; i <= 400; ++i) {
            x.push_back(-0.25 + 4.5 * i / 400);
            y.push_back(bspline(order, x.back()));
        }
        a.add_line(x, y, {colours[order - 2], 3}, "N_" + std::to_string(order));
    }
    a.draw(image, {0, 0, 550, 440});

    Plot b;
    b.title = "(b) N_" + std::to_string(m) + " and its halves (14)";
    b.x_label = "x";
    b.y_max = 1.0;  // room for the legend above the curves
    const std::vector<double> p = two_scale_mask(m);
    std::vector<double> x, y;
    for (int i = 0; i <= 600; ++i) x.push_back(-0.25 + (m + 0.5) * i / 600);
    for (int k = 0; k <= m; ++k) {
        std::vector<double> piece;
        for (double xi : x) piece.push_back(p[k] * bspline(m, 2 * xi - k));
        b.add_line(x, piece, {colours[k % 5], 2, 6, 4}, k == 0 ? "p_mk N_m(2x-k)" : "");
    }
    for (double xi : x) y.push_back(bspline(m, xi));
    b.add_line(x, y, {{0, 0, 0}, 3}, "N_" + std::to_string(m));
    Series dots;  // the values of (18) at x = i / 2^J
    int first = 0;
    const std::vector<double> v = dyadic_values(m, CoefficientRow{0, 0, {1.0}}, j1, &first);
    for (size_t i = 0; i < v.size(); ++i) {
        dots.x.push_back(std::ldexp(first + double(i), -j1));
        dots.y.push_back(v[i]);
    }
    dots.draw_line = false;
    dots.marker = Marker::disc;
    dots.label = "values (18)";
    b.add(dots);
    b.draw(image, {550, 0, 550, 440});
    write_png(path, image);
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const int m = args.integer("--order", 4, 2, 8);
    const int j1 = args.integer("--level", 2, 0, 6);
    args.finish();
    const std::string png =
        (std::filesystem::path(make_output_folder(dir)) / "tutorial_01_bsplines.png").string();
    check_output_path(png);

    // === Part 1. N_m itself (math/bspline.h: bspline, by the Cox-de Boor recursion).
    // A table a student can check by hand: N_2 is the hat with N_2(1) = 1; N_3(1.5) = 3/4;
    // N_4(2) = 2/3; all vanish outside [0, m].
    std::cout << "Part 1. The cardinal B-splines N_m(x), order m = degree + 1, support [0, m]\n";
    Table values({"x", "N_2(x)", "N_3(x)", "N_4(x)"});
    for (int i = 0; i <= 8; ++i)
        values.add_row({cell(0.5 * i, 1), cell(bspline(2, 0.5 * i), 6),
                        cell(bspline(3, 0.5 * i), 6), cell(bspline(4, 0.5 * i), 6)});
    values.write_text(std::cout);
    // The integer translates N_m(x - k) add up to one everywhere ("partition of unity"): this is
    // why a constant function has all its coefficients equal to that constant.
    const double unity = max_abs_on(
        [&](double x) {
            double sum = 0;
            for (int k = -m; k <= 3; ++k) sum += bspline(m, x - k);
            return sum - 1;
        },
        0, 3);
    std::cout << "partition of unity: max |sum_k N_" << m << "(x - k) - 1| = " << cell_g(unity, 3)
              << "\n\n";

    // === Part 2. The two-scale relation (14): N_m is a sum of m + 1 copies of itself at half
    // the width, N_m(x) = sum_k p_{m,k} N_m(2x - k), with p_{m,k} = 2^{1-m} binom(m, k).
    const std::vector<double> p = two_scale_mask(m);  // math/bspline.h
    std::cout << "Part 2. The two-scale relation (14), m = " << m << "\n";
    for (int k = 0; k <= m; ++k)
        std::cout << "p_{" << m << "," << k << "} = " << cell(p[k], 6) << " = "
                  << std::lround(std::ldexp(p[k], m - 1)) << " / 2^" << m - 1 << "\n";
    const double two_scale = max_abs_on(
        [&](double x) {
            double sum = 0;
            for (int k = 0; k <= m; ++k) sum += p[k] * bspline(m, 2 * x - k);
            return bspline(m, x) - sum;
        },
        -1, m + 1);
    std::cout << "two-scale relation: max |N_m(x) - sum_k p_{m,k} N_m(2x - k)| = "
              << cell_g(two_scale, 3) << "\n\n";

    // === Part 3. Refinement (17): a function given at level j0 written at level j0 + 1,
    // a_l^(j0+1) = sum_k p_{m,l-2k} a_k^(j0). Each coarse coefficient spreads the mask over the
    // fine sequence, shifted by two per step (math/bspline.h: refine).
    std::cout << "Part 3. Refinement (17) of f(s) = sum_k a_k N_m(s - k), level 0 -> 1\n";
    const CoefficientRow coarse{0, 0, {1.0, 3.0, 2.0, 4.0}};  // a_0..a_3 at level 0
    const CoefficientRow fine = refine(m, coarse);
    std::cout << "coarse: " << coarse << "\nfine:   " << fine << "\n";
    const CoefficientRow single = refine(m, CoefficientRow{0, 0, {1.0}});
    std::cout << "refining the single coefficient a_0 = 1 gives the mask: " << single << "\n";
    const double same =
        max_abs_on([&](double s) { return evaluate(m, coarse, s) - evaluate(m, fine, s); }, -1,
                   coarse.a.size() + m);
    std::cout << "refinement: max |f_coarse(s) - f_fine(s)| = " << cell_g(same, 3) << "\n\n";

    // === Part 4. Values at dyadic points (18): f(i / 2^J) = sum_l omega_{m,i-l} a_l^(J), with
    // omega_{m,k} = N_m(k). Refine to level J with (17), then one short convolution with the
    // values of N_m at the integers; no B-spline is evaluated anywhere else
    // (math/bspline.h: integer_values, dyadic_values).
    const std::vector<double> omega = integer_values(m);
    double factorial = 1;  // (m - 1)!: N_m(k) (m - 1)! is an integer (the Eulerian numbers)
    for (int q = 2; q < m; ++q) factorial *= q;
    std::cout << "Part 4. Dyadic values (18), m = " << m << ", J = " << j1 << "\n";
    for (int k = 0; k <= m; ++k)
        std::cout << "omega_{" << m << "," << k << "} = N_" << m << "(" << k
                  << ") = " << cell(omega[k], 6) << " = " << std::lround(omega[k] * factorial)
                  << " / " << factorial << "\n";
    // N_m itself is the row with the single coefficient a_0 = 1 at level 0. Its value at i/2^J
    // times D = (m - 1)! 2^{J(m-1)} is a whole number, since each polynomial piece has rational
    // coefficients with denominator (m - 1)!: "exact" means (18) finds that whole number.
    const double D = factorial * std::ldexp(1.0, j1 * (m - 1));
    int first = 0;
    const std::vector<double> dyadic = dyadic_values(m, CoefficientRow{0, 0, {1.0}}, j1, &first);
    Table table({"i", "x = i/2^J", "N_m(x) by (18)", "times D", "Cox-de Boor", "difference"});
    double worst_whole = 0, worst_direct = 0;
    for (size_t n = 0; n < dyadic.size(); ++n) {
        const double x = std::ldexp(first + double(n), -j1);
        const double direct = bspline(m, x);
        worst_whole = std::max(worst_whole, std::fabs(dyadic[n] * D - std::round(dyadic[n] * D)));
        worst_direct = std::max(worst_direct, std::fabs(dyadic[n] - direct));
        table.add_row({std::to_string(first + int(n)), cell(x, 4), cell(dyadic[n], 10),
                       cell(dyadic[n] * D, 6), cell(direct, 10), cell_g(dyadic[n] - direct, 2)});
    }
    table.write_text(std::cout);
    std::cout << "D = (m-1)! 2^(J(m-1)) = " << cell(D, 0) << "\n"
              << "dyadic values: max distance of N_m(x) D from a whole number = "
              << cell_g(worst_whole, 3) << "\n"
              << "dyadic values: max |(18) - Cox-de Boor| = " << cell_g(worst_direct, 3) << "\n";

    draw(png, m, j1);
    std::cout << "\nwrote " << png << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
