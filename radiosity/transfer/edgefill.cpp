// radiosity/transfer/edgefill.cpp - stage 3 of one transfer: boundary values and derivatives,
// eq. (22), by the recursive edgefill (paper section 5).
#include "radiosity/transfer/edgefill.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "math/parallel.h"

namespace mbr {

namespace {

/// Edge e: 0 bottom (t = 0), 1 right (s = 1), 2 top (t = 1), 3 left (s = 0). The point of the
/// edge at parameter sigma, moved `inset` inside, and the unit step into the domain.
void edge_geometry(int e, double sigma, double inset, double& s, double& t, double& ds,
                   double& dt) {
    sigma = std::clamp(sigma, inset, 1 - inset);
    switch (e) {
        case 0:
            s = sigma;
            t = inset;
            ds = 0;
            dt = 1;
            break;
        case 1:
            s = 1 - inset;
            t = sigma;
            ds = -1;
            dt = 0;
            break;
        case 2:
            s = sigma;
            t = 1 - inset;
            ds = 0;
            dt = -1;
            break;
        default:
            s = inset;
            t = sigma;
            ds = 1;
            dt = 0;
            break;
    }
}

/// The size of the finest domain leaf touching edge e.
double finest_leaf_on_edge(const Forest& forest, int e) {
    double h = 1;
    for (int index : forest.leaves(Forest::Region::Domain)) {
        const Rect r = forest.node(index).cell.rect();
        const bool on = (e == 0 && r.y0 == 0) || (e == 1 && r.x1 == 1) || (e == 2 && r.y1 == 1) ||
                        (e == 3 && r.x0 == 0);
        if (on) h = std::min(h, r.width());
    }
    return h;
}

}  // namespace

void fill_boundary(ReceiverState& state, IncrementSampler& sampler) {
    const ReceiverOptions& opt = state.options;

    struct Node {
        double sigma;
        Rgb value, derivative;
    };
    // dB and its derivative with respect to the coordinate normal to edge e at sigma, eq. (22):
    // the forward divided difference into the domain, both points on the same shooter partition.
    double delta = 0, inset = 0;  // set per edge from its finest leaf
    auto evaluate = [&](int e, double sigma, int thread, long* evals) {
        double s, t, ds, dt;
        edge_geometry(e, sigma, inset, s, t, ds, dt);
        Rgb at_p, at_q;
        sampler.sample_pair(s, t, delta * ds, delta * dt, thread, at_p, at_q, evals);
        // Into the domain is +t (bottom), -s (right), -t (top), +s (left): d/dt or d/ds.
        const double sign = (e == 0 || e == 3) ? 1.0 : -1.0;
        const Rgb slope_inward = (1.0 / delta) * (at_q - at_p);
        // DESIGN: the point was moved `inset` inside; the value on the edge is its linear
        // extrapolation back to the edge (the limit from inside, to second order in inset).
        return Node{sigma, at_p - inset * slope_inward, sign * slope_inward};
    };

    for (int e = 0; e < 4; ++e) {
        EdgeProfile& profile = state.edges[e];
        profile = EdgeProfile{};
        profile.h_min = finest_leaf_on_edge(state.forest, e);
        delta = divided_difference_step * profile.h_min;
        inset = boundary_inset * profile.h_min;
        const double v_tol =
            std::max(opt.edgefill_tolerance * state.max_sample, opt.absolute_tolerance);
        const double d_tol = v_tol / profile.h_min;

        long evals = 0;
        // edgefill(a, b), level by level: `open` holds the segments still to bisect, whose
        // midpoints are evaluated in parallel; every evaluated point becomes a node.
        std::vector<Node> accepted_nodes{evaluate(e, 0.0, 0, &evals), evaluate(e, 1.0, 0, &evals)};
        std::vector<std::pair<Node, Node>> open{{accepted_nodes[0], accepted_nodes[1]}};
        while (!open.empty()) {
            const int n = static_cast<int>(open.size());
            std::vector<Node> mid(n);
            std::vector<long> mid_evals(n, 0);
            parallel_for(n, [&](int i) {
                mid[i] = evaluate(e, 0.5 * (open[i].first.sigma + open[i].second.sigma),
                                  thread_index(), &mid_evals[i]);
            });
            std::vector<std::pair<Node, Node>> next;
            for (int i = 0; i < n; ++i) {
                evals += mid_evals[i];
                accepted_nodes.push_back(mid[i]);
                const Node& n1 = open[i].first;
                const Node& n2 = open[i].second;
                const Node& n3 = mid[i];
                // Segments are bisected at least down to the finest boundary leaf and at most
                // edgefill_max_depth levels below it.
                const double half = 0.5 * (n2.sigma - n1.sigma);
                const bool may_stop = half <= profile.h_min * (1 + 1e-12);
                const bool at_cap =
                    half <= std::ldexp(profile.h_min, -opt.edgefill_max_depth) * (1 + 1e-12);
                if (opt.edgefill_test == EdgefillTest::Variation) {
                    // The paper's test on each half: |dB(s3) - dB(s1)| and |dB_t(s3) - dB_t(s1)|.
                    auto smooth = [&](const Node& a, const Node& b) {
                        return max_abs(a.value - b.value) <= v_tol &&
                               max_abs(a.derivative - b.derivative) <= d_tol;
                    };
                    if (!at_cap && !(may_stop && smooth(n3, n1))) next.push_back({n1, n3});
                    if (!at_cap && !(may_stop && smooth(n3, n2))) next.push_back({n3, n2});
                } else {
                    // The chord test: the midpoint agrees with linear interpolation of the ends.
                    const bool linear =
                        max_abs(n3.value - 0.5 * (n1.value + n2.value)) <= v_tol &&
                        max_abs(n3.derivative - 0.5 * (n1.derivative + n2.derivative)) <= d_tol;
                    if (!at_cap && !(may_stop && linear)) {
                        next.push_back({n1, n3});
                        next.push_back({n3, n2});
                    }
                }
            }
            open = std::move(next);
        }
        std::sort(accepted_nodes.begin(), accepted_nodes.end(),
                  [](const Node& a, const Node& b) { return a.sigma < b.sigma; });
        for (const Node& nd : accepted_nodes) {
            profile.sigma.push_back(nd.sigma);
            profile.value.push_back(nd.value);
            profile.derivative.push_back(nd.derivative);
        }
        state.stats.n_kernel_evals += evals;
        state.stats.n_increments += 2 * long(accepted_nodes.size());
        state.stats.n_boundary_increments += 2 * long(accepted_nodes.size());
        state.stats.n_boundary_nodes += static_cast<int>(accepted_nodes.size());
    }
}

}  // namespace mbr
