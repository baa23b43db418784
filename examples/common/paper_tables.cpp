// examples/common/paper_tables.cpp - the shared body of table1_parallel_squares and
// table2_perpendicular_squares.
#include "examples/common/paper_tables.h"

#include <cmath>
#include <iostream>

#include "examples/common/transfer_cli.h"

namespace mbr {

const PaperRow paper_table1[6] = {{1.0, 2, 0.880}, {1.0, 3, 0.126}, {0.5, 2, 2.020},
                                  {0.5, 3, 0.402}, {0.1, 3, 1.700}, {0.1, 4, 0.534}};
const PaperRow paper_table2[2] = {{NAN, 2, 4.670}, {NAN, 3, 0.676}};

namespace {
/// Area form factors of the configurations (DESIGN.md section 6; Hottel's crossed strings for
/// parallel squares, the classical perpendicular plates result).
double area_form_factor(double h) {
    if (std::isnan(h)) return 0.200044;
    if (h == 1.0) return 0.199825;
    if (h == 0.5) return 0.415253;
    if (h == 0.1) return 0.826995;
    return NAN;
}
}  // namespace

int run_paper_table(Args& args, const PaperRow* rows, int n_rows, bool parallel) {
    const bool csv = args.flag("--csv");
    ReceiverOptions options = read_receiver_options(args);
    args.finish();

    Table table(parallel ? std::vector<std::string>{"h", "d", "rea_percent", "paper_rea_percent", "seconds"}
                         : std::vector<std::string>{"d", "rea_percent", "paper_rea_percent", "seconds"});
    Table means({"configuration", "grid mean of exact", "area form factor"});
    double total_seconds = 0, log_ratio = 0;
    int n_below = 0;
    for (int r = 0; r < n_rows; ++r) {
        const PaperRow& row = rows[r];
        options.min_depth = options.max_depth = row.d;
        const TransferSetup setup = parallel ? parallel_squares(row.h) : perpendicular_squares();
        const TransferRun run = run_transfer(setup, options);
        const double rea = 100 * run.errors.rea;
        total_seconds += run.stats.seconds_total;
        log_ratio += std::log(rea / row.rea_percent);
        if (rea <= row.rea_percent) ++n_below;
        std::vector<std::string> cells;
        if (parallel) cells.push_back(cell(row.h, 1));
        cells.insert(cells.end(), {std::to_string(row.d), cell(rea, 4), cell(row.rea_percent, 3),
                                   cell(run.stats.seconds_total, 3)});
        table.add_row(cells);
        if (r == 0 || (parallel && row.h != rows[r - 1].h))
            means.add_row({parallel ? "h = " + cell(row.h, 1) : "perpendicular",
                           cell(run.errors.mean_exact, 6), cell(area_form_factor(row.h), 6)});
    }
    if (csv) {
        table.write_csv(std::cout);
        return 0;
    }
    std::cout << (parallel ? "Table 1: relative error between parallel squares"
                           : "Table 2: relative error between perpendicular squares")
              << "\n  " << describe(options) << "\n  rea of eq. (29) on the 256 x 256 grid of cell centres; "
              << "seconds: the transfer alone\n\n";
    table.write_text(std::cout);
    std::cout << "\n";
    means.write_text(std::cout);
    std::cout << "\n" << n_below << " of " << n_rows << " rows at or below the paper's rea; "
              << "geometric mean of ours / paper = " << cell(std::exp(log_ratio / n_rows), 3)
              << "; " << cell(total_seconds, 3) << " s in all\n";
    return 0;
}

}  // namespace mbr
