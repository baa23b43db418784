// examples/common/paper_tables.cpp - the shared bodies of the paper's tables: Tables 1 and 2
// (table1_parallel_squares, table2_perpendicular_squares) and Table 3
// (table3_dual_coefficients), also printed by `mbr tables`.
#include "examples/common/paper_tables.h"

#include <cmath>
#include <iostream>

#include "examples/common/transfer_cli.h"
#include "math/dual_basis.h"

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

const double paper_table3[19] = {2.842171,  -1.321729, 0.573326,  -0.247042, 0.106378,
                                 -0.045804, 0.019722,  -0.008492, 0.003656,  -0.001574,
                                 0.000678,  -0.000292, 0.000126,  -0.000054, 0.000023,
                                 -0.000010, 0.000004,  -0.000002, 0.000001};

namespace {
constexpr int n_l = 19;
}  // namespace

int run_table3(Args& args) {
    const bool csv = args.flag("--csv");
    const double eps = args.number("--eps", 1e-12);
    args.finish();
    if (!(eps > 0)) throw UsageError("--eps must be positive");

    Table table({"m", "l", "mu", "paper_mu"});
    int n_match = 0;
    for (int m : {3, 2, 4}) {
        const DualCoefficients dc = dual_coefficients(m, n_l - 1, eps);
        for (int l = 0; l < n_l; ++l) {
            const double paper = m == 3 ? paper_table3[l] : NAN;
            if (m == 3 && std::fabs(dc.mu[l] - paper) < 0.5e-6) ++n_match;
            table.add_row({std::to_string(m), std::to_string(l), cell(dc.mu[l], csv ? 12 : 6),
                           std::isnan(paper) ? "" : cell(paper, 6)});
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


}  // namespace mbr
