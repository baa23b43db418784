// examples/tutorial/tutorial_02_dual_basis.cpp - tutorial chapter 2
// (docs/tutorial/02-dual-basis.md): the dual basis DN_m of the B-spline N_m (paper section 3, eqs.
// (5), (13); Figure 1), computed by the appendix's method (eqs. (30)-(32)) and checked against the
// paper's Table 3.
//
// Run:  tutorial_02_dual_basis [-o DIR] [--eps E]
//
// Chapter 1 wrote a function as f(x) = sum_k a_k N_m(x - k). This chapter answers the question
// that comes next: given f, how do we find the a_k? The B-splines overlap, so <f, N_m(. - k)> is
// NOT a_k. The dual functions DN_m(x - k) are made so that <N_m(. - k), DN_m(. - l)> = delta_kl
// (eq. 5); then a_k = <f, DN_m(. - k)> (eq. 13), which chapter 3 uses on functions outside the
// spline space.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/paper_tables.h"
#include "examples/common/plot.h"
#include "math/bspline.h"
#include "math/dual_basis.h"
#include "math/gauss_legendre.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

const char* const usage =
    "usage: tutorial_02_dual_basis [-o DIR] [--eps E]\n"
    "  Tutorial chapter 2: the dual basis DN_m by the paper's appendix, Table 3 beside the\n"
    "  paper, biorthogonality, Figure 1. Writes DIR/tutorial_02_dual_basis.png.\n"
    "  -o DIR    folder for the image (default out; created if missing)\n"
    "  --eps E   the appendix's stopping tolerance, 1e-15..1e-3 (default 1e-12)\n";

// int_a^b g(x) dx for a piecewise polynomial g with integer knots and degree <= 2m - 2 (a
// product of two splines of order m): Gauss-Legendre with m points on each unit interval is
// exact, so what we see below is the mathematics, not quadrature error.
template <class G>
double integrate_pieces(G&& g, int a, int b, int m) {
    const GaussLegendre rule = gauss_legendre(m);  // math/gauss_legendre.h
    double sum = 0;
    for (int i = a; i < b; ++i) sum += integrate_1d(g, i, i + 1, rule);
    return sum;
}

// Figure 1 of the paper, with N_m dashed for comparison: the dual is a spline of the same order
// with the same integer knots, but it oscillates and never quite ends.
void draw(const std::string& path) {
    Image image(1100, 440, {1, 1, 1});
    for (int m : {3, 4}) {
        const DualTable dn(m);
        Plot plot;
        plot.title = std::string(m == 3 ? "(a)" : "(b)") + " DN_" + std::to_string(m) + "(x)";
        plot.x_label = "x";
        std::vector<double> x, y, n;
        for (int i = 0; i <= 1200; ++i) {
            x.push_back(dn.fulcrum() - 6 + 12.0 * i / 1200);
            y.push_back(dn(x.back()));
            n.push_back(bspline(m, x.back()));
        }
        plot.legend = LegendPlace::bottom_right;  // below the lobes: room made by y_min
        plot.y_min = -1.35 * dn.max_abs();
        plot.y_max = 1.1 * dn.max_abs();
        plot.add_vline(dn.fulcrum(), {{0.6, 0.6, 0.6}, 2, 10, 6}, "fulcrum m/2");
        plot.add_line(x, n, {{0.1, 0.1, 0.1}, 2, 3, 3}, "N_" + std::to_string(m));
        plot.add_line(x, y, {m == 3 ? Rgb{0.12, 0.40, 0.75} : Rgb{0.80, 0.20, 0.15}, 3},
                      "DN_" + std::to_string(m));
        plot.draw(image, {m == 3 ? 0 : 550, 0, 550, 440});
    }
    write_png(path, image);
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const double eps = args.number("--eps", 1e-12);
    args.finish();
    if (!(eps >= 1e-15 && eps <= 1e-3)) throw UsageError("--eps must be in 1e-15..1e-3");
    const std::string png =
        (std::filesystem::path(make_output_folder(dir)) / "tutorial_02_dual_basis.png").string();
    check_output_path(png);
    const int m = 3;  // Table 3's order

    // === Part 1. The Gram sequence. The matrix M_m of (30) holds the inner products
    // gamma_{m;k,l} = <N_m(. - k), N_m(. - l)>. They depend only on k - l, and the integral of two
    // B-splines is a value of the B-spline of order 2m: gamma_n = N_{2m}(m + n)
    // (math/dual_basis.h: gram_sequence). Cross-check: the integral itself.
    std::cout << "Part 1. The Gram sequence gamma_n = <N_3, N_3(. - n)> = N_6(3 + n)\n";
    const std::vector<double> gamma = gram_sequence(m);
    for (int n = 0; n < m; ++n) {
        const double integral = integrate_pieces(
            [&](double x) { return bspline(m, x) * bspline(m, x - n); }, 0, m + n, m);
        std::cout << "gamma_" << n << " = " << cell(gamma[n], 9) << "  (integral "
                  << cell(integral, 9) << ")\n";
    }
    std::cout << "gamma_n = 0 for |n| >= " << m << ": M_3 is a band matrix\n\n";

    // === Part 2. The appendix. M_m is an infinite matrix; its inverse [mu_{m;k,l}] gives the
    // dual, DN_m(x - k) = sum_l mu_{m;k,l} N_m(x - l) (32). Since M_m is a Toeplitz matrix only
    // the central row mu_l = mu_{m;0,l} is needed. The paper inverts the finite sections
    // M_{m;N}, M_{m;N+1}, ... (rows -K..K) until the central rows of two successive inverses
    // agree within eps for |l| <= N (math/dual_basis.h: dual_coefficients).
    std::cout << "Part 2. The appendix: growing sections M_{3;K} until mu_l settles (N = 18)\n";
    for (double e : {1e-4, 1e-8, 1e-12}) {
        const DualCoefficients dc = dual_coefficients(m, 18, e);
        std::cout << "eps " << cell_g(e, 2) << ": matrices inverted = " << dc.n_matrices
                  << ", last half-width K = " << dc.final_half_width
                  << ", last change = " << cell_g(dc.last_change, 2) << "\n";
    }
    const DualCoefficients dc = dual_coefficients(m, 18, eps);
    std::cout << "Table 3 by the appendix with eps = " << cell_g(eps, 2) << ":\n";
    Table table({"l", "mu_{3;0,l}", "paper (Table 3)", "difference", "mu_l / mu_{l-1}"});
    int n_match = 0;
    for (int l = 0; l <= 18; ++l) {
        const double diff = dc.mu[l] - paper_table3[l];
        if (std::fabs(diff) < 0.5e-6) ++n_match;  // equal when rounded to six decimals
        table.add_row({std::to_string(l), cell(dc.mu[l], 9), cell(paper_table3[l], 6),
                       cell_g(diff, 2), l ? cell(dc.mu[l] / dc.mu[l - 1], 4) : ""});
    }
    table.write_text(std::cout);
    std::cout << "Table 3: " << n_match << " of 19 values equal the paper's at six decimals\n"
              << "the coefficients alternate in sign and shrink by a constant factor: the dual "
                 "has infinite support, but decays geometrically\n\n";

    // === Part 3. Biorthogonality (5): <N_m(. - k), DN_m> = delta_k0. DualTable holds DN_m as
    // one polynomial per unit interval, built from the mu_l (math/dual_basis.h); the product with
    // N_m(x - k) is integrated exactly, piece by piece.
    std::cout << "Part 3. Biorthogonality <N_m(. - k), DN_m> = delta_k0\n";
    Table bio({"k", "m = 2", "m = 3", "m = 4"});
    std::vector<DualTable> duals = {DualTable(2), DualTable(3), DualTable(4)};
    double worst = 0;
    for (int k = -4; k <= 4; ++k) {
        std::vector<std::string> row{std::to_string(k)};
        for (const DualTable& dn : duals) {
            const int mm = dn.order();
            const double ip = integrate_pieces([&](double x) { return bspline(mm, x - k) * dn(x); },
                                               k, k + mm, mm);
            worst = std::max(worst, std::fabs(ip - (k == 0 ? 1 : 0)));
            row.push_back(cell_g(ip, 3));
        }
        bio.add_row(row);
    }
    bio.write_text(std::cout);
    std::cout << "biorthogonality: max |<N_m(. - k), DN_m> - delta_k0| = " << cell_g(worst, 3)
              << "\n";
    // What it buys (13): the coefficients of a spline come back as its inner products with the
    // duals. f = sum_k a_k N_3(x - k) with a = (1, 3, 2, 4) at k = 0..3.
    const CoefficientRow a{0, 0, {1.0, 3.0, 2.0, 4.0}};
    const DualTable& dn3 = duals[1];
    std::cout << "recovering a = " << a << " by (13):\n";
    for (int k = -1; k <= 4; ++k) {
        const int reach = static_cast<int>(dn3.half_width()) + m + 2;  // where DN_3(x - k) lives
        const double c = integrate_pieces([&](double x) { return evaluate(m, a, x) * dn3(x - k); },
                                          k - reach, k + reach, m);
        std::cout << "<f, DN_3(. " << (k < 0 ? "+ " : "- ") << std::abs(k)
                  << ")> = " << cell(std::fabs(c) < 5e-10 ? 0.0 : c, 9)  // no "-0.000000000"
                  << "  (error " << cell_g(c - a.at(k), 2) << ")\n";
    }

    // === Part 4. Figure 1. DN_m is symmetric about its fulcrum m/2 (where N_m peaks too).
    // (32) at x = 1.5 for m = 3 by hand: N_3(1.5) = 3/4, N_3(0.5) = N_3(2.5) = 1/8, so
    // DN_3(1.5) = 3/4 mu_0 + 2 (1/8) mu_1.
    std::cout << "\nPart 4. Figure 1\n"
              << "DN_3(1.5) = " << cell(dn3(1.5), 6)
              << "  (3/4 mu_0 + 1/4 mu_1 = " << cell(0.75 * dc.mu[0] + 0.25 * dc.mu[1], 6) << ")\n"
              << "DN_4(2) = " << cell(duals[2](2.0), 6) << "\n";
    for (const DualTable& dn : duals)
        std::cout << "m = " << dn.order() << ": table half-width " << dn.half_width()
                  << " units, error bound of the table " << cell_g(dn.error_bound(), 2) << "\n";
    draw(png);
    std::cout << "wrote " << png << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
