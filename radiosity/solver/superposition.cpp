// radiosity/solver/superposition.cpp - light groups, their scenes, and the weighted sum of their
// solutions (relighting by superposition, paper section 8).
#include "radiosity/solver/superposition.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include "math/check.h"

namespace mbr {

namespace {

std::uint64_t cell_key(const DyadicCell& c) {
    return (std::uint64_t(c.level) << 56) | (std::uint64_t(std::uint32_t(c.i)) << 28) |
           std::uint64_t(std::uint32_t(c.j));
}

/// sum_g w_g f_g of one surface's fields, skipping zero weights; the zero field of the first
/// field's order at level 0 when every weight is zero.
SplineField weighted_sum(const std::vector<const SplineField*>& fields,
                         const std::vector<double>& weights) {
    SplineField sum;
    for (size_t g = 0; g < fields.size(); ++g) {
        if (weights[g] == 0 || fields[g]->empty()) continue;
        SplineField term = *fields[g];
        if (weights[g] != 1) term.scale(weights[g]);
        sum.add(term);  // refines the coarser of the two to the finer level, eq. (17)
    }
    if (sum.empty() && !fields[0]->empty()) sum = SplineField(fields[0]->order(), 0);
    return sum;
}

/// The leaves of the union of quadtrees given by their leaves: a cell is split when it is a
/// strict ancestor of a leaf of one of the trees. An empty list is the root alone.
std::vector<DyadicCell> union_of_leaves(const std::vector<const std::vector<DyadicCell>*>& trees) {
    std::unordered_set<std::uint64_t> split;
    for (const std::vector<DyadicCell>* leaves : trees)
        for (DyadicCell c : *leaves)
            while (c.level > 0) {
                c = c.parent();
                if (!split.insert(cell_key(c)).second) break;  // its ancestors are in already
            }
    std::vector<DyadicCell> leaves;
    std::vector<DyadicCell> stack{{0, 0, 0}};
    while (!stack.empty()) {
        const DyadicCell c = stack.back();
        stack.pop_back();
        if (split.count(cell_key(c)))
            for (int q = 3; q >= 0; --q) stack.push_back(c.child(q & 1, q >> 1));
        else
            leaves.push_back(c);
    }
    return leaves;
}

/// What surface i's field holds in `s` (an empty list: B on every surface).
FieldQuantity quantity_of(const Solution& s, size_t i) {
    return i < s.quantity.size() ? s.quantity[i] : FieldQuantity::radiosity;
}

}  // namespace

std::vector<LightGroup> light_groups(const Scene& scene) {
    std::vector<LightGroup> groups;
    std::vector<int> group_of(scene.materials.size(), -1);
    for (size_t m = 0; m < scene.materials.size(); ++m)
        if (scene.materials[m].emits()) {
            group_of[m] = static_cast<int>(groups.size());
            groups.push_back({scene.materials[m].name, static_cast<int>(m), {}});
        }
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        const int g = group_of[size_t(scene.surfaces[i].material)];
        if (g >= 0) groups[size_t(g)].surfaces.push_back(static_cast<int>(i));
    }
    groups.erase(std::remove_if(groups.begin(), groups.end(),
                                [](const LightGroup& g) { return g.surfaces.empty(); }),
                 groups.end());
    return groups;
}

Scene weighted_scene(const Scene& scene, const std::vector<LightGroup>& groups,
                     const std::vector<double>& weights) {
    MBR_CHECK(groups.size() == weights.size());
    Scene out = scene;
    for (size_t g = 0; g < groups.size(); ++g) {
        const double w = weights[g];
        MBR_CHECK_MSG(std::isfinite(w) && w >= 0, "weight " << w << " of " << groups[g].name);
        MBR_CHECK(groups[g].material >= 0 && size_t(groups[g].material) < out.materials.size());
        Texture& E = out.materials[size_t(groups[g].material)].emission;
        if (w == 0)
            E = Texture::constant({0, 0, 0});
        else if (w != 1)
            E = E.scaled({w, w, w});
    }
    return out;
}

Scene light_group_scene(const Scene& scene, const std::vector<LightGroup>& groups, int group) {
    MBR_CHECK(group >= 0 && size_t(group) < groups.size());
    std::vector<double> weights(groups.size(), 0.0);
    weights[size_t(group)] = 1;
    return weighted_scene(scene, groups, weights);
}

Solution combine(const std::vector<const Solution*>& solutions,
                 const std::vector<double>& weights) {
    MBR_CHECK(!solutions.empty() && solutions.size() == weights.size());
    const size_t n = solutions[0]->radiosity.size();
    for (size_t g = 0; g < solutions.size(); ++g) {
        MBR_CHECK_MSG(std::isfinite(weights[g]) && weights[g] >= 0, "weight " << weights[g]);
        MBR_CHECK_MSG(solutions[g]->radiosity.size() == n && solutions[g]->unshot.size() == n,
                      "solution " << g << " has " << solutions[g]->radiosity.size()
                                  << " surfaces, the first " << n);
        // B and H fields do not add: a surface holds the same quantity in every solution; and
        // fields of two orders do not add either: a surface has one order in every solution
        // (the surfaces' orders may differ, SceneSurface::order).
        for (size_t i = 0; i < n; ++i) {
            MBR_CHECK_MSG(quantity_of(*solutions[g], i) == quantity_of(*solutions[0], i),
                          "surface " << i << " holds another quantity in solution " << g);
            MBR_CHECK_MSG(solutions[g]->radiosity[i].order() == solutions[0]->radiosity[i].order(),
                          "surface " << i << " has order " << solutions[g]->radiosity[i].order()
                                     << " in solution " << g << ", "
                                     << solutions[0]->radiosity[i].order() << " in the first");
        }
    }
    // DESIGN: the sum starts as a copy of the first solution, so that every per-surface member
    // of Solution that is not a field (quantity: what a field holds, ...) is carried over as it
    // is, including members added to Solution later; then the members that add are overwritten.
    // An H field adds as a B field does (H is linear in the emission too); its B = E + rho H
    // takes E from the scene it is viewed with, weighted_scene for a relit sum.
    Solution out = *solutions[0];
    std::vector<const SplineField*> fields(solutions.size());
    std::vector<const std::vector<DyadicCell>*> trees;
    const std::vector<DyadicCell> no_leaves;
    for (size_t i = 0; i < n; ++i) {
        for (size_t g = 0; g < solutions.size(); ++g) fields[g] = &solutions[g]->radiosity[i];
        out.radiosity[i] = weighted_sum(fields, weights);
        for (size_t g = 0; g < solutions.size(); ++g) fields[g] = &solutions[g]->unshot[i];
        out.unshot[i] = weighted_sum(fields, weights);
    }
    out.leaves.assign(n, {});
    for (size_t i = 0; i < n; ++i) {
        trees.clear();
        for (size_t g = 0; g < solutions.size(); ++g)
            if (weights[g] > 0)
                trees.push_back(i < solutions[g]->leaves.size() ? &solutions[g]->leaves[i]
                                                                : &no_leaves);
        out.leaves[i] = union_of_leaves(trees);
    }

    SolveStats& st = out.stats;
    st = SolveStats{};
    st.converged = true;
    for (size_t g = 0; g < solutions.size(); ++g) {
        const SolveStats& s = solutions[g]->stats;
        const double w = weights[g];
        st.shots += s.shots;
        st.seconds += s.seconds;
        st.emitted_power += w * s.emitted_power;
        st.unshot_power += w * s.unshot_power;
        st.ambient_power += w * s.ambient_power;
        st.kernel_evals += s.kernel_evals;
        st.rays += s.rays;
        st.peak_memory_bytes = std::max(st.peak_memory_bytes, s.peak_memory_bytes);
        if (w > 0) st.converged = st.converged && s.converged;
    }
    for (const SplineField& f : out.radiosity)
        if (!f.empty()) st.coefficients += long(f.channel(0).a.size());
    return out;
}

}  // namespace mbr
