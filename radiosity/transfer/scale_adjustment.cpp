// radiosity/transfer/scale_adjustment.cpp - stage 2 of one transfer: NeighAdjust (paper section 6,
// Figure 4) and the samples (21) of the leaves; the samples of leaves split after stage 4.
#include "radiosity/transfer/scale_adjustment.h"

#include <algorithm>
#include <vector>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "math/polynomial.h"
#include "radiosity/transfer/expanded_domain.h"
#include "radiosity/transfer/gauss_points.h"

namespace mbr {

int adjust_neighbour_scales(Forest& forest, Forest::Region region) {
    auto in_region = [&](int index) {
        const bool inside = forest.node(index).cell.in_domain();
        return region == Forest::Region::All || (region == Forest::Region::Domain) == inside;
    };
    std::vector<int> work = forest.leaves(region);
    int n_splits = 0;
    while (!work.empty()) {
        const int index = work.back();
        work.pop_back();
        if (!forest.node(index).is_leaf()) continue;
        const DyadicCell c = forest.node(index).cell;
        // NeighAdjust: the twelve neighbours of Figure 4 are the level-(L+1) cells around the
        // 2 x 2 block of c's would-be children (two along each edge, one at each corner). If
        // any of them is itself subdivided, a leaf there is more than twice smaller than c.
        bool must_split = false;
        for (int y = 2 * c.j - 1; y <= 2 * c.j + 2 && !must_split; ++y)
            for (int x = 2 * c.i - 1; x <= 2 * c.i + 2 && !must_split; ++x) {
                const bool inner =
                    x >= 2 * c.i && x <= 2 * c.i + 1 && y >= 2 * c.j && y <= 2 * c.j + 1;
                if (inner) continue;
                const DyadicCell neighbour{c.level + 1, x, y};
                const int found = forest.find(neighbour);
                if (found < 0) continue;
                const Forest::Node& n = forest.node(found);
                must_split = n.cell.level == neighbour.level && !n.is_leaf();
            }
        if (!must_split) continue;
        const int first = forest.split(index);
        ++n_splits;
        for (int ch = 0; ch < 4; ++ch) work.push_back(first + ch);
        // The leaves around c may now be more than twice larger than c's children.
        for (int y = c.j - 1; y <= c.j + 1; ++y)
            for (int x = c.i - 1; x <= c.i + 1; ++x) {
                if (x == c.i && y == c.j) continue;
                const int found = forest.find(DyadicCell{c.level, x, y});
                if (found >= 0 && forest.node(found).is_leaf() && in_region(found))
                    work.push_back(found);
            }
    }
    return n_splits;
}

namespace {

/// max_sample and the per-channel range [sample_lo, sample_hi] widened by one leaf's m x m
/// samples.
void widen_sample_range(ReceiverState& state, const Rgb* samples) {
    const int m = state.options.m;
    for (int i = 0; i < m * m; ++i) {
        state.max_sample = std::max(state.max_sample, max_abs(samples[i]));
        for (int k = 0; k < 3; ++k) {
            state.sample_lo[k] = std::min(state.sample_lo[k], samples[i][k]);
            state.sample_hi[k] = std::max(state.sample_hi[k], samples[i][k]);
        }
    }
}

}  // namespace

void sample_leaves(ReceiverState& state, IncrementSampler& sampler) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    std::vector<int> todo;
    for (int index : state.forest.leaves(Forest::Region::Domain))
        if (state.forest.node(index).samples < 0) todo.push_back(index);
    const size_t first_block = state.samples.size() / (size_t(m) * m);
    state.samples.resize(state.samples.size() + todo.size() * m * m);
    for (size_t c = 0; c < todo.size(); ++c)
        state.forest.node(todo[c]).samples = int(first_block + c);

    const int n = static_cast<int>(todo.size());
    std::vector<long> evals(n, 0);
    std::vector<int> unconverged(n, 0);
    parallel_for(n, [&](int c) {
        const Forest::Node& node = state.forest.node(todo[c]);
        double s[16], t[16];
        gauss_points(node.cell.rect(), rule, s, t);
        Rgb* out = &state.samples[size_t(node.samples) * m * m];
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                bool converged = true;
                out[a * m + b] = sampler.sample(s[a], t[b], thread_index(), &evals[c], &converged);
                if (!converged) ++unconverged[c];
            }
    });
    for (int c = 0; c < n; ++c) {
        state.stats.n_kernel_evals += evals[c];
        state.stats.n_increments += long(m) * m;
        state.stats.n_unconverged += unconverged[c];
        widen_sample_range(state,
                           &state.samples[size_t(state.forest.node(todo[c]).samples) * m * m]);
    }
}

void store_leaf_samples(ReceiverState& state, int index, const Rgb* values) {
    const int m = state.options.m;
    Forest::Node& node = state.forest.node(index);
    MBR_CHECK_MSG(node.is_leaf() && node.samples < 0, "cell " << node.cell << " has samples");
    node.samples = static_cast<int>(state.samples.size() / (size_t(m) * m));
    state.samples.insert(state.samples.end(), values, values + size_t(m) * m);
    widen_sample_range(state, values);
}

void sample_split_leaves(ReceiverState& state) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    Forest& forest = state.forest;
    // Children come after their parents in the node array, so a parent's samples exist (from
    // (21), extrapolation or an earlier resampling) when its children are filled; nodes split
    // before stage 2 sampled anything have no samples and neither do their children.
    const std::vector<double> R[2] = {subcell_resample_matrix(rule, 1, 0),
                                      subcell_resample_matrix(rule, 1, 1)};
    for (int index = 0; index < forest.n_nodes(); ++index) {
        Forest::Node& node = forest.node(index);
        if (node.samples >= 0 || node.parent < 0 || forest.node(node.parent).samples < 0) continue;
        node.samples = static_cast<int>(state.samples.size() / (size_t(m) * m));
        state.samples.resize(state.samples.size() + size_t(m) * m);
        Rgb* out = &state.samples[size_t(node.samples) * m * m];
        if (!node.cell.in_domain()) {
            double s[16], t[16];
            gauss_points(node.cell.rect(), rule, s, t);
            for (int a = 0; a < m; ++a)
                for (int b = 0; b < m; ++b) out[a * m + b] = extrapolate(state, s[a], t[b]);
            continue;
        }
        const Forest::Node& parent = forest.node(node.parent);
        const int di = node.cell.i & 1, dj = node.cell.j & 1;
        const Rgb* in = &state.samples[size_t(parent.samples) * m * m];
        double channel_in[256], channel_out[256];
        for (int c = 0; c < 3; ++c) {
            for (int i = 0; i < m * m; ++i) channel_in[i] = in[i][c];
            resample(m, channel_in, R[di].data(), R[dj].data(), channel_out);
            for (int i = 0; i < m * m; ++i) out[i][c] = channel_out[i];
        }
        node.resampled = true;
    }
}

}  // namespace mbr
