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

/// A node of edgefill: the edge parameter, dB there and its derivative normal to the edge.
struct EdgeNode {
    double sigma;
    Rgb value, derivative;
};

/// Eq. (22) at edge e's parameter sigma: dB and its derivative with respect to the coordinate
/// normal to the edge, the forward divided difference over `delta` into the domain, both points
/// on the same shooter partition.
EdgeNode edge_node(IncrementSampler& sampler, int e, double sigma, double delta, double inset,
                   int thread, long* evals) {
    double s, t, ds, dt;
    edge_geometry(e, sigma, inset, s, t, ds, dt);
    Rgb at_p, at_q;
    sampler.sample_pair(s, t, delta * ds, delta * dt, thread, at_p, at_q, evals);
    // Into the domain is +t (bottom), -s (right), -t (top), +s (left): d/dt or d/ds.
    const double sign = (e == 0 || e == 3) ? 1.0 : -1.0;
    const Rgb slope_inward = (1.0 / delta) * (at_q - at_p);
    // DESIGN: the point was moved `inset` inside; the value on the edge is its linear
    // extrapolation back to the edge (the limit from inside, to second order in inset).
    return EdgeNode{sigma, at_p - inset * slope_inward, sign * slope_inward};
}

/// The paper's edgefill test on one half of a segment (section 5): |dB(s3) - dB(s1)| and
/// |dB_t(s3) - dB_t(s1)| within the tolerances, so that the half may be interpolated linearly.
bool variation_small(const EdgeNode& a, const EdgeNode& b, double v_tol, double d_tol) {
    return max_abs(a.value - b.value) <= v_tol && max_abs(a.derivative - b.derivative) <= d_tol;
}

/// Beyond the paper (EdgefillTest::Linearity): the chord test, the midpoint agrees with the
/// linear interpolation of the segment's ends, in value and derivative.
bool chord_agrees(const EdgeNode& n1, const EdgeNode& n2, const EdgeNode& mid, double v_tol,
                  double d_tol) {
    return max_abs(mid.value - 0.5 * (n1.value + n2.value)) <= v_tol &&
           max_abs(mid.derivative - 0.5 * (n1.derivative + n2.derivative)) <= d_tol;
}

/// edgefill(a, b) along edge e, level by level: the segments still to bisect have their
/// midpoints evaluated in parallel; every evaluated point becomes a node of the profile.
/// Segments are bisected at least down to the finest boundary leaf and at most
/// edgefill_max_depth levels below it.
EdgeProfile edgefill(const ReceiverState& state, IncrementSampler& sampler, int e, long* evals) {
    const ReceiverOptions& opt = state.options;
    EdgeProfile profile;
    profile.h_min = finest_leaf_on_edge(state.forest, e);
    const double delta = divided_difference_step * profile.h_min;
    const double inset = boundary_inset * profile.h_min;
    const double v_tol =
        std::max(opt.edgefill_tolerance * state.max_sample, opt.absolute_tolerance);
    const double d_tol = v_tol / profile.h_min;

    std::vector<EdgeNode> nodes{edge_node(sampler, e, 0.0, delta, inset, 0, evals),
                                edge_node(sampler, e, 1.0, delta, inset, 0, evals)};
    std::vector<std::pair<EdgeNode, EdgeNode>> open{{nodes[0], nodes[1]}};
    while (!open.empty()) {
        const int n = static_cast<int>(open.size());
        std::vector<EdgeNode> mid(n);
        std::vector<long> mid_evals(n, 0);
        parallel_for(n, [&](int i) {
            const double sigma = 0.5 * (open[i].first.sigma + open[i].second.sigma);
            mid[i] = edge_node(sampler, e, sigma, delta, inset, thread_index(), &mid_evals[i]);
        });
        std::vector<std::pair<EdgeNode, EdgeNode>> next;
        for (int i = 0; i < n; ++i) {
            *evals += mid_evals[i];
            nodes.push_back(mid[i]);
            const EdgeNode& n1 = open[i].first;
            const EdgeNode& n2 = open[i].second;
            const EdgeNode& n3 = mid[i];
            const double half = 0.5 * (n2.sigma - n1.sigma);
            const bool may_stop = half <= profile.h_min * (1 + 1e-12);
            const bool at_cap =
                half <= std::ldexp(profile.h_min, -opt.edgefill_max_depth) * (1 + 1e-12);
            if (at_cap) continue;
            if (opt.edgefill_test == EdgefillTest::Variation) {
                if (!(may_stop && variation_small(n3, n1, v_tol, d_tol))) next.push_back({n1, n3});
                if (!(may_stop && variation_small(n3, n2, v_tol, d_tol))) next.push_back({n3, n2});
            } else if (!(may_stop && chord_agrees(n1, n2, n3, v_tol, d_tol))) {
                next.push_back({n1, n3});
                next.push_back({n3, n2});
            }
        }
        open = std::move(next);
    }
    std::sort(nodes.begin(), nodes.end(),
              [](const EdgeNode& a, const EdgeNode& b) { return a.sigma < b.sigma; });
    for (const EdgeNode& nd : nodes) {
        profile.sigma.push_back(nd.sigma);
        profile.value.push_back(nd.value);
        profile.derivative.push_back(nd.derivative);
    }
    return profile;
}

}  // namespace

void fill_boundary(ReceiverState& state, IncrementSampler& sampler) {
    for (int e = 0; e < 4; ++e) {
        long evals = 0;
        state.edges[e] = edgefill(state, sampler, e, &evals);
        const long n_nodes = long(state.edges[e].sigma.size());
        state.stats.n_kernel_evals += evals;
        state.stats.n_increments += 2 * n_nodes;
        state.stats.n_boundary_increments += 2 * n_nodes;
        state.stats.n_boundary_nodes += static_cast<int>(n_nodes);
    }
}

}  // namespace mbr
