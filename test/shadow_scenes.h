// test/shadow_scenes.h - what the tests of visibility share (paper section 5, "Adaptive
// Subdivision in Shadow Computation"; section 6, "Shadow" and "Octree"): the configurations of
// examples/studies/shadow_transfer.cpp (parallel unit squares at h = 1, the receiver [0,1]^2 in
// z = 0 facing up, the shooter in z = 1 facing down, opaque occluders between them, in an octree
// with the shooter as surface 0, the receiver as 1, occluders 2, 3...), small transfers, and
// independent geometry (brute-force kernels, crossings and hull tests) to check against.
#pragma once

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <set>
#include <vector>

#include "math/bspline.h"
#include "math/gauss_legendre.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/visibility/occlusion.h"
#include "radiosity/visibility/visible_parts.h"
#include "test/clip_reference.h"
#include "test/report.h"

namespace mbr::test {

// ---- Scenes ---------------------------------------------------------------------------------

inline std::vector<Vec3> quad_polygon(const Surface& s) {
    const Vec3* c = s.corners();
    return {c[0], c[1], c[2], c[3]};
}

inline Polygon make_polygon(const std::vector<Vec3>& v, int surface) {
    return Polygon(v, std::vector<Vec2>(v.size()), surface);
}

/// The octree of examples/studies/shadow_transfer.cpp: shooter 0, receiver 1, occluder k as 2 + k.
inline Octree make_octree(const ShadowSetup& setup) {
    std::vector<Polygon> polygons;
    polygons.push_back(make_polygon(quad_polygon(setup.shooter), 0));
    polygons.push_back(make_polygon(quad_polygon(setup.receiver), 1));
    for (size_t i = 0; i < setup.occluders.size(); ++i)
        polygons.push_back(make_polygon(setup.occluders[i], int(2 + i)));
    return Octree(std::move(polygons));
}

/// A pair with its octree and occlusion context (which points at the octree: not copyable).
struct Pair {
    ShadowSetup setup;
    Octree octree;
    OcclusionContext context;
    explicit Pair(ShadowSetup s, std::uint64_t shot = 0)
        : setup(std::move(s)),
          octree(make_octree(setup)),
          context(make_occlusion_context(octree, setup.shooter, 0, setup.receiver, 1, shot)) {}
    Pair(const Pair&) = delete;
    Pair& operator=(const Pair&) = delete;
};

/// occluded_squares(0) with its occluder replaced.
inline ShadowSetup squares_with(std::vector<std::vector<Vec3>> occluders) {
    ShadowSetup s = occluded_squares(0);
    s.occluders = std::move(occluders);
    return s;
}

/// A square of side 2a centred at (x, y) in the plane z.
inline std::vector<Vec3> square_at(double x, double y, double z, double a) {
    return {{x - a, y - a, z}, {x + a, y - a, z}, {x + a, y + a, z}, {x - a, y + a, z}};
}

// ---- Transfers ------------------------------------------------------------------------------

/// Small trees and loose tolerances so that a transfer takes a fraction of a second: the
/// receiver's oracle tree at depths 1..2, shadow subdivision down to level 3, edgefill and the
/// quadrature of (21) ten times looser than the defaults (the invariants checked with these hold
/// for any options).
inline ReceiverOptions small_options(ShadowMethod method) {
    ReceiverOptions o;
    o.min_depth = 1;
    o.max_depth = 2;
    o.edgefill_tolerance = 1e-3;
    o.edgefill_max_depth = 4;
    o.quadrature.rel_tolerance = 1e-3;
    o.shadows.method = method;
    o.shadows.max_depth = 3;
    return o;
}

struct Run {
    SplineField field;
    ReceiverState state;
};

/// One transfer from the setup's shooter (radiosity 1) to its receiver (reflectance 1).
inline Run run_transfer(const ShadowSetup& setup, const ReceiverOptions& options,
                        const OcclusionContext* occlusion) {
    Run run;
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    run.field = transfer(shooter, receiver, options, nullptr, &run.state, occlusion);
    return run;
}

/// Coefficients (all channels) that differ, bit for bit; -1 when the levels differ.
inline int n_differing(const SplineField& a, const SplineField& b) {
    if (a.level() != b.level() || a.order() != b.order()) return -1;
    const int first = first_touching_index(a.order()), n = touching_count(a.order(), a.level());
    int differ = 0;
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l)
            if (!(a.coefficient(k, l) == b.coefficient(k, l))) ++differ;
    return differ;
}

/// Coefficients with a channel not exactly zero.
inline int n_nonzero(const SplineField& f) {
    const int first = first_touching_index(f.order()), n = touching_count(f.order(), f.level());
    int count = 0;
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l) {
            const Rgb c = f.coefficient(k, l);
            if (c.r != 0 || c.g != 0 || c.b != 0) ++count;
        }
    return count;
}

inline Shooter unit_shooter(const Surface& surface) {
    Shooter shooter;
    shooter.surface = &surface;
    shooter.unshot = SplineField::constant(4, 0, {1, 1, 1});
    return shooter;
}

// ---- Independent geometry -------------------------------------------------------------------

/// The form factor kernel (3), written out again (no library code): cosines clamped at zero.
inline double kernel_F(Vec3 p, Vec3 n_p, Vec3 x, Vec3 n_x) {
    const Vec3 l = x - p;
    const double a = dot(l, n_p), b = -dot(l, n_x);
    if (a <= 0 || b <= 0) return 0;
    const double r2 = dot(l, l);
    return a * b / (Pi * r2 * r2);
}

/// Whether the open segment p -> x crosses the convex planar polygon (its plane, then the side
/// of every edge): independent of Polygon::intersect.
inline bool crosses(Vec3 p, Vec3 x, const std::vector<Vec3>& poly) {
    Vec3 n{};
    for (size_t i = 0; i < poly.size(); ++i) n += cross(poly[i], poly[(i + 1) % poly.size()]);
    const double dp = dot(n, p - poly[0]), dx = dot(n, x - poly[0]);
    if ((dp > 0) == (dx > 0) || dp == dx) return false;
    const Vec3 q = p + (dp / (dp - dx)) * (x - p);
    for (size_t i = 0; i < poly.size(); ++i) {
        const Vec3 a = poly[i], b = poly[(i + 1) % poly.size()];
        if (dot(cross(b - a, q - a), n) < 0) return false;
    }
    return true;
}

/// Adaptive brute force of int_[0,1]^2 F(p, x(u,v)) VIS(p, x(u,v)) A(u,v) du dv: 5- against
/// 6-point Gauss-Legendre per cell; a cell whose nodes and corners disagree on visibility is
/// split down to the cap. A mixed cell at the cap holds a step of VIS, which no Gauss rule
/// integrates well, and the shadow's straight edges cross the capped cells of one row at the same
/// offset, so a fixed rule's errors add up coherently (measured: 1e-4 of the value at cap 11).
/// There the cell's value is instead estimated from one jittered point in each of 8 x 8 strata
/// (seeded): unbiased, its error random. Per capped cell the error is at most max(F A) x its
/// area (the estimate and the integral both lie in [0, that]): summed, `bound`. Its variance is
/// at most (max(F A) area)^2 x 30 / 4 / 64^2 (at most 30 of the 64 strata are cut by the one or
/// two shadow edges crossing a tiny cell, each a Bernoulli of variance <= 1/4): summed, `variance`.
struct Brute {
    double value = 0;
    double bound = 0;     // rigorous bound on the error of the capped mixed cells
    double variance = 0;  // bound on the variance of their estimate
    long n_evaluations = 0;
    long n_capped = 0;
};
inline Brute brute_shadowed(Vec3 p, Vec3 n_p, const Surface& shooter,
                            const std::vector<std::vector<Vec3>>& occluders, double tol,
                            int min_depth, int cap, unsigned seed) {
    const GaussLegendre g5 = gauss_legendre(5), g6 = gauss_legendre(6);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jitter(0, 1);
    Brute out;
    struct Sample {
        double fa;  // F A, visibility ignored
        bool visible;
    };
    auto sample = [&](double u, double v) {
        const SurfacePoint x = shooter.evaluate(u, v);
        bool vis = true;
        for (const auto& o : occluders) vis = vis && !crosses(p, x.position, o);
        ++out.n_evaluations;
        return Sample{kernel_F(p, n_p, x.position, x.normal) * x.area_factor, vis};
    };
    std::function<void(const Rect&, double, int)> cell = [&](const Rect& r, double t, int depth) {
        int n_vis = 0, n_hid = 0;
        double max_fa = 0;
        auto rule = [&](const GaussLegendre& g) {
            double sum = 0;
            const double hx = 0.5 * r.width(), hy = 0.5 * r.height();
            for (int a = 0; a < g.n(); ++a)
                for (int b = 0; b < g.n(); ++b) {
                    const Sample s = sample(r.x0 + hx * (g.x[a] + 1), r.y0 + hy * (g.x[b] + 1));
                    (s.visible ? n_vis : n_hid) += 1;
                    max_fa = std::max(max_fa, s.fa);
                    if (s.visible) sum += g.w[a] * g.w[b] * s.fa;
                }
            return sum * hx * hy;
        };
        const double q5 = rule(g5), q6 = rule(g6);
        for (double u : {r.x0, r.x1})
            for (double v : {r.y0, r.y1}) {
                const Sample s = sample(u, v);
                (s.visible ? n_vis : n_hid) += 1;
                max_fa = std::max(max_fa, s.fa);
            }
        const bool mixed = n_vis > 0 && n_hid > 0;
        if (depth < min_depth || (depth < cap && (mixed || std::fabs(q6 - q5) > t))) {
            const double xm = 0.5 * (r.x0 + r.x1), ym = 0.5 * (r.y0 + r.y1);
            const double t4 = std::max(0.25 * t, 1e-3 * tol * std::ldexp(1.0, -2 * cap));
            cell({r.x0, xm, r.y0, ym}, t4, depth + 1);
            cell({xm, r.x1, r.y0, ym}, t4, depth + 1);
            cell({r.x0, xm, ym, r.y1}, t4, depth + 1);
            cell({xm, r.x1, ym, r.y1}, t4, depth + 1);
            return;
        }
        if (!mixed) {
            out.value += q6;
            return;
        }
        double sum = 0;
        for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b) {
                const double ju = jitter(rng), jv = jitter(rng);
                const Sample s =
                    sample(r.x0 + (a + ju) / 8 * r.width(), r.y0 + (b + jv) / 8 * r.height());
                if (s.visible) sum += s.fa;
            }
        out.value += sum / 64 * r.area();
        // F A varies by a few per cent at most across a capped cell: 1.1 covers it.
        const double m = 1.1 * max_fa * r.area();
        out.bound += m;
        out.variance += m * m * 30 / 4 / (64.0 * 64.0);
        ++out.n_capped;
    };
    cell(Rect{0, 1, 0, 1}, tol, 0);
    return out;
}

/// The largest gap between the convex hull of `pts` and the convex polygon `poly` over a
/// superset of the separating-axis candidates (normals of every triple of hull points, which
/// include the hull's faces; the polygon's normal; cross products of every pair direction of the
/// hull, which include its edges, with every polygon edge and with the polygon's normal; cross
/// products of polygon edges with the triple normals, for flat hulls). Positive: the two are
/// disjoint with that gap along a unit axis; negative: they overlap on every axis tried, so they
/// meet (the candidates are complete for convex polytopes).
inline double hull_polygon_gap(const std::vector<Vec3>& pts, const std::vector<Vec3>& poly) {
    std::vector<Vec3> axes, dirs, normals;
    const int n = static_cast<int>(pts.size());
    for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b) {
            dirs.push_back(pts[b] - pts[a]);
            for (int c = b + 1; c < n; ++c)
                normals.push_back(cross(pts[b] - pts[a], pts[c] - pts[a]));
        }
    Vec3 n_poly{};
    for (size_t i = 0; i < poly.size(); ++i) n_poly += cross(poly[i], poly[(i + 1) % poly.size()]);
    axes = normals;
    axes.push_back(n_poly);
    for (const Vec3& d : dirs) {
        axes.push_back(cross(d, n_poly));
        for (size_t i = 0; i < poly.size(); ++i)
            axes.push_back(cross(d, poly[(i + 1) % poly.size()] - poly[i]));
    }
    for (const Vec3& nt : normals)
        for (size_t i = 0; i < poly.size(); ++i)
            axes.push_back(cross(nt, poly[(i + 1) % poly.size()] - poly[i]));
    double best = -HUGE_VAL;
    for (Vec3 axis : axes) {
        const double len = length(axis);
        if (len < 1e-12) continue;
        axis = axis / len;
        double lo1 = HUGE_VAL, hi1 = -HUGE_VAL, lo2 = HUGE_VAL, hi2 = -HUGE_VAL;
        for (const Vec3& q : pts) {
            lo1 = std::min(lo1, dot(axis, q));
            hi1 = std::max(hi1, dot(axis, q));
        }
        for (const Vec3& q : poly) {
            lo2 = std::min(lo2, dot(axis, q));
            hi2 = std::max(hi2, dot(axis, q));
        }
        best = std::max(best, std::max(lo2 - hi1, lo1 - hi2));
    }
    return best;
}

inline Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        const Vec3 v{g(rng), g(rng), g(rng)};
        if (length(v) > 1e-3) return normalize(v);
    }
}

/// A random parallelogram (planar, convex) centred at c with sides up to `size`.
inline std::vector<Vec3> random_parallelogram(std::mt19937& rng, Vec3 c, double size) {
    std::uniform_real_distribution<double> u(0.3, 1);
    const Vec3 n = random_unit(rng);
    const Vec3 a = normalize(cross(n, random_unit(rng)));
    const Vec3 b = normalize(cross(n, a) + 0.5 * (u(rng) - 0.65) * a);
    const Vec3 e1 = size * u(rng) * a, e2 = size * u(rng) * b;
    return {c - 0.5 * e1 - 0.5 * e2, c + 0.5 * e1 - 0.5 * e2, c + 0.5 * e1 + 0.5 * e2,
            c - 0.5 * e1 + 0.5 * e2};
}

/// A random triangle centred near c.
inline std::vector<Vec3> random_triangle(std::mt19937& rng, Vec3 c, double size) {
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    std::vector<Vec3> t;
    for (int i = 0; i < 3; ++i) t.push_back(c + size * Vec3{u(rng), u(rng), u(rng)});
    return t;
}

inline Surface quad_surface(const std::vector<Vec3>& q) {
    return Surface::planar_quad(q[0], q[1], q[2], q[3]);
}

}  // namespace mbr::test
