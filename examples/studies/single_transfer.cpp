// examples/studies/single_transfer.cpp - the measurement behind Tables 1 and 2 for any two planar
// quads: one transfer from a shooter of radiosity 1 to a receiver of reflectance 1, compared on the
// 256 x 256 grid of cell centres of the receiver's own (u,v) domain with the analytic
// point-to-polygon form factor; rea of eq. (29), the largest relative error, and the cost.
//
// Run:    single_transfer --shooter x0 y0 z0 ... x3 y3 z3 --receiver x0 ... z3
//                         (--depth d | --adaptive [--oracle-tolerance T] [--min-depth a]
//                         [--max-depth b]) [--order m] [--csv] ...
//         Corners are given in (u,v) = (0,0), (1,0), (1,1), (0,1) order; each quad's front is
//         the side (p10 - p00) x (p01 - p00) points to, and the two fronts must face each other
//         at least in part: some corner of each lies in front of the other's plane.
// Expect: without --shooter/--receiver, the parallel unit squares at distance 1 of Table 1.
#include <array>
#include <iostream>

#include "examples/common/transfer_cli.h"
#include "radiosity/scene/scene_io.h"

namespace {

std::string usage() {
    return std::string(
               "usage: single_transfer [--shooter 12 numbers] [--receiver 12 numbers]\n"
               "                       (--depth d | --adaptive) [options]\n"
               "  One transfer between two planar quads, measured against the analytic form\n"
               "  factor on the receiver's 256 x 256 grid of cell centres.\n"
               "  --shooter x0 y0 z0 x1 y1 z1 x2 y2 z2 x3 y3 z3   corners at (u,v) = (0,0) (1,0)\n"
               "                            (1,1) (0,1) (default: the unit square at z = 1,\n"
               "                            facing down)\n"
               "  --receiver ...            the same (default: the unit square at z = 0,\n"
               "                            facing up)\n"
               "  --depth d                 uniform receiver depth, 0..12 (default 3)\n"
               "  --adaptive                oracle subdivision instead (section 6)\n"
               "  --oracle-tolerance T      oracle threshold (default 1e-3)\n"
               "  --min-depth a --max-depth b   bounds of the adaptive tree, 0..12 (default 1, 6)\n"
               "  --grid N                  error grid, 2..4096 (default 256)\n"
               "  --csv                     header rea_percent,max_rel_percent,leaves,\n"
               "                            coefficients,kernel_evals,seconds\n") +
           mbr::receiver_options_usage + mbr::memory_budget_usage;
}

mbr::Surface read_quad(mbr::Args& args, const std::string& name, const mbr::Surface& fallback) {
    const std::vector<double> v = args.numbers(name, 12);
    if (v.empty()) return fallback;
    std::array<mbr::Vec3, 4> c;
    for (int i = 0; i < 4; ++i) c[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    const std::string problem = mbr::planar_quad_problem(c);
    if (!problem.empty()) throw mbr::UsageError(name + ": " + problem);
    return mbr::Surface::planar_quad(c[0], c[1], c[2], c[3]);
}

int run(mbr::Args& args) {
    using namespace mbr;
    const TransferSetup defaults = parallel_squares(1.0);
    TransferSetup setup{read_quad(args, "--shooter", defaults.shooter),
                        read_quad(args, "--receiver", defaults.receiver)};
    const bool adaptive = args.has("--adaptive");
    const ReceiverOptions options = read_tree_options(args, read_receiver_options(args));
    const int grid = args.integer("--grid", 256, 2, 4096);
    const bool csv = args.flag("--csv");
    args.finish();
    // The two fronts must face each other somewhere (tested at the corners: a receiver that
    // straddles the shooter's plane gets energy on its part in front), or nothing is transferred.
    if (!fronts_face_each_other(setup.shooter, setup.receiver))
        throw UsageError(
            "the shooter and the receiver do not face each other (no corner of one "
            "lies in front of the other)");

    const TransferRun run = run_transfer(setup, options, grid);
    if (run.errors.n_points == 0) throw UsageError("the receiver gets no energy from the shooter");
    Table table(
        {"rea_percent", "max_rel_percent", "leaves", "coefficients", "kernel_evals", "seconds"});
    table.add_row({cell(100 * run.errors.rea, 4), cell(100 * run.errors.max_rel, 4),
                   std::to_string(run.stats.n_leaves), std::to_string(run.n_coefficients),
                   std::to_string(run.stats.n_kernel_evals), cell(run.stats.seconds_total, 3)});
    if (csv) {
        table.write_csv(std::cout);
        return 0;
    }
    const TransferStats& s = run.stats;
    std::cout << "single transfer, " << describe(options) << "\n"
              << (adaptive ? "  adaptive receiver tree, oracle tolerance " +
                                 cell_g(options.oracle_tolerance, 3) + ", depths " +
                                 std::to_string(options.min_depth) + ".." +
                                 std::to_string(options.max_depth)
                           : "  uniform receiver depth " + std::to_string(options.max_depth))
              << "\n\n";
    table.write_text(std::cout);
    std::cout << "\n  unified level j = " << s.level << " (" << run.n_coefficients
              << " coefficients per channel); " << s.n_fulcrums << " fulcrums selected, "
              << s.n_projections << " projections, " << s.n_refined << " by (17)\n"
              << "  " << s.n_increments << " sample values (21): " << s.n_oracle_increments
              << " for the oracle, " << s.n_boundary_increments << " for edgefill ("
              << s.n_boundary_nodes << " nodes); " << s.n_expanded_leaves << " expanded leaves; "
              << "rhombus radius " << cell(s.rhombus_radius, 2) << " cells\n"
              << "  seconds: samples " << cell(s.seconds_sampling, 3) << ", boundary "
              << cell(s.seconds_boundary, 3) << ", expanded domain " << cell(s.seconds_expanded, 3)
              << ", projection and unification " << cell(s.seconds_projection, 3) << "\n"
              << "  grid mean of the exact values " << cell(run.errors.mean_exact, 6) << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage(), run);
}
