// test/test_visible_parts.cpp - exact visibility inside (21) (beyond the paper,
// ShadowMethod::Exact; radiosity/visibility/visible_parts.h and the IncrementIntegrator of
// radiosity/transfer/ sample_values.h with an OcclusionContext): horizon clipping, visible pieces
// and occluders_toward, against the analytic shadowed form factor, itself checked against an
// adaptive brute force.
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
#include "test/report.h"
#include "test/shadow_scenes.h"

using namespace mbr;
using namespace mbr::test;

// ---- Exact visibility --------------------------------------------------------------------------

TEST_CASE("shadow: shadowed_form_factor agrees with adaptive brute force",
          "[shadow][visible_parts]") {
    // The analytic reference (two contour integrals) against the integral of F VIS A over the
    // shooter by an adaptive 5/6-point Gauss rule that splits cells whose nodes or corners
    // disagree on visibility down to level 11 (cells of 1/2048), with an independent
    // ray-occluder test; capped mixed cells are estimated by stratified jittered points (see
    // brute_shadowed). Two tolerances: the rigorous `bound` (the sum over capped cells of
    // max(F A) x area, 1e-4 .. 2e-3 of the unshadowed value here), and 5 standard deviations of
    // the capped cells' estimate (from the variance bound: about 1e-6 of the value) plus the
    // 1e-9 relative asked of the smooth cells and 1e-9 more for the a priori tolerance floor.
    struct Point {
        const char* config;
        ShadowSetup setup;
        Vec2 st;
    };
    const ShadowSetup square = occluded_squares(0), tilted = occluded_squares(30),
                      umbra = occluded_squares(0, 0.3);
    const Point points[] = {
        {"square", square, {0.5, 0.5}},  {"square", square, {0.2, 0.7}},
        {"square", square, {0.9, 0.15}}, {"tilted", tilted, {0.5, 0.5}},
        {"tilted", tilted, {0.35, 0.8}}, {"umbra", umbra, {0.15, 0.45}},
        {"umbra", umbra, {0.5, 0.5}},
    };
    double worst = 0;
    for (const Point& pt : points) {
        const SurfacePoint p = pt.setup.receiver.evaluate(pt.st.x, pt.st.y);
        const double exact = shadowed_form_factor(
            p.position, p.normal, quad_polygon(pt.setup.shooter), pt.setup.occluders[0]);
        const double full =
            point_polygon_form_factor(p.position, p.normal, quad_polygon(pt.setup.shooter));
        const Brute b = brute_shadowed(p.position, p.normal, pt.setup.shooter, pt.setup.occluders,
                                       1e-9 * full, 4, 11, 1234);
        const double sigma = std::sqrt(b.variance);
        CAPTURE(pt.config, pt.st.x, pt.st.y, exact, full, b.value, b.bound, sigma, b.n_capped);
        CHECK(std::fabs(b.value - exact) <= b.bound + 2e-9 * full);
        CHECK(std::fabs(b.value - exact) <= 5 * sigma + 2e-9 * full);
        if (exact == 0) CHECK(b.value == 0);  // the umbra: every node hidden
        worst = std::max(worst, std::fabs(b.value - exact) / full);
        mbr::test::report() << "shadow brute force " << pt.config << " (" << pt.st.x << ", "
                            << pt.st.y << "): exact " << exact << ", brute " << b.value
                            << ", difference " << b.value - exact << " (rigorous bound " << b.bound
                            << ", sigma " << sigma << "), " << b.n_capped << " capped cells, "
                            << b.n_evaluations << " evaluations\n";
    }
    mbr::test::report() << "shadow brute force: worst |brute - exact| / F_unshadowed " << worst
                        << "\n";
}

TEST_CASE("shadow: exact visibility in (21) matches the shadowed form factor",
          "[shadow][visible_parts]") {
    // IncrementIntegrator with an occlusion context (ShadowMethod::Exact) at random receiving
    // points of the square and tilted configurations, and of the small shooter (side 0.3) whose
    // occluder casts an umbra on [0.25, 0.75]^2. The rule's tolerance is 1e-4 relative to the
    // unshadowed estimate (floor 1e-4 of max B): |I - exact| <= 1e-4 F_unshadowed at every point.
    // In the umbra nothing is visible: I is 0. Both the quadrature (the whole minus the hidden
    // part) and the closed form (a constant shooter's default) are checked.
    for (const bool analytic : {false, true}) {
        CAPTURE(analytic);
        QuadratureOptions options;
        options.analytic = analytic;
        struct Config {
            const char* name;
            ShadowSetup setup;
        };
        const Config configs[] = {{"square", occluded_squares(0)},
                                  {"tilted", occluded_squares(30)},
                                  {"umbra", occluded_squares(0, 0.3)}};
        std::mt19937 rng(17);
        std::uniform_real_distribution<double> unit(0, 1);
        for (const Config& c : configs) {
            const Pair pair(c.setup);
            REQUIRE(pair.context.candidates.size() == 1);
            const Shooter shooter = unit_shooter(c.setup.shooter);
            IncrementIntegrator integrator(shooter, options, &pair.context);
            const std::vector<Vec3> polygon = quad_polygon(c.setup.shooter);
            double worst = 0;
            long evaluations = 0, rays = 0;
            int n_points = 0, n_umbra = 0;
            for (int i = 0; i < 40; ++i) {
                const double s = unit(rng), t = unit(rng);
                const SurfacePoint p = c.setup.receiver.evaluate(s, t);
                const double full = point_polygon_form_factor(p.position, p.normal, polygon);
                const double exact =
                    shadowed_form_factor(p.position, p.normal, polygon, c.setup.occluders[0]);
                const IncrementIntegrator::Result r = integrator.integrate(p);
                CAPTURE(c.name, s, t, exact, full, r.value.r);
                CHECK(r.converged);
                CHECK(std::fabs(r.value.r - exact) <= 1e-4 * full);
                worst = std::max(worst, std::fabs(r.value.r - exact) / full);
                evaluations += r.n_evaluations;
                rays += r.n_rays;
                ++n_points;
                if (std::string(c.name) == "umbra" && s > 0.26 && s < 0.74 && t > 0.26 &&
                    t < 0.74) {
                    // The closed form sums the visible pieces: none, exactly 0. The quadrature
                    // subtracts the hidden part from the whole (shadow_subtraction): 0 up to
                    // rounding of the two equal integrals.
                    if (analytic)
                        CHECK(r.value.r == 0);
                    else
                        CHECK(std::fabs(r.value.r) <= 1e-12 * full);
                    ++n_umbra;
                }
            }
            CHECK(rays == 0);  // a planar shooter is clipped, not sampled by rays
            if (std::string(c.name) == "umbra") CHECK(n_umbra >= 5);
            mbr::test::report() << "shadow exact visibility " << c.name
                                << (analytic ? " (closed form)" : "") << ": worst |I - exact| / F "
                                << worst << ", kernel evaluations per point "
                                << evaluations / n_points << "\n";
        }
    }
}

TEST_CASE("shadow: a small shadow under a large shooter is kept", "[shadow][visible_parts]") {
    // The shooter 1e5 across at height 1 over the unit receiver, and an occluder of side 0.02
    // at height 0.5 over the receiver's centre: seen from the centre its shadow on the shooter
    // is 0.04 across, 1.6e-13 of the shooter's area, yet it hides what lies straight above,
    // where the form factor is largest. Slivers must be told from it by their width, not by
    // their area against the shooter's (with regions below 1e-10 of the shooter's area
    // dropped, this test failed). Exact visibility must match the analytic shadowed form
    // factor.
    const double side = 1e5;
    ShadowSetup setup;
    setup.shooter = Surface::planar_quad({-side / 2, -side / 2, 1}, {-side / 2, side / 2, 1},
                                         {side / 2, side / 2, 1}, {side / 2, -side / 2, 1});
    setup.receiver = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    setup.occluders = {square_at(0.5, 0.5, 0.5, 0.01)};
    const Pair pair(setup);
    REQUIRE(pair.context.candidates.size() == 1);
    const std::vector<Vec3> polygon = quad_polygon(setup.shooter);
    const Shooter shooter = unit_shooter(setup.shooter);  // the integrator keeps a reference
    for (const bool analytic : {false, true}) {
        QuadratureOptions options;
        options.analytic = analytic;
        IncrementIntegrator integrator(shooter, options, &pair.context);
        for (double s : {0.5, 0.505, 0.52}) {
            const SurfacePoint p = setup.receiver.evaluate(s, 0.5);
            const double full = point_polygon_form_factor(p.position, p.normal, polygon);
            const double exact =
                shadowed_form_factor(p.position, p.normal, polygon, setup.occluders[0]);
            const double I = integrator.integrate(p).value.r;
            CAPTURE(analytic, s, full, exact, I);
            REQUIRE(full - exact > 1e-4);  // the shadow matters: 5.1e-4 of F at the centre
            CHECK(std::fabs(I - exact) <= 1e-4 * full);
        }
    }
}

TEST_CASE("shadow: exact visibility on a curved shooter casts rays and matches the reference",
          "[shadow][visible_parts]") {
    // The parallel unit shooter given as a bilinear patch (the same flat square, but not a
    // PlanarQuad, so the integrator takes the curved path: one ray per quadrature node, cells
    // whose nodes disagree on visibility split down to max_visibility_depth). Against the
    // analytic reference, at random points of the square and tilted configurations.
    // The n against n + 1 test never passes on a cell holding a visibility step, so the rule's
    // depth is capped at max_visibility_depth (8 here): cells still mixed at the cap are kept,
    // and the rule reports that it did not converge. It also starts from 16 x 16 cells (min_depth
    // 4): the nodes of a coarse cell miss a shadow, or a gap of light, that covers only a sliver
    // along the cell's edge (see the [!mayfail] test below; at min_depth 3 one of these points
    // still errs by 5.9e-4 of F for that reason). At depth 8 the cells along a shadow edge hold a
    // step that the Gauss rule integrates with an error up to max(F) x cell area each, coherent
    // along a straight edge (about 1e-4 of the value summed): 1e-3 of the unshadowed value is the
    // tolerance.
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> unit(0, 1);
    for (double tilt : {0.0, 30.0}) {
        ShadowSetup setup = occluded_squares(tilt);
        const std::vector<Vec3> polygon = quad_polygon(setup.shooter);
        setup.shooter = Surface::bilinear_patch(polygon[0], polygon[1], polygon[2], polygon[3]);
        const Pair pair(setup);
        REQUIRE(pair.context.candidates.size() == 1);
        const Shooter shooter = unit_shooter(setup.shooter);
        QuadratureOptions options;
        options.max_visibility_depth = 8;
        options.min_depth = 4;
        IncrementIntegrator integrator(shooter, options, &pair.context);
        double worst = 0;
        long rays = 0, evaluations = 0;
        for (int i = 0; i < 4; ++i) {
            const double s = unit(rng), t = unit(rng);
            const SurfacePoint p = setup.receiver.evaluate(s, t);
            const double full = point_polygon_form_factor(p.position, p.normal, polygon);
            const double exact =
                shadowed_form_factor(p.position, p.normal, polygon, setup.occluders[0]);
            const IncrementIntegrator::Result r = integrator.integrate(p);
            CAPTURE(tilt, s, t, exact, full, r.value.r);
            CHECK(std::fabs(r.value.r - exact) <= 1e-3 * full);
            worst = std::max(worst, std::fabs(r.value.r - exact) / full);
            rays += r.n_rays;
            evaluations += r.n_evaluations;
        }
        CHECK(rays > 0);
        mbr::test::report() << "shadow exact visibility, curved path, tilt " << tilt
                            << ": worst |I - exact| / F " << worst << ", per point " << rays / 4
                            << " rays, " << evaluations / 4 << " kernel evaluations\n";
    }
}

TEST_CASE("shadow: exact visibility on a curved shooter sees a shadow along a cell's edge",
          "[shadow][visible_parts][!mayfail]") {
    // KNOWN LIMITATION (radiosity/transfer/sample_values.cpp, IncrementIntegrator::cell_value,
    // curved path): a cell is split for visibility only when its quadrature nodes disagree; a
    // shadow that covers only a sliver between the cell's edge and its outermost nodes (up to ~3 %
    // of the cell's width for n = 6) is never seen. Input: the tilted configuration
    // (occluded_squares(30)) with the shooter as a bilinear patch (the same flat square), receiving
    // point (s, t) = (0.8720885877, 0.9264383943), default quadrature options but min_share = 1e-2
    // and max_visibility_depth = 8 (for speed: the miss is the same with the defaults, with
    // max_visibility_depth 8 .. 12 and min_share 1e-2 .. 1e-4). The shadow's edge runs at 0.0044
    // of the shooter's width beside the line u = 1/2 between the level-1 cells; the right cells'
    // nodes all see the shooter. Expected |I - exact| <= 1e-4 F (the requested tolerance), exact
    // = 0.1397576; got I = 0.1401167, 2.1e-3 of F too much. With min_depth 3 the error is 1.1e-4.
    ShadowSetup setup = occluded_squares(30);
    const std::vector<Vec3> polygon = quad_polygon(setup.shooter);
    setup.shooter = Surface::bilinear_patch(polygon[0], polygon[1], polygon[2], polygon[3]);
    const Pair pair(setup);
    const Shooter shooter = unit_shooter(setup.shooter);
    QuadratureOptions options;
    options.min_share = 1e-2;
    options.max_visibility_depth = 8;
    IncrementIntegrator integrator(shooter, options, &pair.context);
    const SurfacePoint p = setup.receiver.evaluate(0.8720885877, 0.9264383943);
    const double full = point_polygon_form_factor(p.position, p.normal, polygon);
    const double exact = shadowed_form_factor(p.position, p.normal, polygon, setup.occluders[0]);
    const double I = integrator.integrate(p).value.r;
    CAPTURE(exact, full, I);
    CHECK(std::fabs(I - exact) <= 1e-4 * full);
}

TEST_CASE("shadow: max_visibility_depth bounds the work of exact visibility on a curved shooter",
          "[shadow][visible_parts]") {
    // The same flat square as a bilinear patch, the square occluder, two points, the default
    // quadrature options and max_visibility_depth 6 and 8. A step never passes the n against
    // n + 1 test, so without a cap the cells along the shadow's edges split down to where the
    // min_share floor stops them (level 15-16, 1.7e7 to 3.6e7 rays per point measured before the
    // cap); with it no cell is deeper than the cap. The error of the cells kept at the cap is
    // about max(F) x their area per cell along the edge: 2e-3 of F at depth 6, 1e-3 at 8.
    ShadowSetup setup = occluded_squares(0);
    const std::vector<Vec3> polygon = quad_polygon(setup.shooter);
    setup.shooter = Surface::bilinear_patch(polygon[0], polygon[1], polygon[2], polygon[3]);
    const Pair pair(setup);
    const Shooter shooter = unit_shooter(setup.shooter);
    for (int depth : {6, 8}) {
        QuadratureOptions options;
        options.max_visibility_depth = depth;
        IncrementIntegrator integrator(shooter, options, &pair.context);
        for (Vec2 st : {Vec2{0.5, 0.5}, Vec2{0.2, 0.7}}) {
            const SurfacePoint p = setup.receiver.evaluate(st.x, st.y);
            const double full = point_polygon_form_factor(p.position, p.normal, polygon);
            const double exact =
                shadowed_form_factor(p.position, p.normal, polygon, setup.occluders[0]);
            const IncrementIntegrator::Result r = integrator.integrate(p, true);
            int deepest = 0;
            for (const auto& cell : r.partition) deepest = std::max(deepest, cell.cell.level);
            CAPTURE(depth, st, r.value.r, exact, full);
            CHECK(deepest <= depth);
            CHECK(std::fabs(r.value.r - exact) <= (depth == 6 ? 2e-3 : 1e-3) * full);
            mbr::test::report() << "shadow cost, curved path, max_visibility_depth " << depth
                                << ", point " << st << ": " << r.n_rays << " rays, "
                                << r.partition.size() << " cells down to level " << deepest
                                << ", |I - exact| / F " << std::fabs(r.value.r - exact) / full
                                << "\n";
        }
    }
}

TEST_CASE("shadow: exact visibility when a shadow's vertex lies on the shooter's outline",
          "[shadow][visible_parts]") {
    // When the central projection of an occluder has a vertex exactly on an edge line of the
    // shooter's outline and the next vertex beyond it, intersect() (with which blocked_view
    // clips the shadow to the shooter) used to return that vertex twice; the zero-length edge
    // made classify() answer "disjoint" for every cell, so the shadow was ignored (fixed in
    // clip). Cases, at the receiver's centre p = (0.5, 0.5, 0) under the parallel unit shooter:
    // (a) the occluder (0.5,0.25,0.5) (0.65,0,0.5) (0.85,0.55,0.5) (0.4,0.6,0.5), whose vertex
    //     (0.5,0.25,0.5) projects onto the edge y = 0: expected I(p) = shadowed_form_factor =
    //     0.138844 (it was 0.239456, the unshadowed form factor: 72 % too much light);
    // (b) the triangle (-1,-1) (3,-1) (3,3) in z = 0.5 (the half x >= y), whose shadow's edge
    //     runs through the shooter's corners (0,0) and (1,1): expected half the form factor,
    //     0.119728 (it was 0.239456 at every point of the receiver's diagonal s = t).
    // Each case is checked first at p moved by 1e-9 in t, where the code is right. In a whole
    // transfer (the Gauss nodes of the receiver's diagonal leaves lie on s = t): shadow_transfer
    // --method exact --max-shadow-depth 3 with the custom occluder (-1,-1,.5) (1,-1,.5) (3,1,.5)
    // (3,3,.5) measured rea 8.39 % (L1 6.2 %) before the fix, and measures 0.64 % (L1 0.42 %)
    // since, as with its first and last vertices moved by 1e-3 off the shooter's corners.
    const std::vector<Vec3> cases[] = {
        {{0.5, 0.25, 0.5}, {0.65, 0, 0.5}, {0.85, 0.55, 0.5}, {0.4, 0.6, 0.5}},
        {{-1, -1, 0.5}, {3, -1, 0.5}, {3, 3, 0.5}},
    };
    for (const std::vector<Vec3>& occluder : cases) {
        const ShadowSetup setup = squares_with({occluder});
        const Pair pair(setup);
        REQUIRE(pair.context.candidates.size() == 1);
        const Shooter shooter = unit_shooter(setup.shooter);
        for (const bool analytic : {false, true}) {  // the quadrature and the closed form
            QuadratureOptions options;
            options.analytic = analytic;
            IncrementIntegrator integrator(shooter, options, &pair.context);
            const std::vector<Vec3> polygon = quad_polygon(setup.shooter);
            for (double dt : {1e-9, 0.0}) {
                const SurfacePoint p = setup.receiver.evaluate(0.5, 0.5 + dt);
                const double full = point_polygon_form_factor(p.position, p.normal, polygon);
                const double exact =
                    shadowed_form_factor(p.position, p.normal, polygon, setup.occluders[0]);
                const double I = integrator.integrate(p).value.r;
                CAPTURE(occluder, analytic, dt, exact, full, I);
                CHECK(std::fabs(I - exact) <= 1e-4 * full);
            }
        }
    }
}

TEST_CASE("shadow: visible pieces of the shooter's cells tile its unshadowed part",
          "[shadow][visible_parts]") {
    // blocked_view, classify_cell and visible_pieces on a grid of 8 x 8 shooter cells: the areas
    // of what each cell shows (all of a clear cell, nothing of a hidden one, the pieces of a cut
    // one) add up to the shooter's area minus the shadow's (one occluder: one shadow polygon,
    // already clipped to the shooter). Areas are sums of a few products: 1e-12 is rounding.
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> unit(0, 1);
    for (double tilt : {0.0, 30.0}) {
        const ShadowSetup setup = occluded_squares(tilt);
        const Pair pair(setup);
        const ShooterPlane plane = make_shooter_plane(setup.shooter);
        int counts[3] = {0, 0, 0};
        for (int i = 0; i < 20; ++i) {
            const double ps = unit(rng), pt = unit(rng);
            const SurfacePoint p = setup.receiver.evaluate(ps, pt);
            const BlockedView view = blocked_view(plane, p.position, p.normal, &pair.context);
            CHECK_FALSE(view.behind_all);
            CHECK_FALSE(view.horizon_cuts);  // parallel planes
            REQUIRE(view.shadows.size() <= 1);
            const double shadow = view.shadows.empty() ? 0 : signed_area(view.shadows[0]);
            double visible = 0;
            for (int a = 0; a < 8; ++a)
                for (int b = 0; b < 8; ++b) {
                    const ConvexPolygon cell{
                        plane.at(a / 8.0, b / 8.0), plane.at((a + 1) / 8.0, b / 8.0),
                        plane.at((a + 1) / 8.0, (b + 1) / 8.0), plane.at(a / 8.0, (b + 1) / 8.0)};
                    const CellVisibility v = classify_cell(cell, view);
                    ++counts[static_cast<int>(v)];
                    if (v == CellVisibility::clear) visible += std::fabs(signed_area(cell));
                    if (v == CellVisibility::cut)
                        for (const ConvexPolygon& piece : visible_pieces(cell, view))
                            visible += signed_area(piece);
                }
            CAPTURE(tilt, p.position, shadow, visible);
            CHECK(visible + shadow == Approx(1.0).margin(1e-12));
        }
        CHECK(counts[0] > 0);
        CHECK(counts[1] > 0);
        CHECK(counts[2] > 0);
    }
}

TEST_CASE("shadow: horizon clipping integrates exactly what the tangent plane leaves",
          "[shadow][visible_parts]") {
    // Receivers whose tangent plane cuts a planar shooter: (a) the perpendicular squares with the
    // shooter extended below the receiver's plane (z from -0.5 to 1), (b) a receiver tilted by
    // 60 degrees under the parallel shooter at h = 1. The analytic point_polygon_form_factor
    // clips at the tangent plane; with clip_horizon the quadrature integrates the front part of
    // each cut cell exactly (convex pieces, collapsed Gauss rule), so the integrand is smooth on
    // every piece: asked for 1e-8 relative, the result is within 1e-8 of the analytic value
    // (the n against n + 1 test overestimates the error of the kept rule). Without clipping the
    // quadrature chases the kink of the clamped cosine down to small cells: at the default
    // tolerance (1e-4, where both are within it) the clipped rule must use at least 4 times fewer
    // kernel evaluations, and at 1e-6 (one point, unclipped) at least 20 times fewer (measured:
    // ~17x and ~300x; the counts are reported, never timed).
    struct Config {
        const char* name;
        Surface shooter, receiver;
    };
    const double c = std::cos(Pi / 3), s = std::sin(Pi / 3);
    const Config configs[] = {
        {"perpendicular, shooter below the horizon",
         Surface::planar_quad({0, 0, -0.5}, {0, 0, 1}, {1, 0, 1}, {1, 0, -0.5}),
         Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0})},
        {"receiver tilted by 60 degrees",
         Surface::planar_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}),
         Surface::planar_quad({0, 0.2, 0.1}, {1, 0.2, 0.1}, {1, 0.2 + c, 0.1 + s},
                              {0, 0.2 + c, 0.1 + s})},
    };
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> unit(0.05, 0.95);
    for (const Config& cf : configs) {
        const Shooter shooter = unit_shooter(cf.shooter);
        QuadratureOptions clipped, unclipped, tight;
        // The quadrature itself is measured: not the closed form a constant shooter would get.
        clipped.analytic = unclipped.analytic = tight.analytic = false;
        unclipped.clip_horizon = false;
        tight.rel_tolerance = 1e-8;
        IncrementIntegrator with(shooter, clipped), without(shooter, unclipped),
            precise(shooter, tight);
        const std::vector<Vec3> polygon = quad_polygon(cf.shooter);
        const ShooterPlane plane = make_shooter_plane(cf.shooter);
        double worst = 0, worst_default = 0, worst_without = 0;
        long evals_with = 0, evals_without = 0, evals_tight = 0;
        int n_cut = 0;
        for (int i = 0; i < 12; ++i) {
            const double ps = unit(rng), pt = unit(rng);
            const SurfacePoint p = cf.receiver.evaluate(ps, pt);
            const double exact = point_polygon_form_factor(p.position, p.normal, polygon);
            if (!(exact > 0)) continue;
            const BlockedView view = blocked_view(plane, p.position, p.normal, nullptr);
            n_cut += view.horizon_cuts;
            const IncrementIntegrator::Result a = with.integrate(p), b = without.integrate(p);
            const IncrementIntegrator::Result t = precise.integrate(p);
            CAPTURE(cf.name, p.position, exact, a.value.r, b.value.r, t.value.r);
            CHECK(a.converged);
            CHECK(t.converged);
            CHECK(a.value.r == Approx(exact).epsilon(1e-4));  // the requested tolerance
            CHECK(b.value.r == Approx(exact).epsilon(1e-4));
            CHECK(t.value.r == Approx(exact).epsilon(1e-8));
            worst = std::max(worst, std::fabs(t.value.r - exact) / exact);
            worst_default = std::max(worst_default, std::fabs(a.value.r - exact) / exact);
            evals_tight += t.n_evaluations;
            worst_without = std::max(worst_without, std::fabs(b.value.r - exact) / exact);
            evals_with += a.n_evaluations;
            evals_without += b.n_evaluations;
        }
        CHECK(n_cut >= 8);  // the tangent plane does cut the shooter at most points
        CHECK(4 * evals_with < evals_without);
        // One point at 1e-6.
        QuadratureOptions mid_clipped, mid_unclipped;
        mid_clipped.analytic = mid_unclipped.analytic = false;
        mid_clipped.rel_tolerance = mid_unclipped.rel_tolerance = 1e-6;
        mid_unclipped.clip_horizon = false;
        IncrementIntegrator mid_with(shooter, mid_clipped), mid_without(shooter, mid_unclipped);
        const SurfacePoint p = cf.receiver.evaluate(0.5, 0.5);
        const IncrementIntegrator::Result c1 = mid_with.integrate(p), c2 = mid_without.integrate(p);
        CHECK(20 * c1.n_evaluations < c2.n_evaluations);
        mbr::test::report() << "shadow horizon " << cf.name << ": " << n_cut
                            << " points cut; clipped: worst relative error " << worst_default
                            << " at tolerance 1e-4 (" << evals_with << " kernel evaluations), "
                            << worst << " at 1e-8 (" << evals_tight
                            << "); unclipped at 1e-4: worst " << worst_without << " ("
                            << evals_without << " evaluations); one point "
                            << "at 1e-6: " << c1.n_evaluations << " clipped, " << c2.n_evaluations
                            << " unclipped\n";
    }
}

TEST_CASE("shadow: a shooter sharing an edge with its receiver is not cut by its horizon",
          "[shadow][visible_parts]") {
    // A floor and a wall meeting along an edge, turned to a generic orientation and given in
    // several decimal units: the wall's two corners on the floor's plane evaluate to rounding
    // (1e-17 either way), and counted by sign they made the horizon cut the wall or not by
    // turns, so that its cells along the edge took triangle rules in one unit and the tensor
    // rule in another (BlockedView::front_tolerance). They must lie on the horizon: never cut,
    // never all behind. A corner 1e-6 of the wall's size below the floor's plane still cuts.
    const Vec3 a = normalize(Vec3{1, 0.3, -0.2}), b0 = Vec3{-0.1, 1, 0.4};
    const Vec3 b = normalize(b0 - dot(b0, a) * a), c = cross(a, b);
    const Vec3 origin{0.37, -0.21, 0.73};
    auto at = [&](double k, double x, double y, double z) {  // frame (a, b, c): floor z = 0
        return k * (origin + x * a + y * b + z * c);
    };
    int points = 0;
    for (double k : {1.0, 1e-6, 1e-3, 0.1, 7.3, 1e3, 1e6}) {
        const Surface floor =
            Surface::planar_quad(at(k, 0, 0, 0), at(k, 1, 0, 0), at(k, 1, 1, 0), at(k, 0, 1, 0));
        const std::optional<Plane> floor_plane = surface_plane(floor);
        REQUIRE(floor_plane);
        for (double dip : {0.0, 1e-6}) {
            // The wall over the floor's edge y = 1, its front facing the floor (-y).
            const Surface wall = Surface::planar_quad(at(k, 0, 1, -dip), at(k, 0, 1, 1),
                                                      at(k, 1, 1, 1), at(k, 1, 1, -dip));
            const ShooterPlane plane = make_shooter_plane(wall);
            for (double s : {0.1, 0.5, 0.9})
                for (double t : {0.2, 0.7}) {
                    const SurfacePoint p = floor.evaluate(s, t);
                    const BlockedView view =
                        blocked_view(plane, p.position, p.normal, nullptr, &*floor_plane);
                    CAPTURE(k, dip, s, t);
                    CHECK_FALSE(view.behind_all);
                    CHECK(view.horizon_cuts == (dip > 0));
                    ++points;
                }
        }
    }
    CHECK(points == 7 * 2 * 6);
}

/// A unit shooter at z = 1 facing down over a unit receiver at z = 0, with n random triangles
/// about 0.08 wide between them: polygon 0 the shooter, 1 the receiver, 2 + k triangle k.
struct TriangleCloud {
    Surface shooter = Surface::planar_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1});
    Surface receiver = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    std::vector<Polygon> polygons;
};

static TriangleCloud triangle_cloud(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> u(0, 1);
    TriangleCloud cloud;
    cloud.polygons.push_back(make_polygon(quad_polygon(cloud.shooter), 0));
    cloud.polygons.push_back(make_polygon(quad_polygon(cloud.receiver), 1));
    for (int i = 0; i < n; ++i)
        cloud.polygons.push_back(
            make_polygon(random_triangle(rng, {u(rng), u(rng), 0.1 + 0.8 * u(rng)}, 0.08), 2 + i));
    return cloud;
}

TEST_CASE("shadow: occluders_toward with a limit gives the whole list or more than the limit",
          "[shadow][visible_parts]") {
    // A unit shooter at z = 1 facing down over a unit receiver at z = 0, with 150 random
    // triangles between them: more candidates than exact_limit, so the octree lists them. For
    // points of the receiver, the list under a limit L must be the whole list when that has at
    // most L polygons, and otherwise more than L of its polygons, increasing and distinct (the
    // paper's fractions then cast their rays through the octree, which needs no list).
    std::mt19937 rng(77);
    std::uniform_real_distribution<double> u(0, 1);
    const TriangleCloud cloud = triangle_cloud(rng, 150);
    const Surface &shooter = cloud.shooter, &receiver = cloud.receiver;
    const Octree octree(cloud.polygons, OctreeOptions{6, 4});
    const OcclusionContext ctx = make_occlusion_context(octree, shooter, 0, receiver, 1, 0);
    REQUIRE(static_cast<int>(ctx.candidates.size()) > exact_limit);
    const ShooterPlane plane = make_shooter_plane(shooter);
    int n_cut = 0, n_whole = 0;
    for (int k = 0; k < 40; ++k) {
        const Vec3 p{u(rng), u(rng), 0};
        const std::vector<int> all = occluders_toward(ctx, plane, p);
        REQUIRE(std::is_sorted(all.begin(), all.end()));
        for (size_t limit : {size_t(0), size_t(1), size_t(5), max_listed_occluders, size_t(1000)}) {
            const std::vector<int> some = occluders_toward(ctx, plane, p, limit);
            CAPTURE(k, limit, all.size(), some.size());
            if (all.size() <= limit) {
                CHECK(some == all);
                ++n_whole;
                continue;
            }
            ++n_cut;
            CHECK(some.size() > limit);
            CHECK(std::is_sorted(some.begin(), some.end()));
            CHECK(std::adjacent_find(some.begin(), some.end()) == some.end());
            CHECK(std::includes(all.begin(), all.end(), some.begin(), some.end()));
        }
    }
    // Both branches ran (the triangles are dense enough that most pyramids hold many).
    CHECK(n_cut > 20);
    CHECK(n_whole > 20);
}

TEST_CASE(
    "shadow: occluders_toward leaves out a polygon beside the pyramid that no one side "
    "separates, scanned or walked",
    "[shadow][visible_parts]") {
    // The pyramid from p = (0.5, 0.5, 0) to the unit shooter at z = 1 crosses z = 0.5 in the
    // square [0.25, 0.75]^2. Triangle 2 lies at that height across the square's corner
    // (0.75, 0.75): one vertex has x < 0.75 and another y < 0.75, so no side of the pyramid has
    // all three beyond it, yet the triangle holds only points with x + y >= 1.6 (the square's:
    // at most 1.5) and casts no shadow at p. Triangle 3 holds (0.7, 0.7). Both must be
    // judged alike whether the pair's candidates are few enough to scan (the triangles alone)
    // or so many that the octree is walked (2,100 small triangles more, near the receiver's
    // corner, far from p's pyramid).
    const Surface shooter = Surface::planar_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1});
    const Surface receiver = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    const ShooterPlane plane = make_shooter_plane(shooter);
    const Vec3 p{0.5, 0.5, 0};
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (int extra : {0, 2100}) {
        std::vector<Polygon> polygons;
        polygons.push_back(make_polygon(quad_polygon(shooter), 0));
        polygons.push_back(make_polygon(quad_polygon(receiver), 1));
        polygons.push_back(make_polygon({{0.7, 0.9, 0.5}, {0.9, 0.7, 0.5}, {0.95, 0.95, 0.5}}, 2));
        polygons.push_back(make_polygon({{0.7, 0.7, 0.5}, {0.9, 0.7, 0.5}, {0.7, 0.9, 0.5}}, 3));
        for (int i = 0; i < extra; ++i)
            polygons.push_back(make_polygon(
                random_triangle(
                    rng, {0.9 + 0.08 * u(rng), 0.9 + 0.08 * u(rng), 0.02 + 0.1 * u(rng)}, 0.01),
                4 + i));
        const Octree octree(polygons, OctreeOptions{6, 4});
        const OcclusionContext ctx = make_occlusion_context(octree, shooter, 0, receiver, 1, 0);
        CAPTURE(extra, ctx.candidates.size());
        REQUIRE((ctx.candidates.size() > max_scanned_candidates) == (extra > 0));
        const std::vector<int> toward = occluders_toward(ctx, plane, p);
        CHECK(toward == std::vector<int>{3});
    }
}

TEST_CASE("shadow: occluders_toward's scan and octree walk list the same occluders",
          "[shadow][visible_parts]") {
    // 2,100 random triangles between a unit shooter and a unit receiver: more candidates than
    // max_scanned_candidates, so the octree is walked. The same pair with its first 2,000
    // candidates only is scanned; at points of the receiver the scan must list exactly the walk's
    // occluders among those 2,000. And every triangle that a segment from the point to a
    // random point of the shooter meets is listed.
    std::mt19937 rng(91);
    std::uniform_real_distribution<double> u(0, 1);
    const TriangleCloud cloud = triangle_cloud(rng, 2100);
    const Octree octree(cloud.polygons, OctreeOptions{6, 4});
    const OcclusionContext ctx =
        make_occlusion_context(octree, cloud.shooter, 0, cloud.receiver, 1, 0);
    REQUIRE(ctx.candidates.size() > max_scanned_candidates);
    OcclusionContext fewer = ctx;
    fewer.candidates.resize(2000);
    const ShooterPlane plane = make_shooter_plane(cloud.shooter);
    size_t listed = 0;
    for (int k = 0; k < 20; ++k) {
        const Vec3 p{u(rng), u(rng), 0};
        const std::vector<int> walked = occluders_toward(ctx, plane, p);
        const std::vector<int> scanned = occluders_toward(fewer, plane, p);
        std::vector<int> walked_among;
        for (int id : walked)
            if (std::binary_search(fewer.candidates.begin(), fewer.candidates.end(), id))
                walked_among.push_back(id);
        CAPTURE(k, walked.size(), scanned.size());
        CHECK(scanned == walked_among);
        listed += walked.size();
        for (int r = 0; r < 200; ++r) {
            const Vec3 x = cloud.shooter.point(u(rng), u(rng));
            for (int id : ctx.candidates)
                if (octree.polygons()[size_t(id)].intersect_segment(Ray{p, x - p, 0, 1}))
                    CHECK(std::binary_search(walked.begin(), walked.end(), id));
        }
    }
    CHECK(listed > 20 * 50);  // the pyramids hold many triangles
}

TEST_CASE("shadow: ray visibility on a planar shooter keeps every occluder of a cell's shaft",
          "[shadow][visible_parts]") {
    // A unit shooter at z = 1 facing down over a unit receiver at z = 0, 150 random triangles
    // between them: more casters toward each point than exact_limit, so each quadrature node
    // casts a ray against its cell's list of occluders (collect_shaft_occluders: the cell's
    // shaft, filtered from its parent cell's list). Against a brute force that tests every
    // triangle from 256 x 256 points of the shooter (the midpoint rule of F VIS: within 3e-5 of
    // F of 512 x 512 and 1024 x 1024 here). The integrator's own error, its visibility steps
    // inside cells at max_visibility_depth, reaches 2.3e-3 of the unshadowed F at these points
    // (the same before the lists were filtered from the parent cell's); a triangle left out of
    // the lists shadows up to a few percent of the shooter. Within 4e-3 of F.
    std::mt19937 rng(91);
    std::uniform_real_distribution<double> u(0, 1);
    const TriangleCloud cloud = triangle_cloud(rng, 150);
    const Surface &shooter = cloud.shooter, &receiver = cloud.receiver;
    const std::vector<Polygon>& polygons = cloud.polygons;
    const Octree octree(polygons, OctreeOptions{6, 4});
    const OcclusionContext ctx = make_occlusion_context(octree, shooter, 0, receiver, 1, 0);
    const Shooter unit = unit_shooter(shooter);
    IncrementIntegrator integrator(unit, QuadratureOptions{}, &ctx);
    const ShooterPlane plane = make_shooter_plane(shooter);
    const int side = 256;
    double worst = 0;
    long rays = 0;
    for (int k = 0; k < 4; ++k) {
        const SurfacePoint p = receiver.evaluate(0.1 + 0.8 * u(rng), 0.1 + 0.8 * u(rng));
        REQUIRE(casters_toward(ctx, plane, p.position) > exact_limit);  // rays, not projection
        const IncrementIntegrator::Result r = integrator.integrate(p);
        double brute = 0, full = 0;
        for (int i = 0; i < side; ++i)
            for (int j = 0; j < side; ++j) {
                const SurfacePoint x = shooter.evaluate((i + 0.5) / side, (j + 0.5) / side);
                const double f = form_factor_kernel(p.position, p.normal, x.position, x.normal) *
                                 x.area_factor / (double(side) * side);
                full += f;
                const Ray ray{p.position, x.position - p.position, 1e-9, 1 - 1e-9};
                bool blocked = false;
                for (size_t q = 2; q < polygons.size() && !blocked; ++q)
                    blocked = polygons[q].intersect_segment(ray).has_value();
                if (!blocked) brute += f;
            }
        CAPTURE(k, brute, full, r.value.r);
        CHECK(brute < 0.98 * full);  // the triangles shadow the point
        CHECK(std::fabs(r.value.r - brute) <= 4e-3 * full);
        worst = std::max(worst, std::fabs(r.value.r - brute) / full);
        rays += r.n_rays;
    }
    CHECK(rays > 0);
    mbr::test::report() << "ray visibility on a planar shooter, 150 triangles: worst |I - brute| "
                        << "/ F " << worst << ", " << rays / 4 << " rays a point\n";
}
