// radiosity/transfer/shadows.cpp - stage 7 of one transfer, the paper's shadows: visible fractions
// (28) at fulcrums, shadow subdivision, and masking of the coefficients (section 5 "Adaptive
// Subdivision in Shadow Computation", section 6 "Shadow"; DESIGN.md section 3, stage 7).
#include "radiosity/transfer/shadows.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/transfer/form_factor.h"
#include "radiosity/transfer/projection.h"
#include "radiosity/transfer/scale_adjustment.h"
#include "radiosity/transfer/unification.h"

namespace mbr {

namespace {

std::uint64_t bits(double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
}

/// The size of the finest domain leaf.
double finest_domain_leaf(const Forest& forest) {
    double h = 1;
    for (int index : forest.leaves(Forest::Region::Domain))
        h = std::min(h, forest.node(index).cell.size());
    return h;
}

/// The depth of a fraction's shooter partition, following energy. 4^d patches of R rays each
/// estimate (28) with a standard error of at most 1 / (2 sqrt(4^d R)); times the largest sample
/// S of the shot, that error must stay below the scene's absolute tolerance tau: 4^d R >=
/// (S / (2 tau))^2. Never deeper than min_patch_depth (the paper's fixed partition), never
/// shallower than 1 (four patches).
int patch_depth(const ReceiverState& state) {
    const ShadowOptions& so = state.options.shadows;
    const double tau = state.options.absolute_tolerance;
    if (tau <= 0 || state.max_sample <= 0) return min_patch_depth;
    const double needed = std::pow(state.max_sample / (2 * tau), 2) / so.rays_per_patch;
    int d = 1;
    while (d < min_patch_depth && std::pow(4.0, d) < needed) ++d;
    return std::min(d, min_patch_depth);
}

/// How many of a fraction's rays go to each patch of the shooter partition (effort follows
/// energy; DESIGN, docs/method.md "Shadow rays follow energy"). The standard error that
/// patch_depth() accepts is that of `budget` = 4^d R rays. The partition (fraction_partition)
/// is finer than 4^d near a receiving point close to the shooter (a ball resting on the floor),
/// and R rays to each patch would buy visibility that the energy does not ask for. So when
/// the partition has more than budget / R patches (with energy), the budget is spread by the
/// patches' energy |e_i| (channel sum) with systematic sampling from a seeded offset: patch i
/// gets n_i rays, about budget |e_i| / sum |e|, and counts in (28) with the weight n_i / (that
/// expected count), which keeps the estimate unbiased. Otherwise every patch gets R rays and
/// weight 1, the paper's rule.
struct PatchRays {
    std::vector<int> count;
    std::vector<double> weight;
};

PatchRays patch_rays(const std::vector<AcceptedCell<Rgb>>& partition, int rays_per_patch,
                     long budget, std::uint64_t key) {
    const size_t n = partition.size();
    PatchRays out;
    out.count.assign(n, rays_per_patch);
    out.weight.assign(n, 1.0);
    std::vector<double> energy(n);
    double total = 0;
    long with_energy = 0;
    for (size_t i = 0; i < n; ++i) {
        const Rgb& e = partition[i].value;
        energy[i] = std::fabs(e.r) + std::fabs(e.g) + std::fabs(e.b);
        total += energy[i];
        with_energy += energy[i] > 0;
    }
    if (with_energy * rays_per_patch <= budget || !(total > 0)) return out;
    const double step = total / static_cast<double>(budget);
    double next = uniform01(key, 0) * step, below = 0;  // the next ray's energy position
    for (size_t i = 0; i < n; ++i) {
        const double above = below + energy[i];
        int k = 0;
        for (; next < above; next += step) ++k;
        out.count[i] = k;
        out.weight[i] = k > 0 ? k / (energy[i] / step) : 0.0;
        below = above;
    }
    return out;
}

/// Above this many candidates in the boxes that a point's pyramid meets, compute_fraction skips
/// the walk for the point's own occluders (see there).
constexpr int walk_candidates = 4 * static_cast<int>(max_listed_occluders);

/// A point's pyramid that meets more boxes of occluding surfaces than this tests its segments
/// without them (each would cost more than the octree it saves): compute_fraction.
constexpr size_t max_near_boxes = 16;

/// Whether no box meets the shaft from p to a planar patch (Shaft).
bool shaft_clear(Vec3 p, const Vec3 (&q)[4], const std::vector<Box3>& boxes) {
    const Shaft shaft(p, q);
    for (const Box3& box : boxes)
        if (shaft.meets(box)) return false;
    return true;
}

/// What one shooter sends to a point in (28): num / den is its visible fraction. `clear`: no
/// occluder meets the point's pyramid to the shooter (the fraction is 1; num and den are not
/// computed).
struct FractionSums {
    Rgb num, den;
    bool clear = false;
};

/// Eq. (28) for one shooter at the receiving point p (the domain point `point`): rays to random
/// points of the patches of the shooter partition (IncrementIntegrator::fraction_partition),
/// weighed by the energy each sends to the point.
FractionSums shooter_fraction(const ReceiverState& state, const OcclusionContext& ctx,
                              IncrementIntegrator& integrator, const Surface& shooter,
                              const SurfacePoint& p, Vec2 point, long* n_rays, long* n_evals) {
    // DESIGN: beyond the paper, the rays of a point are tested only against the occluders that
    // meet its pyramid to a planar shooter; when there are none the fraction is 1 without a ray
    // (what the rays would give, to the bit) and without the partition's kernel evaluations.
    std::vector<int> toward;
    std::vector<Box3> near_boxes;   // the pair's surface boxes that meet p's pyramid, all of them
    std::vector<Box3> grown_boxes;  // the first max_near_boxes of them, grown_for_segments
                                    //   (OcclusionContext::segment_boxes)
    bool many_boxes = false;        // more than max_near_boxes of them
    bool listed = false;           // toward lists every occluder that meets the pyramid
    const ShooterPlane* plane = integrator.shooter_plane();
    if (plane) {
        // First the pyramid against the pair's boxes, one per occluding surface: none met, and
        // the point is clear without the octree.
        const Vec3 corners[4] = {shooter.point(0, 0), shooter.point(1, 0), shooter.point(1, 1),
                                 shooter.point(0, 1)};
        const Shaft pyramid(p.position, corners);
        int near_count = 0;  // candidates in the first max_near_boxes + 1 boxes met
        for (size_t k = 0; k < ctx.surface_boxes.size(); ++k)
            if (pyramid.meets(ctx.surface_boxes[k])) {
                if (near_boxes.size() <= max_near_boxes) {
                    near_count += ctx.surface_box_counts[k];
                    grown_boxes.push_back(ctx.segment_boxes[k]);
                }
                near_boxes.push_back(ctx.surface_boxes[k]);
            }
        many_boxes = near_boxes.size() > max_near_boxes;
        if (near_boxes.empty()) return {{}, {}, true};
        // DESIGN: the search for the occluders that meet the pyramid (occluders_toward: a loop
        // over the pair's candidates, or the octree's walk when they are many; "walk" below
        // names both) stops beyond max_listed_occluders; then the rays go through the octree,
        // so the list need not be complete. When the first max_near_boxes + 1 boxes met hold
        // more than walk_candidates (4 x max_listed_occluders) candidates the walk stops at the
        // first occluder, only to tell a clear point (fraction 1 without a ray) from the
        // others: in the room (a few surfaces of hundreds of facets) 80 % of the full walks
        // overflowed, 13 % of its CPU. Many boxes of few polygons each (the classroom's chairs)
        // keep the full walk, whose short lists pay there (its 3 shots on one thread: 37.0 s
        // with it, 59.8 s without). The rays' answers do not depend on the path (only
        // candidates block on either: segment_blocked).
        const bool walk = many_boxes || near_count <= walk_candidates;
        toward = occluders_toward(ctx, *plane, p.position, walk ? max_listed_occluders : 0);
        if (toward.empty()) return {{}, {}, true};
        listed = walk && toward.size() <= max_listed_occluders;
    }
    // A segment from p to the shooter, tested against toward when it lists every occluder,
    // else against the boxes met and then the octree.
    auto blocked = [&](Vec3 x, RecentBlockers* recent) {
        if (listed)
            return segment_blocked(ctx, toward, p.position, x, n_rays, max_listed_occluders,
                                   recent);
        if (plane && !many_boxes && segment_misses_boxes(p.position, x, grown_boxes)) {
            if (n_rays) ++*n_rays;
            return false;
        }
        return segment_blocked(ctx, p.position, x, n_rays, recent);
    };
    const int depth = patch_depth(state);
    const std::vector<AcceptedCell<Rgb>> partition =
        integrator.fraction_partition(p, depth, n_evals);
    const int n_rays_per_patch = state.options.shadows.rays_per_patch;
    // DESIGN: the rays of a point are seeded from its position (a fulcrum's (level, k, l) in
    // lowest terms: two fulcrums at one point share the fraction), the pair and the shot.
    const std::uint64_t point_key = hash_seed(ctx.seed, bits(point.x), bits(point.y));
    const long budget = (1L << (2 * depth)) * n_rays_per_patch;
    const PatchRays rays =
        patch_rays(partition, n_rays_per_patch, budget, hash_seed(point_key, partition.size(), 1));
    // DESIGN: beyond the paper, a patch whose shaft from p meets no occluder's box is visible
    // without a ray (r_i = 1 exactly; the others keep their rays and weights, so (28) stays
    // unbiased). The boxes: the point's own occluders (toward) when it lists them all, else the
    // pair's boxes (one per occluding surface) that its pyramid meets, all of them (a patch's
    // shaft lies inside the pyramid: the others cannot meet it).
    // DESIGN: before 2026-12-07 a point whose pyramid met more than max_near_boxes boxes tested
    // every patch against all the pair's boxes (office2.mgf: hundreds a pair, 64 patches a point).
    std::vector<Box3> boxes;
    if (plane) {
        if (listed) {
            for (int id : toward) boxes.push_back(ctx.octree->polygons()[size_t(id)].bounds());
        } else {
            boxes = std::move(near_boxes);
        }
    }
    RecentBlockers recent;  // the point's last blockers, tested first (same answers)
    Rgb num, den;
    for (size_t i = 0; i < partition.size(); ++i) {
        const AcceptedCell<Rgb>& patch = partition[i];
        const Rgb e = patch.value;  // energy the patch shoots toward p
        if (max_abs(e) == 0) continue;
        if (plane) {
            const Rect& c = patch.cell.rect;
            const Vec3 q[4] = {shooter.point(c.x0, c.y0), shooter.point(c.x1, c.y0),
                               shooter.point(c.x1, c.y1), shooter.point(c.x0, c.y1)};
            if (shaft_clear(p.position, q, boxes)) {
                num += e;
                den += e;
                continue;
            }
        }
        const int n_patch_rays = rays.count[i];
        if (n_patch_rays == 0) {  // no ray drawn here: counted in sum e_i only (see patch_rays)
            den += e;
            continue;
        }
        const std::uint64_t key = hash_seed(point_key, i);
        // r_i: the share of rays that arrive (the paper's), or beyond the paper
        // (ShadowOptions::kernel_weighted) each ray counted with what the shooter sends along it,
        // B_h (its unshot radiosity, per channel) times the kernel (3) times A (4) at its end:
        // the visible share of what the patch sends to p. DESIGN: the area share darkens a
        // point whose kernel peaks on the visible part of a patch that the shadow cuts (a
        // block's face by the floor it stands on: the Cornell box's short block read -5.6 %
        // with paper shadows, 1.1 % with the kernel's weights); without B_h a patch whose
        // visible part is bright and whose hidden part is dark loses light (a ceiling lamp 1 cm
        // below the ceiling hides a dark square of it: the room read 1.3 % too dark at every
        // point, docs/method.md "Fractions weighted by what the shooter sends").
        const bool weighted = state.options.shadows.kernel_weighted;
        Rgb visible, weight;
        // DESIGN: when the count is a square, the random points are jittered on a grid of as
        // many strata (2 x 2 for the default 4): still uniform over the patch, less variance.
        const int side = static_cast<int>(std::lround(std::sqrt(double(n_patch_rays))));
        const bool strata = side * side == n_patch_rays;
        for (int k = 0; k < n_patch_rays; ++k) {
            const Rect& c = patch.cell.rect;
            double a = uniform01(key, 2 * k), b = uniform01(key, 2 * k + 1);
            if (strata) {
                a = (k % side + a) / side;
                b = (k / side + b) / side;
            }
            const double u = c.x0 + a * c.width(), v = c.y0 + b * c.height();
            Rgb w{1, 1, 1};
            Vec3 x;
            if (weighted) {
                const SurfacePoint q = shooter.evaluate(u, v);
                x = q.position;
                const double kernel =
                    form_factor_kernel(p.position, p.normal, q.position, q.normal) * q.area_factor;
                if (!(kernel > 0)) continue;
                const Rgb b_h = integrator.shooter_radiosity(u, v);
                for (int ch = 0; ch < 3; ++ch) w[ch] = kernel * std::max(b_h[ch], 0.0);
            } else {
                x = shooter.point(u, v);
            }
            if (!(max_abs(w) > 0)) continue;
            weight += w;
            if (!blocked(x, &recent)) visible += w;
        }
        // A channel no ray weighs (no ray ends where the patch shoots toward p) is left out.
        for (int ch = 0; ch < 3; ++ch)
            if (weight[ch] > 0) {
                num[ch] += rays.weight[i] * visible[ch] / weight[ch] * e[ch];
                den[ch] += e[ch];
            }
    }
    return {num, den, false};
}

/// Eq. (28) at the domain point (s, t), computed (no memo). A planar cluster's parts each give
/// their visible share of what they send, and the fraction is the sum of the visible energies
/// over the sum of all (a part nothing occludes sends its integral I(p) whole).
Rgb compute_fraction(const ReceiverState& state, IncrementSampler& sampler, Vec2 point,
                     double inset, int thread, long* n_rays, long* n_evals) {
    // DESIGN: a point of the domain's boundary is moved `inset` inside (boundary_inset of the
    // finest leaf, as edgefill does): on an edge shared with the shooter the kernel is singular.
    const double s = std::clamp(point.x, inset, 1 - inset),
                 t = std::clamp(point.y, inset, 1 - inset);
    // DESIGN: a hidden point's fraction is that of the nearest visible point, whose sample of
    // (21) it already takes (radiosity/visibility/hidden_regions.h): its own would be 0 and cut
    // the continuous extension back to a step (a ceiling behind a hanging lamp read 3.5 % dark
    // for 0.2 m around the lamp's outline).
    const ReceiverSurface& receiver = sampler.receiver();
    const Vec2 at = receiver.hidden ? receiver.hidden->substitute(s, t) : Vec2{s, t};
    const SurfacePoint p = receiver.surface->evaluate(at.x, at.y);
    Rgb num, den;
    if (sampler.n_parts() == 1) {
        const FractionSums one =
            shooter_fraction(state, *state.occlusion, sampler.integrator(thread),
                             *sampler.shooter().surface, p, point, n_rays, n_evals);
        if (one.clear) return {1, 1, 1};
        num = one.num;
        den = one.den;
    } else {
        for (int part = 0; part < sampler.n_parts(); ++part) {
            IncrementIntegrator& integrator = sampler.integrator(thread, part);
            const OcclusionContext* ctx = sampler.part_occlusion(part);
            FractionSums sums;
            sums.clear = ctx == nullptr;
            if (ctx)
                sums = shooter_fraction(state, *ctx, integrator, *sampler.shooter(part).surface, p,
                                        point, n_rays, n_evals);
            if (sums.clear) {
                const IncrementIntegrator::Result r = integrator.integrate(p);
                if (n_evals) *n_evals += r.n_evaluations;
                sums.num = sums.den = r.value;
            }
            num += sums.num;
            den += sums.den;
        }
    }
    Rgb f;
    for (int c = 0; c < 3; ++c) f[c] = den[c] > 0 ? std::clamp(num[c] / den[c], 0.0, 1.0) : 1.0;
    return f;
}

/// Fractions at the given points that are not known yet, computed in parallel and memoised.
void compute_fractions(ReceiverState& state, IncrementSampler& sampler, std::vector<Vec2> points,
                       double inset) {
    std::sort(points.begin(), points.end(),
              [](Vec2 a, Vec2 b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    points.erase(std::unique(points.begin(), points.end(),
                             [](Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }),
                 points.end());
    std::vector<Vec2> todo;
    for (Vec2 q : points)
        if (!state.fractions.count({q.x, q.y})) todo.push_back(q);
    const int n = static_cast<int>(todo.size());
    std::vector<Rgb> values(n);
    std::vector<long> rays(n, 0), evals(n, 0);
    parallel_for(n, [&](int i) {
        values[i] =
            compute_fraction(state, sampler, todo[i], inset, thread_index(), &rays[i], &evals[i]);
    });
    for (int i = 0; i < n; ++i) {
        state.fractions[{todo[i].x, todo[i].y}] = values[i];
        state.stats.n_rays += rays[i];
        state.stats.n_kernel_evals += evals[i];
    }
    state.stats.n_fractions += n;
}

/// The fulcrums of a leaf at its own scale (Figure 2): its corners for even m, its centre for
/// odd m.
std::vector<Fulcrum> leaf_fulcrums(const DyadicCell& c, int m) {
    std::vector<Fulcrum> out;
    if (m % 2 == 1) {
        out.push_back({c.level, c.i - (m - 1) / 2, c.j - (m - 1) / 2});
    } else {
        for (int b = 0; b <= 1; ++b)
            for (int a = 0; a <= 1; ++a) out.push_back({c.level, c.i + a - m / 2, c.j + b - m / 2});
    }
    return out;
}

/// The bilinear interpolation, at a point of the domain, of the fractions at the corners of the
/// domain leaf holding it (the point's own fraction when it has one); nothing when a corner's
/// fraction is unknown.
std::optional<Rgb> interpolated_fraction(const ReceiverState& state, Vec2 q) {
    const auto own = state.fractions.find({q.x, q.y});
    if (own != state.fractions.end()) return own->second;
    // Points on the domain's upper edges belong to its last cells (not to a ring cell).
    const double below_one = std::nextafter(1.0, 0.0);
    const int leaf = state.forest.leaf_at(std::min(q.x, below_one), std::min(q.y, below_one));
    if (leaf < 0) return std::nullopt;
    const Rect r = state.forest.node(leaf).cell.rect();
    Rgb corner[4];
    const double xs[2] = {r.x0, r.x1}, ys[2] = {r.y0, r.y1};
    for (int k = 0; k < 4; ++k) {
        const auto it = state.fractions.find({xs[k & 1], ys[k >> 1]});
        if (it == state.fractions.end()) return std::nullopt;
        corner[k] = it->second;
    }
    const double a = (q.x - r.x0) / r.width(), b = (q.y - r.y0) / r.height();
    return (1 - a) * (1 - b) * corner[0] + a * (1 - b) * corner[1] + (1 - a) * b * corner[2] +
           a * b * corner[3];
}

double difference(Rgb a, Rgb b) {
    return max_abs(a - b);
}

/// "If the fraction corresponding to two adjacent fulcrums differs significantly, the
/// corresponding subdomains are subdivided": the domain leaves (of `leaves`, whose fulcrums
/// have fractions) between fulcrums whose fractions differ by more than the threshold, each
/// with the largest such difference. The fulcrums that split leaves are recorded in
/// state.split_fulcrums.
std::map<int, double> leaves_across_shadow_edges(ReceiverState& state,
                                                 const std::vector<int>& leaves,
                                                 double threshold) {
    const int m = state.options.m;
    const ShadowOptions& so = state.options.shadows;
    const Forest& forest = state.forest;
    auto phi = [&](const Fulcrum& f) {
        const Vec2 q = fraction_point(f, m);
        return state.fractions.at({q.x, q.y});
    };

    std::map<int, double> marked;
    auto mark = [&marked](int index, double d) {
        double& largest = marked[index];
        largest = std::max(largest, d);
    };
    for (int index : leaves) {
        const DyadicCell c = forest.node(index).cell;
        if (m % 2 == 0) {
            // Adjacent fulcrums: the two ends of each edge of the leaf.
            const std::vector<Fulcrum> f = leaf_fulcrums(c, m);  // (0,0) (1,0) (0,1) (1,1)
            const int edges[4][2] = {{0, 1}, {1, 3}, {3, 2}, {2, 0}};
            for (const auto& e : edges)
                if (const double d = difference(phi(f[e[0]]), phi(f[e[1]])); d > threshold) {
                    mark(index, d);
                    if (c.level < so.max_depth) {
                        state.split_fulcrums.push_back(fraction_point(f[e[0]], m));
                        state.split_fulcrums.push_back(fraction_point(f[e[1]], m));
                    }
                }
        } else {
            // Adjacent fulcrums: the centres of leaves sharing an edge (each pair is seen
            // from its finer leaf, or from both when they are of one size).
            const Fulcrum own = leaf_fulcrums(c, m)[0];
            const Rect r = c.rect();
            const double d = 0.25 * c.size();
            const Vec2 across[4] = {{r.x0 - d, 0.5 * (r.y0 + r.y1)},
                                    {r.x1 + d, 0.5 * (r.y0 + r.y1)},
                                    {0.5 * (r.x0 + r.x1), r.y0 - d},
                                    {0.5 * (r.x0 + r.x1), r.y1 + d}};
            for (const Vec2& q : across) {
                if (q.x < 0 || q.x > 1 || q.y < 0 || q.y > 1) continue;
                const int other = forest.leaf_at(q.x, q.y);
                if (other < 0 || forest.node(other).cell.level > c.level) continue;
                const Fulcrum of = leaf_fulcrums(forest.node(other).cell, m)[0];
                if (!state.fractions.count({fraction_point(of, m).x, fraction_point(of, m).y}))
                    continue;  // a leaf of an earlier round's scale adjustment: next round
                if (const double d = difference(phi(own), phi(of)); d > threshold) {
                    mark(index, d);
                    mark(other, d);
                    state.split_fulcrums.push_back(fraction_point(own, m));
                    state.split_fulcrums.push_back(fraction_point(of, m));
                }
            }
        }
    }
    return marked;
}

/// Whether a domain leaf of this level that a shadow edge crosses is split: below the shadow
/// depth, and (effort follows energy; DESIGN, docs/method.md "Shadow splits follow power") when
/// the power the edge can misplace inside it, at most its area times the transfer's largest
/// sample times the largest difference of its fractions (`difference`), is at least the
/// absolute tolerance times ShadowOptions::split_area (the solver's: the area of a finest cell
/// on the scene's largest surface). So a small surface, whose leaves are small in the world,
/// resolves only the shadows that carry power: a stool leg 2 cm thick split to level 6 had
/// leaves of 0.2 mm. DESIGN: the difference enters since a soft penumbra, whose neighbouring
/// fractions differ by little (or by the rays' noise: 256 rays a fraction estimate it within
/// about 0.03), misplaces that share of the leaf's light only; without it, the room's floor
/// shot to the stool's underside (0.14 % of the shot's power) took 4,124 fractions and 0.98 M
/// rays, and the transfers below 0.1 % of their shot's power 35 % of the transfer time for
/// 0.33 % of the energy (docs/method.md, "Shadow splits follow power").
/// `receiver_area` is the receiving surface's area (computed once by the caller: a bilinear
/// patch's takes 4096 evaluations).
bool worth_splitting(const ReceiverState& state, double receiver_area, int level,
                     double difference) {
    const ReceiverOptions& opt = state.options;
    if (level >= opt.shadows.max_depth) return false;
    if (opt.shadows.split_area <= 0 || opt.absolute_tolerance <= 0) return true;
    const double leaf_area = receiver_area * std::pow(0.25, level);
    return leaf_area * state.max_sample * difference >=
           opt.absolute_tolerance * opt.shadows.split_area;
}

/// Shadow subdivision (section 6, "Shadow"): fractions at every domain leaf's fulcrums; the
/// leaves between differing ones split, scale-adjusted and resampled, round after round until
/// none splits or all are at the maximum shadow depth. Returns the domain leaves it made.
std::set<int> subdivide_shadows(ReceiverState& state, IncrementSampler& sampler, double inset,
                                double threshold) {
    const int m = state.options.m;
    Forest& forest = state.forest;
    const double receiver_area = sampler.receiver().surface->area();
    std::set<int> new_leaves;  // domain leaves made by shadow subdivision (node indices)
    for (;;) {
        // Fractions at every domain leaf's fulcrums.
        const std::vector<int> leaves = forest.leaves(Forest::Region::Domain);
        std::vector<Vec2> points;
        for (int index : leaves)
            for (const Fulcrum& f : leaf_fulcrums(forest.node(index).cell, m))
                points.push_back(fraction_point(f, m));
        compute_fractions(state, sampler, points, inset);
        const std::map<int, double> marked = leaves_across_shadow_edges(state, leaves, threshold);
        std::vector<int> to_split;
        for (const auto& [index, difference] : marked)
            if (worth_splitting(state, receiver_area, forest.node(index).cell.level, difference))
                to_split.push_back(index);
        if (to_split.empty()) break;
        for (int index : to_split) {
            if (!forest.node(index).is_leaf()) continue;
            forest.split(index);
            ++state.stats.n_shadow_splits;
        }
        // "Here, the scale of adjacent subdomains is also adjusted."
        state.stats.n_shadow_splits += adjust_neighbour_scales(forest, Forest::Region::All);
        sample_split_leaves(state);
        for (int index : forest.leaves(Forest::Region::Domain))
            if (forest.node(index).resampled) new_leaves.insert(index);
    }

    return new_leaves;
}

/// The new leaves' fulcrums, with their coefficients carried from the coarser ones by (17)
/// ("During subdivision, (17) is applied to those projection coefficients computed in the
/// previous section to obtain projection coefficients at a smaller scale"); projections on demand
/// may now reach finer leaves, so the resampling tables cover every level.
void carry_coefficients(ReceiverState& state, const DualTable& dn,
                        const std::set<int>& new_leaves) {
    const int m = state.options.m;
    const Forest& forest = state.forest;
    if (!new_leaves.empty()) {
        int finest = 0;
        for (int index = 0; index < forest.n_nodes(); ++index)
            finest = std::max(finest, forest.node(index).cell.level);
        state.tables = std::make_shared<const ProjectionTables>(
            make_projection_tables(m, dn, state.rhombus_radius, finest));
    }

    std::set<Fulcrum> added;
    for (int index : new_leaves) {
        if (!forest.node(index).is_leaf()) continue;
        for (const Fulcrum& f : leaf_fulcrums(forest.node(index).cell, m))
            if (!state.coefficients.count(f)) added.insert(f);
    }
    std::map<Fulcrum, Rgb> refined;
    for (const Fulcrum& f : added) {
        state.fulcrums.push_back(f);
        if (!state.options.unify_by_projection) {
            const Rgb c = resolve_coefficient(state, dn, f, refined);
            state.coefficients[f] = c;
        }
    }
    std::sort(state.fulcrums.begin(), state.fulcrums.end());
    state.fulcrums.erase(std::unique(state.fulcrums.begin(), state.fulcrums.end()),
                         state.fulcrums.end());
    state.stats.n_fulcrums = static_cast<int>(state.fulcrums.size());
}

/// "After subdivision, each resulting coefficient is multiplied by its corresponding
/// fraction": every stored coefficient, and (through state.mask) those stage 8 projects on
/// demand. An expanded fulcrum takes the fraction of the nearest point of the domain.
void mask_coefficients(ReceiverState& state, IncrementSampler& sampler, double inset) {
    const ReceiverOptions& opt = state.options;
    const int m = opt.m;
    std::vector<Vec2> points;
    for (const auto& [f, c] : state.coefficients) points.push_back(fraction_point(f, m));
    // Stage 8 will project every finest-scale coefficient (unify_by_projection). For odd m
    // their fractions are computed, in parallel now. DESIGN: for even m a fine fulcrum inside a
    // leaf takes the bilinear interpolation of the fractions at the leaf's corners (its own
    // fulcrums): the leaf was not split, so those fractions differ by less than the threshold
    // (or the leaf is at max_depth) and the fraction varies less than that inside it. Computing
    // (28) at every fine fulcrum instead cast 4225 x 256 rays per receiver at level 6.
    const bool interpolate = opt.unify_by_projection && m % 2 == 0;
    if (opt.unify_by_projection && !interpolate) {
        int j = 0;
        for (const Fulcrum& f : state.fulcrums) j = std::max(j, f.level);
        const int first = first_touching_index(m), n = touching_count(m, j);
        for (int k = first; k < first + n; ++k)
            for (int l = first; l < first + n; ++l) points.push_back(fraction_point({j, k, l}, m));
    }
    compute_fractions(state, sampler, points, inset);
    for (auto& [f, c] : state.coefficients) {
        const Vec2 q = fraction_point(f, m);
        c = c * state.fractions.at({q.x, q.y});
    }
    state.mask = [&state, &sampler, m, interpolate](const Fulcrum& f) {
        const Vec2 q = fraction_point(f, m);
        if (interpolate) {
            if (const std::optional<Rgb> r = interpolated_fraction(state, q)) return *r;
        }
        return fraction_at(state, sampler, q.x, q.y, 0);
    };
}

}  // namespace

Vec2 fraction_point(const Fulcrum& f, int m) {
    const Vec2 c = f.position(m);
    return {std::clamp(c.x, 0.0, 1.0), std::clamp(c.y, 0.0, 1.0)};
}

Rgb fraction_at(ReceiverState& state, IncrementSampler& sampler, double s, double t, int thread) {
    auto it = state.fractions.find({s, t});
    if (it != state.fractions.end()) return it->second;
    if (!state.occlusion) return {1, 1, 1};
    long rays = 0, evals = 0;
    const double inset = boundary_inset * finest_domain_leaf(state.forest);
    const Rgb f = compute_fraction(state, sampler, {s, t}, inset, thread, &rays, &evals);
    state.fractions[{s, t}] = f;
    state.stats.n_rays += rays;
    state.stats.n_kernel_evals += evals;
    ++state.stats.n_fractions;
    return f;
}

void apply_shadows(ReceiverState& state, IncrementSampler& sampler, const DualTable& dn) {
    if (!state.occlusion) return;
    const ReceiverOptions& opt = state.options;
    const double inset = boundary_inset * finest_domain_leaf(state.forest);
    // Fractions that differ by more than the threshold split, unless the difference they make
    // is below the scene's absolute tolerance (a weak shot keeps coarse shadows).
    const double threshold =
        std::max(opt.shadows.threshold,
                 state.max_sample > 0 ? opt.absolute_tolerance / state.max_sample : 0.0);
    const std::set<int> new_leaves = subdivide_shadows(state, sampler, inset, threshold);
    carry_coefficients(state, dn, new_leaves);
    mask_coefficients(state, sampler, inset);
}

}  // namespace mbr
