// examples/tutorial/tutorial_05_expanded_domain.cpp - tutorial chapter 5
// (docs/tutorial/05-expanded-domain.md): one transfer, part 2. The coefficient of a dual basis
// function is an integral (19) over the function's support, and the dual basis DN_m has no compact
// support: a fulcrum near the edge of [0,1]^2 integrates over points outside the receiver, where dB
// is not defined. The paper continues dB outward: edgefill computes dB and its normal derivative
// (22) along the four edges, the expanded domain (eight patches around [0,1]^2, Figure 5) is
// subdivided and sampled by extrapolation, linear (23)-(25) or higher order (26)-(27). This
// program, on the Table 1 configuration at a uniform depth,
//   1. runs stages 1-3 (radiosity/transfer/transfer.h) and checks the edgefill profile of the
//   bottom edge
//      against the analytic form factor and its derivative;
//   2. builds the expanded domain (expand_domain) and counts its leaves per patch and level;
//   3. finishes the transfer with each continuation: none (zero outside), linear, quadratic (26),
//      cubic (27), and the exact form factor continued, and measures the error (29) near the
//      boundary and inside.
// Run: tutorial_05_expanded_domain [-o DIR] [--h H] [--depth d] [--eps E]
// Writes DIR/tutorial_05_expanded_domain.png and DIR/tutorial_05_extrapolation_profiles.png.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_05_expanded_domain [-o DIR] [options]\n"
    "  Chapter 5 of the tutorial: edgefill (22), the expanded domain and the extrapolation\n"
    "  (23)-(27), and why the transfer needs them.\n"
    "  -o DIR     folder for the images (default out; created if missing)\n"
    "  --h H      distance of the parallel unit squares, (0, 10] (default 0.5)\n"
    "  --depth d  uniform receiver depth, 1..5 (default 3)\n"
    "  --eps E    truncation of the dual basis, (0, 1) (default 1e-7)\n";

// The exact dB (shooter radiosity 1, reflectance 1) at any point of the receiver's plane.
double exact_at(const TransferSetup& setup, double s, double t) {
    const SurfacePoint p = setup.receiver.evaluate(s, t);
    return point_polygon_form_factor(p.position, p.normal, setup.shooter_polygon());
}

// Gives every expanded leaf the values of f at its m x m Gauss-Legendre nodes, in the layout
// expand_domain uses (node a along s, b along t): the lesson's own continuations.
template <class F>
void resample_ring(ReceiverState& state, F&& f) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    for (int index : state.forest.leaves(Forest::Region::Expanded)) {
        const Forest::Node& node = state.forest.node(index);
        const Rect r = node.cell.rect();
        Rgb* out = &state.samples[size_t(node.samples) * m * m];
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                const double v = f(r.x0 + 0.5 * (rule.x[a] + 1) * r.width(),
                                   r.y0 + 0.5 * (rule.x[b] + 1) * r.height());
                out[a * m + b] = {v, v, v};
            }
    }
}

// Eq. (29) split by where the grid point lies: within `band` of an edge, or inside.
struct Errors {
    double rea = 0, rea_band = 0, rea_inside = 0, max_rel = 0;
};
Errors errors(const SplineField& field, const TransferSetup& setup, double band) {
    const int n = 256;
    const std::vector<double> ours = field_grid(field, n), exact = exact_grid(setup, n);
    Errors e;
    int n_band = 0, n_inside = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double s = (i + 0.5) / n, t = (j + 0.5) / n;
            const double rel = std::fabs(ours[j * n + i] / exact[j * n + i] - 1);
            const bool near = std::min({s, t, 1 - s, 1 - t}) < band;
            (near ? e.rea_band : e.rea_inside) += rel;
            ++(near ? n_band : n_inside);
            e.rea += rel;
            e.max_rel = std::max(e.max_rel, rel);
        }
    e.rea /= n * n;
    e.rea_band /= std::max(n_band, 1);
    e.rea_inside /= std::max(n_inside, 1);
    return e;
}

// Panel: the values on a window of the (s,t) plane (exact inside the domain, the state's
// extrapolation outside), the leaves outlined, the domain and the eight patches marked.
void draw_ring(Image& image, const PixelRect& area, const ReceiverState& state,
               const TransferSetup& setup, double lo_w, double hi_w, double v_lo, double v_hi) {
    const int px = area.w;
    std::vector<double> v(size_t(px) * px);
    for (int y = 0; y < px; ++y)
        for (int x = 0; x < px; ++x) {
            const double s = lo_w + (x + 0.5) / px * (hi_w - lo_w);
            const double t = hi_w - (y + 0.5) / px * (hi_w - lo_w);
            const bool inside = s >= 0 && s <= 1 && t >= 0 && t <= 1;
            v[size_t(y) * px + x] = inside ? exact_at(setup, s, t) : extrapolate(state, s, t)[0];
        }
    draw_scalar_field(image, area, v, px, px, v_lo, v_hi, diverging_map);
    const PlotLayout L = map_layout(area, lo_w, hi_w, lo_w, hi_w, 2);
    Canvas canvas(image);
    canvas.set_clip(area);
    for (int index : state.forest.leaves()) {
        const Rect r = state.forest.node(index).cell.rect();
        const Vec2 a = L.to_pixel(r.x0, r.y0), b = L.to_pixel(r.x1, r.y1);
        if (b.x - a.x >= 4)
            canvas.polyline({a, {b.x, a.y}, b, {a.x, b.y}, a}, {{0.4, 0.4, 0.4}, 1});
    }
    const int K = state.forest.extent();
    for (double c : {0.0, 1.0}) {  // the lines s, t = 0, 1 cut the ring into the eight patches
        canvas.line(L.to_pixel(c, -K), L.to_pixel(c, 1 + K), {{0, 0, 0}, 2.5});
        canvas.line(L.to_pixel(-K, c), L.to_pixel(1 + K, c), {{0, 0, 0}, 2.5});
    }
    for (int a = -1; a <= 1; ++a)  // patch numbers of Figure 5 (DyadicCell::patch)
        for (int b = -1; b <= 1; ++b) {
            if (a == 0 && b == 0) continue;
            const double s = a < 0 ? 0.5 * lo_w : (a > 0 ? 0.5 * (1 + hi_w) : 0.5);
            const double t = b < 0 ? 0.5 * lo_w : (b > 0 ? 0.5 * (1 + hi_w) : 0.5);
            const Vec2 p = L.to_pixel(s, t);
            canvas.fill_rect({int(p.x) - 12, int(p.y) - 12, 24, 24}, {1, 1, 1});
            canvas.text(int(p.x), int(p.y), std::to_string(DyadicCell{0, a, b}.patch()), {0, 0, 0},
                        2, Align::centre, Align::centre);
        }
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", {0, 0, 0}, 2);
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    const double h = args.number("--h", 0.5);
    ReceiverOptions options;
    options.min_depth = options.max_depth = args.integer("--depth", 3, 1, 5);
    options.truncation_eps = args.number("--eps", 1e-7);
    args.finish();
    if (!(h > 0 && h <= 10)) throw UsageError("--h must be in (0, 10]");
    if (!(options.truncation_eps > 0 && options.truncation_eps < 1))
        throw UsageError("--eps must be in (0, 1)");
    make_output_folder(dir);
    const int m = options.m, d = options.max_depth;
    const TransferSetup setup = parallel_squares(h);
    const SplineField unshot = SplineField::constant(m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    IncrementSampler sampler(shooter, receiver, options.quadrature);
    const DualTable dn(m);
    std::cout << "Chapter 5: edgefill and the expanded domain, parallel unit squares at h = " << h
              << ", uniform depth " << d << ", m = " << m << "\n\n";

    // Stages 1-3: the tree (uniform here), its samples (21), and edgefill along the four edges.
    ReceiverState base(options, rhombus_radius_cells(options, dn));
    subdivide_by_oracle(base, sampler);
    adjust_neighbour_scales(base.forest, Forest::Region::Domain);
    sample_leaves(base, sampler);
    fill_boundary(base, sampler);
    const char* edge_name[4] = {"bottom", "right", "top", "left"};
    std::cout << "1. Edgefill (22): nodes per edge";
    for (int e = 0; e < 4; ++e)
        std::cout << (e ? ", " : ": ") << edge_name[e] << " " << base.edges[e].sigma.size();
    std::cout << "\n";
    // The bottom edge's profile against the analytic dB(s, 0) and d/dt dB(s, 0) (one-sided,
    // second order, step 1e-5: the derivative from inside, as (22) takes it).
    double value_error = 0, slope_error = 0, slope_max = 0;
    for (int q = 0; q <= 200; ++q) {
        const double s = q / 200.0, dt = 1e-5;
        Rgb v, dv;
        base.edges[0].at(s, v, dv);
        const double f0 = exact_at(setup, s, 0), f1 = exact_at(setup, s, dt),
                     f2 = exact_at(setup, s, 2 * dt);
        const double slope = (-3 * f0 + 4 * f1 - f2) / (2 * dt);
        value_error = std::max(value_error, std::fabs(v[0] - f0));
        slope_error = std::max(slope_error, std::fabs(dv[0] - slope));
        slope_max = std::max(slope_max, std::fabs(slope));
    }
    std::cout << "  bottom edge, 201 points: largest |dB| error "
              << cell_g(value_error / base.max_sample, 3) << " of max dB, largest |dB_t| error "
              << cell_g(slope_error / slope_max, 3) << " of max |dB_t| (" << cell_g(slope_max, 4)
              << ")\n";
    Rgb v0, slope0;
    base.edges[0].at(0.5, v0, slope0);
    std::cout << "  at (0.5, 0): dB = " << cell_g(v0[0], 7) << ", dB_t = " << cell_g(slope0[0], 7)
              << "\n\n";

    // Stage 4 and the rest of the transfer, once per continuation. Stages 1-3 do not depend on
    // it, so each variant starts from a copy of `base`.
    struct Variant {
        std::string name;
        Extrapolation kind;
        int replace;  // 0: the library's extrapolation; 1: zero outside; 2: exact continuation
    };
    const std::vector<Variant> variants = {{"none (zero outside)", Extrapolation::Linear, 1},
                                           {"linear (23)-(25)", Extrapolation::Linear, 0},
                                           {"quadratic (26)", Extrapolation::Quadratic, 0},
                                           {"cubic (27)", Extrapolation::Cubic, 0},
                                           {"exact continuation", Extrapolation::Linear, 2}};
    std::vector<ReceiverState> states;
    std::vector<Errors> results;
    const double band = std::ldexp(1.0, -d);  // one leaf from the edge
    for (const Variant& v : variants) {
        ReceiverState state = base;
        state.options.extrapolation = v.kind;
        expand_domain(state, sampler);  // stage 4: the ring, sampled by (23)-(27)
        if (v.replace == 1) resample_ring(state, [](double, double) { return 0.0; });
        if (v.replace == 2)
            resample_ring(state, [&](double s, double t) { return exact_at(setup, s, t); });
        state.fulcrums = select_fulcrums(state.forest, m);  // stages 5, 6 and 8 (chapter 6)
        project_in_rhombi(state, dn);
        results.push_back(errors(unify_scales(state, dn), setup, band));
        states.push_back(std::move(state));
    }
    const ReceiverState& linear = states[1];
    const int K = linear.forest.extent();
    std::map<int, int> per_patch, per_level;
    for (int index : linear.forest.leaves(Forest::Region::Expanded)) {
        ++per_patch[linear.forest.node(index).cell.patch()];
        ++per_level[linear.forest.node(index).cell.level];
    }
    std::cout << "2. The expanded domain (linear): ring width " << K << " units, rhombus radius "
              << cell_g(linear.rhombus_radius, 4)
              << " cells = " << cell_g(linear.rhombus_radius * band, 4)
              << " units\n  expanded leaves: " << linear.stats.n_expanded_leaves << "\n";
    for (const auto& [patch, n] : per_patch)
        std::cout << "  leaves in patch " << patch << ": " << n << "\n";
    for (const auto& [level, n] : per_level)
        std::cout << "  leaves at level " << level << ": " << n << "\n";
    std::cout
        << "\n3. The transfer with each continuation: rea (29) in %, over the whole grid, the\n"
        << "   edge band (points within " << cell_g(band, 3) << " of an edge) and inside it\n";
    for (size_t k = 0; k < variants.size(); ++k)
        std::cout << "  " << variants[k].name << ": rea " << cell(100 * results[k].rea, 4)
                  << ", edge band " << cell(100 * results[k].rea_band, 4) << ", inside "
                  << cell(100 * results[k].rea_inside, 4) << ", max "
                  << cell(100 * results[k].max_rel, 3) << "\n";

    // Pictures: the ring near the domain and the whole ring, then profiles along t = 1/2.
    const double v_hi = linear.max_sample, v_lo = -v_hi;  // diverging: negative values blue
    const int side = 480, margin = axes_margin(2, 4);
    Image ring(2 * (margin + side) + 40, side + margin + 150, {1, 1, 1});
    draw_ring(ring, {margin, 50, side, side}, linear, setup, -0.75, 1.75, v_lo, v_hi);
    draw_ring(ring, {2 * margin + side + 20, 50, side, side}, linear, setup, -K, 1 + K, v_lo, v_hi);
    Canvas(ring).text(margin, 14,
                      "Linear extrapolation (23)-(25) on the expanded domain: near the "
                      "domain, and the whole ring",
                      {0, 0, 0}, 2);
    draw_colour_scale(ring, {margin + side / 2, side + margin + 90, side, 20}, v_lo, v_hi,
                      "dB (exact inside, extrapolated outside)", diverging_map, 2);
    write_png((std::filesystem::path(dir) / "tutorial_05_expanded_domain.png").string(), ring);

    Plot plot;
    plot.title = "dB along t = 1/2: the receiver continued";
    plot.x_label = "s";
    plot.y_label = "dB";
    plot.legend = LegendPlace::top_left;
    const Rgb colours[5] = {
        {0.5, 0.5, 0.5}, {0.0, 0.45, 0.70}, {0.84, 0.37, 0.0}, {0.0, 0.62, 0.45}, {0, 0, 0}};
    for (size_t k = 0; k < states.size(); ++k) {
        std::vector<double> xs, ys;
        for (int q = 0; q <= 400; ++q) {
            const double s = -1.5 + 4.0 * q / 400;
            const bool inside = s >= 0 && s <= 1;
            xs.push_back(s);
            ys.push_back(inside || variants[k].replace == 2 ? exact_at(setup, s, 0.5)
                         : variants[k].replace == 1         ? 0.0
                                                            : extrapolate(states[k], s, 0.5)[0]);
        }
        plot.add_line(xs, ys, {colours[k], 2.5, variants[k].replace == 2 ? 8.0 : 0.0, 6},
                      variants[k].name);
    }
    plot.add_vline(0, {{0.3, 0.3, 0.3}, 1, 4, 4});
    plot.add_vline(1, {{0.3, 0.3, 0.3}, 1, 4, 4});
    Image profiles(900, 560, {1, 1, 1});
    plot.draw(profiles, {0, 0, 900, 560});
    write_png((std::filesystem::path(dir) / "tutorial_05_extrapolation_profiles.png").string(),
              profiles);
    std::cout << "\nwrote " << dir << "/tutorial_05_expanded_domain.png and " << dir
              << "/tutorial_05_extrapolation_profiles.png\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
