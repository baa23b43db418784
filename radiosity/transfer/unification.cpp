// radiosity/transfer/unification.cpp - stage 8 of one transfer: scale unification by eq. (17)
// (paper section 5, "Scale Unification and Superposition").
#include "radiosity/transfer/unification.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "math/bspline.h"
#include "radiosity/transfer/projection.h"

namespace mbr {

Rgb resolve_coefficient(ReceiverState& state, const DualTable& dn, const Fulcrum& f,
                        std::map<Fulcrum, Rgb>& refined) {
    auto stored = state.coefficients.find(f);
    if (stored != state.coefficients.end()) return stored->second;
    auto memo = refined.find(f);
    if (memo != refined.end()) return memo->second;
    const int m = state.options.m;
    const Forest& forest = state.forest;

    // The finest level of (21) samples around a fulcrum's position: its own cell for odd m (a
    // centre), the four cells around the corner for even m. A leaf of shadow subdivision holds
    // its parent's samples resampled: it counts at the level those samples were taken.
    auto sample_level = [&](int leaf) {
        while (forest.node(leaf).resampled) leaf = forest.node(leaf).parent;
        return forest.node(leaf).cell.level;
    };
    auto local_level = [&]() {
        const Vec2 c = f.position(m);
        if (m % 2 == 1) {
            const int leaf = forest.leaf_at(c.x, c.y);
            return leaf >= 0 ? sample_level(leaf) : -1;
        }
        const double eps = std::ldexp(0.25, -f.level);
        int level = -1;
        for (int q = 0; q < 4; ++q) {
            const int leaf =
                forest.leaf_at(c.x + ((q & 1) ? eps : -eps), c.y + ((q & 2) ? eps : -eps));
            if (leaf >= 0) level = std::max(level, sample_level(leaf));
        }
        return level;
    };

    // DESIGN: a coefficient is projected (stored, or on demand) where the samples around its
    // fulcrum are at least as fine as its scale; elsewhere it is refined from the level above
    // by (17): a_l = sum_k p_{m,l-2k} a_k in each direction, recursively.
    if (f.level == 0 || state.options.unify_by_projection || local_level() >= f.level) {
        Rgb c = state.tables ? project(state, dn, *state.tables, f) : project(state, dn, f);
        if (state.mask) c = c * state.mask(f);
        state.coefficients[f] = c;
        ++state.stats.n_projections;
        return c;
    }
    const std::vector<double> p_mk = two_scale_mask(m);
    Rgb sum;
    // Coarse k' with 0 <= k - 2k' <= m, i.e. ceil((k - m) / 2) <= k' <= floor(k / 2).
    auto floor_half = [](int x) { return x >= 0 ? x / 2 : -((-x + 1) / 2); };
    const int k0 = -floor_half(m - f.k), k1 = floor_half(f.k);
    const int l0 = -floor_half(m - f.l), l1 = floor_half(f.l);
    for (int kc = k0; kc <= k1; ++kc)
        for (int lc = l0; lc <= l1; ++lc)
            sum += (p_mk[f.k - 2 * kc] * p_mk[f.l - 2 * lc]) *
                   resolve_coefficient(state, dn, {f.level - 1, kc, lc}, refined);
    refined[f] = sum;
    ++state.stats.n_refined;
    return sum;
}

SplineField unify_scales(ReceiverState& state, const DualTable& dn) {
    const int m = state.options.m;
    int j = 0;
    for (const Fulcrum& f : state.fulcrums) j = std::max(j, f.level);
    std::map<Fulcrum, Rgb> refined;  // coefficients obtained by (17), memoised
    SplineField field(m, j);
    const int first = first_touching_index(m), n = touching_count(m, j);
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l)
            field.set_coefficient(k, l, resolve_coefficient(state, dn, {j, k, l}, refined));
    state.stats.level = j;
    return field;
}

}  // namespace mbr
