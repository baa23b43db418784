// examples/common/paper_tables.h - Tables 1 and 2 of the paper (section 7): the rows, the
// printed rea values, and the program body both table examples share; Table 3 (the appendix).
#pragma once

#include "examples/common/cli.h"

namespace mbr {

struct PaperRow {
    double h;            // distance of the parallel squares; NaN for the perpendicular ones
    int d;               // receiver depth: leaves 2^-d wide
    double rea_percent;  // the paper's value
};

/// Table 1: relative error between parallel squares.
extern const PaperRow paper_table1[6];
/// Table 2: relative error between perpendicular squares.
extern const PaperRow paper_table2[2];

/// Runs the rows, prints them beside the paper (or as CSV), the grid mean of the exact values
/// beside the area form factor, and a summary. Returns the process exit code.
int run_paper_table(Args& args, const PaperRow* rows, int n_rows, bool parallel);

/// Table 3 as printed: mu_{3;0,l} for l = 0..18, six decimals.
extern const double paper_table3[19];

/// Table 3: mu_{m;0,l} (l = 0..18) for m = 3 beside the paper's values, and m = 2, 4 (--csv,
/// --eps). Returns 0 when all 19 values match the paper's six decimals, else 1.
int run_table3(Args& args);

}  // namespace mbr
