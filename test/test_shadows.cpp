// test/test_shadows.cpp - stage 7 of one transfer, the paper's shadows (section 5, "Adaptive
// Subdivision in Shadow Computation"; section 6, "Shadow"; eq. (28); radiosity/transfer/shadows.h):
// the fractions (28) against their statistics, and stage 7's invariants (no occluder -> nothing
// changes, a full blocker -> zero, reproducibility, NeighAdjust after shadow subdivision).
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

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mbr;
using namespace mbr::test;

// ---- Stage 7 and the transfer ------------------------------------------------------------------

TEST_CASE("shadow: an occluder outside the region between the surfaces changes nothing",
          "[shadow][shadows]") {
    // Occluders outside the convex hull of the two surfaces: beside the parallel squares, above
    // the shooter, and, for the perpendicular squares (hull: the prism y, z >= 0, y + z <= 1),
    // one inside the bounding box [0,1]^3 but beyond the hull's slanted face y + z = 1 (a bounding
    // box test would keep it). The candidate list is empty in all three. For the parallel squares
    // and both methods: no ray is cast, no fraction computed, no leaf split, and the field equals
    // the unshadowed transfer's bit for bit. (The perpendicular squares' singular common edge
    // makes their transfer slow; transfer() treats any clear context as no context, which the
    // parallel cases check.) A control occluder inside the hull is a candidate and does change
    // the field, so the comparison can fail.
    const TransferSetup perpendicular = perpendicular_squares();
    const std::vector<Vec3> beyond_slant{
        {0.3, 0.6, 0.9}, {0.7, 0.6, 0.9}, {0.7, 0.9, 0.6}, {0.3, 0.9, 0.6}};
    {
        const Pair pair(ShadowSetup{perpendicular.shooter, perpendicular.receiver, {beyond_slant}});
        CHECK(pair.context.candidates.empty());
        CHECK(pair.context.clear());
        // The same occluder moved inside the hull (y + z = 0.9) is a candidate.
        const std::vector<Vec3> inside{
            {0.3, 0.3, 0.6}, {0.7, 0.3, 0.6}, {0.7, 0.6, 0.3}, {0.3, 0.6, 0.3}};
        const Pair control(ShadowSetup{perpendicular.shooter, perpendicular.receiver, {inside}});
        CHECK(control.context.candidates.size() == 1);
    }
    const ShadowSetup beside = squares_with({square_at(1.4, 0.5, 0.5, 0.2)});
    const ShadowSetup above = squares_with({square_at(0.5, 0.5, 1.5, 0.3)});
    const Pair pair_beside(beside), pair_above(above);
    CHECK(pair_beside.context.candidates.empty());
    CHECK(pair_above.context.candidates.empty());
    for (ShadowMethod method : {ShadowMethod::Fractions, ShadowMethod::Exact}) {
        CAPTURE(int(method));
        const ReceiverOptions options = small_options(method);
        const Run plain = run_transfer(beside, options, nullptr);
        for (const Pair* pair : {&pair_beside, &pair_above}) {
            const Run shadowed = run_transfer(pair->setup, options, &pair->context);
            CHECK(n_differing(shadowed.field, plain.field) == 0);
            CHECK(shadowed.state.stats.n_rays == 0);
            CHECK(shadowed.state.stats.n_fractions == 0);
            CHECK(shadowed.state.stats.n_shadow_splits == 0);
            CHECK(shadowed.state.stats.n_kernel_evals == plain.state.stats.n_kernel_evals);
        }
    }
    // Control: the square occluder between the squares changes the field.
    const Pair control(occluded_squares(0));
    REQUIRE(control.context.candidates.size() == 1);
    const ReceiverOptions options = small_options(ShadowMethod::Exact);
    CHECK(n_differing(run_transfer(control.setup, options, &control.context).field,
                      run_transfer(control.setup, options, nullptr).field) > 0);
}

TEST_CASE("shadow: a blocker covering the whole shooter makes every coefficient zero",
          "[shadow][shadows]") {
    // A square [-1, 2]^2 in z = 0.5 between the parallel unit squares: every segment from the
    // receiver to the shooter crosses z = 0.5 inside [0, 1]^2, so VIS = 0 everywhere. Claims:
    // - Fractions: every fraction (28) is exactly 0 (every ray blocked), hence every stored
    //   coefficient is masked to 0, and those made in stage 8 by (17) from them, or projected on
    //   demand and masked, are 0 too: every coefficient of the field is exactly 0 (all channels).
    // - Exact: the whole shooter is one shadow, every cell hidden, every sample of (21) exactly
    //   0, so again every coefficient is exactly 0; no ray is cast (planar shooter: clipping).
    const ShadowSetup setup = squares_with({square_at(0.5, 0.5, 0.5, 1.5)});
    const Pair pair(setup);
    REQUIRE(pair.context.candidates.size() == 1);
    {
        const Run run = run_transfer(setup, small_options(ShadowMethod::Fractions), &pair.context);
        CHECK(n_nonzero(run.field) == 0);
        CHECK(run.state.stats.n_rays > 0);
        CHECK(run.state.stats.n_fractions > 0);
        int n_nonzero_fractions = 0;
        for (const auto& [point, f] : run.state.fractions)
            if (f.r != 0 || f.g != 0 || f.b != 0) ++n_nonzero_fractions;
        CHECK(n_nonzero_fractions == 0);
    }
    {
        const Run run = run_transfer(setup, small_options(ShadowMethod::Exact), &pair.context);
        CHECK(n_nonzero(run.field) == 0);
        CHECK(run.state.stats.n_rays == 0);
    }
    // Control: without the occluder the field is far from zero.
    CHECK(n_nonzero(run_transfer(setup, small_options(ShadowMethod::Exact), nullptr).field) > 0);
}

TEST_CASE("shadow: an occluder hiding half of a point's view gives a fraction near one half",
          "[shadow][shadows]") {
    // The receiver's centre p = (0.5, 0.5, 0) under the unit shooter in z = 1; the occluder is the
    // triangle (-1,-1) (3,-1) (3,3) in z = 0.5, i.e. the half x >= y near the axis. Seen from p it
    // hides exactly the half x >= y of the shooter, and since F(p, x) depends on |x - p| only,
    // exactly half of the energy (swapping x and y maps one half onto the other).
    //
    // Statistics of (28). The shooter partition of (21) at p is symmetric under that swap, so the
    // off-diagonal patches come in pairs of equal energy, one seen and one hidden: they add
    // exactly E/2. Only the patches the diagonal cuts (cells with i = j) are partly visible; each
    // is cut into two halves of equal energy. With 4 rays stratified 2 x 2, two strata lie
    // wholly on either side and two are cut in half: r_i = (1 + B1 + B2) / 4 with B Bernoulli(1/2),
    // so E r_i = 1/2 and Var r_i = 1/32 (1/16 without strata: Binomial(4, 1/2) / 4). Hence
    //   f - 1/2 = sum_diag (r_i - 1/2) e_i / E,   Var f = sum_diag e_i^2 / (32 E^2),
    // and by Hoeffding (terms in [-e_i/4, e_i/4] / E) P(|f - 1/2| >= t) <= 2 exp(-8 t^2 E^2 /
    // sum e_i^2): t for a failure probability of 1e-6 per seed is the bound checked at each of
    // 200 seeds (the shot number). Over the 200 seeds the mean must be within 4 standard errors
    // of 1/2 and the sample variance near the stratified prediction (the variance of a sample
    // variance of 200 such sums is ~2/199 of its square: 0.6 .. 1.5 is beyond 4 sigma), and
    // clearly below the unstratified one.
    const ShadowSetup setup = squares_with({{{-1, -1, 0.5}, {3, -1, 0.5}, {3, 3, 0.5}}});
    ReceiverOptions options = small_options(ShadowMethod::Fractions);
    REQUIRE(options.shadows.rays_per_patch == 4);
    const Shooter shooter = unit_shooter(setup.shooter);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    IncrementSampler sampler(shooter, receiver, options.quadrature);
    const SurfacePoint p = setup.receiver.evaluate(0.5, 0.5);

    // The partition (28) uses at p, and the statistics above.
    const std::vector<AcceptedCell<Rgb>> partition =
        sampler.integrator(0).fraction_partition(p, min_patch_depth, nullptr);
    double E = 0, sum_e2_diag = 0;
    int n_diag = 0;
    for (const auto& patch : partition) {
        const Rect& c = patch.cell.rect;
        E += patch.value.r;
        if (c.x0 - c.y1 < 0 && c.x1 - c.y0 > 0) {  // the diagonal u = v cuts it
            CHECK(c.x0 == c.y0);                   // a square on the diagonal: cut in halves
            sum_e2_diag += patch.value.r * patch.value.r;
            ++n_diag;
        }
    }
    REQUIRE(n_diag >= 8);  // min_patch_depth 3: at least 8 diagonal cells
    const double var_stratified = sum_e2_diag / (32 * E * E);
    const double var_plain = sum_e2_diag / (16 * E * E);
    const double t_hoeffding = std::sqrt(sum_e2_diag * std::log(2 / 1e-6) / (8 * E * E));

    const int n_seeds = 200;
    double sum = 0, sum2 = 0, worst = 0;
    for (int shot = 0; shot < n_seeds; ++shot) {
        const Pair pair(setup, shot);
        ReceiverState state(options, 0, &pair.context);
        const Rgb f = fraction_at(state, sampler, 0.5, 0.5, 0);
        CAPTURE(shot, f);
        CHECK(f.r == f.g);
        CHECK(f.r == f.b);
        CHECK(std::fabs(f.r - 0.5) <= t_hoeffding);
        worst = std::max(worst, std::fabs(f.r - 0.5));
        sum += f.r;
        sum2 += (f.r - 0.5) * (f.r - 0.5);
        // Memoised: asking again casts no ray and gives the same value.
        const long rays = state.stats.n_rays;
        CHECK(fraction_at(state, sampler, 0.5, 0.5, 0) == f);
        CHECK(state.stats.n_rays == rays);
    }
    const double mean = sum / n_seeds;
    const double var = sum2 / n_seeds;  // about the known mean 1/2
    CHECK(std::fabs(mean - 0.5) <= 4 * std::sqrt(var_stratified / n_seeds));
    CHECK(var / var_stratified > 0.6);
    CHECK(var / var_stratified < 1.5);
    CHECK(var < 0.75 * var_plain);

    // Exact visibility at p: the integral is exactly half the unshadowed form factor. (The
    // diagonal half-plane's shadow passes exactly through two corners of the shooter, the case
    // of the test "exact visibility when a shadow's vertex lies on the shooter's outline");
    // here the half x >= 1/2 is hidden (the rectangle [1/2, 3] x [-1, 3] in
    // z = 1/2), equally exactly half by the symmetry x -> 1 - x. The quadrature's tolerance is
    // 1e-4 relative (the shadow's edge is clipped exactly, so the error is far smaller).
    const ShadowSetup half_x =
        squares_with({{{0.5, -1, 0.5}, {3, -1, 0.5}, {3, 3, 0.5}, {0.5, 3, 0.5}}});
    const Pair pair(half_x);
    const Shooter half_shooter = unit_shooter(half_x.shooter);  // the integrator keeps a reference
    IncrementIntegrator exact_integrator(half_shooter, QuadratureOptions{}, &pair.context);
    const double half =
        0.5 * point_polygon_form_factor(p.position, p.normal, quad_polygon(setup.shooter));
    const double I = exact_integrator.integrate(p).value.r;
    CHECK(I == Approx(half).epsilon(1e-4));
    mbr::test::report() << "shadow fraction (28), half view: " << partition.size() << " patches, "
                        << n_diag << " cut; sigma stratified " << std::sqrt(var_stratified)
                        << " (unstratified " << std::sqrt(var_plain) << "), Hoeffding bound "
                        << t_hoeffding << "; over " << n_seeds << " seeds: mean " << mean
                        << ", rms deviation " << std::sqrt(var) << ", worst " << worst
                        << "; exact method " << I << " vs " << half << " (relative "
                        << std::fabs(I - half) / half << ")\n";
}

TEST_CASE("shadow: the same seed gives the same field, whatever the number of threads",
          "[shadow][shadows]") {
    // Rays are seeded from the pair, the shot and the fulcrum's position, never from thread
    // order: two runs agree bit for bit, and so do runs on one and on two threads (both methods).
    // A different shot number changes the rays and so, somewhere, the field: the comparison can
    // fail.
    const ShadowSetup setup = occluded_squares(30);
    const Pair pair(setup, 7);
    const ReceiverOptions fractions = small_options(ShadowMethod::Fractions);
    const Run a = run_transfer(setup, fractions, &pair.context);
    const Run b = run_transfer(setup, fractions, &pair.context);
    CHECK(n_differing(a.field, b.field) == 0);
    CHECK(a.state.stats.n_rays == b.state.stats.n_rays);
    CHECK(a.state.stats.n_rays > 0);
    CHECK(a.state.fractions == b.state.fractions);

    const Pair other(setup, 8);
    CHECK(n_differing(a.field, run_transfer(setup, fractions, &other.context).field) > 0);

#ifdef _OPENMP
    const int saved = omp_get_max_threads();
    for (ShadowMethod method : {ShadowMethod::Fractions, ShadowMethod::Exact}) {
        CAPTURE(int(method));
        const ReceiverOptions options = small_options(method);
        omp_set_num_threads(1);
        const Run one = run_transfer(setup, options, &pair.context);
        omp_set_num_threads(2);
        const Run two = run_transfer(setup, options, &pair.context);
        omp_set_num_threads(saved);
        CHECK(n_differing(one.field, two.field) == 0);
        CHECK(one.state.stats.n_rays == two.state.stats.n_rays);
        CHECK(one.state.stats.n_kernel_evals == two.state.stats.n_kernel_evals);
        CHECK(one.state.stats.n_shadow_splits == two.state.stats.n_shadow_splits);
    }
#endif
}

TEST_CASE("shadow: after shadow subdivision no leaf is more than twice its twelve neighbours",
          "[shadow][shadows]") {
    // A real shadowed transfer (the square occluder, the paper's fractions, receiver tree at depth
    // 1..2, shadow subdivision down to level 4). Shadow subdivision splits leaves where
    // neighbouring fractions differ, then NeighAdjust runs over the whole forest. For every leaf
    // D (domain and expanded ring), the twelve neighbours of Figure 4 are the leaves holding the
    // three other quadrants at each of D's corners (found with leaf_at just outside the corner):
    // D may be at most twice as large as each. Cross-check: every pair of leaves of the domain
    // that touch (edges or corners) differs by at most one level.
    const ShadowSetup setup = occluded_squares(0);
    const Pair pair(setup);
    ReceiverOptions options = small_options(ShadowMethod::Fractions);
    options.shadows.max_depth = 4;
    const Run run = run_transfer(setup, options, &pair.context);
    const Forest& forest = run.state.forest;
    CHECK(run.state.stats.n_shadow_splits > 0);
    CHECK_FALSE(run.state.split_fulcrums.empty());
    int finest = 0;
    const std::vector<int> domain = forest.leaves(Forest::Region::Domain);
    for (int index : domain) finest = std::max(finest, forest.node(index).cell.level);
    CHECK(finest > options.max_depth);  // shadow subdivision went below the oracle's tree
    CHECK(finest <= options.shadows.max_depth + 1);

    const std::vector<int> leaves = forest.leaves(Forest::Region::All);
    double h_min = 1;
    for (int index : leaves) h_min = std::min(h_min, forest.node(index).cell.size());
    const double eps = 0.25 * h_min;
    int n_checked = 0, n_violations = 0;
    for (int index : leaves) {
        const DyadicCell d = forest.node(index).cell;
        const Rect r = d.rect();
        for (double x : {r.x0, r.x1})
            for (double y : {r.y0, r.y1})
                for (int q = 0; q < 4; ++q) {
                    const double sx = x + ((q & 1) ? eps : -eps), sy = y + ((q & 2) ? eps : -eps);
                    if (sx > r.x0 && sx < r.x1 && sy > r.y0 && sy < r.y1) continue;  // D itself
                    const int other = forest.leaf_at(sx, sy);
                    if (other < 0) continue;  // beyond the forest
                    ++n_checked;
                    const DyadicCell o = forest.node(other).cell;
                    CAPTURE(d, o);
                    if (d.size() > 2 * o.size()) ++n_violations;
                    CHECK(d.size() <= 2 * o.size());
                }
    }
    CHECK(n_violations == 0);
    CHECK(n_checked > 12 * static_cast<int>(domain.size()));
    for (size_t a = 0; a < domain.size(); ++a)
        for (size_t b = a + 1; b < domain.size(); ++b) {
            const DyadicCell ca = forest.node(domain[a]).cell, cb = forest.node(domain[b]).cell;
            const Rect ra = ca.rect(), rb = cb.rect();
            if (ra.x0 <= rb.x1 && rb.x0 <= ra.x1 && ra.y0 <= rb.y1 && rb.y0 <= ra.y1) {
                CAPTURE(ca, cb);
                CHECK(std::abs(ca.level - cb.level) <= 1);
            }
        }
    mbr::test::report() << "shadow NeighAdjust: " << domain.size() << " domain leaves ("
                        << leaves.size() << " in all), finest level " << finest << ", "
                        << run.state.stats.n_shadow_splits << " shadow splits, " << n_checked
                        << " neighbour pairs checked\n";
}

TEST_CASE(
    "shadow: splits follow power: a leaf splits only while its area times the largest "
    "sample times its fractions' difference reaches the tolerance times split_area",
    "[shadow][shadows]") {
    // worth_splitting (shadows.cpp): with ShadowOptions::split_area set so that the bound falls
    // between the leaves of level L with fractions differing by at least 1/2 and those of level
    // L + 1 (whose differences are at most 1), shadow subdivision stops at level L + 1 (leaves of
    // level L across the shadow's edge still split) where without it the same transfer reaches
    // the shadow depth; the fractions it computes are fewer. The occluder is close to the
    // receiver, so that its shadow's edge is sharp: fractions of 0 and 1 side by side at every
    // level. The samples come before stage 7, so max_sample is the same in every run.
    const ShadowSetup setup = squares_with({square_at(0.5, 0.5, 0.05, 0.2)});
    const Pair pair(setup);
    ReceiverOptions options = small_options(ShadowMethod::Fractions);
    options.shadows.max_depth = 5;
    const Run probe = run_transfer(setup, options, &pair.context);
    const double S = probe.state.max_sample;
    REQUIRE(S > 0);
    options.absolute_tolerance = 1e-9 * S;  // changes no other test of the transfer
    auto finest = [](const Run& run) {
        int level = 0;
        for (int index : run.state.forest.leaves(Forest::Region::Domain))
            level = std::max(level, run.state.forest.node(index).cell.level);
        return level;
    };
    const Run full = run_transfer(setup, options, &pair.context);
    CHECK(finest(full) == options.shadows.max_depth);
    CHECK(full.state.stats.n_fractions == probe.state.stats.n_fractions);
    const double area = setup.receiver.area();
    for (int L : {2, 3}) {
        CAPTURE(L);
        ReceiverOptions limited = options;
        limited.shadows.split_area = area * std::pow(0.25, L) * S / options.absolute_tolerance * 0.5;
        const Run run = run_transfer(setup, limited, &pair.context);
        CHECK(finest(run) == L + 1);
        CHECK(run.state.stats.n_fractions < full.state.stats.n_fractions);
        CHECK(run.state.stats.n_shadow_splits < full.state.stats.n_shadow_splits);
    }
    // A soft penumbra (the occluder half way up): neighbouring fractions never differ by 1, so
    // with the bound at exactly a level-L leaf's area times S no leaf of level L splits (without
    // the difference in the bound they did, down to level L + 1).
    const ShadowSetup soft = occluded_squares(0);
    const Pair soft_pair(soft);
    const Run soft_probe = run_transfer(soft, options, &soft_pair.context);
    const double S_soft = soft_probe.state.max_sample;
    REQUIRE(finest(soft_probe) == options.shadows.max_depth);
    for (int L : {2, 3}) {
        CAPTURE(L);
        ReceiverOptions limited = options;
        limited.shadows.split_area =
            area * std::pow(0.25, L) * S_soft / options.absolute_tolerance * (1 - 1e-9);
        const Run run = run_transfer(soft, limited, &soft_pair.context);
        CHECK(finest(run) <= L);
    }
}

TEST_CASE("shadow: a fraction's rays follow energy when the partition is finer than the budget",
          "[shadow][shadows]") {
    // patch_rays (shadows.cpp): a weak transfer (largest sample 8 times the tolerance) asks for
    // 4^1 patches of 4 rays, 16 in all (patch_depth); the adaptive partition of (21) at the
    // receiver's centre has more patches than 16 / 4, so the 16 rays are spread over them by
    // energy with unbiased weights. The half-view scene of the test above: the fraction is 1/2
    // in expectation; each estimate casts 16 rays (systematic sampling: exactly the budget, up
    // to rounding) and their mean over 200 seeds is within 4 standard errors of 1/2 (each
    // estimate's variance is about 1/(4 x 16)). The shooter is lowered to z = 0.1 (the occluder
    // to 0.05), so that the kernel at the centre is peaked and the partition fine.
    ShadowSetup setup = squares_with({{{-1, -1, 0.05}, {3, -1, 0.05}, {3, 3, 0.05}}});
    setup.shooter = Surface::planar_quad({0, 0, 0.1}, {0, 1, 0.1}, {1, 1, 0.1}, {1, 0, 0.1});
    ReceiverOptions options = small_options(ShadowMethod::Fractions);
    const double S = 1.0;
    options.absolute_tolerance = S / 8;
    const Shooter shooter = unit_shooter(setup.shooter);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    IncrementSampler sampler(shooter, receiver, options.quadrature);
    const SurfacePoint p = setup.receiver.evaluate(0.5, 0.5);
    const std::vector<AcceptedCell<Rgb>> partition =
        sampler.integrator(0).fraction_partition(p, 1, nullptr);
    REQUIRE(partition.size() > 4);  // finer than the budget's 4 patches
    const int n_seeds = 200;
    double sum = 0;
    for (int shot = 0; shot < n_seeds; ++shot) {
        const Pair pair(setup, shot);
        ReceiverState state(options, 0, &pair.context);
        state.max_sample = S;
        const Rgb f = fraction_at(state, sampler, 0.5, 0.5, 0);
        CAPTURE(shot, f);
        CHECK(state.stats.n_rays >= 15);
        CHECK(state.stats.n_rays <= 17);
        CHECK(f.r >= 0);
        CHECK(f.r <= 1);
        sum += f.r;
    }
    const double mean = sum / n_seeds;
    CHECK(std::fabs(mean - 0.5) <= 4 * std::sqrt(1.0 / (4 * 16) / n_seeds));
    mbr::test::report() << "fraction rays by energy: " << partition.size()
                        << " patches, 16 rays; mean over " << n_seeds << " seeds " << mean << "\n";
}

TEST_CASE("shadow: a fraction's partition is the uniform grid, split near the point",
          "[shadow][shadows]") {
    // fraction_partition (sample_values.h): far from the shooter, exactly the 2^d x 2^d grid;
    // close to it, the cells near the point's foot split (the near-field guard) down to at most
    // max_fraction_depth. Either way the cells tile the shooter's [0,1]^2 and their energies add
    // up to I(p) (the adaptive rule of (21), 1e-4 relative) within 1 % (one n-point rule per
    // cell instead of (21)'s refinement).
    const ShadowSetup setup = occluded_squares(0);
    const ReceiverOptions options = small_options(ShadowMethod::Fractions);
    for (double h : {1.0, 0.02}) {
        CAPTURE(h);
        const Surface shooter_surface =
            Surface::planar_quad({0, 0, h}, {0, 1, h}, {1, 1, h}, {1, 0, h});
        const Shooter shooter = unit_shooter(shooter_surface);
        const ReceiverSurface receiver{&setup.receiver, [](double, double) {
                                           return Rgb{1, 1, 1};
                                       }};
        IncrementSampler sampler(shooter, receiver, options.quadrature);
        const SurfacePoint p = setup.receiver.evaluate(0.3, 0.6);
        long n_evals = 0;
        const std::vector<AcceptedCell<Rgb>> partition =
            sampler.integrator(0).fraction_partition(p, 3, &n_evals);
        double area = 0, energy = 0;
        int deepest = 0;
        for (const AcceptedCell<Rgb>& patch : partition) {
            area += patch.cell.rect.area();
            energy += patch.value.r;
            deepest = std::max(deepest, patch.cell.level);
            CHECK(patch.cell.level >= 3);
        }
        CHECK(area == Approx(1).epsilon(1e-12));
        CHECK(deepest <= max_fraction_depth);
        CHECK(n_evals >= static_cast<long>(partition.size()));
        if (h == 1.0) CHECK(partition.size() == 64);
        if (h < 1) CHECK(partition.size() > 64);
        QuadratureOptions accurate;
        IncrementIntegrator reference(shooter, accurate);
        const double I = reference.integrate(p).value.r;
        CHECK(energy == Approx(I).epsilon(0.01));
        mbr::test::report() << "fraction partition at height " << h << ": " << partition.size()
                            << " patches, deepest level " << deepest << ", energy " << energy
                            << " against I(p) " << I << "\n";
    }
}
