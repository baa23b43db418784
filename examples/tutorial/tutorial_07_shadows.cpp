// examples/tutorial/tutorial_07_shadows.cpp - tutorial chapter 7 (docs/tutorial/07-shadows.md): the
// paper's shadows in one energy transfer (section 5 "Adaptive Subdivision in Shadow
// Computation", section 6 "Shadow" and "Octree", eq. (28)).
//
// Chapters 4-6 computed one transfer as if nothing stood between the two surfaces. Here an
// opaque square hangs between a shooter and a receiver, and we follow the paper's answer:
//   1. an octree over the three polygons finds what can block the pair (octree/octree.h);
//   2. at every fulcrum, rays to the patches of the shooter's quadrature partition give the
//      visible fraction (28), sum r_i e_i / sum e_i (fraction_at, radiosity/transfer/shadows.h);
//   3. leaves between fulcrums whose fractions differ are split ("shadow subdivision"), down
//      to a maximum shadow depth, and every coefficient is multiplied by its fraction
//      (apply_shadows, radiosity/transfer/shadows.cpp).
// The exact shadowed value at a receiving point is known in closed form (the form factor of the
// shooter minus that of the occluder's projection onto it, radiosity/reference/configurations.h),
// so we can measure the error of (28) and watch it, and the ray count, as the shadow depth grows.
//
// Run:  tutorial_07_shadows [-o DIR] [--depths a b] [--tilt DEG] [--shooter-side S]
//                           [--rays R] [--threshold T] [--grid n]
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "octree/octree.h"
#include "radiosity/output/image.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/visibility/visible_parts.h"

namespace mbr {
namespace {

const char* usage =
    "usage: tutorial_07_shadows [-o DIR] [options]\n"
    "  Tutorial chapter 7: the paper's shadow fractions (28) and shadow subdivision in one\n"
    "  transfer (unit squares at h = 1, an opaque square of side 0.4 half-way), against the\n"
    "  exact shadowed form factor.\n"
    "  -o DIR              folder for the images (default out; created if missing)\n"
    "  --depths a b        shadow depths a..b, 1..8 (default 2 6); also the receiver's depth\n"
    "  --tilt DEG          the occluder turned about the x axis, -60..60 (default 0)\n"
    "  --shooter-side S    the shooter's side, (0, 1] (default 1; 0.3 gives an umbra)\n"
    "  --rays R            rays per shooter patch in (28), 1..256 (default 4)\n"
    "  --threshold T       fraction difference that splits leaves, (0, 1] (default 0.05)\n"
    "  --grid n            error grid n x n, 16..256 (default 256, as eq. (29))\n";

/// rea (29) over the points where the exact value is at least 1 % of its largest (the umbra,
/// where it is 0, has no relative error), and the L1 error relative to the exact mean.
struct Errors {
    double rea = 0, l1 = 0;
};
Errors errors(const std::vector<double>& approx, const std::vector<double>& exact) {
    const double largest = *std::max_element(exact.begin(), exact.end());
    double sum_rel = 0, sum_abs = 0, sum_exact = 0;
    int n_rel = 0;
    for (size_t i = 0; i < exact.size(); ++i) {
        const double e = std::fabs(approx[i] - exact[i]);
        sum_abs += e;
        sum_exact += exact[i];
        if (exact[i] >= 0.01 * largest) {
            sum_rel += e / exact[i];
            ++n_rel;
        }
    }
    return {n_rel ? sum_rel / n_rel : 0, sum_exact > 0 ? sum_abs / sum_exact : 0};
}

/// Three panels, exact | mbr | |mbr - exact|, each an n x n grid (s right, t up).
Image error_panels(const std::vector<double>& exact, const std::vector<double>& mbr, int n,
                   const std::string& caption) {
    const int side = 256, scale = 2, margin = axes_margin(scale, 3), pad = 20;
    const int title = 2 * glyph_line_height * scale, bar = 14;
    const int panel_w = margin + side + pad;
    Image image(3 * panel_w + pad, title + pad + side + margin + 4 * glyph_line_height * scale,
                {1, 1, 1});
    Canvas canvas(image);
    canvas.text(pad, pad / 2, caption, {0, 0, 0}, scale);
    std::vector<double> err(exact.size());
    double hi = 0, err_max = 0;
    for (size_t i = 0; i < exact.size(); ++i) {
        err[i] = std::fabs(mbr[i] - exact[i]);
        hi = std::max({hi, exact[i], mbr[i]});
        err_max = std::max(err_max, err[i]);
    }
    const std::vector<double>* grids[3] = {&exact, &mbr, &err};
    const char* titles[3] = {"exact", "mbr (28)", "|mbr - exact|"};
    for (int k = 0; k < 3; ++k) {
        // Grid rows run upwards in t, image rows downwards: flip.
        std::vector<double> rows(grids[k]->size());
        for (int j = 0; j < n; ++j)
            std::copy_n(grids[k]->begin() + size_t(j) * n, n, rows.begin() + size_t(n - 1 - j) * n);
        const PixelRect r{k * panel_w + pad + margin, title + pad, side, side};
        const double top = k < 2 ? hi : std::max(err_max, 1e-300);
        draw_scalar_field(image, r, rows, n, n, 0, top);
        draw_axes(image, map_layout(r, 0, 1, 0, 1, scale), "s", "t", {0, 0, 0}, scale);
        canvas.text(r.x + r.w / 2, r.y - 8, titles[k], {0, 0, 0}, scale, Align::centre, Align::end);
        draw_colour_scale(image, {r.x, r.bottom() + margin, r.w, bar}, 0, top, "");
    }
    return image;
}

/// A line through (x[i], y[i]) with a disc at each point.
Series markers(std::vector<double> x, std::vector<double> y, Rgb colour) {
    Series series;
    series.x = std::move(x);
    series.y = std::move(y);
    series.stroke.colour = colour;
    series.marker = Marker::disc;
    return series;
}

/// Two log plots side by side: rea against the shadow depth, rays against the shadow depth.
Image depth_plots(const std::vector<double>& depth, const std::vector<double>& rea_percent,
                  const std::vector<double>& rays) {
    Image image(960, 400, {1, 1, 1});
    Plot left;
    left.title = "rea (29), %";
    left.x_label = "shadow depth";
    left.y_label = "rea %";
    left.log_y = true;
    left.legend = LegendPlace::none;
    Plot right = left;
    right.title = "shadow rays";
    right.y_label = "rays";
    left.add(markers(depth, rea_percent, {0.8, 0.2, 0.1}));
    right.add(markers(depth, rays, {0.1, 0.3, 0.8}));
    left.draw(image, {0, 0, 480, 400});
    right.draw(image, {480, 0, 480, 400});
    return image;
}

int run(Args& args) {
    const std::string dir = args.text("-o", "out");
    std::vector<double> depths = args.numbers("--depths", 2);
    if (depths.empty()) depths = {2, 6};
    const double tilt = args.number("--tilt", 0);
    const double shooter_side = args.number("--shooter-side", 1);
    ReceiverOptions options;  // the single-transfer defaults of chapters 4-6
    options.shadows.method = ShadowMethod::Fractions;
    options.shadows.rays_per_patch = args.integer("--rays", options.shadows.rays_per_patch, 1, 256);
    options.shadows.threshold = args.number("--threshold", options.shadows.threshold);
    const int n = args.integer("--grid", 256, 16, 256);
    args.finish();
    const int d_first = int(depths[0]), d_last = int(depths[1]);
    if (d_first != depths[0] || d_last != depths[1] || d_first < 1 || d_last > 8 ||
        d_first > d_last)
        throw UsageError("--depths expects two integers 1 <= a <= b <= 8");
    if (!(std::fabs(tilt) <= 60)) throw UsageError("--tilt must be in -60..60");
    if (!(shooter_side > 0 && shooter_side <= 1))
        throw UsageError("--shooter-side must be in (0, 1]");
    if (!(options.shadows.threshold > 0 && options.shadows.threshold <= 1))
        throw UsageError("--threshold must be in (0, 1]");
    make_output_folder(dir);

    // The configuration: receiver [0,1]^2 in z = 0, shooter (radiosity 1) in z = 1 facing down,
    // the occluder centred at (0.5, 0.5, 0.5) (radiosity/reference/configurations.h).
    const ShadowSetup setup = occluded_squares(tilt, shooter_side);
    const Vec3* c = setup.shooter.corners();
    const std::vector<Vec3> shooter_polygon{c[0], c[1], c[2], c[3]};
    const std::vector<Vec3>& occluder = setup.occluders[0];

    // Step 1, the octree (section 6 "Octree"): one polygon per surface, tagged with an id.
    // make_occlusion_context keeps the polygons that meet the convex hull of the pair: the
    // only ones a ray from the receiver to the shooter can hit.
    std::vector<Polygon> polygons;
    polygons.emplace_back(shooter_polygon, std::vector<Vec2>(4), 0);
    const Vec3* r = setup.receiver.corners();
    polygons.emplace_back(std::vector<Vec3>{r[0], r[1], r[2], r[3]}, std::vector<Vec2>(4), 1);
    polygons.emplace_back(occluder, std::vector<Vec2>(occluder.size()), 2);
    const Octree octree(std::move(polygons));
    const OcclusionContext occlusion =
        make_occlusion_context(octree, setup.shooter, 0, setup.receiver, 1, /*shot=*/0);
    std::cout << "tutorial_07_shadows: occluder tilted " << tilt << " degrees, shooter side "
              << shooter_side << ", " << options.shadows.rays_per_patch
              << " rays per patch, threshold " << options.shadows.threshold << "\n"
              << "occluder candidates of the pair: " << occlusion.candidates.size() << "\n";

    // The exact shadowed values on the n x n grid of cell centres (machine precision).
    const std::vector<double> exact = exact_shadowed_grid(setup, n);

    // A constant shooter of radiosity 1 and a receiver of reflectance 1, as in Tables 1-2.
    const Shooter shooter = make_shooter(
        setup.shooter, SplineField::constant(options.m, 0, {1, 1, 1}), options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};

    // Steps 2 and 3 at each shadow depth: transfer() runs stages 1-6 without shadows, then
    // apply_shadows (stage 7) computes (28) at the fulcrums, splits and masks.
    Table table({"depth", "leaves_before", "leaves_after", "fractions", "shadow_splits", "rays",
                 "rea_%", "L1_%"});
    std::vector<double> x_depth, y_rea, y_rays, last_grid;
    ReceiverState last_state;
    Errors last{};
    for (int depth = d_first; depth <= d_last; ++depth) {
        ReceiverOptions o = options;
        o.max_depth = depth;  // the receiver's oracle tree is bounded by it too
        o.min_depth = std::min(o.min_depth, depth);
        o.shadows.max_depth = depth;
        TransferStats stats;
        ReceiverState state;
        const SplineField field =
            transfer(shooter, receiver, o, &stats, &state, &occlusion, /*dual=*/nullptr);
        const std::vector<double> grid = field_grid(field, n);
        const Errors e = errors(grid, exact);
        // Leaves of the domain before stage 7 (the oracle's tree) and after shadow subdivision.
        const size_t leaves_after = state.forest.leaves(Forest::Region::Domain).size();
        table.add_row({std::to_string(depth), std::to_string(stats.n_leaves),
                       std::to_string(leaves_after), std::to_string(stats.n_fractions),
                       std::to_string(stats.n_shadow_splits), std::to_string(stats.n_rays),
                       cell(100 * e.rea, 3), cell(100 * e.l1, 3)});
        std::cout << "shadow depth " << depth << ": rea = " << cell(100 * e.rea, 4)
                  << " %, rays = " << stats.n_rays << "\n";
        x_depth.push_back(depth);
        y_rea.push_back(100 * e.rea);
        y_rays.push_back(double(stats.n_rays));
        last_grid = grid;
        last_state = std::move(state);
        last = e;
    }
    std::cout << "\n";
    table.write_text(std::cout);

    // Eq. (28) at single points along t = 0.5, through the penumbra, beside the exact visible
    // fraction F(p -> shooter past the occluder) / F(p -> shooter). fraction_at is what stage 7
    // calls at each fulcrum; it reuses the last transfer's state (its largest sample sets the
    // partition depth) and memoises its answers there.
    IncrementSampler sampler(shooter, receiver, last_state.options.quadrature);
    std::cout << "\nfractions (28) at depth " << d_last << " along t = 0.5 (rays "
              << options.shadows.rays_per_patch << " per patch):\n";
    Table fractions({"s", "fraction_28", "exact_fraction", "difference"});
    double worst = 0, centre_28 = 0, centre_exact = 0;
    for (double s : {0.0, 0.1, 0.2, 0.3, 0.4, 0.5}) {
        const double f28 = fraction_at(last_state, sampler, s, 0.5, /*thread=*/0).r;
        const Vec3 p{s, 0.5, 0}, up{0, 0, 1};
        const double visible = shadowed_form_factor(p, up, shooter_polygon, occluder) /
                               point_polygon_form_factor(p, up, shooter_polygon);
        worst = std::max(worst, std::fabs(f28 - visible));
        if (s == 0.5) {
            centre_28 = f28;
            centre_exact = visible;
        }
        fractions.add_row({cell(s, 1), cell(f28, 4), cell(visible, 4), cell(f28 - visible, 4)});
    }
    fractions.write_text(std::cout);
    std::cout << "fraction (28) at the centre: " << cell(centre_28, 4) << "\n"
              << "exact fraction at the centre: " << cell(centre_exact, 4) << "\n";
    std::cout << "largest fraction error along the line: " << cell(worst, 4) << "\n";

    // For contrast, visibility inside (21) itself (ShadowMethod::Exact, beyond the paper): the
    // occluder is projected onto the shooter and the quadrature integrates the visible part.
    ReceiverOptions o = options;
    o.max_depth = d_last;
    o.min_depth = std::min(o.min_depth, d_last);
    o.shadows.method = ShadowMethod::Exact;
    TransferStats exact_stats;
    const Errors exact_method = errors(
        field_grid(transfer(shooter, receiver, o, &exact_stats, nullptr, &occlusion), n), exact);
    std::cout << "\nexact visibility in (21) at depth " << d_last
              << ": rea = " << cell(100 * exact_method.rea, 4)
              << " %, rays = " << exact_stats.n_rays << "\n";

    const std::string panels = (std::filesystem::path(dir) / "tutorial_07_shadow.png").string();
    const std::string plots = (std::filesystem::path(dir) / "tutorial_07_depths.png").string();
    write_png(panels, error_panels(exact, last_grid, n,
                                   "shadow depth " + std::to_string(d_last) + ": rea " +
                                       cell(100 * last.rea, 3) + " %, L1 " +
                                       cell(100 * last.l1, 3) + " %"));
    write_png(plots, depth_plots(x_depth, y_rea, y_rays));
    std::cout << "wrote " << panels << "\nwrote " << plots << "\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage, mbr::run);
}
