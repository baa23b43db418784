// examples/paper/table1_parallel_squares.cpp - the paper's Table 1: rea (eq. 29) of one transfer
// between parallel unit squares at distance h, shooter radiosity 1, receiver reflectance 1,
// receiver at uniform depth d (leaves 2^-d wide), against the analytic form factor
// (radiosity/transfer/form_factor.h).
//
// Run:    table1_parallel_squares [--order m] [--extrapolation linear|higher] [--eps E |
//                                  --rhombus-radius R] [--csv] ...
// Expect: with the defaults (m = 4, linear extrapolation, eps = 1e-7) every row well below the
//         paper's value; with --rhombus-radius 14 figures of the paper's own size.
#include "examples/common/paper_tables.h"
#include "examples/common/transfer_cli.h"

namespace {
std::string usage() {
    return std::string(
               "usage: table1_parallel_squares [options]\n"
               "  Table 1 of the paper: rea between parallel unit squares, beside the paper.\n"
               "  --csv                     header h,d,rea_percent,paper_rea_percent,seconds\n") +
           mbr::receiver_options_usage;
}
}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage(), [](mbr::Args& args) {
        return mbr::run_paper_table(args, mbr::paper_table1, 6, true);
    });
}
