// radiosity/transfer/projection.cpp - stages 5 and 6 of one transfer: the fulcrums (paper section
// 5, Figure 2) and their projection in the rhombus, eq. (19), Figure 3.
#include "radiosity/transfer/projection.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "math/polynomial.h"

namespace mbr {

double rhombus_radius_cells(const ReceiverOptions& options, const DualTable& dn) {
    return options.rhombus_radius > 0 ? options.rhombus_radius
                                      : dn.rhombus_radius(options.truncation_eps);
}

std::vector<Fulcrum> select_fulcrums(const Forest& forest, int m) {
    std::vector<Fulcrum> out;
    auto touches_domain = [&](const Fulcrum& f) {
        // N_m(2^L s - k) is supported on [k, k + m] 2^-L: does it reach into (0, 1)?
        const int n = 1 << f.level;
        return f.k < n && f.k + m > 0 && f.l < n && f.l + m > 0;
    };
    for (int index = 0; index < forest.n_nodes(); ++index) {
        const Forest::Node& node = forest.node(index);
        if (!node.is_leaf()) continue;
        const DyadicCell c = node.cell;
        std::vector<Fulcrum> here;
        if (m % 2 == 1) {
            // Odd m: the leaf's centre, (k + m/2) 2^-L = (i + 1/2) 2^-L.
            here.push_back({c.level, c.i - (m - 1) / 2, c.j - (m - 1) / 2});
        } else {
            // Even m: the leaf's four corners, (k + m/2) 2^-L = (i + a) 2^-L.
            for (int b = 0; b <= 1; ++b)
                for (int a = 0; a <= 1; ++a)
                    here.push_back({c.level, c.i + a - m / 2, c.j + b - m / 2});
        }
        for (const Fulcrum& f : here)
            if (c.in_domain() || touches_domain(f)) out.push_back(f);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

namespace {

/// Distance in the (s,t) plane, in the 1-norm, from a point to a rectangle (0 inside): a cell
/// meets the rhombus |s - cx| + |t - cy| <= R exactly when this is at most R.
double rhombus_distance(const Rect& r, Vec2 c) {
    const double dx = std::max({0.0, r.x0 - c.x, c.x - r.x1});
    const double dy = std::max({0.0, r.y0 - c.y, c.y - r.y1});
    return dx + dy;
}
/// The deepest leaf level of the forest.
int finest_level(const Forest& forest) {
    int level = 0;
    for (int index = 0; index < forest.n_nodes(); ++index)
        level = std::max(level, forest.node(index).cell.level);
    return level;
}
}  // namespace

ProjectionTables make_projection_tables(int m, const DualTable& dn, double rhombus_radius,
                                        int max_levels) {
    ProjectionTables t;
    t.m = m;
    t.rule = gauss_legendre(m);
    // Offsets o = i - k of cells that can meet a rhombus: the fulcrum is at k + m/2.
    const int reach = static_cast<int>(std::ceil(rhombus_radius)) + m + 2;
    t.first_offset = -reach;
    t.n_offsets = 2 * reach + 1;
    t.dn_at_nodes.resize(size_t(t.n_offsets) * m);
    for (int i = 0; i < t.n_offsets; ++i)
        for (int a = 0; a < m; ++a)
            t.dn_at_nodes[size_t(i) * m + a] = dn(t.first_offset + i + 0.5 * (t.rule.x[a] + 1));
    t.resample.resize(max_levels + 1);
    for (int levels = 1; levels <= max_levels; ++levels) {
        std::vector<double>& block = t.resample[levels];
        const int n_sub = 1 << levels;
        block.reserve(size_t(n_sub) * m * m);
        for (int index = 0; index < n_sub; ++index) {
            const std::vector<double> R = subcell_resample_matrix(t.rule, levels, index);
            block.insert(block.end(), R.begin(), R.end());
        }
    }
    return t;
}

Rgb project(const ReceiverState& state, const DualTable& dn, const Fulcrum& f) {
    const int levels = std::max(0, f.level);
    return project(state, dn,
                   make_projection_tables(state.options.m, dn, state.rhombus_radius, levels), f);
}

namespace {

/// The sum of eq. (19) for one fulcrum, cell by cell over the leaves that meet its rhombus.
struct RhombusSum {
    RhombusSum(int m_, const DualTable& dn_, const ProjectionTables& tables_, const Fulcrum& f_,
               double rhombus_radius)
        : m(m_),
          dn(dn_),
          tables(tables_),
          f(f_),
          scale(std::ldexp(1.0, f_.level)),
          centre(f_.position(m_)),
          R(rhombus_radius / scale) {}

    int m;
    const DualTable& dn;
    const ProjectionTables& tables;
    const Fulcrum& f;
    double scale;  // x = 2^L s
    Vec2 centre;   // the fulcrum's position
    double R;      // rhombus radius in parameter units
    Rgb sum;
    Rgb resampled[256];  // scratch of add_coarse_leaf: one sub-cell's samples
    double channel_in[256], channel_out[256];

    /// m x m Gauss-Legendre on a rectangle of the fulcrum's scale or finer, where DN_m(x - k)
    /// is one polynomial piece: c += sum_a sum_b w_a w_b J DN(x_a - k) DN(y_b - l) dB_ab, with
    /// J the Jacobian of [-1,1]^2 -> the rectangle in x = 2^L s units (not the area factor
    /// A_i). Cells of exactly the fulcrum's scale take DN from the table of node values.
    void add_cell(const Rect& r, const Rgb* f_ab) {
        const GaussLegendre& rule = tables.rule;
        double wx[16], wy[16];
        const double hx = 0.5 * r.width() * scale, hy = 0.5 * r.height() * scale;
        if (hx == 0.5 && hy == 0.5) {
            const int ox = static_cast<int>(std::lround(r.x0 * scale)) - f.k;
            const int oy = static_cast<int>(std::lround(r.y0 * scale)) - f.l;
            for (int a = 0; a < m; ++a) {
                wx[a] = rule.w[a] * hx * tables.dn(ox, a);
                wy[a] = rule.w[a] * hy * tables.dn(oy, a);
            }
        } else {
            for (int a = 0; a < m; ++a) {
                const double x = (r.x0 + 0.5 * (rule.x[a] + 1) * r.width()) * scale - f.k;
                const double y = (r.y0 + 0.5 * (rule.x[a] + 1) * r.height()) * scale - f.l;
                wx[a] = rule.w[a] * hx * dn(x);
                wy[a] = rule.w[a] * hy * dn(y);
            }
        }
        for (int a = 0; a < m; ++a) {
            if (wx[a] == 0) continue;
            Rgb row;
            for (int b = 0; b < m; ++b) row += wy[b] * f_ab[a * m + b];
            sum += wx[a] * row;
        }
    }

    /// A leaf `levels` coarser than the dual: fit the tensor polynomial of degree m-1 to its
    /// samples (the Lagrange interpolant at the Gauss-Legendre nodes), split the leaf to the
    /// fulcrum's scale and resample it on the sub-cells that meet the rhombus.
    void add_coarse_leaf(const Rect& r, const Rgb* f_ab, int levels) {
        MBR_CHECK_MSG(levels < int(tables.resample.size()),
                      "no resampling table for " << levels << " levels");
        const std::vector<double>& block = tables.resample[levels];
        const int n_sub = 1 << levels;
        const double h = r.width() / n_sub;
        for (int p = 0; p < n_sub; ++p) {
            const Rect strip{r.x0 + p * h, r.x0 + (p + 1) * h, r.y0, r.y1};
            if (rhombus_distance(strip, centre) > R) continue;  // no sub-cell of it can meet
            const double* Rx = &block[size_t(p) * m * m];
            // Sub-cells q of this strip that meet the rhombus have |t - cy| <= R - dx, with dx
            // the distance along s alone (not the strip's 1-norm distance, which also counts
            // the leaf's distance along t and would drop sub-cells that meet the rhombus);
            // one row more below, so that a sub-cell touching the rhombus is not lost to
            // rounding; the exact test follows.
            const double dx = std::max({0.0, strip.x0 - centre.x, centre.x - strip.x1});
            const double reach = R - dx;
            const int q0 =
                std::max(0, static_cast<int>(std::floor((centre.y - reach - r.y0) / h)) - 1);
            const int q1 =
                std::min(n_sub - 1, static_cast<int>(std::floor((centre.y + reach - r.y0) / h)));
            for (int q = q0; q <= q1; ++q) {
                const Rect sub{strip.x0, strip.x1, r.y0 + q * h, r.y0 + (q + 1) * h};
                if (rhombus_distance(sub, centre) > R) continue;
                const double* Ry = &block[size_t(q) * m * m];
                for (int c = 0; c < 3; ++c) {
                    for (int i = 0; i < m * m; ++i) channel_in[i] = f_ab[i][c];
                    resample(m, channel_in, Rx, Ry, channel_out);
                    for (int i = 0; i < m * m; ++i) resampled[i][c] = channel_out[i];
                }
                add_cell(sub, resampled);
            }
        }
    }
};

}  // namespace

Rgb project(const ReceiverState& state, const DualTable& dn, const ProjectionTables& tables,
            const Fulcrum& f) {
    const int m = state.options.m;
    MBR_CHECK(tables.m == m);
    const Forest& forest = state.forest;
    RhombusSum rhombus(m, dn, tables, f, state.rhombus_radius);
    const Vec2 centre = rhombus.centre;
    const double R = rhombus.R;

    // Roots [I, I+1] x [J, J+1] within the rhombus's bounding box, touching included (as in
    // the walk below: a cell at 1-norm distance exactly R meets the closed rhombus).
    const int K = forest.extent();
    const int I0 = std::max(-K, static_cast<int>(std::ceil(centre.x - R)) - 1);
    const int I1 = std::min(K, static_cast<int>(std::floor(centre.x + R)));
    const int J0 = std::max(-K, static_cast<int>(std::ceil(centre.y - R)) - 1);
    const int J1 = std::min(K, static_cast<int>(std::floor(centre.y + R)));
    std::vector<int> stack;
    for (int J = J0; J <= J1; ++J)
        for (int I = I0; I <= I1; ++I) stack.push_back(forest.root(I, J));
    while (!stack.empty()) {
        const int index = stack.back();
        stack.pop_back();
        const Forest::Node& node = forest.node(index);
        const Rect r = node.cell.rect();
        if (rhombus_distance(r, centre) > R) continue;  // the subdomain misses the rhombus
        if (!node.is_leaf()) {
            for (int ch = 0; ch < 4; ++ch) stack.push_back(node.first_child + ch);
            continue;
        }
        MBR_CHECK_MSG(node.samples >= 0, "leaf " << node.cell << " has no samples");
        const Rgb* f_ab = &state.samples[size_t(node.samples) * m * m];
        const int levels = f.level - node.cell.level;
        if (levels <= 0)
            rhombus.add_cell(r, f_ab);
        else
            rhombus.add_coarse_leaf(r, f_ab, levels);
    }
    return rhombus.sum;
}

void project_in_rhombi(ReceiverState& state, const DualTable& dn) {
    // Fulcrums are no finer than the finest leaf and leaves no coarser than level 0.
    state.tables = std::make_shared<const ProjectionTables>(make_projection_tables(
        state.options.m, dn, state.rhombus_radius, finest_level(state.forest)));
    const ProjectionTables& tables = *state.tables;
    const int n = static_cast<int>(state.fulcrums.size());
    std::vector<Rgb> values(n);
    parallel_for(n, [&](int i) { values[i] = project(state, dn, tables, state.fulcrums[i]); });
    for (int i = 0; i < n; ++i) state.coefficients[state.fulcrums[i]] = values[i];
    state.stats.n_projections += n;
}

}  // namespace mbr
