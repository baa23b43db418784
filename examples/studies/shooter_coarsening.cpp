// examples/studies/shooter_coarsening.cpp - what coarsening the shooter's unshot field costs in
// accuracy and saves in time (section 6, "Adaptive Quadrature": "the radiosity distribution on
// A_h is replaced with a lower resolution version by applying the decomposition relation in
// wavelet analysis to remove higher resolution details").
//
// Two bounces: a small light 0.3 above one corner of the floor A lights A (uniform depth d, so
// B_A is a level-d spline with a sharp peak); then A shoots to the ceiling B at height 1. The
// second transfer is run with A's field coarsened by c = 0, 1, ..., d levels (orthogonal
// projection, math/wavelet.h). The reference is the same transfer with c = 0 and a quadrature
// tolerance 100 times tighter; the table gives the mean and largest relative difference from it on
// the 256 x 256 grid of B, the relative change of the shot power, and the cost: kernel evaluations
// and seconds.
//
// Run:    shooter_coarsening [--depth d] [--order m] [--csv]
// Expect: every level of coarsening removes detail the quadrature would have to resolve, so
//         kernel evaluations fall; the error grows once the levels removed carry the peak.
#include <cmath>
#include <iostream>

#include "examples/common/cli.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"

namespace {

const char* usage =
    "usage: shooter_coarsening [--depth d] [--order m] [--csv]\n"
    "  The cost and the accuracy of coarsening the shooter's unshot field (section 6).\n"
    "  --depth d   depth of the first bounce's receiver, the shooter of the second, 1..7\n"
    "              (default 4)\n"
    "  --order m   B-spline order, 2..8 (default 4)\n"
    "  --csv       header levels_removed,shooter_level,mean_rel_percent,max_rel_percent,\n"
    "              power_change_percent,kernel_evals,seconds\n";

int run(mbr::Args& args) {
    using namespace mbr;
    const int depth = args.integer("--depth", 4, 1, 7);
    const int m = args.integer("--order", 4, 2, 8);
    const bool csv = args.flag("--csv");
    args.finish();

    const Surface light =
        Surface::planar_quad({0.1, 0.1, 0.3}, {0.1, 0.4, 0.3}, {0.4, 0.4, 0.3}, {0.4, 0.1, 0.3});
    const Surface floor = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    // The ceiling at height 1 facing down: no shared edge, so the only roughness the
    // quadrature meets is the detail of the shooter's field.
    const Surface ceiling = Surface::planar_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1});
    auto white = [](double, double) { return Rgb{1, 1, 1}; };

    ReceiverOptions first;
    first.m = m;
    first.min_depth = first.max_depth = depth;
    const SplineField floor_field =
        transfer(make_shooter(light, SplineField::constant(m, 0, {1, 1, 1}), 0),
                 ReceiverSurface{&floor, white}, first);

    ReceiverOptions second;
    second.m = m;
    second.min_depth = second.max_depth = 3;
    auto shoot = [&](int levels, double tolerance, TransferStats* stats) {
        ReceiverOptions o = second;
        o.quadrature.rel_tolerance = tolerance;
        return transfer(make_shooter(floor, floor_field, levels), ReceiverSurface{&ceiling, white},
                        o, stats);
    };
    auto power = [&](const SplineField& f) {
        return f.integrate_weighted([&](double s, double t) { return floor.area_factor(s, t); }, m)
            .r;
    };
    const SplineField reference = shoot(0, second.quadrature.rel_tolerance / 100, nullptr);
    const std::vector<double> ref_grid = field_grid(reference, 256);
    const double power_full = power(floor_field);

    Table table({"levels_removed", "shooter_level", "mean_rel_percent", "max_rel_percent",
                 "power_change_percent", "kernel_evals", "seconds"});
    for (int c = 0; c <= depth; ++c) {
        TransferStats stats;
        const SplineField result = shoot(c, second.quadrature.rel_tolerance, &stats);
        const std::vector<double> grid = field_grid(result, 256);
        double mean = 0, worst = 0;
        for (size_t i = 0; i < grid.size(); ++i) {
            const double rel = std::fabs(grid[i] - ref_grid[i]) / std::fabs(ref_grid[i]);
            mean += rel;
            worst = std::max(worst, rel);
        }
        mean /= grid.size();
        const double power_c = power(floor_field.coarsened_to(depth - c));
        table.add_row({std::to_string(c), std::to_string(depth - c), cell(100 * mean, 4),
                       cell(100 * worst, 4), cell(100 * (power_c - power_full) / power_full, 4),
                       std::to_string(stats.n_kernel_evals), cell(stats.seconds_total, 3)});
    }
    if (csv) {
        table.write_csv(std::cout);
        return 0;
    }
    std::cout << "Coarsening the shooter (section 6): a light lights the floor at depth " << depth
              << ", the floor shoots to the ceiling (depth 3), m = " << m << "\n"
              << "  errors against the uncoarsened shooter with a 100x tighter quadrature\n\n";
    table.write_text(std::cout);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, run);
}
