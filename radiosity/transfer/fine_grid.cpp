// radiosity/transfer/fine_grid.cpp - stages 6 and 8 on the finest grid (ReceiverOptions::
// unify_by_projection, beyond the paper): eq. (19) as two one-dimensional sums.
#include "radiosity/transfer/fine_grid.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "math/bspline.h"
#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "math/polynomial.h"
#include "radiosity/transfer/expanded_domain.h"
#include "radiosity/transfer/projection.h"

namespace mbr {

namespace {

/// The values at the m x m Gauss-Legendre nodes of every level-J cell lo .. hi - 1 along each
/// axis: f[(j m + b) * n_nodes + (i m + a)] at node (a, b) of cell (lo + i, lo + j).
struct NodeGrid {
    int lo = 0, hi = 0;  // cells lo .. hi - 1 along each axis
    int n_cells = 0, n_nodes = 0;
    std::vector<Rgb> f;
};

/// The grid's values: inside [0,1]^2 the samples of the leaf holding each cell (a coarser
/// leaf's polynomial resampled, as project() does), outside it the extrapolation (23)-(27) at
/// the nodes themselves.
void fill_node_values(const ReceiverState& state, const ProjectionTables& tables, int J,
                      NodeGrid& grid) {
    const int m = state.options.m;
    const Forest& forest = state.forest;
    const GaussLegendre& rule = tables.rule;
    const int cells = 1 << J, lo = grid.lo, n_nodes = grid.n_nodes;
    std::vector<std::vector<std::vector<double>>> resample_rows(J + 1);  // [levels][index] -> m x m
    for (int levels = 1; levels <= J; ++levels)
        for (int index = 0; index < (1 << levels); ++index)
            resample_rows[levels].push_back(subcell_resample_matrix(rule, levels, index));
    // Outside [0,1]^2 the nodes take extrapolate()'s values, from the edges' values at the
    // nodes' feet (one EdgeProfile look-up per node column and edge, not per node) and the
    // corners' values: node k's coordinate along either axis is coordinate[k].
    std::vector<double> coordinate(static_cast<size_t>(n_nodes));
    for (int k = 0; k < n_nodes; ++k)
        coordinate[size_t(k)] = (lo + k / m + 0.5 * (rule.x[k % m] + 1)) / cells;
    std::vector<EdgeValue> at_foot[4];  // [edge][node index along the edge]
    for (int e = 0; e < 4; ++e) {
        at_foot[e].resize(size_t(n_nodes));
        for (int k = 0; k < n_nodes; ++k)
            if (coordinate[size_t(k)] > 0 && coordinate[size_t(k)] < 1)
                at_foot[e][size_t(k)] = edge_value(state, e, coordinate[size_t(k)]);
    }
    const CornerValue corner[2][2] = {
        {corner_value(state, 0, 0), corner_value(state, 0, 1)},
        {corner_value(state, 1, 0), corner_value(state, 1, 1)}};  // [s_c][t_c]
    auto outside = [&](int ka, int kb) {  // the value at node (ka, kb) of the grid, outside
        const double s = coordinate[size_t(ka)], t = coordinate[size_t(kb)];
        const int si = s < 0 ? -1 : (s > 1 ? 1 : 0), ti = t < 0 ? -1 : (t > 1 ? 1 : 0);
        if (si != 0 && ti != 0) return extrapolate_corner(state, corner[si > 0][ti > 0], s, t);
        const SidePatch side = side_patch(s, t);
        const int foot = side.e == 0 || side.e == 2 ? ka : kb;  // the foot's node index
        return extrapolate_side(state, side.e, at_foot[side.e][size_t(foot)], side.offset);
    };
    parallel_for(grid.n_cells, [&](int jj) {
        const int j = lo + jj;
        double channel_in[256], channel_out[256];
        for (int ii = 0; ii < grid.n_cells; ++ii) {
            const int i = lo + ii;
            Rgb* out_base = &grid.f[size_t(jj * m) * n_nodes + size_t(ii * m)];
            auto put = [&](int a, int b, Rgb v) { out_base[size_t(b) * n_nodes + a] = v; };
            if (i < 0 || j < 0 || i >= cells || j >= cells) {
                for (int b = 0; b < m; ++b)
                    for (int a = 0; a < m; ++a) put(a, b, outside(ii * m + a, jj * m + b));
                continue;
            }
            const int leaf = forest.find(DyadicCell{J, i, j});
            const Forest::Node& node = forest.node(leaf);
            MBR_CHECK_MSG(node.is_leaf() && node.samples >= 0,
                          "cell " << node.cell << " has no samples");
            const Rgb* s = &state.samples[size_t(node.samples) * m * m];  // s[a * m + b]
            const int levels = J - node.cell.level;
            if (levels == 0) {
                for (int b = 0; b < m; ++b)
                    for (int a = 0; a < m; ++a) put(a, b, s[a * m + b]);
                continue;
            }
            const int sub_i = i - (node.cell.i << levels), sub_j = j - (node.cell.j << levels);
            const double* Rx = resample_rows[levels][sub_i].data();
            const double* Ry = resample_rows[levels][sub_j].data();
            Rgb tmp[256];
            for (int c = 0; c < 3; ++c) {
                for (int q = 0; q < m * m; ++q) channel_in[q] = s[q][c];
                resample(m, channel_in, Rx, Ry, channel_out);
                for (int q = 0; q < m * m; ++q) tmp[q][c] = channel_out[q];
            }
            for (int b = 0; b < m; ++b)
                for (int a = 0; a < m; ++a) put(a, b, tmp[a * m + b]);
        }
    });
}

}  // namespace

SplineField project_fine_grid(ReceiverState& state, const DualTable& dn) {
    const int m = state.options.m;
    const Forest& forest = state.forest;
    int J = 0;
    for (int index : forest.leaves(Forest::Region::Domain))
        J = std::max(J, forest.node(index).cell.level);
    for (const Fulcrum& f : state.fulcrums) J = std::max(J, f.level);
    const ProjectionTables tables = make_projection_tables(m, dn, state.rhombus_radius, J);
    const GaussLegendre& rule = tables.rule;
    const int first = first_touching_index(m), n_coef = touching_count(m, J);
    // Cells within reach of some coefficient: DN(x - k) is kept for |x - k - m/2| <= r.
    const double r = state.rhombus_radius;
    NodeGrid grid;
    grid.lo = static_cast<int>(std::floor(first + 0.5 * m - r)) - 1;
    grid.hi = static_cast<int>(std::ceil(first + n_coef - 1 + 0.5 * m + r)) + 1;
    grid.n_cells = grid.hi - grid.lo;
    grid.n_nodes = grid.n_cells * m;
    grid.f.resize(size_t(grid.n_nodes) * grid.n_nodes);
    fill_node_values(state, tables, J, grid);
    const int lo = grid.lo, hi = grid.hi, n_nodes = grid.n_nodes;

    // Eq. (19) in x = 2^J s units: c_kl = sum over cells and nodes of (w_a / 2)(w_b / 2)
    // DN(i + x_a - k) DN(j + y_b - l) f; first along s for every node row, then along t.
    auto window = [&](int k, int& c0, int& c1) {  // cells i with DN(x - k) kept on them
        const double centre = k + 0.5 * m;
        c0 = std::max(lo, static_cast<int>(std::floor(centre - r)) - 1);
        c1 = std::min(hi - 1, static_cast<int>(std::ceil(centre + r)));
    };
    // The weights (w_a / 2) DN(o + x_a) of the cell at offset o = i - k from coefficient k, laid
    // out as the grid's nodes are, so that a window of cells is one contiguous run of both.
    std::vector<double> weights(size_t(tables.n_offsets) * m);
    for (int o = 0; o < tables.n_offsets; ++o)
        for (int a = 0; a < m; ++a)
            weights[size_t(o) * m + a] = 0.5 * rule.w[a] * tables.dn(tables.first_offset + o, a);
    // One of the one-dimensional sums: sum over the cells and nodes of `row` (stride 1) of
    // (w_a / 2) DN(i + x_a - k) row[i m + a], for the coefficient index k.
    auto sum_along = [&](const Rgb* row, int k) {
        int c0, c1;
        window(k, c0, c1);
        MBR_CHECK(c0 - k >= tables.first_offset && c1 - k < tables.first_offset + tables.n_offsets);
        const double* w = &weights[size_t(c0 - k - tables.first_offset) * m];
        const Rgb* f = &row[size_t(c0 - lo) * m];
        double r = 0, g = 0, b = 0;  // in the order of the cells and nodes
        for (int q = 0, n = (c1 - c0 + 1) * m; q < n; ++q) {
            r += w[q] * f[q].r;
            g += w[q] * f[q].g;
            b += w[q] * f[q].b;
        }
        return Rgb{r, g, b};
    };
    std::vector<Rgb> g(size_t(n_coef) * n_nodes);  // g[k * n_nodes + row]: summed along s
    parallel_for(n_nodes, [&](int row) {
        const Rgb* fr = &grid.f[size_t(row) * n_nodes];
        for (int kk = 0; kk < n_coef; ++kk)
            g[size_t(kk) * n_nodes + row] = sum_along(fr, first + kk);
    });
    std::vector<Rgb> coef(size_t(n_coef) * n_coef);  // then along t
    parallel_for(n_coef, [&](int kk) {
        const Rgb* gk = &g[size_t(kk) * n_nodes];
        for (int ll = 0; ll < n_coef; ++ll)
            coef[size_t(kk) * n_coef + ll] = sum_along(gk, first + ll);
    });
    SplineField field(m, J);
    for (int kk = 0; kk < n_coef; ++kk)
        for (int ll = 0; ll < n_coef; ++ll) {
            const Fulcrum fu{J, first + kk, first + ll};
            Rgb c = coef[size_t(kk) * n_coef + ll];
            if (state.mask) c = c * state.mask(fu);
            field.set_coefficient(fu.k, fu.l, c);
        }
    state.stats.n_projections += n_coef * n_coef;
    state.stats.level = J;
    return field;
}

}  // namespace mbr
