// examples/tutorial/tutorial_06_fulcrums_and_projection.cpp - tutorial chapter 6
// (docs/tutorial/06-fulcrums-and-projection.md): one transfer, part 3. The samples of chapter 4
// and the ring of chapter 5 become coefficients: the fulcrums are chosen from the leaves
// (Figure 2), each coefficient is the projection (19) onto a dual basis function truncated to a
// rhombus (Figure 3), and coefficients of different scales are unified to the finest by (17).
// On parallel squares at h = 0.1 with an adaptive tree (leaves of two sizes), this program
//   1. selects the fulcrums (select_fulcrums, radiosity/transfer/projection.h) and counts them per
//   level;
//   2. gives the rhombus radius for a ladder of truncations (DualTable::rhombus_radius) and
//      projects one coefficient with each (project), against the widest;
//   3. projects all selected coefficients (project_in_rhombi), unifies the scales
//      (unify_scales) and measures rea (29), beside the unification by projection;
//   4. runs the whole transfer (transfer) for each truncation;
//   5. reproduces the paper's Table 1 (examples/common/paper_tables.h) with our cost.
// Run: tutorial_06_fulcrums_and_projection [-o DIR] [--h H] [--min-depth a] [--max-depth b]
//                                          [--oracle-tolerance T] [--table-rows N]
// Writes DIR/tutorial_06_fulcrums.png and DIR/tutorial_06_truncation.png.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "examples/common/cli.h"
#include "examples/common/paper_tables.h"
#include "examples/common/plot.h"
#include "examples/common/transfer_cli.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_06_fulcrums_and_projection [-o DIR] [options]\n"
    "  Chapter 6 of the tutorial: fulcrums, projection in the rhombus, scale unification,\n"
    "  and the paper's Table 1.\n"
    "  -o DIR                folder for the images (default out; created if missing)\n"
    "  --h H                 distance of the parallel unit squares, (0, 10] (default 0.1)\n"
    "  --min-depth a         adaptive tree bounds, 0..6 (default 1 and 4)\n"
    "  --max-depth b\n"
    "  --oracle-tolerance T  oracle threshold (default 3e-3)\n"
    "  --table-rows N        rows of Table 1 to run, 0..6 (default 6)\n";

const std::vector<double> eps_ladder = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7};

Rgb level_colour(int level) {  // Okabe and Ito's colour-blind safe set (2008)
    static const Rgb palette[] = {{0.55, 0.55, 0.55}, {0.90, 0.80, 0.10}, {0.80, 0.47, 0.65},
                                  {0.00, 0.45, 0.70}, {0.84, 0.37, 0.00}, {0.00, 0.62, 0.45}};
    return palette[level % 6];
}

// A panel of the (s,t) plane: the leaves tinted by level, the domain outlined, the fulcrums as
// discs (coarser levels larger and drawn first, so two scales at one corner show as a ring
// around a dot), and the rhombus |x| + |y| <= r of the chosen fulcrum (r in cells of its scale).
void draw_panel(Image& image, const PixelRect& area, const ReceiverState& state,
                const Fulcrum& chosen, double lo, double hi, double disc) {
    const int m = state.options.m;
    const PlotLayout L = map_layout(area, lo, hi, lo, hi, 2);
    Canvas canvas(image);
    canvas.set_clip(area);
    for (int index : state.forest.leaves()) {
        const DyadicCell c = state.forest.node(index).cell;
        const Rect r = c.rect();
        const Vec2 a = L.to_pixel(r.x0, r.y0), b = L.to_pixel(r.x1, r.y1);
        const Rgb fill = 0.75 * Rgb{1, 1, 1} + 0.25 * level_colour(c.level);
        canvas.fill_rect({int(a.x), int(b.y), int(b.x - a.x) + 1, int(a.y - b.y) + 1}, fill);
        if (b.x - a.x >= 4)
            canvas.polyline({a, {b.x, a.y}, b, {a.x, b.y}, a}, {{0.5, 0.5, 0.5}, 1});
    }
    const Vec2 d0 = L.to_pixel(0, 0), d1 = L.to_pixel(1, 1);
    canvas.polyline({d0, {d1.x, d0.y}, d1, {d0.x, d1.y}, d0}, {{0, 0, 0}, 3});
    int finest = 0;
    for (const Fulcrum& f : state.fulcrums) finest = std::max(finest, f.level);
    for (int level = 0; level <= finest; ++level)
        for (const Fulcrum& f : state.fulcrums) {
            if (f.level != level) continue;
            const Vec2 q = f.position(m), p = L.to_pixel(q.x, q.y);
            canvas.disc(p, disc * (1 + finest - level) + 1, {0.1, 0.1, 0.1});
            canvas.disc(p, disc * (1 + finest - level), level_colour(level));
        }
    const Vec2 q = chosen.position(m), p = L.to_pixel(q.x, q.y);
    const double R = std::ldexp(state.rhombus_radius, -chosen.level);
    canvas.polyline({L.to_pixel(q.x, q.y + R), L.to_pixel(q.x + R, q.y), L.to_pixel(q.x, q.y - R),
                     L.to_pixel(q.x - R, q.y), L.to_pixel(q.x, q.y + R)},
                    {{0.85, 0.05, 0.1}, 3});
    canvas.stroke_rect({int(p.x) - 9, int(p.y) - 9, 19, 19}, {0.85, 0.05, 0.1}, 2);
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", {0, 0, 0}, 2);
}

Image draw_fulcrums(const ReceiverState& state, const Fulcrum& chosen) {
    const int side = 520, margin = axes_margin(2, 4), K = state.forest.extent();
    Image image(2 * (margin + side) + 40, 60 + side + margin, {1, 1, 1});
    draw_panel(image, {margin, 60, side, side}, state, chosen, -0.2, 1.2, 3.5);
    draw_panel(image, {2 * margin + side + 30, 60, side, side}, state, chosen, -K, 1.0 + K, 1.0);
    Canvas canvas(image);
    canvas.text(margin, 10, "Fulcrums (discs, larger = coarser) on leaves tinted by level",
                {0, 0, 0}, 2);
    canvas.text(margin, 32, "red: the chosen fulcrum and its rhombus; right: the whole ring",
                {0, 0, 0}, 2);
    return image;
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const double h = args.number("--h", 0.1);
    ReceiverOptions options;
    options.min_depth = args.integer("--min-depth", 1, 0, 6);
    options.max_depth = args.integer("--max-depth", 4, 0, 6);
    options.oracle_tolerance = args.number("--oracle-tolerance", 3e-3);
    const int table_rows = args.integer("--table-rows", 6, 0, 6);
    args.finish();
    if (!(h > 0 && h <= 10)) throw UsageError("--h must be in (0, 10]");
    if (options.min_depth > options.max_depth)
        throw UsageError("--min-depth must not exceed --max-depth");
    if (!(options.oracle_tolerance > 0)) throw UsageError("--oracle-tolerance must be positive");
    make_output_folder(dir);
    const int m = options.m;
    const TransferSetup setup = parallel_squares(h);
    const SplineField unshot = SplineField::constant(m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    IncrementSampler sampler(shooter, receiver, options.quadrature);
    const DualTable dn(m);
    std::cout << "Chapter 6: fulcrums, projection and Table 1; parallel unit squares at h = " << h
              << ", adaptive tree, depths " << options.min_depth << ".." << options.max_depth
              << ", oracle tolerance " << cell_g(options.oracle_tolerance, 3) << "\n\n";

    // Stages 1-4 as in chapters 4 and 5, then stage 5: the fulcrums (Figure 2). For even m the
    // corners of every domain leaf at the leaf's scale, so a corner shared by leaves of two
    // sizes carries two fulcrums; and the fulcrums of ring leaves whose B-spline reaches inside.
    ReceiverState state(options, rhombus_radius_cells(options, dn));
    subdivide_by_oracle(state, sampler);
    adjust_neighbour_scales(state.forest, Forest::Region::Domain);
    sample_leaves(state, sampler);
    fill_boundary(state, sampler);
    expand_domain(state, sampler);
    state.fulcrums = select_fulcrums(state.forest, m);
    std::map<int, int> leaves, fulcrums, outside;
    std::map<std::pair<double, double>, int> at;  // dyadic positions: exact in double
    for (int index : state.forest.leaves(Forest::Region::Domain))
        ++leaves[state.forest.node(index).cell.level];
    for (const Fulcrum& f : state.fulcrums) {
        const Vec2 q = f.position(m);
        ++fulcrums[f.level];
        if (q.x < 0 || q.x > 1 || q.y < 0 || q.y > 1) ++outside[f.level];
        ++at[{q.x, q.y}];
    }
    int shared = 0;
    for (const auto& [q, n] : at) shared += n > 1;
    std::cout << "1. Fulcrums (stage 5)\n";
    for (const auto& [level, n] : leaves)
        std::cout << "  domain leaves at level " << level << ": " << n << "\n";
    for (const auto& [level, n] : fulcrums)
        std::cout << "  fulcrums at level " << level << ": " << n
                  << " (outside [0,1]^2: " << outside[level] << ")\n";
    std::cout << "  corners carrying fulcrums of two scales: " << shared << "\n\n";

    // Stage 6, one coefficient: eq. (19), c = 4^L int int dB DN(2^L s - k) DN(2^L t - l), over
    // the leaves that meet the rhombus |x| + |y| <= r. The chosen fulcrum: the finest one at the
    // middle of the bottom edge, whose rhombus is half in the ring.
    Fulcrum chosen = state.fulcrums.back();
    for (const Fulcrum& f : state.fulcrums) {
        const Vec2 q = f.position(m), c = chosen.position(m);
        if (f.level == chosen.level && std::hypot(q.x - 0.5, q.y) < std::hypot(c.x - 0.5, c.y))
            chosen = f;
    }
    const Vec2 cq = chosen.position(m);
    const SurfacePoint cp = setup.receiver.evaluate(cq.x, cq.y);
    const double exact_dB =
        point_polygon_form_factor(cp.position, cp.normal, setup.shooter_polygon());
    std::cout << "2. Truncation: rhombus radius r for |DN(x) DN(y)| > eps max|DN|^2 (m = " << m
              << ")\n"
              << "  one coefficient: level " << chosen.level << ", k = " << chosen.k
              << ", l = " << chosen.l << ", fulcrum at (" << cq.x << ", " << cq.y
              << "), exact dB there " << cell_g(exact_dB, 7) << "\n";
    const double r_default = state.rhombus_radius;
    std::vector<double> coefficient;
    for (double eps : eps_ladder) {
        state.rhombus_radius = dn.rhombus_radius(eps);
        coefficient.push_back(project(state, dn, chosen)[0]);
    }
    state.rhombus_radius = r_default;
    for (size_t i = 0; i < eps_ladder.size(); ++i)
        std::cout << "  eps " << cell_g(eps_ladder[i], 1)
                  << ": r = " << cell_g(dn.rhombus_radius(eps_ladder[i]), 4)
                  << " cells, coefficient " << cell_g(coefficient[i], 9)
                  << ", change against eps 1e-7 "
                  << cell_g(std::fabs(coefficient[i] - coefficient.back()), 2) << "\n";

    // Stage 6 for every fulcrum, then stage 8: every coefficient at the finest scale 2^-j, a
    // missing one from (17) on the coarser ones (or projected where the samples are as fine).
    project_in_rhombi(state, dn);
    const ErrorStats paper_rule = compare_with_exact(unify_scales(state, dn), setup);
    ReceiverOptions by_projection = options;
    by_projection.unify_by_projection = true;
    TransferStats stats_p;
    const ErrorStats projection_rule =
        compare_with_exact(transfer(shooter, receiver, by_projection, &stats_p), setup);
    const int n_coef = touching_count(m, state.stats.level);
    std::cout << "\n3. Projection (stage 6) and scale unification (stage 8)\n"
              << "  unified level j: " << state.stats.level << " (" << n_coef << " x " << n_coef
              << " coefficients)\n  coefficients projected: " << state.stats.n_projections
              << "\n  coefficients by (17): " << state.stats.n_refined
              << "\n  rea with unification by (17): " << cell(100 * paper_rule.rea, 4)
              << " %\n  rea with unification by projection: " << cell(100 * projection_rule.rea, 4)
              << " %\n\n";

    // The whole transfer (radiosity/transfer/transfer.h, transfer) for each truncation.
    std::cout << "4. The whole transfer against the truncation\n";
    Plot plot;
    plot.title = "rea against the rhombus radius, h = " + cell_g(h, 3);
    plot.x_label = "rhombus radius r (cells)";
    plot.y_label = "rea (%)";
    plot.log_y = true;
    std::vector<double> xs, ys[2];
    for (double eps : eps_ladder) {
        xs.push_back(dn.rhombus_radius(eps));
        std::cout << "  eps " << cell_g(eps, 1) << ", r = " << cell_g(xs.back(), 4) << ":";
        for (int rule = 0; rule < 2; ++rule) {
            ReceiverOptions o = options;
            o.truncation_eps = eps;
            o.unify_by_projection = rule == 1;
            ys[rule].push_back(100 * compare_with_exact(transfer(shooter, receiver, o), setup).rea);
            std::cout << (rule == 0 ? " rea by (17) " : ", rea by projection ")
                      << cell(ys[rule].back(), 4) << " %";
        }
        std::cout << "\n";
    }
    plot.add({xs, ys[0], {{0.0, 0.45, 0.70}, 2.5}, true, Marker::disc, 5, "unification by (17)"});
    plot.add({xs,
              ys[1],
              {{0.0, 0.62, 0.45}, 2.5},
              true,
              Marker::square,
              5,
              "unification by projection"});
    plot.add_vline(14, {{0.84, 0.37, 0}, 2, 6, 4}, "r = 14, the paper's size");

    // Table 1: uniform depth d, the library's defaults. The paper gives rea only.
    std::cout << "\n5. Table 1: parallel squares, uniform depth d\n";
    for (int r = 0; r < table_rows; ++r) {
        const PaperRow& row = paper_table1[r];
        ReceiverOptions o;
        o.min_depth = o.max_depth = row.d;
        o.quadrature.analytic = false;  // (21) by quadrature, as in the paper: a real cost
        const TransferRun t = run_transfer(parallel_squares(row.h), o);
        std::cout << "  h = " << cell(row.h, 1) << ", d = " << row.d << ": rea "
                  << cell(100 * t.errors.rea, 4) << " % (paper " << cell(row.rea_percent, 3)
                  << " %), samples (21) " << t.stats.n_increments << ", coefficients "
                  << t.n_coefficients << ", kernel evaluations " << t.stats.n_kernel_evals << "\n";
    }

    write_png((std::filesystem::path(dir) / "tutorial_06_fulcrums.png").string(),
              draw_fulcrums(state, chosen));
    Image truncation(860, 520, {1, 1, 1});
    plot.draw(truncation, {0, 0, 860, 520});
    write_png((std::filesystem::path(dir) / "tutorial_06_truncation.png").string(), truncation);
    std::cout << "\nwrote " << dir << "/tutorial_06_fulcrums.png and " << dir
              << "/tutorial_06_truncation.png\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
