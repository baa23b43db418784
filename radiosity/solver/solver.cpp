// radiosity/solver/solver.cpp - progressive refinement over a whole scene (paper section 4).
#include "radiosity/solver/solver.h"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>

#include "math/bspline.h"
#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "radiosity/visibility/occlusion.h"
#include "radiosity/visibility/visible_parts.h"

namespace mbr {

namespace {

double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

/// For each j, the sum of values[k] over k != j: the sum before j plus the sum after it, not the
/// total minus values[j] (which a floor of 1e16 beside a 1 x 1 lamp cancels to zero: 1e16 + 1
/// rounds to 1e16). Linear in the values.
template <class T>
std::vector<T> sums_of_the_others(const std::vector<T>& values) {
    std::vector<T> out(values.size());
    T before{};
    for (size_t j = 0; j < values.size(); ++j) {
        out[j] = before;
        before += values[j];
    }
    T after{};
    for (size_t j = values.size(); j-- > 0;) {
        out[j] += after;
        after += values[j];
    }
    return out;
}

long peak_memory_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return long(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

/// Dense Cholesky solve of G x = b for a small symmetric positive definite G (row-major n x n).
std::vector<double> cholesky_solve(std::vector<double> G, std::vector<double> b, int n) {
    for (int j = 0; j < n; ++j) {
        double d = G[j * n + j];
        for (int k = 0; k < j; ++k) d -= G[j * n + k] * G[j * n + k];
        MBR_CHECK_MSG(d > 0, "Gram matrix not positive definite");
        G[j * n + j] = std::sqrt(d);
        for (int i = j + 1; i < n; ++i) {
            double s = G[i * n + j];
            for (int k = 0; k < j; ++k) s -= G[i * n + k] * G[j * n + k];
            G[i * n + j] = s / G[j * n + j];
        }
    }
    for (int i = 0; i < n; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k) s -= G[i * n + k] * b[k];
        b[i] = s / G[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < n; ++k) s -= G[k * n + i] * b[k];
        b[i] = s / G[i * n + i];
    }
    return b;
}

/// How far the other surface's hull reaches in front of the planar one's plane (its largest
/// signed distance), and the plane tolerance of behind() below.
double front_reach(const Surface& planar, const Surface& other, double* tolerance) {
    const Vec3 n = planar.normal(0.5, 0.5);
    const Vec3 o = planar.point(0.5, 0.5);
    const Box3 b = planar.bounds();
    *tolerance = 1e-9 * std::max(length(b.extent()), length(o));
    double reach = -std::numeric_limits<double>::infinity();
    for (const Vec3& q : hull_points(other)) reach = std::max(reach, dot(n, q - o));
    return reach;
}

/// The points of one planar surface's hull on the far side of the other's plane (or all on its
/// plane): nothing can pass between them. Curved surfaces are never ruled out here.
bool behind(const Surface& planar, const Surface& other) {
    if (!planar.is_planar()) return false;
    double tolerance = 0;
    return front_reach(planar, other, &tolerance) <= tolerance;
}

/// Whether planar surface b lies in planar surface a's plane and faces its way (the planar
/// cluster's test, planar_cluster).
bool coplanar_alike(const Surface& a, const Surface& b) {
    if (!a.is_planar() || !b.is_planar() || a.is_concave() || b.is_concave()) return false;
    if (dot(a.normal(0.5, 0.5), b.normal(0.5, 0.5)) < 1 - 1e-9) return false;
    double tolerance = 0;
    if (front_reach(a, b, &tolerance) > tolerance) return false;
    const Vec3 n = a.normal(0.5, 0.5), o = a.point(0.5, 0.5);
    for (const Vec3& q : hull_points(b))
        if (dot(n, q - o) < -tolerance) return false;
    return true;
}

/// The least distance between two boxes (0 when they meet).
double box_distance(const Box3& a, const Box3& b) {
    const Vec3 gap = max(max(a.lo - b.hi, b.lo - a.hi), Vec3{0, 0, 0});
    return length(gap);
}

/// The counts of another transfer to the same receiver in one shot (a planar cluster's: from
/// another member, or from the members that took the other shadow method) added to the first's.
void add_counts(TransferStats& a, const TransferStats& b) {
    a.n_kernel_evals += b.n_kernel_evals;
    a.n_analytic_evals += b.n_analytic_evals;
    a.n_increments += b.n_increments;
    a.n_oracle_increments += b.n_oracle_increments;
    a.n_boundary_increments += b.n_boundary_increments;
    a.n_unconverged += b.n_unconverged;
    a.n_leaves += b.n_leaves;
    a.n_rays += b.n_rays;
    a.n_fractions += b.n_fractions;
    a.n_shadow_splits += b.n_shadow_splits;
    a.weak = a.weak && b.weak;
    a.level = std::max(a.level, b.level);
    a.seconds_total += b.seconds_total;
}

std::uint64_t cell_key(const DyadicCell& c) {
    return (std::uint64_t(c.level) << 56) | (std::uint64_t(std::uint32_t(c.i)) << 28) |
           std::uint64_t(std::uint32_t(c.j));
}

}  // namespace

std::vector<NearContact> near_contacts(const Scene& scene) {
    std::vector<NearContact> found;
    const int n = static_cast<int>(scene.surfaces.size());
    const std::vector<int> emitters = scene.emitters();
    std::vector<bool> emits(size_t(n), false);
    for (int e : emitters) emits[size_t(e)] = true;
    for (int e : emitters)
        for (int i = 0; i < n; ++i) {
            if (i == e || (emits[size_t(i)] && i < e)) continue;  // each pair once
            for (const auto& [a, b] : {std::pair{e, i}, std::pair{i, e}}) {
                const Surface& planar = scene.surfaces[size_t(a)].surface;
                if (!planar.is_planar()) continue;
                double tolerance = 0;
                const double reach =
                    front_reach(planar, scene.surfaces[size_t(b)].surface, &tolerance);
                // Above rounding (1e-4 of the tolerance, 1e-13 of the size) and within the
                // tolerance: apart, but treated as lying on the plane.
                if (reach > 1e-4 * tolerance && reach <= tolerance) {
                    found.push_back({a, b, reach});
                    break;  // one report per pair
                }
            }
        }
    return found;
}

std::vector<int> planar_cluster(const Scene& scene, int h, const std::vector<double>& unshot) {
    const Surface& lead = scene.surfaces[size_t(h)].surface;
    if (!lead.is_planar() || lead.is_concave() || !(unshot[size_t(h)] > 0)) return {h};
    std::vector<int> candidates;
    for (int j = 0; j < int(scene.surfaces.size()); ++j)
        if (j != h && unshot[size_t(j)] > 0 &&
            unshot[size_t(j)] >= cluster_share * unshot[size_t(h)] &&
            coplanar_alike(lead, scene.surfaces[size_t(j)].surface))
            candidates.push_back(j);
    // Grown from h: a candidate joins when its box comes within cluster_reach of the smaller
    // diagonal of a member's box (the pieces of one floor, the tubes of one luminaire; not the
    // lamps of a whole ceiling, whose every sample would integrate over all of them).
    std::vector<Box3> boxes{lead.bounds()};
    Box3 all = lead.bounds();  // the cluster's, kept within cluster_extent of the lead's size
    const double largest = cluster_extent * length(all.extent());
    std::vector<int> others;
    std::vector<bool> joined(candidates.size(), false);
    for (bool grew = true; grew && int(others.size()) < max_cluster_members - 1;) {
        grew = false;
        for (size_t c = 0; c < candidates.size(); ++c) {
            if (joined[c]) continue;
            const Box3 b = scene.surfaces[size_t(candidates[c])].surface.bounds();
            for (size_t k = 0; k < boxes.size() && !joined[c]; ++k) {
                const double reach =
                    cluster_reach * std::min(length(b.extent()), length(boxes[k].extent()));
                Box3 grown = boxes[k];
                grown.lo = grown.lo - Vec3{reach, reach, reach};
                grown.hi = grown.hi + Vec3{reach, reach, reach};
                joined[c] = overlaps(grown, b);
            }
            if (joined[c]) {
                Box3 with = all;
                with.extend(b);
                joined[c] = length(with.extent()) <= largest;
            }
            if (!joined[c]) continue;
            all.extend(b);
            boxes.push_back(b);
            others.push_back(candidates[c]);
            grew = true;
            if (int(others.size()) == max_cluster_members - 1) break;
        }
    }
    std::sort(others.begin(), others.end());
    std::vector<int> members{h};
    members.insert(members.end(), others.begin(), others.end());
    return members;
}

namespace {

OracleTest oracle_test(OracleSetting s) {
    switch (s) {
        case OracleSetting::Hybrid:
            return OracleTest::Hybrid;
        case OracleSetting::Interpolation:
            return OracleTest::Interpolation;
        case OracleSetting::Means:
            break;
    }
    return OracleTest::Means;
}

}  // namespace

SolverOptions solver_options(const SolverSettings& s) {
    SolverOptions o;
    // DESIGN: in a scene every shooter partition refines its worst cell first (the sum of the
    // error estimates is bounded as the paper's rule bounds it, with far fewer cells on spline
    // shooters); see docs/method.md.
    o.receiver.quadrature.global = true;
    // DESIGN: 4 against 5 points per cell: a scene's tolerances are absolute and coarse, where
    // the lower pair needs half the kernel evaluations of 6 against 7 (docs/method.md).
    o.receiver.quadrature.n = 4;
    // DESIGN: every finest-level coefficient projected on the fine grid (project_fine_grid):
    // adaptive trees then reach the accuracy of uniform ones (docs/method.md, adaptive study).
    o.receiver.unify_by_projection = s.unify == UnifySetting::Projection;
    // DESIGN: cost follows energy (measured on the Cornell box, docs/method.md): a receiver
    // that gets less than 10 absolute tolerances starts its oracle at the root, the shadowed
    // part's triangles use 3 against 4 points, edgefill stops 2 levels below the finest
    // boundary leaf.
    o.receiver.weak_receiver = 10;
    // DESIGN: a transfer whose root samples are all below 0.3 absolute tolerances, its shooter
    // at least half the receiver's diagonal away, is a weak transfer (weak_transfer.h):
    // cube.mgf solved to 1e-5 in 26.4 s instead of 47.3 s, its error at 196 random points
    // against the path tracer 1.10 / 13.4 % (mean / max) against 1.05 / 16.1 % (1 tolerance:
    // 24.5 s, 1.52 / 20.2 %); the Cornell box unchanged (docs/method.md).
    o.receiver.weak_transfer = s.weak_transfer;
    // DESIGN: cells touching a planar shooter split to contact_depth (2) whatever the oracle
    // says (ReceiverOptions::contact_depth; measured on the cubes and the Cornell box,
    // docs/method.md).
    o.receiver.contact_depth = s.contact_depth;
    // DESIGN: and with it the thin rim rule (thin_rim_ratio, 3): corridor.mgf 1.84 / 11.95 % ->
    // 0.61 / 2.04 % at 28 path-traced points (22 cm under a board 12 % -> 0.3 %) in 1.23 times
    // the time; the Cornell box and cube.mgf unchanged, office2.mgf 1.15 times (docs/method.md,
    // "Hidden regions").
    o.receiver.thin_rim = s.contact_depth > 0 ? thin_rim_ratio : 0;
    // DESIGN: the hybrid oracle (OracleTest::Hybrid, `set oracle`): the paper's means where
    // the relative tolerance governs, the fit where the absolute one does (cube.mgf 1.06 /
    // 36.5 % -> 0.72 / 12.1 % at 183 path-traced points for the same time; the Cornell box
    // unchanged at 1.15 times its time; docs/method.md, "The hybrid oracle").
    o.receiver.oracle_test = oracle_test(s.oracle);
    // DESIGN: cells touching a planar shooter take the Interpolation test (`set contact_oracle
    // interpolation`, the default since 2026-12-07): next to a contact the paper's two means
    // agree long before the spline follows B. The floor beside the Cornell box's blocks: 20 %
    // dark within 4 cm with the means, 5 % with the fit, for 1.17 times the time
    // (ReceiverOptions::contact_oracle_test, docs/method.md "Contact oracle").
    o.receiver.contact_oracle_test = oracle_test(s.contact_oracle);
    o.receiver.quadrature.n_pieces = 3;
    o.receiver.edgefill_max_depth = 2;
    o.receiver.m = s.order;
    o.receiver.min_depth = s.min_depth;
    o.receiver.max_depth = s.max_depth;
    o.receiver.oracle_tolerance = s.oracle_tolerance;
    o.receiver.truncation_eps = s.truncation_eps;
    o.receiver.rhombus_radius = s.rhombus_radius;
    o.receiver.extrapolation = s.extrapolation == ExtrapolationSetting::Linear
                                   ? Extrapolation::Linear
                                   : Extrapolation::Quadratic;
    o.receiver.shadows.rays_per_patch = s.shadow_rays;
    // DESIGN: kernel-weighted fractions by default (docs/method.md): the Cornell box with paper
    // shadows 1.26 / 5.60 % with the paper's area shares, 0.62 / 3.20 % with them.
    o.receiver.shadows.kernel_weighted = s.fraction_rays == FractionRaysSetting::Kernel;
    o.receiver.shadows.method =
        s.shadows == ShadowSetting::Exact || s.shadows == ShadowSetting::Auto ? ShadowMethod::Exact
        : s.shadows == ShadowSetting::Paper ? ShadowMethod::Fractions
                                            : ShadowMethod::None;
    // DESIGN: auto, the default: exact visibility costs per sample with the occluders that cut
    // the shooter's image, the paper's fractions (28) per fulcrum with a bounded count of rays;
    // the Cornell box's pairs have at most 10 occluding surfaces between them and keep exact
    // visibility, a floor under 500 boxes takes the fractions (docs/method.md, "Shadows auto").
    if (s.shadows == ShadowSetting::Auto) o.exact_shadow_casters = 16;
    o.max_shots = s.max_shots;
    o.convergence = s.convergence;
    o.self_transfer = s.self_transfer;
    o.cluster_shots = s.cluster_shots;
    o.tolerance = s.tolerance;
    o.ambient = s.ambient;
    o.ambient_rays = s.ambient_rays;
    o.ambient_level = s.ambient_level;
    o.ambient_final = s.ambient_final;
    static_assert(max_ambient_level == 4, "the option table's range of ambient_level");
    o.limiter = s.limiter;
    o.irradiance_fields = s.texture_field == TextureFieldSetting::Irradiance;
    o.hidden_regions = s.hidden;
    o.shooter_level = s.shooter_level;
    return o;
}

namespace {

// Gauss-Legendre points per cell along each direction of l2_projection's rule (textures are
// only piecewise smooth).
constexpr int projection_points = 8;

// The coordinates along one direction of l2_projection's samples at `level`
// (projection_sample_coordinate for every index).
std::vector<double> projection_coordinates(int level) {
    const GaussLegendre rule = gauss_legendre(projection_points);
    std::vector<double> at(size_t(1 << level) * projection_points);
    for (size_t i = 0; i < at.size(); ++i)
        at[i] = projection_sample_coordinate(rule, int(i), level);
    return at;
}

// DESIGN (`set shadows auto`): a pair with more shadow casters than exact_shadow_casters keeps
// exact visibility when its shooter is a planar quad and at each of 3 x 3 points of the
// receiver (at 1/6, 1/2 and 5/6 of its parameters) at most half of exact_limit casters meet the
// point's pyramid to the shooter (blocked_view projects up to exact_limit there; beyond, one
// ray per quadrature node: the half leaves a margin for the points between the samples). A
// small lamp under a ceiling has a whole room of casters between itself and a wall, but each
// point of the wall only the few in its thin pyramid to the lamp: the paper's fractions missed
// a board's shadow there (corridor.mgf, docs/method.md "A small lamp keeps exact visibility").
// With the whole exact_limit at the samples, office2.mgf took 1.49 times its time (more points
// fell to rays). A pair of 17 to 24 casters, which blocked_view projects whole at every point
// (casters_toward counts them all), keeps the fractions.
bool projects_at_samples(const OcclusionContext& occlusion, const Surface& shooter,
                         const Surface& receiver) {
    if (shooter.kind() != Surface::Kind::PlanarQuad) return false;
    const ShooterPlane plane = make_shooter_plane(shooter);
    for (double u : {1.0 / 6, 0.5, 5.0 / 6})
        for (double v : {1.0 / 6, 0.5, 5.0 / 6}) {
            const Vec3 p = receiver.point(u, v);
            if (dot(plane.normal, p - plane.origin) <= 0) continue;  // behind: no shadows
            if (casters_toward(occlusion, plane, p) > exact_limit / 2) return false;
        }
    return true;
}

}  // namespace

SplineField l2_projection_of_samples(int m, int level, int points, const Rgb* samples) {
    // L2([0,1]^2) projection onto the touching basis of the level: (G x G) c = b with
    // b_kl = int int f N_k N_l by the samples' Gauss rule and the 1D Gram matrix G, exact by
    // m-point Gauss per cell.
    const int first = first_touching_index(m), n = touching_count(m, level), cells = 1 << level;
    const GaussLegendre rule_g = gauss_legendre(m), rule_b = gauss_legendre(points);
    const int side = cells * points;  // samples along each direction
    std::vector<double> G(size_t(n) * n, 0.0);
    double v[16];
    for (int cell = 0; cell < cells; ++cell)
        for (int q = 0; q < rule_g.n(); ++q) {
            const double s = (cell + 0.5 * (rule_g.x[q] + 1)) / cells;
            const int fk = bspline_values(m, std::ldexp(s, level), v);
            const double w = 0.5 * rule_g.w[q] / cells;
            for (int a = 0; a < m; ++a)
                for (int b = 0; b < m; ++b) {
                    const int ka = fk + a - first, kb = fk + b - first;
                    if (ka >= 0 && ka < n && kb >= 0 && kb < n)
                        G[size_t(ka) * n + kb] += w * v[a] * v[b];
                }
        }
    // b_kl = sum_S sum_T w_S w_T f(s_S, t_T) N_k(s_S) N_l(t_T), summed separably: first along
    // t for every row S (T_S,l), then along s (m + m n / side products a sample instead of m^2).
    struct Node1d {
        int first;  // the first basis function not zero there, minus `first`
        double w;   // the weight of the node's Gauss rule, scaled to its cell
        double v[16];
    };
    std::vector<Node1d> nodes(side);
    for (int S = 0; S < side; ++S) {
        const double s = projection_sample_coordinate(rule_b, S, level);
        nodes[S].first = bspline_values(m, std::ldexp(s, level), nodes[S].v) - first;
        nodes[S].w = 0.5 * rule_b.w[S % points] / cells;
    }
    std::vector<std::array<double, 3>> rows(size_t(side) * n);  // rows[S * n + l][c]
    for (int S = 0; S < side; ++S) {
        std::array<double, 3>* row = rows.data() + size_t(S) * n;
        for (int T = 0; T < side; ++T) {
            const Node1d& t = nodes[T];
            const Rgb value = samples[size_t(S) * side + T];
            for (int b = 0; b < m; ++b) {
                const int l = t.first + b;
                if (l < 0 || l >= n) continue;
                const double e = t.w * t.v[b];
                for (int c = 0; c < 3; ++c) row[l][c] += e * value[c];
            }
        }
    }
    std::array<std::vector<double>, 3> B;  // B[c][k][l]
    for (std::vector<double>& b : B) b.assign(size_t(n) * n, 0.0);
    for (int S = 0; S < side; ++S) {
        const Node1d& s = nodes[S];
        const std::array<double, 3>* row = rows.data() + size_t(S) * n;
        for (int a = 0; a < m; ++a) {
            const int k = s.first + a;
            if (k < 0 || k >= n) continue;
            const double e = s.w * s.v[a];
            for (int c = 0; c < 3; ++c)
                for (int l = 0; l < n; ++l) B[c][size_t(k) * n + l] += e * row[l][c];
        }
    }
    SplineField field(m, level);
    for (int c = 0; c < 3; ++c) {
        // C = G^-1 B G^-1: solve column by column, then row by row.
        std::vector<double>& Bc = B[c];
        std::vector<double> col(n);
        for (int l = 0; l < n; ++l) {
            for (int k = 0; k < n; ++k) col[k] = Bc[size_t(k) * n + l];
            col = cholesky_solve(G, col, n);
            for (int k = 0; k < n; ++k) Bc[size_t(k) * n + l] = col[k];
        }
        for (int k = 0; k < n; ++k) {
            std::vector<double> row(Bc.begin() + size_t(k) * n, Bc.begin() + size_t(k + 1) * n);
            row = cholesky_solve(G, row, n);
            for (int l = 0; l < n; ++l) field.channel(c)(first + k, first + l) = row[l];
        }
    }
    return field;
}

SplineField l2_projection(const std::function<Rgb(double, double)>& f, int m, int level) {
    // f at 8 x 8 Gauss points per cell.
    const std::vector<double> at = projection_coordinates(level);
    const size_t side = at.size();
    std::vector<Rgb> samples(side * side);
    for (size_t i = 0; i < side; ++i)
        for (size_t j = 0; j < side; ++j) samples[i * side + j] = f(at[i], at[j]);
    return l2_projection_of_samples(m, level, projection_points, samples.data());
}

double projection_sample_coordinate(const GaussLegendre& rule, int index, int level) {
    const int points = rule.n();
    return (index / points + 0.5 * (rule.x[index % points] + 1)) / (1 << level);
}

SplineField project_emission(const Texture& emission, int m, int level) {
    if (emission.is_constant()) return SplineField::constant(m, 0, emission.value(0.5, 0.5));
    return l2_projection([&emission](double s, double t) { return emission.value(s, t); }, m,
                         level);
}

Rgb coefficient_bound(const SplineField& field) {
    Rgb bound;
    for (int c = 0; c < 3; ++c)
        for (double a : field.channel(c).a) bound[c] = std::max(bound[c], a);
    return bound;
}

bool stores_irradiance(const Scene& scene, int surface, const SolverOptions& options) {
    return options.irradiance_fields && !scene.material_of(surface).reflectance.is_constant();
}

RadiosityView radiosity_view(const Scene& scene, const Solution& solution) {
    const int n = static_cast<int>(solution.radiosity.size());
    MBR_CHECK(n == static_cast<int>(scene.surfaces.size()));
    MBR_CHECK(solution.quantity.empty() || static_cast<int>(solution.quantity.size()) == n);
    // The scene's limiter setting makes what is viewed never negative (limit_positive), on
    // copies: the solution itself stays linear in the emission, so that light groups'
    // solutions add (superposition.h) before they are made positive.
    std::shared_ptr<std::vector<SplineField>> positive;
    if (scene.settings.limiter) {
        positive = std::make_shared<std::vector<SplineField>>(solution.radiosity);
        // Each field on its own, side by side (73 s of one core at 100,000 quads, serial).
        std::vector<SplineField>& fields = *positive;
        parallel_for(n, [&fields](int i) { limit_positive(fields[size_t(i)]); });
    }
    std::vector<ShadedField> surfaces(n);
    for (int i = 0; i < n; ++i) {
        ShadedField& s = surfaces[i];
        s.field = positive ? &(*positive)[i] : &solution.radiosity[i];
        if (!solution.quantity.empty()) s.quantity = solution.quantity[i];
        if (s.quantity == FieldQuantity::irradiance) {
            const Material& mat = scene.material_of(i);
            s.reflectance = &mat.reflectance;
            if (mat.emits()) s.emission = &mat.emission;
        }
    }
    return RadiosityView(std::move(surfaces), std::move(positive));
}

std::vector<double> area_weights_by_cells(const Surface& S, int m, int level) {
    // w_kl = int int N_m(2^j s - k) N_m(2^j t - l) A(s, t) ds dt, by (m + 2)-point Gauss per
    // cell: exact for planar quads (A is linear in s and t), accurate for curved surfaces.
    const int first = first_touching_index(m), n = touching_count(m, level), cells = 1 << level;
    const GaussLegendre rule = gauss_legendre(m + 2);
    std::vector<double> w(size_t(n) * n, 0.0);
    double vs[16], vt[16];
    for (int ci = 0; ci < cells; ++ci)
        for (int qa = 0; qa < rule.n(); ++qa) {
            const double s = (ci + 0.5 * (rule.x[qa] + 1)) / cells;
            const int fk = bspline_values(m, std::ldexp(s, level), vs);
            for (int cj = 0; cj < cells; ++cj)
                for (int qb = 0; qb < rule.n(); ++qb) {
                    const double t = (cj + 0.5 * (rule.x[qb] + 1)) / cells;
                    const int fl = bspline_values(m, std::ldexp(t, level), vt);
                    const double a = 0.25 * rule.w[qa] * rule.w[qb] / (double(cells) * cells) *
                                     S.area_factor(s, t);
                    for (int p = 0; p < m; ++p)
                        for (int q = 0; q < m; ++q) {
                            const int k = fk + p - first, l = fl + q - first;
                            if (k >= 0 && k < n && l >= 0 && l < n)
                                w[size_t(k) * n + l] += a * vs[p] * vt[q];
                        }
                }
        }
    return w;
}

std::vector<double> area_weights(const Surface& S, int m, int level) {
    if (S.kind() != Surface::Kind::PlanarQuad) return area_weights_by_cells(S, m, level);
    // DESIGN: on a planar quad x_s x x_t = e1 x e2 + s (e1 x d) + t (d x e2) with e1, e2 its
    // edges from x(0,0) and d = x(1,1) - x(1,0) - x(0,1) + x(0,0), all three along the plane's
    // normal: A(s, t) is linear, and equals the bilinear interpolant of its corner values. With
    // J0_k = int (1 - s) N_k(s) ds and J1_k = int s N_k(s) ds (by (m + 2)-point Gauss per cell,
    // exact), w_kl = A00 J0_k J0_l + A10 J1_k J0_l + A01 J0_k J1_l + A11 J1_k J1_l: n^2 terms
    // instead of 36 m^2 4^j products (the solver's power() at 100,000 quads, level 7). A quad
    // the scene format accepts as planar within its tolerance has A linear up to the square of
    // its deviation from its plane, and so have these weights.
    const int first = first_touching_index(m), n = touching_count(m, level), cells = 1 << level;
    const GaussLegendre rule = gauss_legendre(m + 2);
    std::vector<double> j0(size_t(n), 0.0), j1(size_t(n), 0.0);
    double v[16];
    for (int c = 0; c < cells; ++c)
        for (int q = 0; q < rule.n(); ++q) {
            const double s = (c + 0.5 * (rule.x[q] + 1)) / cells;
            const double weight = 0.5 * rule.w[q] / cells;
            const int fk = bspline_values(m, std::ldexp(s, level), v);
            for (int p = 0; p < m; ++p) {
                const int k = fk + p - first;
                if (k < 0 || k >= n) continue;
                j0[size_t(k)] += weight * (1 - s) * v[p];
                j1[size_t(k)] += weight * s * v[p];
            }
        }
    const double a00 = S.area_factor(0, 0), a10 = S.area_factor(1, 0), a01 = S.area_factor(0, 1),
                 a11 = S.area_factor(1, 1);
    std::vector<double> w(size_t(n) * n);
    for (int k = 0; k < n; ++k)
        for (int l = 0; l < n; ++l)
            w[size_t(k) * n + l] =
                a00 * j0[size_t(k)] * j0[size_t(l)] + a10 * j1[size_t(k)] * j0[size_t(l)] +
                a01 * j0[size_t(k)] * j1[size_t(l)] + a11 * j1[size_t(k)] * j1[size_t(l)];
    return w;
}

// ---- The loop -----------------------------------------------------------------------------

ProgressiveSolver::ProgressiveSolver(const Scene& scene, const Octree& octree,
                                     const SolverOptions& options,
                                     const std::function<void(int done, int total)>& on_setup)
    : scene_(scene), octree_(octree), options_(options) {
    start_seconds_ = now();
    const int n = static_cast<int>(scene.surfaces.size());
    // DESIGN: each surface's fields take its own order ("on different surfaces in an
    // environment, different B-spline bases can be used", section 3): B, dB_unshot, the
    // emission's projection, the ambient constant and every transfer to it. A transfer's
    // receiver is of the receiver's order and its shooter field of the shooter's; the samples
    // (21) evaluate the shooter field whatever its order, so the two never need to agree.
    order_.resize(n);
    duals_.resize(9);
    for (int i = 0; i < n; ++i) {
        const int m = order_[i] = surface_order(scene, i, options.receiver.m);
        MBR_CHECK_MSG(m >= 2 && m <= 8, "order m = " << m << " of surface " << i);
        if (!duals_[m]) duals_[m] = std::make_unique<DualTable>(m);
    }
    solution_.radiosity.resize(n);
    solution_.quantity.assign(n, FieldQuantity::radiosity);
    solution_.unshot.resize(n);
    solution_.leaves.resize(n);
    split_cells_.resize(n);
    coupling_.resize(n);
    shot_power_.assign(n, Rgb{});
    last_seconds_.assign(n, 0.0);
    weights_.resize(n);
    hidden_.resize(n);
    std::optional<HiddenContacts> contacts;
    if (options.hidden_regions) {
        // DESIGN: only the surfaces that another polygon touches from in front can hold a
        // hidden region, and only near those polygons (find_contacts); the others keep an
        // empty mask.
        contacts = find_contacts(octree, n);
        // DESIGN: the surfaces side by side (each one's texels are then tasks of its own
        // thread): the classroom's 9,804 surfaces one after the other, each parallel inside,
        // spent a fifth of the setup's CPU waking threads (`perf`: futex). Each mask depends
        // on its surface alone, so the result does not depend on the order or the threads.
        std::mutex progress_mutex;
        int done = 0;
        parallel_for(n, [&](int i) {
            if (!contacts->occluders[size_t(i)].empty())
                hidden_[i] = find_hidden(scene.surfaces[i].surface, i, octree, &*contacts);
            if (!on_setup) return;
            std::lock_guard<std::mutex> lock(progress_mutex);
            on_setup(++done, n);
        });
    }
    // DESIGN: exact visibility projects each convex solid of the scene's polygons (a block, a
    // table top) as one silhouette instead of face by face (convex_solids.h; docs/method.md).
    // find_contacts has found them already when the hidden regions are on.
    if (options.receiver.shadows.method == ShadowMethod::Exact)
        solids_ = std::make_unique<ConvexSolids>(contacts ? std::move(contacts->solids)
                                                          : find_convex_solids(octree.polygons()));
    // "for each emitting surface L_i compute the projection of its emittance distribution".
    double emitted = 0;
    Rgb emitted_rgb;
    for (int i = 0; i < n; ++i) {
        const Material& mat = scene.material_of(i);
        const int m = order_[i];
        if (stores_irradiance(scene, i, options)) solution_.quantity[i] = FieldQuantity::irradiance;
        if (mat.emits()) {
            solution_.unshot[i] = project_emission(mat.emission, m, options.emission_level);
            // An irradiance field starts at zero: its B = E + rho H reads E from the texture.
            solution_.radiosity[i] = solution_.quantity[i] == FieldQuantity::radiosity
                                         ? solution_.unshot[i]
                                         : SplineField::constant(m, 0, {0, 0, 0});
            const Rgb p = power(i, solution_.unshot[i]);
            emitted += channel_sum(p);
            emitted_rgb += p;
        } else {
            solution_.radiosity[i] = SplineField::constant(m, 0, {0, 0, 0});
            solution_.unshot[i] = SplineField::constant(m, 0, {0, 0, 0});
        }
    }
    solution_.stats.emitted_power = emitted;
    solution_.stats.unshot_power = emitted;
    const double area = scene.total_area();
    radiosity_scale_ =
        area > 0 ? std::max({emitted_rgb.r, emitted_rgb.g, emitted_rgb.b}) / area : 0;
    for (const SceneSurface& s : scene.surfaces)
        largest_area_ = std::max(largest_area_, s.surface.area());
}

const std::vector<double>& ProgressiveSolver::power_weights(int surface, int level) const {
    std::vector<std::vector<double>>& cache = weights_[surface];
    if (int(cache.size()) <= level) cache.resize(level + 1);
    std::vector<double>& w = cache[level];
    if (w.empty()) w = area_weights(scene_.surfaces[surface].surface, order_[surface], level);
    return w;
}

Rgb ProgressiveSolver::power(int surface, const SplineField& field) const {
    // int B A = sum_kl c_kl w_kl (the B-splines' weights against the area factor), the
    // weights of the surface's order, which every field of it has.
    MBR_CHECK_MSG(field.order() == order_[surface],
                  "a field of order " << field.order() << " on surface " << surface << " of order "
                                      << order_[surface]);
    const std::vector<double>& w = power_weights(surface, field.level());
    Rgb p;
    for (int c = 0; c < 3; ++c) {
        const std::vector<double>& a = field.channel(c).a;
        double sum = 0;
        for (size_t i = 0; i < a.size(); ++i) sum += a[i] * w[i];
        p[c] = sum;
    }
    return p;
}

SplineField ProgressiveSolver::reflected_field(int surface, const SplineField& dH) const {
    // dB = rho dH (eq. (2)), projected at the increment's level, at most the emission's: the
    // unshot field only shoots, coarsened to shooter_level, and its power is what must be right
    // (an L2 projection keeps the integral of rho dH over a planar surface).
    // The samples of l2_projection's rule, dH on the tensor grid (evaluate_grid: separable).
    const Texture& rho = scene_.material_of(surface).reflectance;
    const int level = std::min(dH.level(), SolverOptions::emission_level);
    const std::vector<double> at = projection_coordinates(level);
    const int side = static_cast<int>(at.size());
    std::vector<Rgb> samples(size_t(side) * side);
    dH.evaluate_grid(at.data(), side, at.data(), side, samples.data());
    parallel_for(side, [&](int i) {
        for (int j = 0; j < side; ++j) {
            Rgb& sample = samples[size_t(i) * side + j];
            sample = rho.value(at[i], at[j]) * sample;
        }
    });
    return l2_projection_of_samples(order_[surface], level, projection_points, samples.data());
}

double ProgressiveSolver::unshot_power(int surface) const {
    return channel_sum(power(surface, solution_.unshot[surface]));
}

bool ProgressiveSolver::done() const {
    const SolveStats& st = solution_.stats;
    if (st.shots >= options_.max_shots) return true;
    double largest = 0;
    for (int i = 0; i < int(scene_.surfaces.size()); ++i)
        largest = std::max(largest, unshot_power(i));
    return largest <= options_.convergence * st.emitted_power;
}

std::vector<int> ProgressiveSolver::receivers_of(int h) const {
    const Surface& shooter_surface = scene_.surfaces[h].surface;
    std::vector<int> receivers;
    for (int i = 0; i < int(scene_.surfaces.size()); ++i) {
        const Surface& r = scene_.surfaces[i].surface;
        if (i == h) {
            if (options_.self_transfer && r.is_concave()) receivers.push_back(i);
            continue;
        }
        if (max_abs(scene_.material_of(i).reflectance.maximum()) == 0)
            continue;  // reflects nothing
        if (behind(shooter_surface, r) || behind(r, shooter_surface)) continue;
        receivers.push_back(i);
    }
    return receivers;
}

std::vector<int> ProgressiveSolver::receivers_of(const std::vector<int>& members) const {
    if (members.size() == 1) return receivers_of(members[0]);
    std::vector<int> receivers;
    for (int h : members) {
        const std::vector<int> r = receivers_of(h);
        receivers.insert(receivers.end(), r.begin(), r.end());
    }
    std::sort(receivers.begin(), receivers.end());
    receivers.erase(std::unique(receivers.begin(), receivers.end()), receivers.end());
    // The members lie in one plane: none receives from another.
    receivers.erase(
        std::remove_if(
            receivers.begin(), receivers.end(),
            [&](int i) { return std::find(members.begin(), members.end(), i) != members.end(); }),
        receivers.end());
    return receivers;
}

OcclusionContext ProgressiveSolver::occlusion_of(int h, int i, int shot) const {
    // Without shadows no ray is cast: the pair needs its ids and seed, no candidates (their
    // search took 76 % of the time of a sphere in 20 pieces).
    if (options_.receiver.shadows.method == ShadowMethod::None)
        return pair_context(octree_, h, i, std::uint64_t(shot));
    const auto it = candidates_.find({h, i});
    if (it == candidates_.end()) {
        const Surface& shooter = scene_.surfaces[h].surface;
        const Surface& receiver = scene_.surfaces[i].surface;
        OcclusionContext ctx =
            make_occlusion_context(octree_, shooter, h, receiver, i, std::uint64_t(shot));
        // DESIGN: pieces of one concave sphere or cylinder do not occlude each other: a segment
        // between two of its points lies inside the solid, on the far side of every facet's
        // chord plane from the thin shell the facet stands for (except within a facet's own
        // piece, where the segment's end lies and the thickness rule already lets it pass). The
        // facets of a sphere in 20 pieces were the exact method's candidates along every edge.
        if (shooter.is_concave() && shooter.on_same_quadric(receiver)) {
            const std::vector<Polygon>& polys = octree_.polygons();
            std::vector<int>& c = ctx.candidates;
            c.erase(std::remove_if(c.begin(), c.end(),
                                   [&](int id) {
                                       const int s = polys[size_t(id)].surface();
                                       return s >= 0 && s < int(scene_.surfaces.size()) &&
                                              scene_.surfaces[size_t(s)].surface.on_same_quadric(
                                                  shooter);
                                   }),
                    c.end());
            group_surface_boxes(ctx);
        }
        if (solids_) attach_solids(ctx, *solids_);
        return ctx;
    }
    // DESIGN: the candidates depend on the two surfaces only, the seed on the shot too: the
    // same context as a new search, without the search.
    OcclusionContext ctx = it->second;
    ctx.seed = pair_context(octree_, h, i, std::uint64_t(shot)).seed;
    return ctx;
}

std::vector<ProgressiveSolver::Received> ProgressiveSolver::transfer_to(
    const std::vector<int>& receivers, const std::vector<int>& members,
    const std::vector<Shooter>& shooters, const ReceiverOptions& ro, int shot_number) {
    const int n_rec = static_cast<int>(receivers.size());
    std::vector<Received> results(receivers.size());
    // Per receiver the members that face it (one shooter: itself), and their pairs' occluders.
    std::vector<std::vector<int>> faced(receivers.size());
    std::vector<std::vector<OcclusionContext>> contexts(receivers.size());
    parallel_for(n_rec, [&](int k) {
        const int i = receivers[k];
        const Surface& r = scene_.surfaces[size_t(i)].surface;
        for (int j = 0; j < int(members.size()); ++j) {
            const Surface& h = scene_.surfaces[size_t(members[j])].surface;
            if (members.size() > 1 && (behind(h, r) || behind(r, h))) continue;
            faced[size_t(k)].push_back(j);
            contexts[size_t(k)].push_back(occlusion_of(members[j], i, shot_number));
        }
    });
    for (int k = 0; k < n_rec; ++k)  // keep new pairs' candidates, within the bound
        for (size_t p = 0; p < faced[size_t(k)].size(); ++p) {
            const int h = members[size_t(faced[size_t(k)][p])];
            const OcclusionContext& c = contexts[size_t(k)][p];
            const size_t size =
                c.candidates.size() + 25 * c.surface_boxes.size();  // in ints: two boxes, a count
            if (options_.receiver.shadows.method == ShadowMethod::None ||
                candidates_.count({h, receivers[k]}) ||
                cached_candidates_ + size > max_cached_candidates)
                continue;
            cached_candidates_ += size;
            candidates_[{h, receivers[k]}] = c;
        }
    Box3 cluster_box;  // the members' bounds together
    for (int h : members) cluster_box.extend(scene_.surfaces[size_t(h)].surface.bounds());
    // Each receiver's options and surface, then its transfers (jobs).
    std::vector<ReceiverOptions> options(receivers.size(), ro);
    std::vector<ReceiverSurface> surfaces(receivers.size());
    struct Job {
        int k = 0;  // the receiver
        std::vector<ShooterPart> parts;
        bool paper = false;
    };
    std::vector<Job> jobs;
    for (int k = 0; k < n_rec; ++k) {
        const int i = receivers[k];
        const Texture& rho = scene_.material_of(i).reflectance;
        const bool irradiance = solution_.quantity[i] == FieldQuantity::irradiance;
        // An irradiance receiver's samples are H, eq. (21) without rho: its tolerance is the
        // receiver's over its largest reflectance, so that B = rho H keeps the receiver's.
        // DESIGN: and its oracle tests the polynomial fit itself (OracleTest::Interpolation):
        // H has no texture steps to force splits, and the paper's two means agree on a smooth
        // H long before the spline follows it (a checker plate under a square light: 1.8 % at
        // the square centres with the means, 0.29 % with the fit; docs/method.md).
        ReceiverOptions& o = options[size_t(k)];
        o.m = order_[i];  // the receiver's basis
        if (irradiance) {
            const double largest = max_abs(rho.maximum());
            o.absolute_tolerance /= largest;
            o.quadrature.abs_tolerance /= largest;
            o.oracle_test = OracleTest::Interpolation;
            o.contact_oracle_test = OracleTest::Interpolation;
        }
        // The reflectance is read after this loop: the lambda keeps the scene's texture.
        surfaces[size_t(k)] = ReceiverSurface{
            &scene_.surfaces[i].surface,
            irradiance ? std::function<Rgb(double, double)>([](double, double) {
                return Rgb{1, 1, 1};
            })
                       : std::function<Rgb(double, double)>(
                             [tex = &rho](double s, double t) { return tex->value(s, t); }),
            hidden_[i].any() ? &hidden_[i] : nullptr};
        // Under shadows auto each pair chooses its method. A receiver at least cluster_far
        // diagonals from a planar cluster takes one transfer of the parts that chose alike (at
        // most two: exact visibility, the paper's fractions); a nearer one a transfer per part,
        // as from shots of their own. The transfers' fields add up.
        const bool far = members.size() > 1 &&
                         box_distance(cluster_box, scene_.surfaces[size_t(i)].surface.bounds()) >=
                             cluster_far * length(cluster_box.extent());
        const size_t first_job = jobs.size();
        for (size_t p = 0; p < faced[size_t(k)].size(); ++p) {
            const Shooter& shooter = shooters[size_t(faced[size_t(k)][p])];
            const OcclusionContext& occlusion = contexts[size_t(k)][p];
            const bool paper =
                options_.exact_shadow_casters > 0 && o.shadows.method == ShadowMethod::Exact &&
                shadow_casters(occlusion) > options_.exact_shadow_casters &&
                !projects_at_samples(occlusion, *shooter.surface, scene_.surfaces[i].surface);
            const auto alike = std::find_if(jobs.begin() + long(first_job), jobs.end(),
                                            [&](const Job& g) { return g.paper == paper; });
            if (far && alike != jobs.end())
                alike->parts.push_back({&shooter, &occlusion});
            else
                jobs.push_back({k, {{&shooter, &occlusion}}, paper});
        }
    }
    const int n_jobs = static_cast<int>(jobs.size());
    std::vector<Received> done(jobs.size());
    auto run_transfer = [&](int j) {
        const Job& job = jobs[size_t(j)];
        ReceiverOptions job_options = options[size_t(job.k)];
        if (job.paper) job_options.shadows.method = ShadowMethod::Fractions;
        ReceiverState state;
        Received& r = done[size_t(j)];
        r.paper = job.paper;
        r.field = transfer(job.parts, surfaces[size_t(job.k)], job_options, &r.stats, &state,
                           duals_[size_t(job_options.m)].get());
        for (int index = 0; index < state.forest.n_nodes(); ++index) {
            const Forest::Node& node = state.forest.node(index);
            if (!node.is_leaf() && node.cell.in_domain()) r.splits.push_back(cell_key(node.cell));
        }
    };
    std::mutex progress_mutex;  // on_transfer_'s calls, one at a time
    int n_done = 0;
    auto run_one = [&](int j) {
        run_transfer(j);
        if (!on_transfer_) return;
        std::lock_guard<std::mutex> lock(progress_mutex);
        on_transfer_(++n_done, n_jobs);
    };
    if (n_jobs == 1) {
        run_one(0);  // parallel inside
    } else {
        // The receivers that took longest last time first, so that no thread is left with one
        // big transfer at the end (the results do not depend on the order). Both shadow methods:
        // the paper's fractions are seeded by their points, not by threads, and running the
        // room's transfers side by side instead of each one's fractions in parallel took its
        // 2-thread wall time from 20.7 to 17.5 s (farm-bench, 3 runs each), the same output.
        std::vector<int> order(n_jobs);
        for (int j = 0; j < n_jobs; ++j) order[j] = j;
        std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
            return last_seconds_[receivers[jobs[size_t(a)].k]] >
                   last_seconds_[receivers[jobs[size_t(b)].k]];
        });
        parallel_for(n_jobs, [&](int j) { run_one(order[j]); });
    }
    // Each receiver's transfers in job order: the first's field and counts, the others added.
    for (int j = 0; j < n_jobs; ++j) {
        Received& result = results[size_t(jobs[size_t(j)].k)];
        Received& r = done[size_t(j)];
        result.paper = result.paper || r.paper;
        if (result.field.empty()) {
            result.field = std::move(r.field);
            result.stats = r.stats;
        } else {
            result.field.add(r.field);
            add_counts(result.stats, r.stats);
        }
        result.splits.insert(result.splits.end(), r.splits.begin(), r.splits.end());
    }
    for (int k = 0; k < n_rec; ++k) last_seconds_[receivers[k]] = results[k].stats.seconds_total;
    return results;
}

void ProgressiveSolver::superpose(const std::vector<int>& receivers, std::vector<Received>& results,
                                  const std::vector<int>& members,
                                  const std::vector<Shooter>& shooters, ShotStats& shot) {
    const int n = static_cast<int>(scene_.surfaces.size());
    const int n_rec = static_cast<int>(receivers.size());
    const int h = members[0];
    // Each member's power, and its share of the shot's (a cluster's coupling is shared so).
    std::vector<Rgb> member_power(members.size());
    Rgb total_power;
    for (size_t j = 0; j < members.size(); ++j) {
        member_power[j] = power(members[j], shooters[j].unshot);
        total_power += member_power[j];
        std::vector<Rgb>& row = coupling_[size_t(members[j])];
        if (row.empty()) row.assign(n, Rgb{});
        shot_power_[size_t(members[j])] += member_power[j];
    }
    std::vector<Rgb> member_share(members.size(), Rgb{1, 1, 1});
    if (members.size() > 1)
        for (size_t j = 0; j < members.size(); ++j)
            for (int c = 0; c < 3; ++c)
                member_share[j][c] = total_power[c] > 0 ? member_power[j][c] / total_power[c] : 0;
    std::vector<SplineField> unshot_increments(n_rec);  // dB_i of the irradiance receivers
    Rgb shooter_bound;  // >= max B_h over the members (a sum of their kernels' shares of it)
    for (const Shooter& shooter : shooters) {
        const Rgb bound = coefficient_bound(shooter.unshot);
        for (int c = 0; c < 3; ++c) shooter_bound[c] = std::max(shooter_bound[c], bound[c]);
    }
    // What each receiver adds to the shot's sums, added in the receivers' order afterwards.
    struct Part {
        double limited = 0;
        Rgb reflected, arrived;
    };
    std::vector<Part> parts(n_rec);
    // DESIGN: each receiver's part (limiter, reflected field, powers, its fields and split
    // cells) side by side: each touches its own surface only (the receivers are distinct). In
    // the room it ran on one thread between the shots' parallel transfers, 4.7 % of its CPU.
    parallel_for(n_rec, [&](int k) {
        const int i = receivers[k];
        Received& r = results[k];
        Part& part = parts[k];
        const bool irradiance = solution_.quantity[i] == FieldQuantity::irradiance;
        const Rgb rho_max = scene_.material_of(i).reflectance.maximum();
        if (options_.limiter) {
            const Rgb before = power(i, r.field);
            const double slack =
                options_.tolerance * radiosity_scale_ / (irradiance ? max_abs(rho_max) : 1.0);
            limit_increment(r.field, irradiance ? shooter_bound : rho_max * shooter_bound, slack);
            const Rgb change = power(i, r.field) - before;
            part.limited = channel_sum(
                irradiance ? scene_.material_of(i).reflectance.mean() * change : change);
        }
        if (irradiance) {
            unshot_increments[k] = reflected_field(i, r.field);
            if (options_.limiter)
                limit_increment(unshot_increments[k], rho_max * shooter_bound,
                                options_.tolerance * radiosity_scale_);
        }
        const SplineField& dB = irradiance ? unshot_increments[k] : r.field;
        part.reflected = power(i, dB);
        if (irradiance) part.arrived = power(i, r.field);
        solution_.radiosity[i].add(r.field);
        solution_.unshot[i].add(dB);
        std::vector<std::uint64_t>& cells = split_cells_[i];
        cells.insert(cells.end(), r.splits.begin(), r.splits.end());
        std::sort(cells.begin(), cells.end());
        cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    });
    for (int k = 0; k < n_rec; ++k) {
        const int i = receivers[k];
        const Received& r = results[k];
        const Part& part = parts[k];
        const bool irradiance = solution_.quantity[i] == FieldQuantity::irradiance;
        shot.limited += part.limited;
        shot.reflected += channel_sum(part.reflected);
        // Incident power: int dH A for an irradiance receiver, else what was reflected over the
        // reflectance (its mean for a texture stored as B).
        const Rgb rv = scene_.material_of(i).reflectance.mean();
        for (int c = 0; c < 3; ++c)
            if (rv[c] > 0) {
                const double incident = irradiance ? part.arrived[c] : part.reflected[c] / rv[c];
                shot.incident += incident;
                for (size_t j = 0; j < members.size(); ++j)
                    coupling_[size_t(members[j])][size_t(i)][c] += member_share[j][c] * incident;
            }
        shot.kernel_evals += r.stats.n_kernel_evals;
        shot.analytic_evals += r.stats.n_analytic_evals;
        shot.rays += r.stats.n_rays;
        shot.paper_transfers += r.paper ? 1 : 0;
        shot.weak_transfers += r.stats.weak ? 1 : 0;
        shot.finest_level = std::max(shot.finest_level, r.field.level());
    }
    for (size_t j = 1; j < members.size(); ++j)  // a cluster's other members (all planar)
        solution_.unshot[size_t(members[j])] =
            SplineField::constant(order_[size_t(members[j])], 0, {0, 0, 0});
    const Surface& shooter_surface = scene_.surfaces[h].surface;
    if (!(options_.self_transfer && shooter_surface.is_concave() &&
          std::find(receivers.begin(), receivers.end(), h) != receivers.end())) {
        solution_.unshot[h] = SplineField::constant(order_[h], 0, {0, 0, 0});
    } else {
        // The shooter received from itself during the shot: keep only what it received.
        for (int k = 0; k < n_rec; ++k)
            if (receivers[k] == h)
                solution_.unshot[h] = solution_.quantity[h] == FieldQuantity::irradiance
                                          ? unshot_increments[k]
                                          : results[k].field;
    }
}

ShotStats ProgressiveSolver::shoot() {
    const double start = now();
    const int n = static_cast<int>(scene_.surfaces.size());
    ShotStats shot;
    shot.shot = solution_.stats.shots + 1;
    // "pick out the surface A_jm which has the largest value of int int_Aj dB" (sum of the
    // channels' unshot power; ties to the lowest index).
    std::vector<double> unshot(n);
    for (int i = 0; i < n; ++i) {
        unshot[i] = unshot_power(i);
        shot.unshot_before += unshot[i];
        if (shot.shooter < 0 || unshot[i] > unshot[shot.shooter]) shot.shooter = i;
    }
    const int h = shot.shooter;
    shot.shooter_power = unshot[h];
    // Beyond the paper: the surfaces in h's plane with a share of its power shoot with it.
    const std::vector<int> members =
        options_.cluster_shots ? planar_cluster(scene_, h, unshot) : std::vector<int>{h};
    shot.members = static_cast<int>(members.size());
    for (size_t j = 1; j < members.size(); ++j) shot.shooter_power += unshot[size_t(members[j])];

    // The receivers: every surface that can see a shooter's front and be seen by it.
    const std::vector<int> receivers = receivers_of(members);
    shot.receivers = static_cast<int>(receivers.size());

    // Tolerances against the scene's scale (cost follows energy).
    ReceiverOptions ro = options_.receiver;
    ro.absolute_tolerance = options_.tolerance * radiosity_scale_;
    ro.quadrature.abs_tolerance = options_.quadrature_share * ro.absolute_tolerance;
    // Shadow splits follow power (shadows.cpp, worth_splitting): against a finest cell of the
    // scene's largest surface.
    ro.shadows.split_area = largest_area_ * std::pow(0.25, ro.max_depth);
    std::vector<Shooter> shooters;
    for (int j : members) {
        const SplineField& unshot_j = solution_.unshot[size_t(j)];
        const int coarsen =
            std::max(ro.shooter_coarsening, unshot_j.level() - options_.shooter_level);
        shooters.push_back(make_shooter(scene_.surfaces[size_t(j)].surface, unshot_j, coarsen));
    }

    std::vector<Received> results = transfer_to(receivers, members, shooters, ro, shot.shot);
    superpose(receivers, results, members, shooters, shot);
    for (int i = 0; i < n; ++i) shot.unshot_after += unshot_power(i);
    shot.seconds = now() - start;

    SolveStats& st = solution_.stats;
    ++st.shots;
    st.unshot_power = shot.unshot_after;
    st.kernel_evals += shot.kernel_evals;
    st.analytic_evals += shot.analytic_evals;
    st.rays += shot.rays;
    st.transfers += shot.receivers;
    st.paper_transfers += shot.paper_transfers;
    st.weak_transfers += shot.weak_transfers;
    if (shot.members > 1) {
        ++st.clustered_shots;
        st.clustered_surfaces += shot.members;
    }
    st.limited_power += shot.limited;
    st.per_shot.push_back(shot);
    return shot;
}

std::vector<Rgb> ProgressiveSolver::ambient_correction() const {
    // The power still unshot, U_j, and what it will become: X_i = U_i + rho_i sum_j F_ji X_j,
    // with F_ji the measured fraction of j's shot power that reaches i (a surface that never
    // shot spreads in proportion to the other surfaces' areas). Solved by Jacobi iteration
    // (it converges: rho < 1 and each row of F sums to at most one). What surface i gains,
    // rho_i sum_j F_ji X_j, is spread over its area as a constant radiosity.
    const int n = static_cast<int>(scene_.surfaces.size());
    std::vector<Rgb> U(n), rho(n);
    std::vector<double> area(n);
    for (int i = 0; i < n; ++i) {
        U[i] = power(i, solution_.unshot[i]);
        rho[i] = scene_.material_of(i).reflectance.mean();
        area[i] = scene_.surfaces[i].surface.area();
    }
    // The area of the surfaces other than j, summed without j, so that a surface's share never
    // divides by zero.
    const std::vector<double> others = sums_of_the_others(area);
    // The measured fraction of shooter j's shot power that reached i (j has shot).
    auto coupling = [&](int j, int i) -> Rgb {
        Rgb f;
        for (int c = 0; c < 3; ++c)
            f[c] = shot_power_[j][c] > 0 ? coupling_[j][i][c] / shot_power_[j][c] : 0.0;
        return f;
    };
    // A surface that never shot sends area_i / others_j of X_j to every other surface i: its
    // part of what reaches i is area_i times the sum over the other such j of X_j / others_j,
    // for every i at once (sums_of_the_others: linear in the surfaces). Only the surfaces that
    // shot have a row of their own to visit.
    std::vector<int> shot;
    for (int j = 0; j < n; ++j)
        if (!coupling_[j].empty()) shot.push_back(j);
    std::vector<Rgb> X = U, gain(n), share(n);
    for (int iteration = 0; iteration < 1000; ++iteration) {
        double change = 0, size = 0;
        for (int j = 0; j < n; ++j)
            share[j] = coupling_[j].empty() && others[j] > 0 ? (1 / others[j]) * X[j] : Rgb{};
        const std::vector<Rgb> spread = sums_of_the_others(share);
        for (int i = 0; i < n; ++i) {
            Rgb arriving = area[i] * spread[i];
            for (int j : shot) arriving += coupling(j, i) * X[j];
            gain[i] = rho[i] * arriving;
        }
        for (int i = 0; i < n; ++i) {
            const Rgb next = U[i] + gain[i];
            change += max_abs(next - X[i]);
            size += max_abs(next);
            X[i] = next;
        }
        if (change <= 1e-12 * size) break;
    }
    std::vector<Rgb> correction(n);
    for (int i = 0; i < n; ++i) correction[i] = area[i] > 0 ? (1 / area[i]) * gain[i] : Rgb{};
    return correction;
}

Solution ProgressiveSolver::finish() {
    // What needs the solver's own fields first: the ambient correction's sources and the
    // convergence test. Then the fields move into the result instead of being copied (the copy
    // doubled the fields' memory at the end: scene_scaling's 10,000 quads after 2 shots hold
    // 19 M coefficients a channel, 0.9 GB in the radiosity and unshot fields).
    std::vector<SplineField> added;  // per surface, what the ambient correction adds
    double ambient_power = 0, ambient_seconds = 0;
    long ambient_rays = 0;
    if (options_.ambient && options_.ambient_rays > 0) {
        // The unshot power and its further bounces gathered where they fall.
        std::vector<bool> irradiance;
        for (size_t i = 0; i < solution_.radiosity.size(); ++i)
            irradiance.push_back(!solution_.quantity.empty() &&
                                 solution_.quantity[i] == FieldQuantity::irradiance);
        const AmbientSources sources{solution_.unshot, order_, irradiance, hidden_};
        const double gather_start = now();
        AmbientGather gather = gather_ambient(
            scene_, octree_, sources, options_.ambient_rays, options_.ambient_level, 1,
            options_.ambient_final ? final_gather_share * options_.tolerance * radiosity_scale_
                                   : 0.0);
        ambient_seconds = now() - gather_start;
        added = std::move(gather.added);
        ambient_power = gather.power;
        ambient_rays = gather.rays;
    } else if (options_.ambient) {
        const std::vector<Rgb> correction = ambient_correction();
        added.resize(correction.size());
        for (size_t i = 0; i < correction.size(); ++i) {
            if (max_abs(correction[i]) == 0) continue;
            // An irradiance field takes the constant's H, correction / mean rho, so that the
            // power added is the same and B = rho H carries the texture.
            Rgb a = correction[i];
            if (solution_.quantity[i] == FieldQuantity::irradiance) {
                const Rgb rv = scene_.material_of(i).reflectance.mean();
                for (int c = 0; c < 3; ++c) a[c] = rv[c] > 0 ? a[c] / rv[c] : 0.0;
            }
            added[i] = SplineField::constant(order_[i], 0, a);
            ambient_power += channel_sum(correction[i]) * scene_.surfaces[i].surface.area();
        }
    }
    double largest = 0;
    for (int i = 0; i < int(scene_.surfaces.size()); ++i)
        largest = std::max(largest, unshot_power(i));
    Solution out = std::move(solution_);
    solution_ = Solution{};
    SolveStats& st = out.stats;
    for (size_t i = 0; i < added.size(); ++i)
        if (!added[i].empty()) out.radiosity[i].add(added[i]);
    st.ambient_seconds = ambient_seconds;
    st.ambient_power = ambient_power;
    st.ambient_rays = ambient_rays;
    // NaN anywhere in a solution is an error, never an output.
    for (size_t i = 0; i < out.radiosity.size(); ++i)
        for (int c = 0; c < 3 && !out.radiosity[i].empty(); ++c)
            for (double a : out.radiosity[i].channel(c).a)
                if (!std::isfinite(a))
                    throw std::runtime_error(
                        "the solution of surface '" + scene_.surfaces[i].name +
                        "' is not finite (NaN or infinity): the scene's sizes or emissions are "
                        "beyond what the solver resolves; try `set ambient false` or a smaller "
                        "scene extent");
    st.seconds = now() - start_seconds_;
    st.peak_memory_bytes = peak_memory_bytes();
    st.converged = largest <= options_.convergence * st.emitted_power;
    st.coefficients = 0;
    for (const SplineField& f : out.radiosity)
        if (!f.empty()) st.coefficients += long(f.channel(0).a.size());
    // Each surface's final quadtree: the union of the trees it received (a cell is split when
    // some transfer split it).
    for (size_t i = 0; i < out.leaves.size(); ++i) {
        const std::vector<std::uint64_t>& split = split_cells_[i];
        std::vector<DyadicCell> leaves;
        std::vector<DyadicCell> stack{{0, 0, 0}};
        while (!stack.empty()) {
            const DyadicCell c = stack.back();
            stack.pop_back();
            if (std::binary_search(split.begin(), split.end(), cell_key(c)))
                for (int q = 3; q >= 0; --q) stack.push_back(c.child(q & 1, q >> 1));
            else
                leaves.push_back(c);
        }
        out.leaves[i] = std::move(leaves);
    }
    return out;
}

Solution solve(const Scene& scene, const Octree& octree, const SolverOptions& options,
               const std::function<void(const ShotStats&, const ProgressiveSolver&)>& on_shot,
               const std::function<void(int done, int total)>& on_setup,
               const std::function<void(int done, int total)>& on_transfer) {
    ProgressiveSolver solver(scene, octree, options, on_setup);
    solver.on_transfer(on_transfer);
    while (!solver.done()) {
        const ShotStats shot = solver.shoot();
        if (on_shot) on_shot(shot, solver);
    }
    return solver.finish();
}

}  // namespace mbr
