// examples/studies/explain_transfer.cpp - one energy transfer (paper section 5, "Energy Transfer
// between a Pair of Surfaces", with section 6's oracle, scale adjustment and expanded domain),
// run stage by stage and drawn so that a student can see the method work:
//   (a) the receiver's quadtree after the oracle (stage 1) and NeighAdjust (stage 2, Figure 4),
//       leaves shaded by level, with the selected fulcrums (stage 5, Figure 2) of both scales;
//   (b) the expanded domain (stage 4, Figure 5): its eight patches, numbered 0..7 counter-
//       clockwise from below-left as DyadicCell::patch() does, with their adaptive leaves;
//   (c) a zoom where leaves of two sizes meet: coincident fulcrums of two scales at one corner
//       drawn as concentric markers;
//   (d) the rhombus |x| + |y| <= r (x, y in cells of the fulcrum's scale) that truncates the dual
//       basis function of one fulcrum (stage 6, Figure 3), over a faint map of |DN(x) DN(y)| on a
//       log scale: its level lines are diamonds, which is why a rhombus.
//
// Run:  explain_transfer -o FILE.png [--h H | --perpendicular] [--min-depth 1] [--max-depth 4]
//                        [--oracle-tolerance 3e-3] [--fulcrum-index I] [receiver options]
//
// Default: parallel unit squares at h = 0.1 with the oracle between depths 1 and 4 at tolerance
// 3e-3, which gives a mixed tree: 48 leaves of size 1/8 (a cross through the middle) and 64 of
// size 1/16 (four corner blocks); 65 + 200 fulcrums of the two scales, 32 corners carrying both;
// a ring 4 units wide (the rhombus of a coarse boundary fulcrum, 25.7 cells of 1/8 = 3.2 units,
// must fit in it) with 3536 leaves of levels 1-4; rea 0.73 %. The rhombus panel shows by default
// the finest-scale fulcrum on the bottom edge nearest its middle; --fulcrum-index picks any other
// (indices as printed: sorted by level, then k, then l). stdout gets the summary: leaves per level
// in the domain and the ring, splits made by scale adjustment, edgefill nodes per edge, fulcrums
// per level, coincident pairs, the rhombus radius and the rea of the transfer (on stderr when
// the image itself goes to stdout, -o /dev/stdout). A bad option gives one error line and exit
// 2; an output path that cannot be written one line and exit 1, before the transfer is run when
// the path is already wrong (a missing or read-only folder, a directory), and no partial image
// ever (radiosity/output/output_file.h).
#include <algorithm>
#include <climits>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/plot.h"
#include "examples/common/transfer_cli.h"
#include "radiosity/output/output_file.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: explain_transfer -o FILE.png [options]\n"
               "  One transfer, stage by stage, as a picture: the receiver quadtree, the eight\n"
               "  patches of the expanded domain, the fulcrums of both scales and the rhombus of\n"
               "  one fulcrum.\n"
               "  -o FILE.png                output image (required)\n"
               "  --h H                      parallel unit squares at distance H (default 0.1)\n"
               "  --perpendicular            perpendicular unit squares instead\n"
               "  --min-depth D              oracle quadtree bounds, 0..7 (default 1 and 4)\n"
               "  --max-depth D\n"
               "  --oracle-tolerance T       oracle threshold (default 3e-3)\n"
               "  --fulcrum-index I          fulcrum of the rhombus panel (default: the finest\n"
               "                             one on the bottom edge nearest its middle)\n") +
           receiver_options_usage;
}

// ---- Running the stages ------------------------------------------------------------------

// One transfer run stage by stage, with what the pictures need from between the stages.
struct Explained {
    TransferSetup setup;
    std::string geometry;
    ReceiverState state;
    std::set<std::tuple<int, int, int>> oracle_leaves;  // domain leaves after stage 1
    int n_adjust_splits = 0;      // stage 2 NeighAdjust splits inside the domain
    int n_domain_after_ring = 0;  // domain leaves split when the ring was scale-adjusted
    ErrorStats errors;
    double seconds = 0;
};

std::tuple<int, int, int> key(const DyadicCell& c) {
    return {c.level, c.i, c.j};
}

Explained explain(const TransferSetup& setup, const std::string& geometry,
                  const ReceiverOptions& options) {
    const double start = now_seconds();
    Explained out;
    out.setup = setup;
    out.geometry = geometry;
    // Shooter radiosity 1, receiver reflectance 1, as in Tables 1-2.
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};

    // The stages of transfer() (radiosity/transfer/transfer.h), one at a time.
    const DualTable dn(options.m);
    out.state = ReceiverState(options, rhombus_radius_cells(options, dn));
    ReceiverState& state = out.state;
    state.stats.rhombus_radius = state.rhombus_radius;
    IncrementSampler sampler(shooter, receiver, options.quadrature);

    subdivide_by_oracle(state, sampler);  // stage 1
    for (int index : state.forest.leaves(Forest::Region::Domain))
        out.oracle_leaves.insert(key(state.forest.node(index).cell));
    out.n_adjust_splits = adjust_neighbour_scales(state.forest, Forest::Region::Domain);  // 2
    sample_leaves(state, sampler);
    const size_t n_domain = state.forest.leaves(Forest::Region::Domain).size();
    state.stats.n_leaves = static_cast<int>(n_domain);
    fill_boundary(state, sampler);  // stage 3
    expand_domain(state, sampler);  // stage 4
    out.n_domain_after_ring =
        static_cast<int>(state.forest.leaves(Forest::Region::Domain).size() - n_domain);
    state.fulcrums = select_fulcrums(state.forest, options.m);  // stage 5
    state.stats.n_fulcrums = static_cast<int>(state.fulcrums.size());
    project_in_rhombi(state, dn);                       // stage 6
    const SplineField field = unify_scales(state, dn);  // stage 8
    out.errors = compare_with_exact(field, setup);
    out.seconds = now_seconds() - start;
    return out;
}

// ---- What the pictures share ---------------------------------------------------------------

// One colour per level (Okabe and Ito's colour-blind safe set, 2008): fulcrum markers in full
// colour, leaves filled with a light tint of it.
Rgb level_colour(int level) {
    static const Rgb palette[] = {{0.55, 0.55, 0.55}, {0.90, 0.80, 0.10}, {0.80, 0.47, 0.65},
                                  {0.00, 0.45, 0.70}, {0.84, 0.37, 0.00}, {0.00, 0.62, 0.45},
                                  {0.90, 0.62, 0.00}, {0.34, 0.71, 0.91}};
    return palette[level % 8];
}
Rgb tint(Rgb c, double amount) {
    return (1 - amount) * Rgb{1, 1, 1} + amount * c;
}

const Rgb ink{0, 0, 0};
const Rgb leaf_line{0.35, 0.35, 0.35};
const Rgb patch_line{0.10, 0.10, 0.10};
const Rgb rhombus_colour{0.85, 0.05, 0.10};

// A data window of the (s,t) plane.
struct Window {
    double s0, s1, t0, t1;
};

// The pixel rectangle of a data rectangle (rounded outwards so neighbours share edges).
PixelRect to_pixels(const PlotLayout& L, const Rect& r) {
    const Vec2 a = L.to_pixel(r.x0, r.y1), b = L.to_pixel(r.x1, r.y0);
    const int x0 = static_cast<int>(std::lround(a.x)), y0 = static_cast<int>(std::lround(a.y));
    const int x1 = static_cast<int>(std::lround(b.x)), y1 = static_cast<int>(std::lround(b.y));
    return {x0, y0, x1 - x0, y1 - y0};
}

// Leaves in view: filled by level (fill_amount 0 leaves them unfilled), outlined when they are
// at least min_px pixels wide.
void draw_leaves(Canvas& canvas, const PlotLayout& L, const Forest& forest, double fill_amount,
                 int min_px, Rgb line_colour) {
    const Window w{L.x_min, L.x_max, L.y_min, L.y_max};
    std::vector<std::pair<PixelRect, int>> in_view;  // pixels and level
    for (int index : forest.leaves()) {
        const DyadicCell c = forest.node(index).cell;
        const Rect r = c.rect();
        if (r.x1 < w.s0 || r.x0 > w.s1 || r.y1 < w.t0 || r.y0 > w.t1) continue;
        in_view.push_back({to_pixels(L, r), c.level});
    }
    // All fills first, then all outlines, so that no fill covers a neighbour's outline.
    if (fill_amount > 0)
        for (const auto& [p, level] : in_view)
            canvas.fill_rect(p, tint(level_colour(level), fill_amount));
    for (const auto& [p, level] : in_view)
        if (p.w >= min_px) canvas.stroke_rect({p.x, p.y, p.w + 1, p.h + 1}, line_colour, 1);
}

// Leaves split by NeighAdjust (their ancestor was an oracle leaf): a diagonal hatch.
void hatch_adjusted(Canvas& canvas, const PlotLayout& L, const Explained& E) {
    const Forest& forest = E.state.forest;
    for (int index : forest.leaves(Forest::Region::Domain)) {
        DyadicCell c = forest.node(index).cell;
        if (E.oracle_leaves.count(key(c))) continue;
        const PixelRect p = to_pixels(L, c.rect());
        for (int d = -p.h; d < p.w; d += 6)
            canvas.line(
                {double(p.x + std::max(0, d)), double(p.bottom() - std::max(0, -d))},
                {double(p.x + std::min(p.w, d + p.h)), double(p.bottom() - std::min(p.h, p.w - d))},
                {{0.3, 0.3, 0.3}, 1});
    }
}

// The lines s = 0, 1 and t = 0, 1 across the ring split it into the eight patches of Figure 5;
// the domain is outlined thicker. Patch numbers go at the middle of each patch's visible part.
void draw_patches(Canvas& canvas, const PlotLayout& L, int K, int number_scale) {
    const double lo = -K, hi = 1 + K;
    const Stroke line{patch_line, 2.5};
    for (double v : {0.0, 1.0}) {
        canvas.line(L.to_pixel(v, lo), L.to_pixel(v, hi), line);
        canvas.line(L.to_pixel(lo, v), L.to_pixel(hi, v), line);
    }
    canvas.line(L.to_pixel(lo, lo), L.to_pixel(hi, lo), line);
    canvas.line(L.to_pixel(hi, lo), L.to_pixel(hi, hi), line);
    canvas.line(L.to_pixel(hi, hi), L.to_pixel(lo, hi), line);
    canvas.line(L.to_pixel(lo, hi), L.to_pixel(lo, lo), line);
    const Stroke domain{ink, 4};
    canvas.line(L.to_pixel(0, 0), L.to_pixel(1, 0), domain);
    canvas.line(L.to_pixel(1, 0), L.to_pixel(1, 1), domain);
    canvas.line(L.to_pixel(1, 1), L.to_pixel(0, 1), domain);
    canvas.line(L.to_pixel(0, 1), L.to_pixel(0, 0), domain);
    if (number_scale <= 0) return;
    // Patch p occupies [s-range] x [t-range] by the signs of DyadicCell::patch().
    const double span[3][2] = {{lo, 0}, {0, 1}, {1, hi}};
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            if (a == 1 && b == 1) continue;
            const int p = DyadicCell{0, a - 1, b - 1}.patch();
            const double s0 = std::max(span[a][0], L.x_min), s1 = std::min(span[a][1], L.x_max);
            const double t0 = std::max(span[b][0], L.y_min), t1 = std::min(span[b][1], L.y_max);
            if (s1 <= s0 || t1 <= t0) continue;
            const Vec2 c = L.to_pixel(0.5 * (s0 + s1), 0.5 * (t0 + t1));
            const std::string label = std::to_string(p);
            const int w = text_width(label, number_scale), h = glyph_height * number_scale;
            const int x = static_cast<int>(c.x), y = static_cast<int>(c.y);
            canvas.fill_rect({x - w / 2 - 2 * number_scale, y - h / 2 - 2 * number_scale,
                              w + 4 * number_scale, h + 4 * number_scale},
                             {1, 1, 1});
            canvas.stroke_rect({x - w / 2 - 2 * number_scale, y - h / 2 - 2 * number_scale,
                                w + 4 * number_scale, h + 4 * number_scale},
                               patch_line, 2);
            canvas.text(x, y, label, ink, number_scale, Align::centre, Align::centre);
        }
}

// Fulcrum markers: a disc for the finest level, rings growing by `step` pixels per level
// coarser, so that fulcrums of two scales at one corner show as concentric marks.
struct MarkerStyle {
    int finest = 0;
    double radius = 3.5, step = 4;
    double size(int level) const { return radius + step * (finest - level); }
};

void draw_fulcrum(Canvas& canvas, Vec2 p, int level, const MarkerStyle& style) {
    const Rgb c = level_colour(level);
    if (level == style.finest) {
        canvas.disc(p, style.radius + 1, {0.15, 0.15, 0.15});
        canvas.disc(p, style.radius, c);
    } else {
        canvas.circle(p, style.size(level), {{1, 1, 1}, 4});
        canvas.circle(p, style.size(level), {c, 2.5});
    }
}

void draw_fulcrums(Canvas& canvas, const PlotLayout& L, const std::vector<Fulcrum>& fulcrums, int m,
                   const MarkerStyle& style) {
    // Coarse first, so the finer marks sit on top inside their rings.
    std::vector<Fulcrum> order = fulcrums;
    std::stable_sort(order.begin(), order.end(),
                     [](const Fulcrum& a, const Fulcrum& b) { return a.level < b.level; });
    for (const Fulcrum& f : order) {
        const Vec2 q = f.position(m);
        if (q.x < L.x_min || q.x > L.x_max || q.y < L.y_min || q.y > L.y_max) continue;
        draw_fulcrum(canvas, L.to_pixel(q.x, q.y), f.level, style);
    }
}

// A cross-hair square around the chosen fulcrum, labelled with its index.
void mark_chosen(Canvas& canvas, const PlotLayout& L, Vec2 q, int index, int s) {
    const Vec2 p = L.to_pixel(q.x, q.y);
    if (q.x < L.x_min || q.x > L.x_max || q.y < L.y_min || q.y > L.y_max) return;
    const int r = 13;
    canvas.stroke_rect({int(p.x) - r, int(p.y) - r, 2 * r + 1, 2 * r + 1}, ink, 2);
    canvas.text(int(p.x) + r + 3, int(p.y) - r - 2, "#" + std::to_string(index), ink, s,
                Align::start, Align::end);
}

// A dashed rectangle showing where another panel looks.
void mark_window(Canvas& canvas, const PlotLayout& L, const Window& w, const std::string& label,
                 int s) {
    const Stroke dashed{{0.1, 0.1, 0.1}, 2, 8, 5};
    const Vec2 a = L.to_pixel(w.s0, w.t0), b = L.to_pixel(w.s1, w.t0);
    const Vec2 c = L.to_pixel(w.s1, w.t1), d = L.to_pixel(w.s0, w.t1);
    canvas.polyline({a, b, c, d, a}, dashed);
    const int lw = text_width(label, s), lh = glyph_height * s;
    canvas.fill_rect({int(c.x) - lw - 6, int(c.y) - 6 - lh, lw + 4, lh + 4}, {1, 1, 1});
    canvas.text(int(c.x) - 4, int(c.y) - 4, label, ink, s, Align::end, Align::end);
}

// ---- The figure --------------------------------------------------------------------------

struct Counts {
    std::map<int, int> domain_leaves, ring_leaves, fulcrums, fulcrums_outside;
    int coincident_pairs = 0;
    std::vector<Vec2> coincident;    // positions carrying fulcrums of two (or more) levels
    std::map<int, int> beyond_ring;  // fulcrums whose rhombus reaches past the expanded domain
};

Counts count(const Explained& E) {
    Counts c;
    const Forest& forest = E.state.forest;
    const int m = E.state.options.m;
    for (int index : forest.leaves(Forest::Region::Domain))
        ++c.domain_leaves[forest.node(index).cell.level];
    for (int index : forest.leaves(Forest::Region::Expanded))
        ++c.ring_leaves[forest.node(index).cell.level];
    std::map<std::pair<double, double>, int> at;
    for (const Fulcrum& f : E.state.fulcrums) {
        const Vec2 q = f.position(m);
        ++c.fulcrums[f.level];
        if (q.x < 0 || q.x > 1 || q.y < 0 || q.y > 1) ++c.fulcrums_outside[f.level];
        ++at[{q.x, q.y}];  // dyadic positions: exact in double
    }
    for (const auto& [q, n] : at)
        if (n > 1) {
            c.coincident_pairs += n - 1;
            c.coincident.push_back({q.first, q.second});
        }
    // The projection walks only the forest: a rhombus reaching past [-K, 1 + K]^2 is cut there.
    const double lo = -forest.extent(), hi = 1.0 + forest.extent();
    for (const Fulcrum& f : E.state.fulcrums) {
        const Vec2 q = f.position(m);
        const double R = std::ldexp(E.state.rhombus_radius, -f.level);
        if (q.x - R < lo || q.x + R > hi || q.y - R < lo || q.y + R > hi) ++c.beyond_ring[f.level];
    }
    return c;
}

// The default fulcrum of the rhombus panel: among those in [0,1]^2, the finest, then the one
// nearest (1/2, 0), the middle of the bottom edge (for even m a boundary fulcrum sits there).
int default_fulcrum(const Explained& E) {
    const int m = E.state.options.m;
    int best = 0, finest = 0;
    double best_score = HUGE_VAL;
    for (const Fulcrum& f : E.state.fulcrums) finest = std::max(finest, f.level);
    for (size_t i = 0; i < E.state.fulcrums.size(); ++i) {
        const Fulcrum& f = E.state.fulcrums[i];
        const Vec2 q = f.position(m);
        if (q.x < 0 || q.x > 1 || q.y < 0 || q.y > 1) continue;
        const double score = 100.0 * (finest - f.level) + std::hypot(q.x - 0.5, q.y);
        if (score < best_score - 1e-12) best_score = score, best = static_cast<int>(i);
    }
    return best;
}

// A faint log-scale map for the background of the rhombus panel.
Rgb faint_map(double t) {
    return tint(colour_map(t), 0.6);
}
constexpr double dn_log_floor = -10;  // the map covers |DN DN| / max in [1e-10, 1]

// Picks the zoom window: around a corner where leaves of two levels meet (for even m, where
// fulcrums of two scales coincide), preferring corners on the domain's boundary (where the ring
// and the patches meet too) and, among them, those nearest a corner of the domain; four cells
// of the coarsest fulcrum scale wide.
Window zoom_window(const Explained& E) {
    const Forest& forest = E.state.forest;
    int coarse = 1 << 20, finest = 0;
    for (const Fulcrum& f : E.state.fulcrums)
        coarse = std::min(coarse, f.level), finest = std::max(finest, f.level);
    const double e = std::ldexp(0.25, -finest - 2);  // well inside the four cells at a corner
    Vec2 centre{0, 0};
    double best = HUGE_VAL;
    for (int index : forest.leaves(Forest::Region::Domain)) {
        const Rect r = forest.node(index).cell.rect();
        for (Vec2 q : {Vec2{r.x0, r.y0}, Vec2{r.x1, r.y0}, Vec2{r.x0, r.y1}, Vec2{r.x1, r.y1}}) {
            std::set<int> levels;
            for (int c = 0; c < 4; ++c) {
                const int leaf = forest.leaf_at(q.x + (c & 1 ? e : -e), q.y + (c & 2 ? e : -e));
                if (leaf >= 0) levels.insert(forest.node(leaf).cell.level);
            }
            if (levels.size() < 2) continue;
            const bool on_boundary = q.x == 0 || q.x == 1 || q.y == 0 || q.y == 1;
            double d = HUGE_VAL;
            for (Vec2 corner : {Vec2{0, 0}, Vec2{1, 0}, Vec2{0, 1}, Vec2{1, 1}})
                d = std::min(d, std::hypot(q.x - corner.x, q.y - corner.y));
            const double score = (on_boundary ? 0 : 10) + d;
            if (score < best - 1e-12) best = score, centre = q;
        }
    }
    const double half = 2 * std::ldexp(1.0, -coarse);
    return {centre.x - half, centre.x + half, centre.y - half, centre.y + half};
}

// The sheet compose() draws: four panels in two rows under a header, a legend below; what the
// panels show (the explained transfer, its counts, the chosen fulcrum) and the layout they share.
struct Sheet {
    Sheet(const Explained& E_, const Counts& counts_, int chosen_);
    Sheet(const Sheet&) = delete;  // the canvas draws into this sheet's image
    Sheet& operator=(const Sheet&) = delete;

    void header();
    void quadtree_panel(const Window& view_a, const Window& view_c);  // (a)
    void expanded_panel(const Window& view_a);                        // (b)
    void zoom_panel(const Window& view_c);                            // (c)
    void rhombus_panel();                                             // (d)
    void level_legend();  // the legend's left column: levels, hatching, marks
    void map_scale();     // its right column: the colour scale of panel (d)

    PixelRect panel_area(int column, int row) const {
        return PixelRect{column * panel_w + pad + margin, header_h + row * panel_h + title_h, area,
                         area};
    }
    void panel_title(const PixelRect& a, const std::string& t1, const std::string& t2) {
        canvas.text(a.x + a.w / 2, a.y - 2 * glyph_line_height * s + 2, t1, ink, s + 1,
                    Align::centre, Align::end);
        canvas.text(a.x + a.w / 2, a.y - glyph_line_height * s / 2, t2, {0.3, 0.3, 0.3}, s,
                    Align::centre, Align::end);
    }
    PlotLayout square_layout(const PixelRect& a, const Window& w) const {
        return map_layout(a, w.s0, w.s1, w.t0, w.t1, s);
    }

    const Explained& E;
    const Counts& counts;
    const int chosen;
    const ReceiverState& st;
    const Forest& forest;
    const int m, K;
    const int s = 2, pad = 16 * s;
    const int area = 620;
    const int margin, title_h, panel_w, panel_h, width;
    const int legend_h = 330;
    int finest = 0, coarsest = 1 << 20;
    MarkerStyle style;
    const std::vector<std::string> subtitle;
    const int header_h;
    Image image;
    Canvas canvas;  // draws into image
    const Fulcrum& cf;
    const Vec2 chosen_q;
    const double cell_size;
    const double R;  // the chosen fulcrum's rhombus radius in parameter units
};

// The sheet's subtitle: the options and the result, wrapped to `width` pixels at scale s.
std::vector<std::string> sheet_subtitle(const Explained& E, int width, int s) {
    const ReceiverOptions& o = E.state.options;
    return wrap_text(describe(o) + "; oracle depths " + std::to_string(o.min_depth) + ".." +
                         std::to_string(o.max_depth) + ", tolerance " +
                         cell_g(o.oracle_tolerance, 3) +
                         "; rea = " + cell_g(100 * E.errors.rea, 3) + " %.",
                     width, s);
}

Sheet::Sheet(const Explained& E_, const Counts& counts_, int chosen_)
    : E(E_),
      counts(counts_),
      chosen(chosen_),
      st(E_.state),
      forest(E_.state.forest),
      m(E_.state.options.m),
      K(E_.state.forest.extent()),
      margin(axes_margin(s, 4)),
      title_h(3 * glyph_line_height * s),
      panel_w(margin + area + pad),
      panel_h(title_h + area + margin),
      width(2 * panel_w + pad),
      subtitle(sheet_subtitle(E_, width - 2 * pad, s)),
      header_h(pad / 2 + glyph_line_height * 3 + int(subtitle.size()) * glyph_line_height * s +
               pad / 2),
      image(width, header_h + 2 * panel_h + legend_h, {1, 1, 1}),
      canvas(image),
      cf(E_.state.fulcrums[chosen_]),
      chosen_q(cf.position(m)),
      cell_size(std::ldexp(1.0, -cf.level)),
      R(st.rhombus_radius * cell_size) {
    for (const Fulcrum& f : st.fulcrums)
        finest = std::max(finest, f.level), coarsest = std::min(coarsest, f.level);
    style.finest = finest;
}

void Sheet::header() {
    const std::string title = "One transfer, stage by stage: " + E.geometry;
    canvas.text(pad, pad / 2, title, ink, 3);
    for (size_t i = 0; i < subtitle.size(); ++i)
        canvas.text(pad, pad / 2 + glyph_line_height * 3 + int(i) * glyph_line_height * s,
                    subtitle[i], ink, s);
}

// (a) The domain and a strip of the ring around it.
void Sheet::quadtree_panel(const Window& view_a, const Window& view_c) {
    const PixelRect a = panel_area(0, 0);
    const PlotLayout L = square_layout(a, view_a);
    canvas.set_clip(a);
    draw_leaves(canvas, L, forest, 0.30, 4, leaf_line);
    hatch_adjusted(canvas, L, E);
    draw_patches(canvas, L, K, 3);
    draw_fulcrums(canvas, L, st.fulcrums, m, style);
    mark_chosen(canvas, L, chosen_q, chosen, s);
    mark_window(canvas, L, view_c, "(c)", s);
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", ink, s);
    panel_title(a, "(a) quadtree and fulcrums",
                "domain + inner " + cell_g(-view_a.s0, 2) + " of the ring; colour: level");
}

// (b) The whole expanded domain.
void Sheet::expanded_panel(const Window& view_a) {
    const PixelRect a = panel_area(1, 0);
    const Window w{-double(K), 1.0 + K, -double(K), 1.0 + K};
    const PlotLayout L = square_layout(a, w);
    canvas.set_clip(a);
    draw_leaves(canvas, L, forest, 0.45, 5, {0.55, 0.55, 0.55});
    draw_patches(canvas, L, K, 4);
    mark_window(canvas, L, view_a, "(a)", s);
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", ink, s);
    panel_title(a, "(b) expanded domain: eight patches",
                "whole ring, " + std::to_string(K) + " units wide; numbered as in Figure 5");
}

// (c) Zoom where two sizes meet.
void Sheet::zoom_panel(const Window& view_c) {
    const PixelRect a = panel_area(0, 1);
    const PlotLayout L = square_layout(a, view_c);
    MarkerStyle big = style;
    big.radius = 6;
    big.step = 7;
    canvas.set_clip(a);
    draw_leaves(canvas, L, forest, 0.30, 4, leaf_line);
    hatch_adjusted(canvas, L, E);
    draw_patches(canvas, L, K, 3);
    draw_fulcrums(canvas, L, st.fulcrums, m, big);
    mark_chosen(canvas, L, chosen_q, chosen, s);
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", ink, s);
    panel_title(a, "(c) zoom: two scales meet",
                m % 2 == 0 ? "concentric marks: two scales at one corner"
                           : "fulcrums at the leaves' centres, one per leaf");
}

// (d) The rhombus of the chosen fulcrum over |DN(x) DN(y)|.
void Sheet::rhombus_panel() {
    const PixelRect a = panel_area(1, 1);
    const double half = 1.12 * R + 2 * cell_size;
    const Window w{chosen_q.x - half, chosen_q.x + half, chosen_q.y - half, chosen_q.y + half};
    const PlotLayout L = square_layout(a, w);
    const DualTable dn(m);
    const double peak = dn.max_abs() * dn.max_abs();
    const double scale = std::ldexp(1.0, cf.level);
    const double eps = st.options.rhombus_radius > 0 ? dn.eps_for_rhombus_radius(st.rhombus_radius)
                                                     : st.options.truncation_eps;
    // The monotone envelope of |DN_m| about its fulcrum, on a 1/64 grid: env[q] = max |DN|
    // over |u| >= q / 64 (u the distance from the fulcrum in cells). The rhombus radius is
    // defined by this envelope (DualTable::rhombus_radius), so its contour E(x) E(y) = eps
    // is what the rhombus has to contain.
    const int n_env = static_cast<int>(64 * dn.half_width()) + 2;
    std::vector<double> env(n_env + 1, 0.0);
    for (int q = n_env - 1; q >= 0; --q)
        env[q] = std::max({env[q + 1], std::fabs(dn(dn.fulcrum() + q / 64.0)),
                           std::fabs(dn(dn.fulcrum() - q / 64.0))});
    auto envelope = [&](double u) {
        const int q = static_cast<int>(std::fabs(u) * 64);
        return q < n_env ? env[q] : 0.0;
    };
    // Per pixel: x = 2^L s - k, y = 2^L t - l, as in project().
    std::vector<char> above(size_t(a.w) * a.h);
    for (int py = 0; py < a.h; ++py)
        for (int px = 0; px < a.w; ++px) {
            const double sv = w.s0 + (px + 0.5) / a.w * (w.s1 - w.s0);
            const double tv = w.t1 - (py + 0.5) / a.h * (w.t1 - w.t0);
            const double v = std::fabs(dn(scale * sv - cf.k) * dn(scale * tv - cf.l)) / peak;
            const double lg = v > 0 ? std::log10(v) : dn_log_floor;
            image.at(a.x + px, a.y + py) = faint_map((lg - dn_log_floor) / -dn_log_floor);
            above[size_t(py) * a.w + px] = envelope(scale * sv - cf.k - dn.fulcrum()) *
                                               envelope(scale * tv - cf.l - dn.fulcrum()) >
                                           eps * peak;
        }
    canvas.set_clip(a);
    draw_leaves(canvas, L, forest, 0, 8, {0.78, 0.78, 0.78});
    draw_patches(canvas, L, K, 0);
    // The set where the envelope of |DN DN| exceeds eps: its boundary, two pixels wide.
    for (int py = 1; py < a.h - 1; ++py)
        for (int px = 1; px < a.w - 1; ++px) {
            const size_t i = size_t(py) * a.w + px;
            if (above[i] != above[i - 1] || above[i] != above[i + 1] ||
                above[i] != above[i - a.w] || above[i] != above[i + a.w])
                canvas.blend(a.x + px, a.y + py, {0.1, 0.1, 0.1});
        }
    const Vec2 top = L.to_pixel(chosen_q.x, chosen_q.y + R),
               right = L.to_pixel(chosen_q.x + R, chosen_q.y),
               bottom = L.to_pixel(chosen_q.x, chosen_q.y - R),
               left = L.to_pixel(chosen_q.x - R, chosen_q.y);
    canvas.polyline({top, right, bottom, left, top}, {rhombus_colour, 3});
    draw_fulcrum(canvas, L.to_pixel(chosen_q.x, chosen_q.y), cf.level, style);
    mark_chosen(canvas, L, chosen_q, chosen, s);
    const Vec2 edge = 0.5 * (top + left);
    const std::string r_label = "r = " + cell_g(st.rhombus_radius, 3) + " cells = " + cell_g(R, 3);
    const int lw = text_width(r_label, s), lh = glyph_height * s;
    const int lx = std::max(a.x + 4, int(edge.x) - 10 - lw);
    canvas.fill_rect({lx - 3, int(edge.y) - 12 - lh, lw + 6, lh + 6}, {1, 1, 1});
    canvas.text(lx, int(edge.y) - 9, r_label, rhombus_colour, s, Align::start, Align::end);
    canvas.reset_clip();
    draw_axes(image, L, "s", "t", ink, s);
    panel_title(a, "(d) rhombus of fulcrum #" + std::to_string(chosen),
                "|x| + |y| <= r, x = 2^" + std::to_string(cf.level) + " s - k; map: |DN(x) DN(y)|");
}

// The legend's left column: levels, the leaves NeighAdjust made, the marks.
void Sheet::level_legend() {
    const int top = header_h + 2 * panel_h + 4;
    const int line = glyph_line_height * s + 4;
    const int x0 = pad, column_w = width / 2 - 2 * pad;
    const int swatch_w = 36, text_x = x0 + swatch_w + 10;
    int y = top;
    canvas.text(x0, y, "colour = level L of a leaf or fulcrum (cell size 2^-L):", ink, s);
    y += line + 4;
    std::set<int> levels;
    for (const auto& [l, n] : counts.domain_leaves) levels.insert(l);
    for (const auto& [l, n] : counts.ring_leaves) levels.insert(l);
    auto entry = [&](const std::string& text) {
        for (const std::string& t : wrap_text(text, column_w - (text_x - x0), s)) {
            canvas.text(text_x, y, t, ink, s);
            y += glyph_line_height * s;
        }
        y += 10;
    };
    auto lookup = [](const std::map<int, int>& mp, int l) {
        const auto it = mp.find(l);
        return it == mp.end() ? 0 : it->second;
    };
    for (int l : levels) {
        canvas.fill_rect({x0, y - 3, swatch_w, 20}, tint(level_colour(l), 0.30));
        canvas.stroke_rect({x0, y - 3, swatch_w, 20}, leaf_line, 1);
        if (counts.fulcrums.count(l)) draw_fulcrum(canvas, {x0 + 18.0, y + 7.0}, l, style);
        entry("L" + std::to_string(l) + " (1/" + std::to_string(1 << l) +
              "): " + std::to_string(lookup(counts.domain_leaves, l)) + " domain + " +
              std::to_string(lookup(counts.ring_leaves, l)) + " ring leaves, " +
              std::to_string(lookup(counts.fulcrums, l)) + " fulcrums");
    }
    // Hatch swatch for leaves that NeighAdjust made.
    canvas.fill_rect({x0, y - 3, swatch_w, 20}, {1, 1, 1});
    for (int d = -20; d < swatch_w; d += 6)
        canvas.line(
            {double(x0 + std::max(0, d)), double(y + 17 - std::max(0, -d))},
            {double(x0 + std::min(swatch_w, d + 20)), double(y + 17 - std::min(20, swatch_w - d))},
            {{0.3, 0.3, 0.3}, 1});
    canvas.stroke_rect({x0, y - 3, swatch_w, 20}, leaf_line, 1);
    entry(E.n_adjust_splits > 0
              ? "hatched: leaves made by NeighAdjust (" + std::to_string(E.n_adjust_splits) +
                    " splits after the oracle)"
              : "hatched: leaves made by NeighAdjust; none here, the oracle's tree is "
                "already graded by 2");
    // Concentric marks.
    if (m % 2 == 0) {
        draw_fulcrum(canvas, {x0 + 18.0, y + 7.0}, coarsest, style);
        draw_fulcrum(canvas, {x0 + 18.0, y + 7.0}, finest, style);
    } else {
        draw_fulcrum(canvas, {x0 + 6.0, y + 7.0}, finest, style);
        draw_fulcrum(canvas, {x0 + 26.0, y + 7.0}, coarsest, style);
    }
    entry(m % 2 == 0 ? std::to_string(counts.coincident_pairs) +
                           " corners carry fulcrums of two scales: a ring (coarser) "
                           "around a dot (finer)"
                     : "odd m: one fulcrum at each leaf's centre, so none coincide; a ring "
                       "(coarser) or a dot (finest level)");
    canvas.stroke_rect({x0 + 8, y - 3, 20, 20}, ink, 2);
    entry("#" + std::to_string(chosen) +
          ": the fulcrum of panel (d); dashed: the views of "
          "panels (a) and (c)");
    int n_beyond = 0;
    for (const auto& [l, n] : counts.beyond_ring) n_beyond += n;
    if (n_beyond > 0)
        entry("note: the rhombi of " + std::to_string(n_beyond) +
              " fulcrums reach past the ring and are cut at its edge");
}

// The legend's right column: the map's colour scale, with eps marked.
void Sheet::map_scale() {
    const int top = header_h + 2 * panel_h + 4;
    const int line = glyph_line_height * s + 4;
    const int bx = width / 2 + pad, bw = width / 2 - 3 * pad;
    const int by = top + line + 4;
    const DualTable dn(m);
    const double eps = st.options.rhombus_radius > 0 ? dn.eps_for_rhombus_radius(st.rhombus_radius)
                                                     : st.options.truncation_eps;
    draw_colour_scale(image, {bx, by, bw, 22}, std::pow(10.0, dn_log_floor), 1,
                      "|DN(x) DN(y)| / max, panel (d)", faint_map, s, true);
    const double te = (std::log10(eps) - dn_log_floor) / -dn_log_floor;
    const int ex = bx + static_cast<int>(std::lround(te * (bw - 1)));
    canvas.fill_rect({ex - 1, by - 4, 3, 30}, rhombus_colour);
    canvas.text(ex, by + 22 + 3 * glyph_line_height * s / 2 + 6, "eps = " + cell_g(eps, 2),
                rhombus_colour, s, Align::centre);
    int ty = by + 22 + 3 * glyph_line_height * s + 8;
    for (const std::string& t :
         wrap_text("Red: the rhombus |x| + |y| <= r inside which the projection integrates. "
                   "Dark line: where the decay envelope of |DN(x) DN(y)| falls to eps. DN decays "
                   "by about the same factor per cell in x and in y, so the level lines of the "
                   "product are diamonds. Light lattice: zeros of DN. Grey squares: leaves; "
                   "black lines: domain and patches.",
                   bw, s)) {
        canvas.text(bx, ty, t, {0.3, 0.3, 0.3}, s);
        ty += glyph_line_height * s;
    }
}

Image compose(const Explained& E, const Counts& counts, int chosen) {
    Sheet sheet(E, counts, chosen);
    sheet.header();
    const Window view_a{-0.25, 1.25, -0.25, 1.25};
    const Window view_c = zoom_window(E);
    sheet.quadtree_panel(view_a, view_c);
    sheet.expanded_panel(view_a);
    sheet.zoom_panel(view_c);
    sheet.rhombus_panel();
    sheet.level_legend();  // legend: levels, the map's colour scale, the summary
    sheet.map_scale();
    return sheet.image;
}

std::string per_level(const std::map<int, int>& counts) {
    std::string out;
    for (const auto& [l, n] : counts)
        out += (out.empty() ? "" : ", ") + ("L" + std::to_string(l)) + ": " + std::to_string(n);
    return out.empty() ? "none" : out;
}

int run(Args& args) {
    const std::string path = args.text("-o", "");
    const bool perpendicular = args.flag("--perpendicular");
    const double h = args.number("--h", 0.1);
    ReceiverOptions options = read_receiver_options(args);
    options.min_depth = args.integer("--min-depth", 1, 0, 7);
    options.max_depth = args.integer("--max-depth", 4, 0, 7);
    options.oracle_tolerance = args.number("--oracle-tolerance", 3e-3);
    // The upper end depends on the transfer; it is checked once the fulcrums are known.
    const int fulcrum_index = args.integer("--fulcrum-index", -1, 0, INT_MAX);
    args.finish();
    if (path.empty()) throw UsageError("-o FILE.png is required");
    if (perpendicular && args.has("--h"))
        throw UsageError("--h and --perpendicular exclude each other");
    if (!(h > 0 && h <= 10)) throw UsageError("--h must be in (0, 10]");
    if (options.min_depth > options.max_depth)
        throw UsageError("--min-depth must not exceed --max-depth");
    if (!(options.oracle_tolerance > 0)) throw UsageError("--oracle-tolerance must be positive");
    check_output_path(path);  // fail now, not after the transfer

    const TransferSetup setup = perpendicular ? perpendicular_squares() : parallel_squares(h);
    const std::string geometry =
        perpendicular ? "perpendicular unit squares" : "parallel unit squares, h = " + cell_g(h, 3);
    const Explained E = explain(setup, geometry, options);
    const ReceiverState& st = E.state;
    const int n_fulcrums = static_cast<int>(st.fulcrums.size());
    if (args.has("--fulcrum-index") && (fulcrum_index < 0 || fulcrum_index >= n_fulcrums))
        throw UsageError("--fulcrum-index must be in 0.." + std::to_string(n_fulcrums - 1) +
                         " (this transfer has " + std::to_string(n_fulcrums) + " fulcrums)");
    const int chosen = fulcrum_index >= 0 ? fulcrum_index : default_fulcrum(E);
    const Counts counts = count(E);

    const Image image = compose(E, counts, chosen);
    write_png(path, image);

    // The report goes on stderr when the image went to stdout, so that the two do not mix.
    std::ostream& report = is_standard_output(path) ? std::cerr : std::cout;
    const int m = options.m;
    const Fulcrum& cf = st.fulcrums[chosen];
    const Vec2 q = cf.position(m);
    report << "explain_transfer: " << geometry << "\n  " << describe(options)
           << "\n  oracle depths " << options.min_depth << ".." << options.max_depth
           << ", tolerance " << options.oracle_tolerance << "\n\n"
           << "stage 1-2  domain leaves per level:   " << per_level(counts.domain_leaves)
           << "  (NeighAdjust splits: " << E.n_adjust_splits
           << "; further domain leaves from the ring's scale adjustment: " << E.n_domain_after_ring
           << ")\n"
           << "stage 3    edgefill nodes per edge:   bottom " << st.edges[0].sigma.size()
           << ", right " << st.edges[1].sigma.size() << ", top " << st.edges[2].sigma.size()
           << ", left " << st.edges[3].sigma.size() << "\n"
           << "stage 4    ring: " << st.forest.extent() << " units wide on each side, "
           << "expanded leaves per level: " << per_level(counts.ring_leaves) << "\n"
           << "stage 5    fulcrums per level:        " << per_level(counts.fulcrums)
           << "  (outside [0,1]^2: " << per_level(counts.fulcrums_outside) << ")\n"
           << "           coincident pairs:          " << counts.coincident_pairs
           << " corners carry fulcrums of two scales\n"
           << "stage 6    rhombus radius:            " << cell_g(st.rhombus_radius, 4)
           << " cells of each fulcrum's scale";
    for (const auto& [l, n] : counts.fulcrums)
        report << (l == counts.fulcrums.begin()->first ? " (= " : ", ")
               << cell_g(std::ldexp(st.rhombus_radius, -l), 4) << " at L" << l;
    report << ")\n"
           << "           rhombi reaching past the ring (cut there): "
           << per_level(counts.beyond_ring) << "\n"
           << "           panel (d): fulcrum #" << chosen << " = level " << cf.level
           << ", k = " << cf.k << ", l = " << cf.l << ", at (s, t) = (" << q.x << ", " << q.y
           << ")\n"
           << "result     rea = " << cell_g(100 * E.errors.rea, 4)
           << " %, max relative error = " << cell_g(100 * E.errors.max_rel, 4) << " %, "
           << cell(E.seconds, 2) << " s\n"
           << "wrote " << path << " (" << image.width << " x " << image.height << ")\n";
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
