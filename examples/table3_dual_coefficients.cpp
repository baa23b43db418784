// examples/table3_dual_coefficients.cpp - the paper's Table 3: mu_{3;0,l}, l = 0..18, the
// central row of the inverse Gram matrix, computed by the appendix's method (invert M_{m;N},
// M_{m;N+1}, ... until successive central rows agree), printed beside the paper's six decimals;
// m = 2 and 4 are printed for reference.
//
// Run:    table3_dual_coefficients [--csv] [--eps E]
// Expect: every m = 3 value equal to the paper's at six decimals (the "match" column).
#include <cmath>
#include <iostream>

#include "examples/common/cli.h"
#include "math/dual_basis.h"

namespace {

// Table 3 of the paper, mu_{3;0,l} for l = 0..18.
constexpr double paper_mu3[] = {2.842171,  -1.321729, 0.573326,  -0.247042, 0.106378,
                                -0.045804, 0.019722,  -0.008492, 0.003656,  -0.001574,
                                0.000678,  -0.000292, 0.000126,  -0.000054, 0.000023,
                                -0.000010, 0.000004,  -0.000002, 0.000001};
constexpr int n_l = 19;

const char* usage =
    "usage: table3_dual_coefficients [--csv] [--eps E]\n"
    "  Prints mu_{m;0,l} (l = 0..18) for m = 3 beside the paper's Table 3, and m = 2, 4.\n"
    "  --csv    header m,l,mu,paper_mu and one row per value\n"
    "  --eps E  agreement of successive inverses (default 1e-12)\n";

int run(mbr::Args& args) {
    const bool csv = args.flag("--csv");
    const double eps = args.number("--eps", 1e-12);
    args.finish();
    if (!(eps > 0)) throw mbr::UsageError("--eps must be positive");

    mbr::Table table({"m", "l", "mu", "paper_mu"});
    int n_match = 0;
    for (int m : {3, 2, 4}) {
        const mbr::DualCoefficients dc = mbr::dual_coefficients(m, n_l - 1, eps);
        for (int l = 0; l < n_l; ++l) {
            const double paper = m == 3 ? paper_mu3[l] : NAN;
            if (m == 3 && std::fabs(dc.mu[l] - paper) < 0.5e-6) ++n_match;
            table.add_row({std::to_string(m), std::to_string(l), mbr::cell(dc.mu[l], csv ? 12 : 6),
                           std::isnan(paper) ? "" : mbr::cell(paper, 6)});
        }
        if (!csv)
            std::cout << "m = " << m << ": " << dc.n_matrices
                      << " matrices inverted (half-widths " << n_l - 1 << ".."
                      << dc.final_half_width << "), last change " << dc.last_change << "\n";
    }
    if (csv) {
        table.write_csv(std::cout);
        return 0;
    }
    std::cout << "\n";
    table.write_text(std::cout);
    std::cout << "\nm = 3: " << n_match << " of " << n_l
              << " values equal the paper's Table 3 at six decimals\n";
    return n_match == n_l ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) { return mbr::run_main(argc, argv, usage, run); }
