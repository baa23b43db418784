// examples/paper/table3_dual_coefficients.cpp - the paper's Table 3: mu_{3;0,l}, l = 0..18, the
// central row of the inverse Gram matrix, computed by the appendix's method (invert M_{m;N},
// M_{m;N+1}, ... until successive central rows agree), printed beside the paper's six decimals;
// m = 2 and 4 are printed for reference.
//
// Run:    table3_dual_coefficients [--csv] [--eps E]
// Expect: every m = 3 value equal to the paper's at six decimals (the "match" column).
#include "examples/common/paper_tables.h"

namespace {
const char* usage =
    "usage: table3_dual_coefficients [--csv] [--eps E]\n"
    "  Prints mu_{m;0,l} (l = 0..18) for m = 3 beside the paper's Table 3, and m = 2, 4.\n"
    "  --csv    header m,l,mu,paper_mu and one row per value\n"
    "  --eps E  agreement of successive inverses (default 1e-12)\n";
}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, mbr::run_table3);
}
