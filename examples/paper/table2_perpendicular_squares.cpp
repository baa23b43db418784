// examples/paper/table2_perpendicular_squares.cpp - the paper's Table 2: rea (eq. 29) of one
// transfer between perpendicular unit squares sharing an edge, shooter radiosity 1, receiver
// reflectance 1, receiver at uniform depth d, against the analytic form factor
// (radiosity/transfer/form_factor.h).
//
// Run:    table2_perpendicular_squares [--order m] [--extrapolation linear|higher] [--eps E |
//                                       --rhombus-radius R] [--csv] ...
// Expect: both rows below the paper's value with the defaults. The kernel is singular on the
//         shared edge: most of the time goes into edgefill's boundary samples near it.
#include "examples/common/paper_tables.h"
#include "examples/common/transfer_cli.h"

namespace {
std::string usage() {
    return std::string(
               "usage: table2_perpendicular_squares [options]\n"
               "  Table 2 of the paper: rea between perpendicular unit squares, beside the paper.\n"
               "  --csv                     header d,rea_percent,paper_rea_percent,seconds\n") +
           mbr::receiver_options_usage;
}
}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage(), [](mbr::Args& args) {
        return mbr::run_paper_table(args, mbr::paper_table2, 2, false);
    });
}
