// radiosity/transfer/expanded_domain.cpp - stage 4 of one transfer: the expanded domain (paper
// section 5, Figure 5) sampled by the extrapolation of section 6, eqs. (23)-(27).
#include "radiosity/transfer/expanded_domain.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "radiosity/transfer/gauss_points.h"
#include "radiosity/transfer/scale_adjustment.h"

namespace mbr {

namespace {

/// Per-channel clamp of a derivative into [-bound, bound].
Rgb clamp_rgb(Rgb d, double bound) {
    for (int c = 0; c < 3; ++c) d[c] = std::clamp(d[c], -bound, bound);
    return d;
}

/// Closed rectangles meet (touching counts).
bool touches(const Rect& a, const Rect& b) {
    return a.x0 <= b.x1 && b.x0 <= a.x1 && a.y0 <= b.y1 && b.y0 <= a.y1;
}

}  // namespace

namespace {

/// The decay profiles of the higher-order extrapolation in units of the boundary cell:
/// f(x) = v phi0(x) + w f'(0) phi1(x), x >= 0 the distance from the boundary.
void decay_profiles(Extrapolation kind, double x, double& phi0, double& phi1) {
    if (kind == Extrapolation::Cubic) {
        // Eq. (27): value and derivative match at the boundary and vanish from x = 1 on.
        if (x >= 1) {
            phi0 = phi1 = 0;
            return;
        }
        phi0 = 1 - 3 * x * x + 2 * x * x * x;
        phi1 = x - 2 * x * x + x * x * x;
        return;
    }
    // Eq. (26): a C^1 quadratic on [0,1] and [1,2], zero with zero derivative from x = 2 on.
    if (x >= 2) {
        phi0 = phi1 = 0;
        return;
    }
    if (x <= 1) {
        phi0 = 1 - 0.5 * x * x;
        phi1 = x - 0.75 * x * x;
    } else {
        phi0 = 0.5 * (2 - x) * (2 - x);
        phi1 = 0.25 * (2 - x) * (2 - x);
    }
}

}  // namespace

namespace {
/// Linear extrapolation (23)-(25), each channel kept within the samples' range widened by its
/// own width on both sides when clamp_values is set.
Rgb clamp_to_samples(const ReceiverState& state, Rgb v) {
    if (!state.options.clamp_values) return v;
    for (int c = 0; c < 3; ++c) {
        const double span = state.sample_hi[c] - state.sample_lo[c];
        v[c] = std::clamp(v[c], state.sample_lo[c] - span, state.sample_hi[c] + span);
    }
    return v;
}
}  // namespace

namespace {
/// DESIGN: derivatives are clamped so that the extrapolation changes by at most clamp_factor *
/// max|dB| over one of the finest boundary leaves of that edge.
double clamp_bound(const ReceiverState& state, const EdgeProfile& p) {
    return state.options.clamp_factor * state.max_sample / p.h_min;
}
}  // namespace

EdgeValue edge_value(const ReceiverState& state, int e, double sigma) {
    const EdgeProfile& p = state.edges[e];
    EdgeValue out;
    p.at(sigma, out.v, out.d);
    out.d = clamp_rgb(out.d, clamp_bound(state, p));
    return out;
}

Rgb extrapolate_side(const ReceiverState& state, int e, const EdgeValue& at_foot, double offset) {
    const ReceiverOptions& opt = state.options;
    if (opt.extrapolation == Extrapolation::Linear)
        return clamp_to_samples(state, at_foot.v + offset * at_foot.d);  // eq. (23)
    const double w = state.edges[e].h_min, x = std::fabs(offset) / w;
    const Rgb d_out = (offset < 0 ? -1.0 : 1.0) * at_foot.d;  // along the outward normal
    double phi0, phi1;
    decay_profiles(opt.extrapolation, x, phi0, phi1);
    return phi0 * at_foot.v + (w * phi1) * d_out;
}

SidePatch side_patch(double s, double t) {
    const int si = s < 0 ? -1 : (s > 1 ? 1 : 0);
    const int ti = t < 0 ? -1 : (t > 1 ? 1 : 0);
    const int e = ti < 0 ? 0 : (si > 0 ? 1 : (ti > 0 ? 2 : 3));
    const double foot = (e == 0 || e == 2) ? s : t;
    const double offset = e == 0 ? t : (e == 1 ? s - 1 : (e == 2 ? t - 1 : s));
    return {e, foot, offset};
}

CornerValue corner_value(const ReceiverState& state, double s_c, double t_c) {
    const EdgeProfile& horizontal = state.edges[t_c < 0.5 ? 0 : 2];  // carries d/dt there
    const EdgeProfile& vertical = state.edges[s_c > 0.5 ? 1 : 3];    // carries d/ds there
    CornerValue c;
    Rgb v2;
    horizontal.at(s_c, c.v, c.d_t);
    vertical.at(t_c, v2, c.d_s);
    c.d_t = clamp_rgb(c.d_t, clamp_bound(state, horizontal));
    c.d_s = clamp_rgb(c.d_s, clamp_bound(state, vertical));
    return c;
}

Rgb extrapolate_corner(const ReceiverState& state, const CornerValue& c, double s, double t) {
    const ReceiverOptions& opt = state.options;
    const int si = s < 0 ? -1 : 1, ti = t < 0 ? -1 : 1;
    const double s_c = si > 0 ? 1 : 0, t_c = ti > 0 ? 1 : 0;
    if (opt.extrapolation == Extrapolation::Linear)
        return clamp_to_samples(state, c.v + (s - s_c) * c.d_s + (t - t_c) * c.d_t);  // (24-25)
    const double w_s = state.edges[si > 0 ? 1 : 3].h_min, w_t = state.edges[ti < 0 ? 0 : 2].h_min;
    double phi0_x, phi1_x, phi0_y, phi1_y;
    decay_profiles(opt.extrapolation, std::fabs(s - s_c) / w_s, phi0_x, phi1_x);
    decay_profiles(opt.extrapolation, std::fabs(t - t_c) / w_t, phi0_y, phi1_y);
    const Rgb d_s_out = double(si) * c.d_s, d_t_out = double(ti) * c.d_t;
    return (phi0_x * phi0_y) * c.v + (w_s * phi1_x * phi0_y) * d_s_out +
           (w_t * phi0_x * phi1_y) * d_t_out;
}

Rgb extrapolate(const ReceiverState& state, double s, double t) {
    const int si = s < 0 ? -1 : (s > 1 ? 1 : 0);
    const int ti = t < 0 ? -1 : (t > 1 ? 1 : 0);
    MBR_CHECK_MSG(si != 0 || ti != 0, "extrapolate inside the domain at " << s << ", " << t);
    if (si == 0 || ti == 0) {
        // Patches 1, 3, 5, 7: along the edge normal, eq. (23) or (26)/(27), from the edge's
        // value at the point's foot, at its signed offset (t - c or s - b) from the edge.
        const SidePatch side = side_patch(s, t);
        return extrapolate_side(state, side.e, edge_value(state, side.e, side.foot), side.offset);
    }
    // Patches 0, 2, 4, 6: from the corner (s_c, t_c), eqs. (24)-(25) or the tensor form.
    return extrapolate_corner(state, corner_value(state, si > 0 ? 1 : 0, ti > 0 ? 1 : 0), s, t);
}

// ---- Stage 4: the expanded domain --------------------------------------------------------

void expand_domain(ReceiverState& state, IncrementSampler& sampler) {
    const ReceiverOptions& opt = state.options;
    const int m = opt.m;
    Forest& forest = state.forest;

    // Domain leaves on the boundary fix the size of the expanded cells next to them. Every
    // leaf's fulcrums (and the expanded ones half a support outside) need their rhombus inside
    // the ring: a leaf of size h at distance g from the boundary asks for a ring of
    // (r + m + 1) h - g, r the rhombus radius in cells.
    std::vector<Rect> boundary;
    double h_fine = 1, width = 0;
    for (int index : forest.leaves(Forest::Region::Domain)) {
        const Rect r = forest.node(index).cell.rect();
        if (r.x0 == 0 || r.y0 == 0 || r.x1 == 1 || r.y1 == 1) {
            boundary.push_back(r);
            h_fine = std::min(h_fine, r.width());
        }
        const double gap = std::min({r.x0, r.y0, 1 - r.x1, 1 - r.y1});
        width = std::max(width, (state.rhombus_radius + m + 1) * r.width() - gap);
    }
    forest.grow(static_cast<int>(std::ceil(width)));
    const int fine_level = static_cast<int>(std::lround(-std::log2(h_fine)));

    // The smallest domain leaf an expanded cell touches (0 when it touches none).
    auto smallest_touching = [&](const Rect& r) {
        double h = 0;
        for (const Rect& b : boundary)
            if (touches(r, b)) h = h == 0 ? b.width() : std::min(h, b.width());
        return h;
    };
    const GaussLegendre rule_c = gauss_legendre((m + 1) / 2), rule_m = gauss_legendre(m);
    auto mean = [&](const Rect& r, const GaussLegendre& rule) {
        Rgb sum;
        double s[16], t[16];
        gauss_points(r, rule, s, t);
        for (int a = 0; a < rule.n(); ++a)
            for (int b = 0; b < rule.n(); ++b)
                sum += (0.25 * rule.w[a] * rule.w[b]) * extrapolate(state, s[a], t[b]);
        return sum;
    };

    // Subdivide each expanded root: cells touching the domain down to the size of the leaves
    // they touch (the scale-matching rule of section 6); elsewhere the oracle of stage 1 on the
    // extrapolated values, no finer than the finest boundary leaf.
    std::vector<std::pair<int, bool>> work;  // node, "split once more and stop" already used
    const int K = forest.extent();
    for (int J = -K; J <= K; ++J)
        for (int I = -K; I <= K; ++I)
            if (I != 0 || J != 0) work.push_back({forest.root(I, J), false});
    while (!work.empty()) {
        auto [index, final_split] = work.back();
        work.pop_back();
        const DyadicCell c = forest.node(index).cell;
        const Rect r = c.rect();
        bool split = false, once_more = false;
        const double h_touch = smallest_touching(r);
        if (h_touch > 0 && r.width() > h_touch) {
            split = true;
        } else if (!final_split && c.level < fine_level) {
            const Rgb coarse = mean(r, rule_c), fine = mean(r, rule_m);
            const double tol =
                opt.oracle_tolerance * std::max(max_abs(fine), 0.01 * state.max_sample);
            split = true;
            once_more = max_abs(fine - coarse) <= tol;
        }
        if (!split) continue;
        const int first = forest.split(index);
        for (int ch = 0; ch < 4; ++ch) work.push_back({first + ch, final_split || once_more});
    }
    // NeighAdjust over the whole forest; if it splits a domain leaf, sample the new ones.
    adjust_neighbour_scales(forest, Forest::Region::All);
    sample_leaves(state, sampler);

    // Extrapolated samples on every expanded leaf.
    std::vector<int> expanded = forest.leaves(Forest::Region::Expanded);
    const size_t first_block = state.samples.size() / (size_t(m) * m);
    state.samples.resize(state.samples.size() + expanded.size() * m * m);
    const int n = static_cast<int>(expanded.size());
    for (int c = 0; c < n; ++c) forest.node(expanded[c]).samples = int(first_block + c);
    parallel_for(n, [&](int c) {
        const Forest::Node& node = forest.node(expanded[c]);
        double s[16], t[16];
        gauss_points(node.cell.rect(), rule_m, s, t);
        Rgb* out = &state.samples[size_t(node.samples) * m * m];
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) out[a * m + b] = extrapolate(state, s[a], t[b]);
    });
    state.stats.n_expanded_leaves = n;
}

}  // namespace mbr
