// radiosity/transfer/receiver.cpp - the per-receiver pipeline of section 5, one function per stage.
#include "radiosity/transfer/receiver.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <cmath>
#include <set>

#include "math/bspline.h"
#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "math/polynomial.h"


namespace mbr {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Per-channel clamp of a derivative into [-bound, bound].
Rgb clamp_rgb(Rgb d, double bound) {
    for (int c = 0; c < 3; ++c) d[c] = std::clamp(d[c], -bound, bound);
    return d;
}

/// Closed rectangles meet (touching counts).
bool touches(const Rect& a, const Rect& b) {
    return a.x0 <= b.x1 && b.x0 <= a.x1 && a.y0 <= b.y1 && b.y0 <= a.y1;
}

/// Distance in the (s,t) plane, in the 1-norm, from a point to a rectangle (0 inside): a cell
/// meets the rhombus |s - cx| + |t - cy| <= R exactly when this is at most R.
double rhombus_distance(const Rect& r, Vec2 c) {
    const double dx = std::max({0.0, r.x0 - c.x, c.x - r.x1});
    const double dy = std::max({0.0, r.y0 - c.y, c.y - r.y1});
    return dx + dy;
}

/// The m x m Gauss-Legendre points of a rectangle, as (s_a, t_b) coordinates.
void gauss_points(const Rect& r, const GaussLegendre& rule, double* s, double* t) {
    for (int a = 0; a < rule.n(); ++a) {
        s[a] = r.x0 + 0.5 * (rule.x[a] + 1) * r.width();
        t[a] = r.y0 + 0.5 * (rule.x[a] + 1) * r.height();
    }
}

}  // namespace

// ---- Fulcrums and edges ------------------------------------------------------------------

Vec2 Fulcrum::position(int m) const {
    const double h = std::ldexp(1.0, -level);
    return {(k + 0.5 * m) * h, (l + 0.5 * m) * h};
}

void EdgeProfile::at(double s, Rgb& v, Rgb& d) const {
    MBR_CHECK(!sigma.empty());
    if (s <= sigma.front()) {
        v = value.front();
        d = derivative.front();
        return;
    }
    if (s >= sigma.back()) {
        v = value.back();
        d = derivative.back();
        return;
    }
    const size_t i = std::upper_bound(sigma.begin(), sigma.end(), s) - sigma.begin();  // >= 1
    const double w = (s - sigma[i - 1]) / (sigma[i] - sigma[i - 1]);
    v = (1 - w) * value[i - 1] + w * value[i];
    d = (1 - w) * derivative[i - 1] + w * derivative[i];
}

// ---- Sample values, eq. (21) -------------------------------------------------------------

IncrementSampler::IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                                   const QuadratureOptions& options,
                                   const OcclusionContext* occlusion)
    : shooter_(shooter), receiver_(receiver) {
    MBR_CHECK(receiver.surface != nullptr && receiver.reflectance);
    const std::optional<Plane> plane = surface_plane(*receiver.surface);
    for (int i = 0; i < thread_count(); ++i) {
        integrators_.push_back(std::make_unique<IncrementIntegrator>(shooter, options, occlusion));
        if (plane) integrators_.back()->set_receiver_plane(*plane);
    }
    rays_.assign(integrators_.size(), 0);
}

long IncrementSampler::n_rays() const {
    long n = 0;
    for (long r : rays_) n += r;
    return n;
}

Rgb IncrementSampler::sample(double s, double t, int thread, long* n_kernel_evals,
                             bool* converged) {
    // Eq. (21): dB_i(s,t) = rho_i(s,t) * int int F VIS B_h A_h du dv (at the nearest visible
    // point when (s, t) is hidden: radiosity/visibility/hidden_regions.h).
    const Vec2 at = receiver_.hidden ? receiver_.hidden->substitute(s, t) : Vec2{s, t};
    const SurfacePoint p = receiver_.surface->evaluate(at.x, at.y);
    const IncrementIntegrator::Result r = integrators_[thread]->integrate(p);
    if (n_kernel_evals) *n_kernel_evals += r.n_evaluations;
    rays_[thread] += r.n_rays;
    if (converged) *converged = r.converged;
    return receiver_.reflectance(s, t) * r.value;
}

void IncrementSampler::sample_pair(double s, double t, double ds, double dt, int thread,
                                   Rgb& at_p, Rgb& at_q, long* n_kernel_evals) {
    IncrementIntegrator& integrator = *integrators_[thread];
    if (receiver_.hidden && receiver_.hidden->hidden(s, t)) {  // constant extension: no slope
        at_p = at_q = sample(s, t, thread, n_kernel_evals);
        return;
    }
    const SurfacePoint p = receiver_.surface->evaluate(s, t);
    if (integrator.analytic()) {  // closed form at both points: no partition to share
        const SurfacePoint q = receiver_.surface->evaluate(s + ds, t + dt);
        at_p = receiver_.reflectance(s, t) * integrator.integrate(p).value;
        at_q = receiver_.reflectance(s + ds, t + dt) * integrator.integrate(q).value;
        return;
    }
    const IncrementIntegrator::Result r = integrator.integrate(p, true);
    const SurfacePoint q = receiver_.surface->evaluate(s + ds, t + dt);
    long evals = r.n_evaluations;
    rays_[thread] += r.n_rays;
    const Rgb value_q = integrator.integrate_on(q, r.partition, &evals, &rays_[thread], &r);
    if (n_kernel_evals) *n_kernel_evals += evals;
    at_p = receiver_.reflectance(s, t) * r.value;
    at_q = receiver_.reflectance(s + ds, t + dt) * value_q;
}

// ---- Stage 1: oracle subdivision ---------------------------------------------------------

namespace {

/// Distance from x to a planar shooter's closed polygon (its frame and outline).
double distance_to_shooter(const ShooterPlane& plane, Vec3 x) {
    const double height = dot(x - plane.origin, plane.normal);
    const Vec2 q = plane.to_plane(x);
    double across = 0;
    if (!contains(plane.outline, q)) {
        across = std::numeric_limits<double>::infinity();
        const size_t n = plane.outline.size();
        for (size_t k = 0; k < n; ++k) {
            const Vec2 a = plane.outline[k], b = plane.outline[(k + 1) % n];
            const Vec2 e = b - a;
            const double len2 = dot(e, e);
            const double t = len2 > 0 ? std::clamp(dot(q - a, e) / len2, 0.0, 1.0) : 0.0;
            const Vec2 d = q - (a + t * e);
            across = std::min(across, std::sqrt(dot(d, d)));
        }
    }
    return std::sqrt(height * height + across * across);
}

/// True when the receiver's cell comes within half its size of a planar shooter: its corners,
/// edge midpoints and centre are tested (the contact lines of scenes are straight).
bool touches_shooter(const Surface& receiver, const ShooterPlane& plane, const Rect& r) {
    Vec3 p[9];
    int k = 0;
    for (double t : {r.y0, 0.5 * (r.y0 + r.y1), r.y1})
        for (double s : {r.x0, 0.5 * (r.x0 + r.x1), r.x1}) p[k++] = receiver.evaluate(s, t).position;
    const double size = std::max(length(p[8] - p[0]), length(p[6] - p[2]));
    for (const Vec3& x : p)
        if (distance_to_shooter(plane, x) <= 0.5 * size) return true;
    return false;
}

}  // namespace

void subdivide_by_oracle(ReceiverState& state, IncrementSampler& sampler) {
    const ReceiverOptions& opt = state.options;
    const int m = opt.m;
    const GaussLegendre rule_c = gauss_legendre((m + 1) / 2), rule_m = gauss_legendre(m);
    Forest& forest = state.forest;
    TransferStats& stats = state.stats;

    // The mean of dB over a cell with an n x n rule; counts its (21) evaluations and, when
    // asked, keeps the largest sample.
    auto cell_mean = [&](const Rect& r, const GaussLegendre& rule, int thread, long* evals,
                         long* increments, double* largest = nullptr) {
        Rgb sum;
        double s[16], t[16];
        gauss_points(r, rule, s, t);
        for (int a = 0; a < rule.n(); ++a)
            for (int b = 0; b < rule.n(); ++b) {
                const Rgb v = sampler.sample(s[a], t[b], thread, evals);
                if (largest) *largest = std::max(*largest, max_abs(v));
                sum += (0.25 * rule.w[a] * rule.w[b]) * v;
                ++*increments;
            }
        return sum;
    };

    // Beyond the paper (OracleTest::Interpolation): the tensor polynomial through the m x m
    // samples must predict the samples at the ceil(m/2)^2 points within the tolerance, point by
    // point: a direct test of "can be approximated by a double (m-1)th order tensor product
    // polynomial", which a kink of a shadow boundary fails even where the two means agree.
    std::vector<double> c_nodes(rule_c.x.begin(), rule_c.x.end());
    const std::vector<double> L = lagrange_matrix(rule_m, c_nodes);  // [p * m + a]
    auto interpolation_agrees = [&](const Rect& r, int thread, long* evals, long* increments,
                                    double scale) {
        const int nc = rule_c.n();
        double s_m[16], t_m[16], s_c[16], t_c[16];
        gauss_points(r, rule_m, s_m, t_m);
        gauss_points(r, rule_c, s_c, t_c);
        Rgb f_m[256], f_c[64];
        double largest = 0;
        for (int a = 0; a < m; ++a)
            for (int b = 0; b < m; ++b) {
                f_m[a * m + b] = sampler.sample(s_m[a], t_m[b], thread, evals);
                largest = std::max(largest, max_abs(f_m[a * m + b]));
            }
        for (int a = 0; a < nc; ++a)
            for (int b = 0; b < nc; ++b) {
                f_c[a * nc + b] = sampler.sample(s_c[a], t_c[b], thread, evals);
                largest = std::max(largest, max_abs(f_c[a * nc + b]));
            }
        *increments += m * m + nc * nc;
        const double tol = std::max(opt.oracle_tolerance * std::max(largest, 0.01 * scale),
                                    opt.oracle_share * opt.absolute_tolerance);
        for (int a = 0; a < nc; ++a)
            for (int b = 0; b < nc; ++b) {
                Rgb p;
                for (int i = 0; i < m; ++i)
                    for (int j = 0; j < m; ++j) p += (L[a * m + i] * L[b * m + j]) * f_m[i * m + j];
                if (max_abs(p - f_c[a * nc + b]) > tol) return false;
            }
        return true;
    };

    // Scale for the oracle's floor: the largest of the m x m samples of the whole domain
    // (not needed when the bounds leave the oracle nothing to decide).
    double scale = 0;
    if (opt.min_depth < opt.max_depth) {
        long evals = 0, increments = 0;
        cell_mean(Rect{0, 1, 0, 1}, rule_m, 0, &evals, &increments, &scale);
        stats.n_kernel_evals += evals;
        stats.n_increments += increments;
        stats.n_oracle_increments += increments;
    }
    // DESIGN (cost follows energy): a receiver whose largest root sample is below
    // weak_receiver times the absolute tolerance starts the oracle at the root.
    int min_depth = opt.min_depth;
    if (opt.weak_receiver > 0 && opt.absolute_tolerance > 0 && scale < opt.weak_receiver * opt.absolute_tolerance)
        min_depth = 0;

    // The shooter's plane when it is planar (the contact rule of ReceiverOptions::contact_depth
    // and contact_oracle_test).
    const bool contact_test = opt.contact_oracle_test != opt.oracle_test;
    const ShooterPlane* contact_plane =
        opt.contact_depth > 0 || contact_test ? sampler.integrator(0).shooter_plane() : nullptr;

    enum Action { Leaf, Split, SplitOnceMore };
    std::vector<int> frontier{forest.domain_root()};
    while (!frontier.empty()) {
        const int n = static_cast<int>(frontier.size());
        std::vector<Action> action(n, Leaf);
        std::vector<long> evals(n, 0), increments(n, 0);
        parallel_for(n, [&](int c) {
            const DyadicCell cell = forest.node(frontier[c]).cell;
            if (cell.level < min_depth) {
                action[c] = Split;
                return;
            }
            // Whether the cell touches the shooter, asked only when an answer matters.
            const bool ask = contact_plane && (cell.level < opt.contact_depth ||
                                               (contact_test && cell.level < opt.max_depth));
            const bool contact =
                ask && touches_shooter(*sampler.receiver().surface, *contact_plane, cell.rect());
            if (cell.level < opt.contact_depth && contact) {
                action[c] = Split;
                return;
            }
            if (cell.level >= opt.max_depth) return;  // a leaf
            const int th = thread_index();
            // DESIGN: a cell touching the shooter takes contact_oracle_test (`set
            // contact_oracle interpolation`): there dB grows like d log d, whose two means
            // agree long before the spline can follow it.
            const OracleTest test = contact ? opt.contact_oracle_test : opt.oracle_test;
            if (test == OracleTest::Interpolation) {
                action[c] = interpolation_agrees(cell.rect(), th, &evals[c], &increments[c], scale)
                                ? SplitOnceMore
                                : Split;
                return;
            }
            // Section 6 "Oracle": ceil(m/2)^2 against m^2 Gauss-Legendre points.
            const Rgb coarse = cell_mean(cell.rect(), rule_c, th, &evals[c], &increments[c]);
            const Rgb fine = cell_mean(cell.rect(), rule_m, th, &evals[c], &increments[c]);
            // DESIGN: relative agreement, with a floor at 1% of the largest value in the domain
            // so that nearly dark cells do not split forever.
            const double tol = std::max(opt.oracle_tolerance * std::max(max_abs(fine), 0.01 * scale),
                                        opt.oracle_share * opt.absolute_tolerance);
            action[c] = max_abs(fine - coarse) <= tol ? SplitOnceMore : Split;
        });
        std::vector<int> next;
        for (int c = 0; c < n; ++c) {
            stats.n_kernel_evals += evals[c];
            stats.n_increments += increments[c];
            stats.n_oracle_increments += increments[c];
            if (action[c] == Leaf) continue;
            const int first = forest.split(frontier[c]);
            if (action[c] == Split)
                for (int ch = 0; ch < 4; ++ch) next.push_back(first + ch);
            // SplitOnceMore: "nearly sufficient ... stopped after once more": children are leaves.
        }
        frontier = std::move(next);
    }
}

// ---- Stage 2: scale adjustment and samples -----------------------------------------------

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
                const bool inner = x >= 2 * c.i && x <= 2 * c.i + 1 && y >= 2 * c.j && y <= 2 * c.j + 1;
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

void sample_leaves(ReceiverState& state, IncrementSampler& sampler) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    std::vector<int> todo;
    for (int index : state.forest.leaves(Forest::Region::Domain))
        if (state.forest.node(index).samples < 0) todo.push_back(index);
    const size_t first_block = state.samples.size() / (size_t(m) * m);
    state.samples.resize(state.samples.size() + todo.size() * m * m);
    for (size_t c = 0; c < todo.size(); ++c) state.forest.node(todo[c]).samples = int(first_block + c);

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
        const Rgb* out = &state.samples[size_t(state.forest.node(todo[c]).samples) * m * m];
        for (int i = 0; i < m * m; ++i) {
            state.max_sample = std::max(state.max_sample, max_abs(out[i]));
            for (int k = 0; k < 3; ++k) {
                state.sample_lo[k] = std::min(state.sample_lo[k], out[i][k]);
                state.sample_hi[k] = std::max(state.sample_hi[k], out[i][k]);
            }
        }
    }
}

// ---- Stage 3: boundary values and derivatives, eq. (22) and edgefill ---------------------

namespace {

/// Edge e: 0 bottom (t = 0), 1 right (s = 1), 2 top (t = 1), 3 left (s = 0). The point of the
/// edge at parameter sigma, moved `inset` inside, and the unit step into the domain.
void edge_geometry(int e, double sigma, double inset, double& s, double& t, double& ds, double& dt) {
    sigma = std::clamp(sigma, inset, 1 - inset);
    switch (e) {
        case 0: s = sigma; t = inset; ds = 0; dt = 1; break;
        case 1: s = 1 - inset; t = sigma; ds = -1; dt = 0; break;
        case 2: s = sigma; t = 1 - inset; ds = 0; dt = -1; break;
        default: s = inset; t = sigma; ds = 1; dt = 0; break;
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
        delta = opt.divided_difference_step * profile.h_min;
        inset = opt.boundary_inset * profile.h_min;
        const double v_tol = std::max(opt.edgefill_tolerance * state.max_sample, opt.absolute_tolerance);
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
                mid[i] = evaluate(e, 0.5 * (open[i].first.sigma + open[i].second.sigma), thread_index(),
                                  &mid_evals[i]);
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
                const bool at_cap = half <= std::ldexp(profile.h_min, -opt.edgefill_max_depth) * (1 + 1e-12);
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

// ---- Extrapolation, eqs. (23)-(27) -------------------------------------------------------

namespace {

/// The decay profiles of the higher-order extrapolation in units of the boundary cell:
/// f(x) = v phi0(x) + w f'(0) phi1(x), x >= 0 the distance from the boundary.
void decay_profiles(Extrapolation kind, double x, double& phi0, double& phi1) {
    if (kind == Extrapolation::Cubic) {
        // Eq. (27): value and derivative match at the boundary and vanish from x = 1 on.
        if (x >= 1) { phi0 = phi1 = 0; return; }
        phi0 = 1 - 3 * x * x + 2 * x * x * x;
        phi1 = x - 2 * x * x + x * x * x;
        return;
    }
    // Eq. (26): a C^1 quadratic on [0,1] and [1,2], zero with zero derivative from x = 2 on.
    if (x >= 2) { phi0 = phi1 = 0; return; }
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

Rgb extrapolate(const ReceiverState& state, double s, double t) {
    const ReceiverOptions& opt = state.options;
    const int si = s < 0 ? -1 : (s > 1 ? 1 : 0);
    const int ti = t < 0 ? -1 : (t > 1 ? 1 : 0);
    MBR_CHECK_MSG(si != 0 || ti != 0, "extrapolate inside the domain at " << s << ", " << t);
    // DESIGN: derivatives are clamped so that the extrapolation changes by at most
    // clamp_factor * max|dB| over one of the finest boundary leaves of that edge.
    auto clamp_bound = [&](const EdgeProfile& p) {
        return opt.clamp_factor * state.max_sample / p.h_min;
    };
    const bool linear = opt.extrapolation == Extrapolation::Linear;

    if (si == 0 || ti == 0) {
        // Patches 1, 3, 5, 7: extrapolate along the edge normal, eq. (23) or (26)/(27).
        const int e = ti < 0 ? 0 : (si > 0 ? 1 : (ti > 0 ? 2 : 3));
        const EdgeProfile& p = state.edges[e];
        Rgb v, d;
        p.at((e == 0 || e == 2) ? s : t, v, d);
        d = clamp_rgb(d, clamp_bound(p));
        // Signed offset from the edge along its normal coordinate (t - c or s - b).
        const double offset = e == 0 ? t : (e == 1 ? s - 1 : (e == 2 ? t - 1 : s));
        if (linear) return clamp_to_samples(state, v + offset * d);  // eq. (23)
        const double w = p.h_min, x = std::fabs(offset) / w;
        const Rgb d_out = (offset < 0 ? -1.0 : 1.0) * d;  // derivative along the outward normal
        double phi0, phi1;
        decay_profiles(opt.extrapolation, x, phi0, phi1);
        return phi0 * v + (w * phi1) * d_out;
    }
    // Patches 0, 2, 4, 6: from the corner (s_c, t_c), eqs. (24)-(25) or the tensor form.
    const double s_c = si > 0 ? 1 : 0, t_c = ti > 0 ? 1 : 0;
    const EdgeProfile& horizontal = state.edges[ti < 0 ? 0 : 2];  // carries d/dt at the corner
    const EdgeProfile& vertical = state.edges[si > 0 ? 1 : 3];    // carries d/ds at the corner
    Rgb v, d_t, v2, d_s;
    horizontal.at(s_c, v, d_t);
    vertical.at(t_c, v2, d_s);
    d_t = clamp_rgb(d_t, clamp_bound(horizontal));
    d_s = clamp_rgb(d_s, clamp_bound(vertical));
    if (linear) return clamp_to_samples(state, v + (s - s_c) * d_s + (t - t_c) * d_t);  // (24), (25)
    const double w_s = vertical.h_min, w_t = horizontal.h_min;
    double phi0_x, phi1_x, phi0_y, phi1_y;
    decay_profiles(opt.extrapolation, std::fabs(s - s_c) / w_s, phi0_x, phi1_x);
    decay_profiles(opt.extrapolation, std::fabs(t - t_c) / w_t, phi0_y, phi1_y);
    const Rgb d_s_out = double(si) * d_s, d_t_out = double(ti) * d_t;
    return (phi0_x * phi0_y) * v + (w_s * phi1_x * phi0_y) * d_s_out +
           (w_t * phi0_x * phi1_y) * d_t_out;
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
            const double tol = opt.oracle_tolerance * std::max(max_abs(fine), 0.01 * state.max_sample);
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

void sample_split_leaves(ReceiverState& state) {
    const int m = state.options.m;
    const GaussLegendre rule = gauss_legendre(m);
    Forest& forest = state.forest;
    // Children come after their parents in the node array, so a parent's samples exist (from
    // (21), extrapolation or an earlier resampling) when its children are filled; nodes split
    // before stage 2 sampled anything have no samples and neither do their children.
    const std::vector<double> R[2] = {subcell_resample_matrix(rule, 1, 0), subcell_resample_matrix(rule, 1, 1)};
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

// ---- Stage 5: fulcrums -------------------------------------------------------------------

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
                for (int a = 0; a <= 1; ++a) here.push_back({c.level, c.i + a - m / 2, c.j + b - m / 2});
        }
        for (const Fulcrum& f : here)
            if (c.in_domain() || touches_domain(f)) out.push_back(f);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

// ---- Stage 6: projection in the rhombus, eq. (19) ----------------------------------------

namespace {
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
    return project(state, dn, make_projection_tables(state.options.m, dn, state.rhombus_radius, levels), f);
}

Rgb project(const ReceiverState& state, const DualTable& dn, const ProjectionTables& tables,
            const Fulcrum& f) {
    const int m = state.options.m;
    MBR_CHECK(tables.m == m);
    const Forest& forest = state.forest;
    const GaussLegendre& rule = tables.rule;
    const double scale = std::ldexp(1.0, f.level);  // x = 2^L s
    const Vec2 centre = f.position(m);
    const double R = state.rhombus_radius / scale;  // rhombus radius in parameter units

    // m x m Gauss-Legendre on a rectangle of the fulcrum's scale or finer, where DN_m(x - k) is
    // one polynomial piece: c += sum_a sum_b w_a w_b J DN(x_a - k) DN(y_b - l) dB_ab, with J the
    // Jacobian of [-1,1]^2 -> the rectangle in x = 2^L s units (not the area factor A_i).
    // Cells of exactly the fulcrum's scale take DN from the table of node values.
    Rgb sum;
    auto integrate_cell = [&](const Rect& r, const Rgb* f_ab) {
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
    };

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
    Rgb resampled[256];
    double channel_in[256], channel_out[256];
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
        if (levels <= 0) {
            integrate_cell(r, f_ab);
            continue;
        }
        // The leaf is coarser than the dual: fit the tensor polynomial of degree m-1 to its
        // samples (the Lagrange interpolant at the Gauss-Legendre nodes), split the leaf to
        // the fulcrum's scale and resample it on the sub-cells that meet the rhombus.
        MBR_CHECK_MSG(levels < int(tables.resample.size()), "no resampling table for " << levels << " levels");
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
            const int q1 = std::min(n_sub - 1, static_cast<int>(std::floor((centre.y + reach - r.y0) / h)));
            for (int q = q0; q <= q1; ++q) {
                const Rect sub{strip.x0, strip.x1, r.y0 + q * h, r.y0 + (q + 1) * h};
                if (rhombus_distance(sub, centre) > R) continue;
                const double* Ry = &block[size_t(q) * m * m];
                for (int c = 0; c < 3; ++c) {
                    for (int i = 0; i < m * m; ++i) channel_in[i] = f_ab[i][c];
                    resample(m, channel_in, Rx, Ry, channel_out);
                    for (int i = 0; i < m * m; ++i) resampled[i][c] = channel_out[i];
                }
                integrate_cell(sub, resampled);
            }
        }
    }
    return sum;
}

void project_in_rhombi(ReceiverState& state, const DualTable& dn) {
    // Fulcrums are no finer than the finest leaf and leaves no coarser than level 0.
    state.tables = std::make_shared<const ProjectionTables>(
        make_projection_tables(state.options.m, dn, state.rhombus_radius, finest_level(state.forest)));
    const ProjectionTables& tables = *state.tables;
    const int n = static_cast<int>(state.fulcrums.size());
    std::vector<Rgb> values(n);
    parallel_for(n, [&](int i) { values[i] = project(state, dn, tables, state.fulcrums[i]); });
    for (int i = 0; i < n; ++i) state.coefficients[state.fulcrums[i]] = values[i];
    state.stats.n_projections += n;
}

// ---- Stages 6 and 8 on the finest grid (unify_by_projection) -------------------------------

SplineField project_fine_grid(ReceiverState& state, const DualTable& dn) {
    const int m = state.options.m;
    const Forest& forest = state.forest;
    int J = 0;
    for (int index : forest.leaves(Forest::Region::Domain)) J = std::max(J, forest.node(index).cell.level);
    for (const Fulcrum& f : state.fulcrums) J = std::max(J, f.level);
    const ProjectionTables tables = make_projection_tables(m, dn, state.rhombus_radius, J);
    const GaussLegendre& rule = tables.rule;
    const int first = first_touching_index(m), n_coef = touching_count(m, J), cells = 1 << J;
    // Cells within reach of some coefficient: DN(x - k) is kept for |x - k - m/2| <= r.
    const double r = state.rhombus_radius;
    const int lo = static_cast<int>(std::floor(first + 0.5 * m - r)) - 1;
    const int hi = static_cast<int>(std::ceil(first + n_coef - 1 + 0.5 * m + r)) + 1;
    const int n_cells = hi - lo;  // cells lo .. hi - 1 along each axis
    const int n_nodes = n_cells * m;
    // f[(j m + b) * n_nodes + (i m + a)]: the value at node (a, b) of cell (lo + i, lo + j).
    std::vector<Rgb> f(size_t(n_nodes) * n_nodes);
    std::vector<std::vector<std::vector<double>>> resample_rows(J + 1);  // [levels][index] -> m x m
    for (int levels = 1; levels <= J; ++levels)
        for (int index = 0; index < (1 << levels); ++index)
            resample_rows[levels].push_back(subcell_resample_matrix(rule, levels, index));
    parallel_for(n_cells, [&](int jj) {
        const int j = lo + jj;
        double channel_in[256], channel_out[256];
        for (int ii = 0; ii < n_cells; ++ii) {
            const int i = lo + ii;
            Rgb* out_base = &f[size_t(jj * m) * n_nodes + size_t(ii * m)];
            auto put = [&](int a, int b, Rgb v) { out_base[size_t(b) * n_nodes + a] = v; };
            if (i < 0 || j < 0 || i >= cells || j >= cells) {
                for (int b = 0; b < m; ++b)
                    for (int a = 0; a < m; ++a)
                        put(a, b, extrapolate(state, (i + 0.5 * (rule.x[a] + 1)) / cells,
                                              (j + 0.5 * (rule.x[b] + 1)) / cells));
                continue;
            }
            const int leaf = forest.find(DyadicCell{J, i, j});
            const Forest::Node& node = forest.node(leaf);
            MBR_CHECK_MSG(node.is_leaf() && node.samples >= 0, "cell " << node.cell << " has no samples");
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
    // Eq. (19) in x = 2^J s units: c_kl = sum over cells and nodes of (w_a / 2)(w_b / 2)
    // DN(i + x_a - k) DN(j + y_b - l) f; first along s for every node row, then along t.
    const int reach = static_cast<int>(std::ceil(r)) + 1;
    auto window = [&](int k, int& c0, int& c1) {  // cells i with DN(x - k) kept on them
        const double centre = k + 0.5 * m;
        c0 = std::max(lo, static_cast<int>(std::floor(centre - r)) - 1);
        c1 = std::min(hi - 1, static_cast<int>(std::ceil(centre + r)));
        (void)reach;
    };
    std::vector<Rgb> g(size_t(n_coef) * n_nodes);  // g[k * n_nodes + row]
    parallel_for(n_nodes, [&](int row) {
        const Rgb* fr = &f[size_t(row) * n_nodes];
        for (int kk = 0; kk < n_coef; ++kk) {
            const int k = first + kk;
            int c0, c1;
            window(k, c0, c1);
            Rgb sum;
            for (int i = c0; i <= c1; ++i)
                for (int a = 0; a < m; ++a) {
                    const double w = 0.5 * rule.w[a] * tables.dn(i - k, a);
                    if (w != 0) sum += w * fr[size_t(i - lo) * m + a];
                }
            g[size_t(kk) * n_nodes + row] = sum;
        }
    });
    SplineField field(m, J);
    std::vector<Rgb> coef(size_t(n_coef) * n_coef);
    parallel_for(n_coef, [&](int kk) {
        const Rgb* gk = &g[size_t(kk) * n_nodes];
        for (int ll = 0; ll < n_coef; ++ll) {
            const int l = first + ll;
            int c0, c1;
            window(l, c0, c1);
            Rgb sum;
            for (int j = c0; j <= c1; ++j)
                for (int b = 0; b < m; ++b) {
                    const double w = 0.5 * rule.w[b] * tables.dn(j - l, b);
                    if (w != 0) sum += w * gk[size_t(j - lo) * m + b];
                }
            coef[size_t(kk) * n_coef + ll] = sum;
        }
    });
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

// ---- Stage 8: scale unification, eq. (17) ------------------------------------------------

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
            const int leaf = forest.leaf_at(c.x + ((q & 1) ? eps : -eps), c.y + ((q & 2) ? eps : -eps));
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

// ---- The whole transfer ------------------------------------------------------------------

double rhombus_radius_cells(const ReceiverOptions& options, const DualTable& dn) {
    return options.rhombus_radius > 0 ? options.rhombus_radius : dn.rhombus_radius(options.truncation_eps);
}

Shooter make_shooter(const Surface& surface, const SplineField& unshot, int levels) {
    Shooter shooter;
    shooter.surface = &surface;
    shooter.unshot = unshot.coarsened_to(std::max(0, unshot.level() - std::max(0, levels)));
    return shooter;
}

SplineField transfer(const Shooter& shooter, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats_out,
                     ReceiverState* keep_state, const OcclusionContext* occlusion,
                     const DualTable* dual) {
    MBR_CHECK_MSG(options.m >= 2 && options.m <= 8, "order m = " << options.m);
    MBR_CHECK(options.min_depth >= 0 && options.min_depth <= options.max_depth &&
              options.max_depth <= 14);
    const auto start = std::chrono::steady_clock::now();
    ReceiverState local;
    ReceiverState& state = keep_state ? *keep_state : local;
    state = ReceiverState{};
    state.options = options;
    std::unique_ptr<DualTable> own_dual;
    if (!dual || dual->order() != options.m) {
        own_dual = std::make_unique<DualTable>(options.m);
        dual = own_dual.get();
    }
    const DualTable& dn = *dual;
    state.rhombus_radius = rhombus_radius_cells(options, dn);
    // A pair that nothing can come between casts no rays and projects nothing.
    state.occlusion = (occlusion && !occlusion->clear()) ? occlusion : nullptr;
    const ShadowMethod shadows = state.occlusion ? options.shadows.method : ShadowMethod::None;
    IncrementSampler sampler(shooter, receiver, options.quadrature,
                             shadows == ShadowMethod::Exact ? state.occlusion : nullptr);

    auto t = std::chrono::steady_clock::now();
    subdivide_by_oracle(state, sampler);                                // stage 1
    adjust_neighbour_scales(state.forest, Forest::Region::Domain);      // stage 2
    sample_leaves(state, sampler);                                      //   eq. (21)
    state.stats.n_leaves = static_cast<int>(state.forest.leaves(Forest::Region::Domain).size());
    if (options.absolute_tolerance > 0 && options.rhombus_radius <= 0 && state.max_sample > 0) {
        // DESIGN: a weak shot needs no more truncation accuracy than the scene's tolerance. The
        // error a truncation eps causes is about 50 eps relative to max|dB| (rea against eps on
        // Tables 1-2, docs/method.md: 0.3-0.9 % at 1e-4, 0.04-0.07 % more at 1e-5 than at 1e-6),
        // so eps = (absolute tolerance / max|dB|) / 50, at most 1e-4.
        const double eps = std::clamp(0.02 * options.absolute_tolerance / state.max_sample,
                                      options.truncation_eps, std::max(options.truncation_eps, 1e-4));
        state.rhombus_radius = dn.rhombus_radius(eps);
    }
    state.stats.rhombus_radius = state.rhombus_radius;
    state.stats.seconds_sampling = seconds_since(t);
    t = std::chrono::steady_clock::now();
    fill_boundary(state, sampler);                                      // stage 3, eq. (22)
    state.stats.seconds_boundary = seconds_since(t);
    t = std::chrono::steady_clock::now();
    // With unify_by_projection the expanded domain is not built: project_fine_grid evaluates
    // the extrapolation (23)-(27) at the nodes it needs.
    const bool fine_grid = options.unify_by_projection;
    if (!fine_grid) expand_domain(state, sampler);                      // stage 4, (23)-(27)
    state.stats.seconds_expanded = seconds_since(t);
    t = std::chrono::steady_clock::now();
    state.fulcrums = select_fulcrums(state.forest, options.m);          // stage 5
    state.stats.n_fulcrums = static_cast<int>(state.fulcrums.size());
    if (!fine_grid) project_in_rhombi(state, dn);                       // stage 6, eq. (19)
    state.stats.seconds_projection = seconds_since(t);
    t = std::chrono::steady_clock::now();
    if (shadows == ShadowMethod::Fractions) apply_shadows(state, sampler, dn);  // stage 7, (28)
    state.stats.seconds_shadows = seconds_since(t);
    t = std::chrono::steady_clock::now();
    SplineField result = fine_grid ? project_fine_grid(state, dn)       // stages 6 and 8
                                   : unify_scales(state, dn);           // stage 8, eq. (17)
    state.mask = nullptr;  // it refers to the sampler, which ends here
    state.stats.seconds_projection += seconds_since(t);
    state.stats.n_rays += sampler.n_rays();
    state.stats.seconds_total = seconds_since(start);
    if (stats_out) *stats_out = state.stats;
    return result;
}

}  // namespace mbr
