// radiosity/transfer/oracle.cpp - stage 1 of one transfer: the oracle subdivision of [0,1]^2
// (paper section 5, "Adaptive Subdivision of the Parametric Domain"; section 6, "Oracle").
#include "radiosity/transfer/oracle.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "math/polynomial.h"
#include "radiosity/transfer/gauss_points.h"
#include "radiosity/transfer/scale_adjustment.h"
#include "radiosity/transfer/weak_transfer.h"

namespace mbr {

namespace {

/// What the oracle needs on every cell: the options, the sampler, its two Gauss-Legendre rules
/// (ceil(m/2) and m points), the scale of its tolerance floor, and the contact rule's plane.
struct Oracle {
    const ReceiverOptions& opt;
    IncrementSampler& sampler;
    GaussLegendre rule_c, rule_m;
    std::vector<double> lagrange;  // [p * m + a]: the m-point interpolant at the rule_c nodes
    double scale = 0;              // the largest root sample (0 when the bounds decide alone)
    int min_depth = 0;             // the weak receiver rule may lower options' min_depth
    // The planar shooters (a cluster's parts), when the contact rule asks; empty when a part is
    // not planar.
    std::vector<const ShooterPlane*> contact_planes{};
    bool contact_test = false;  // the contact oracle differs from the oracle's test
};

/// The mean of dB over a cell with an n x n rule; counts its (21) evaluations and, when asked,
/// keeps the largest sample.
Rgb cell_mean(IncrementSampler& sampler, const Rect& r, const GaussLegendre& rule, int thread,
              long* evals, long* increments, double* largest = nullptr, Rgb* values = nullptr) {
    Rgb sum;
    double s[16], t[16];
    gauss_points(r, rule, s, t);
    for (int a = 0; a < rule.n(); ++a)
        for (int b = 0; b < rule.n(); ++b) {
            const Rgb v = sampler.sample(s[a], t[b], thread, evals);
            if (largest) *largest = std::max(*largest, max_abs(v));
            if (values) values[a * rule.n() + b] = v;
            sum += (0.25 * rule.w[a] * rule.w[b]) * v;
            ++*increments;
        }
    return sum;
}

/// The oracle's relative tolerance for values of the given magnitude. DESIGN: relative
/// agreement, with a floor at 1% of the largest value in the domain so that nearly dark cells
/// do not split forever.
double relative_tolerance(const Oracle& o, double magnitude) {
    return o.opt.oracle_tolerance * std::max(magnitude, 0.01 * o.scale);
}

/// The oracle's absolute floor: the scene's absolute tolerance (its oracle_share).
double oracle_floor(const Oracle& o) {
    return oracle_share * o.opt.absolute_tolerance;
}

/// The oracle's tolerance for values of the given magnitude: the relative one, never below the
/// floor.
double oracle_tolerance(const Oracle& o, double magnitude) {
    return std::max(relative_tolerance(o, magnitude), oracle_floor(o));
}

/// The samples of dB that every oracle test reads on one cell: the m x m and ceil(m/2)^2
/// Gauss-Legendre points ([a * n + b]), and the largest of them.
struct CellSamples {
    Rgb f_m[256], f_c[64];
    double largest = 0;
};

CellSamples sample_cell(const Oracle& o, const Rect& r, int thread, long* evals, long* increments) {
    CellSamples c;
    const int m = o.rule_m.n(), nc = o.rule_c.n();
    double s[16], t[16];
    gauss_points(r, o.rule_m, s, t);
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) c.f_m[a * m + b] = o.sampler.sample(s[a], t[b], thread, evals);
    gauss_points(r, o.rule_c, s, t);
    for (int a = 0; a < nc; ++a)
        for (int b = 0; b < nc; ++b)
            c.f_c[a * nc + b] = o.sampler.sample(s[a], t[b], thread, evals);
    for (int k = 0; k < m * m; ++k) c.largest = std::max(c.largest, max_abs(c.f_m[k]));
    for (int k = 0; k < nc * nc; ++k) c.largest = std::max(c.largest, max_abs(c.f_c[k]));
    *increments += m * m + nc * nc;
    return c;
}

/// The mean of dB over the cell by an n x n rule from its samples f ([a * n + b]).
Rgb rule_mean(const GaussLegendre& rule, const Rgb* f) {
    Rgb sum;
    for (int a = 0; a < rule.n(); ++a)
        for (int b = 0; b < rule.n(); ++b)
            sum += (0.25 * rule.w[a] * rule.w[b]) * f[a * rule.n() + b];
    return sum;
}

/// Section 6 "Oracle", the paper's test: the means of dB over the cell by ceil(m/2)^2 and by
/// m^2 Gauss-Legendre points agree within the tolerance.
bool two_means_agree(const Oracle& o, const CellSamples& c) {
    const Rgb coarse = rule_mean(o.rule_c, c.f_c);
    const Rgb fine = rule_mean(o.rule_m, c.f_m);
    return max_abs(fine - coarse) <= oracle_tolerance(o, max_abs(fine));
}

/// Beyond the paper (OracleTest::Interpolation): the tensor polynomial through the m x m
/// samples must predict the samples at the ceil(m/2)^2 points within the tolerance, point by
/// point: a direct test of "can be approximated by a double (m-1)th order tensor product
/// polynomial", which a kink of a shadow boundary fails even where the two means agree.
bool interpolation_agrees(const Oracle& o, const CellSamples& c, double tol) {
    const int m = o.rule_m.n(), nc = o.rule_c.n();
    const std::vector<double>& L = o.lagrange;
    for (int a = 0; a < nc; ++a)
        for (int b = 0; b < nc; ++b) {
            Rgb p;
            for (int i = 0; i < m; ++i)
                for (int j = 0; j < m; ++j) p += (L[a * m + i] * L[b * m + j]) * c.f_m[i * m + j];
            if (max_abs(p - c.f_c[a * nc + b]) > tol) return false;
        }
    return true;
}

/// Beyond the paper (OracleTest::Hybrid): the paper's two means where the relative tolerance
/// governs the cell, the polynomial fit point by point where the absolute tolerance does.
/// Under the absolute floor a cell's two means agree whenever the increment's variation
/// inside it averages out, however large it is at a point: the dim transfers of a scene with
/// many shooters then each blur a shadow a little, and the blurs of shooters that cast the
/// same shadow add up (cube.mgf: +25 % at the foot of a penumbra after 100 shots). The fit
/// bounds a coarse cell's error by fit_share absolute tolerances at every sample instead.
bool hybrid_agrees(const Oracle& o, const CellSamples& c) {
    const double floor = oracle_floor(o);
    if (relative_tolerance(o, max_abs(rule_mean(o.rule_m, c.f_m))) >= floor)
        return two_means_agree(o, c);
    return interpolation_agrees(o, c,
                                std::max(relative_tolerance(o, c.largest), fit_share * floor));
}

/// Whether the cell passes the given test ("nearly sufficient").
bool oracle_test_passes(const Oracle& o, OracleTest test, const Rect& r, int thread, long* evals,
                        long* increments) {
    const CellSamples c = sample_cell(o, r, thread, evals, increments);
    switch (test) {
        case OracleTest::Means:
            return two_means_agree(o, c);
        case OracleTest::Interpolation:
            return interpolation_agrees(o, c, oracle_tolerance(o, c.largest));
        case OracleTest::Hybrid:
            break;
    }
    return hybrid_agrees(o, c);
}

}  // namespace

double distance_to_outline(const ConvexPolygon& outline, Vec2 q) {
    double best = std::numeric_limits<double>::infinity();
    const size_t n = outline.size();
    for (size_t k = 0; k < n; ++k) {
        const Vec2 a = outline[k], b = outline[(k + 1) % n];
        const Vec2 e = b - a;
        const double len2 = dot(e, e);
        const double t = len2 > 0 ? std::clamp(dot(q - a, e) / len2, 0.0, 1.0) : 0.0;
        const Vec2 d = q - (a + t * e);
        best = std::min(best, std::sqrt(dot(d, d)));
    }
    return best;
}

double distance_to_shooter(const ShooterPlane& plane, Vec3 x) {
    const double height = dot(x - plane.origin, plane.normal);
    const Vec2 q = plane.to_plane(x);
    double across = 0;
    if (!contains(plane.outline, q)) across = distance_to_outline(plane.outline, q);
    return std::sqrt(height * height + across * across);
}

namespace {

/// The corners, edge midpoints and centre of a receiver cell in space (row by row from
/// (x0, y0)), and the cell's size: the longer of its diagonals.
double cell_points(const Surface& receiver, const Rect& r, Vec3 p[9]) {
    int k = 0;
    for (double t : {r.y0, 0.5 * (r.y0 + r.y1), r.y1})
        for (double s : {r.x0, 0.5 * (r.x0 + r.x1), r.x1})
            p[k++] = receiver.evaluate(s, t).position;
    return std::max(length(p[8] - p[0]), length(p[6] - p[2]));
}

/// How near the receiver's cell comes to a planar shooter, over the cell's size: the least
/// distance of its corners, edge midpoints and centre (the contact lines of scenes are
/// straight). The contact rule (beyond the paper, ReceiverOptions::contact_depth) splits a cell
/// within half its size (contact_split_reach); the contact oracle's test (contact_oracle_test) is
/// asked only of a cell within a quarter of it (contact_test_reach).
double nearness_to_shooter(const Surface& receiver, const ShooterPlane& plane, const Rect& r) {
    Vec3 p[9];
    const double size = cell_points(receiver, r, p);
    double nearest = HUGE_VAL;
    for (const Vec3& x : p) nearest = std::min(nearest, distance_to_shooter(plane, x));
    return size > 0 ? nearest / size : HUGE_VAL;
}

/// The hover rule (beyond the paper, part of the contact rule): true when the receiver's cell
/// faces a planar shooter nearly parallel to it (normals within about 25 degrees of opposite)
/// from closer than half its own size, and some of its corners, edge midpoints and centre,
/// projected onto the shooter's plane, come within half the cell's size of the shooter's
/// outline. Under a shooter hovering at height d, dB steps at the outline's shadow over a
/// width of about d (a light 1e-4 above a floor: from rho E to rho E / 2 to 0), which no cell
/// wider than that resolves and whose two means agree on either side.
bool hovers_at_outline(const Surface& receiver, const ShooterPlane& plane, const Rect& r) {
    const SurfacePoint centre = receiver.evaluate(0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1));
    if (dot(centre.normal, plane.normal) > -0.9) return false;
    Vec3 p[9];
    const double size = cell_points(receiver, r, p);
    for (const Vec3& x : p) {
        const double height = dot(x - plane.origin, plane.normal);
        if (height < 0 || height > 0.5 * size) continue;
        if (distance_to_outline(plane.outline, plane.to_plane(x)) <= 0.5 * size) return true;
    }
    return false;
}

/// The hidden rim rule (beyond the paper, part of the contact rule): true when the receiver's
/// cell holds texels of its hidden mask both hidden and visible (radiosity/visibility/
/// hidden_regions.h). Along the rim of a region that an occluder in contact hides (a ceiling
/// behind a lamp hung 1 cm below it) exact visibility drops from the open value to about half
/// within a few times the gap, and the hidden side takes the values of the rim's visible points:
/// a feature far narrower than a coarse cell, which the oracle's samples straddle or miss. A
/// ceiling piece whose corner such a lamp hid read 5.6 % too bright 0.6 m from the lamp and 4.6 %
/// too dark 0.4 m from it, its coarse cells accepted (docs/method.md, "Hidden regions"). Exact
/// visibility only: the paper's fractions leave VIS out of the samples (it is 1 inside (21)),
/// which then have no rim (the room, paper shadows: 12 % more kernel evaluations and the same
/// values at its 32 points when the rule applied there too).
bool holds_hidden_rim(const ReceiverSurface& receiver, const Rect& r) {
    return receiver.hidden && receiver.hidden->mixed(r.x0, r.x1, r.y0, r.y1);
}

/// The thin rim rule (beyond the paper, part of the contact rule): true when the receiver's cell
/// holds the rim of a hidden region more than `ratio` times thinner than the cell
/// (HiddenMask::thin_rim), such as the strip of a wall that a shelf or a board standing out of
/// it hides. Such a cell reaches across the occluder to both of its sides, whose light differs
/// in every shot (under a board the wall sees the floor, above it the ceiling and its lamps),
/// and a dim shot's samples, one or two on each side, pass the oracle: corridor.mgf's wall read
/// 12 % too bright 22 cm under a board of 4 x 4 m that touches it (docs/method.md, "Known wrong
/// answers"). Both shadow methods: the paper's fractions, taken at the fulcrums of such coarse
/// cells, miss the board's shadow alike. A block's footprint on a floor is as wide as the cells
/// the contact rule leaves there, and its rim keeps the hidden rim rule alone.
bool holds_thin_rim(const ReceiverSurface& receiver, const Rect& r, double ratio) {
    return receiver.hidden && receiver.hidden->thin_rim(r.x0, r.x1, r.y0, r.y1, ratio);
}

/// The weak receiver rule (DESIGN, cost follows energy): a receiver whose largest root sample
/// is below weak_receiver times the absolute tolerance starts the oracle at the root.
int weak_receiver_min_depth(const ReceiverOptions& opt, double scale) {
    if (opt.weak_receiver > 0 && opt.absolute_tolerance > 0 &&
        scale < opt.weak_receiver * opt.absolute_tolerance)
        return 0;
    return opt.min_depth;
}

/// What the oracle does with one cell: keep it as a leaf, split it and ask again on its
/// children, or split it once more and stop ("nearly sufficient").
enum class OracleAction { Leaf, Split, SplitOnceMore };

/// The oracle's decision on one cell: the depth bounds, the contact rule, then the test.
OracleAction oracle_action(const Oracle& o, const DyadicCell& cell, long* evals, long* increments) {
    const ReceiverOptions& opt = o.opt;
    if (cell.level < o.min_depth) return OracleAction::Split;
    // Whether the cell touches the shooter, asked only when an answer matters.
    const bool ask = !o.contact_planes.empty() && (cell.level < opt.contact_depth ||
                                                   (o.contact_test && cell.level < opt.max_depth));
    double nearness = HUGE_VAL;  // a cluster's nearest part
    if (ask)
        for (const ShooterPlane* plane : o.contact_planes)
            nearness = std::min(
                nearness, nearness_to_shooter(*o.sampler.receiver().surface, *plane, cell.rect()));
    const bool contact = nearness <= contact_split_reach;
    if (cell.level < opt.contact_depth && contact) return OracleAction::Split;
    if (cell.level >= opt.max_depth) return OracleAction::Leaf;
    if (cell.level < opt.contact_depth && opt.shadows.method == ShadowMethod::Exact &&
        holds_hidden_rim(o.sampler.receiver(), cell.rect()))
        return OracleAction::Split;
    if (opt.thin_rim > 0 && holds_thin_rim(o.sampler.receiver(), cell.rect(), opt.thin_rim))
        return OracleAction::Split;
    if (opt.contact_depth > 0)
        for (const ShooterPlane* plane : o.contact_planes)
            if (hovers_at_outline(*o.sampler.receiver().surface, *plane, cell.rect()))
                return OracleAction::Split;
    const int th = thread_index();
    // DESIGN: a cell touching the shooter takes contact_oracle_test (`set contact_oracle`):
    // there dB grows like d log d. Only a cell within contact_test_reach of it: at half its
    // size a wall cell 2.5 m above a dim floor shooter counted as touching, and the paper's two
    // means agreed across the step of the floor's light at a shelf's underside (a shot 34 %
    // low 10 cm under the shelf; docs/method.md, "Known wrong answers").
    const OracleTest test =
        nearness <= contact_test_reach ? opt.contact_oracle_test : opt.oracle_test;
    return oracle_test_passes(o, test, cell.rect(), th, evals, increments)
               ? OracleAction::SplitOnceMore
               : OracleAction::Split;
}

}  // namespace

void subdivide_by_oracle(ReceiverState& state, IncrementSampler& sampler) {
    const ReceiverOptions& opt = state.options;
    const int m = opt.m;
    Forest& forest = state.forest;
    TransferStats& stats = state.stats;
    Oracle o{opt, sampler, gauss_legendre((m + 1) / 2), gauss_legendre(m), {}};
    const std::vector<double> c_nodes(o.rule_c.x.begin(), o.rule_c.x.end());
    o.lagrange = lagrange_matrix(o.rule_m, c_nodes);

    // Scale for the oracle's floor: the largest of the m x m samples of the whole domain
    // (not needed when the bounds leave the oracle nothing to decide).
    if (opt.min_depth < opt.max_depth) {
        long evals = 0, increments = 0;
        std::vector<Rgb> root(size_t(m) * m);  // [a * m + b], as sample_leaves stores them
        cell_mean(sampler, Rect{0, 1, 0, 1}, o.rule_m, 0, &evals, &increments, &o.scale,
                  root.data());
        stats.n_kernel_evals += evals;
        stats.n_increments += increments;
        stats.n_oracle_increments += increments;
        // The weak transfer rule (weak_transfer.h): below the threshold, with the shooter far
        // enough for these samples to stand for the receiver, the root stays the only leaf.
        bool represent = true;  // for every part of a cluster
        for (int part = 0; part < sampler.n_parts(); ++part)
            represent = represent && root_samples_represent(*sampler.shooter(part).surface,
                                                            *sampler.receiver().surface);
        if (is_weak_transfer(opt, o.scale) && represent) {
            stats.weak = true;
            store_leaf_samples(state, forest.domain_root(), root.data());
            return;
        }
    }
    o.min_depth = weak_receiver_min_depth(opt, o.scale);
    // The shooter's plane when it is planar (the contact rule); a cluster's every part's.
    o.contact_test = opt.contact_oracle_test != opt.oracle_test;
    if (opt.contact_depth > 0 || o.contact_test) {
        for (int part = 0; part < sampler.n_parts(); ++part)
            o.contact_planes.push_back(sampler.integrator(0, part).shooter_plane());
        if (std::count(o.contact_planes.begin(), o.contact_planes.end(), nullptr) > 0)
            o.contact_planes.clear();
    }

    std::vector<int> frontier{forest.domain_root()};
    while (!frontier.empty()) {
        const int n = static_cast<int>(frontier.size());
        std::vector<OracleAction> action(n, OracleAction::Leaf);
        std::vector<long> evals(n, 0), increments(n, 0);
        parallel_for(n, [&](int c) {
            action[c] = oracle_action(o, forest.node(frontier[c]).cell, &evals[c], &increments[c]);
        });
        std::vector<int> next;
        for (int c = 0; c < n; ++c) {
            stats.n_kernel_evals += evals[c];
            stats.n_increments += increments[c];
            stats.n_oracle_increments += increments[c];
            if (action[c] == OracleAction::Leaf) continue;
            const int first = forest.split(frontier[c]);
            if (action[c] == OracleAction::Split)
                for (int ch = 0; ch < 4; ++ch) next.push_back(first + ch);
            // SplitOnceMore: "nearly sufficient ... stopped after once more": children are leaves.
        }
        frontier = std::move(next);
    }
}

}  // namespace mbr
