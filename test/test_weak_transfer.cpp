// test/test_weak_transfer.cpp - the weak transfer (radiosity/transfer/weak_transfer.h, beyond the
// paper): the level-0 field through the root's m x m samples reproduces every polynomial the
// level-0 space holds, the rule picks exactly the transfers below its threshold, a weak
// transfer of the parallel squares stays close to the exact form factor, and under the paper's
// shadows its coefficients carry the corner fractions (28).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "math/bspline.h"
#include "math/gauss_legendre.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/transfer/weak_transfer.h"
#include "test/shadow_scenes.h"

using namespace mbr;
using namespace mbr::test;

namespace {

/// A state of order m whose root (its only leaf) carries the m x m Gauss-Legendre samples of
/// (f, -2 f, f / 2).
template <class F>
ReceiverState root_state(int m, F&& f) {
    ReceiverOptions options;
    options.m = m;
    ReceiverState state(options);
    const GaussLegendre rule = gauss_legendre(m);
    std::vector<Rgb> values;
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) {
            const double v = f(0.5 * (rule.x[a] + 1), 0.5 * (rule.x[b] + 1));
            values.push_back({v, -2 * v, 0.5 * v});
        }
    store_leaf_samples(state, state.forest.domain_root(), values.data());
    return state;
}

}  // namespace

TEST_CASE("weak transfer: the root polynomial reproduces the polynomials of degree below m",
          "[weak]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int m = 2; m <= 6; ++m) {
        // p(s, t) = sum_{i, j < m} a_ij s^i t^j with random a_ij.
        std::vector<double> a(size_t(m) * m);
        for (double& c : a) c = u(rng);
        auto p = [&](double s, double t) {
            double sum = 0, ps = 1;
            for (int i = 0; i < m; ++i, ps *= s) {
                double pt = 1;
                for (int j = 0; j < m; ++j, pt *= t) sum += a[size_t(i) * m + j] * ps * pt;
            }
            return sum;
        };
        ReceiverState state = root_state(m, p);
        const SplineField field = project_root_polynomial(state);
        INFO("m = " << m);
        CHECK(field.level() == 0);
        CHECK(state.stats.level == 0);
        CHECK(state.stats.n_projections == m * m);
        double worst = 0;
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; j <= 20; ++j) {
                const double s = i / 20.0, t = j / 20.0;
                const Rgb v = field.evaluate(s, t);
                worst = std::max(worst, std::fabs(v.r - p(s, t)));
                CHECK(v.g == Approx(-2 * v.r).margin(1e-12));
                CHECK(v.b == Approx(0.5 * v.r).margin(1e-12));
            }
        CHECK(worst < 1e-11);
    }
}

TEST_CASE("weak transfer: the samples widen the state's range as sample_leaves does", "[weak]") {
    ReceiverState state = root_state(4, [](double s, double t) { return s - 2 * t; });
    CHECK(state.max_sample > 1.5);  // |-2 (s - 2t)| reaches about 3.7 at the nodes
    CHECK(state.sample_lo.g < 0);
    CHECK(state.sample_hi.g > 0);
    CHECK(state.sample_lo.r < 0);
    CHECK(state.sample_hi.r > 0);
}

TEST_CASE("weak transfer: the rule takes a transfer below its threshold only", "[weak]") {
    ReceiverOptions o;
    o.absolute_tolerance = 1e-3;
    CHECK_FALSE(is_weak_transfer(o, 1e-6));  // weak_transfer 0: off
    o.weak_transfer = 0.3;
    CHECK(is_weak_transfer(o, 2.9e-4));
    CHECK_FALSE(is_weak_transfer(o, 3e-4));
    CHECK_FALSE(is_weak_transfer(o, 1e-2));
    o.absolute_tolerance = 0;  // single transfers (Tables 1-2): relative tests only
    CHECK_FALSE(is_weak_transfer(o, 1e-9));
}

TEST_CASE("weak transfer: the root's samples stand for the receiver only with the shooter afar",
          "[weak]") {
    // Half the receiver's diagonal (0.71 for the unit square) is the least distance.
    CHECK(root_samples_represent(parallel_squares(1.0).shooter, parallel_squares(1.0).receiver));
    CHECK(root_samples_represent(parallel_squares(0.75).shooter, parallel_squares(0.75).receiver));
    CHECK_FALSE(
        root_samples_represent(parallel_squares(0.5).shooter, parallel_squares(0.5).receiver));
    const TransferSetup corner = perpendicular_squares();  // a shared edge
    CHECK_FALSE(root_samples_represent(corner.shooter, corner.receiver));
}

TEST_CASE("weak transfer: a weak transfer of the parallel squares is close to the exact one",
          "[weak]") {
    const ShadowSetup squares = occluded_squares(0);  // parallel unit squares at h = 1
    const TransferSetup exact_setup{squares.shooter, squares.receiver};
    ReceiverOptions o = small_options(ShadowMethod::None);
    const Run full = run_transfer(squares, o, nullptr);
    REQUIRE_FALSE(full.state.stats.weak);
    const double largest = full.state.max_sample;  // about F at the centre, 0.2
    REQUIRE(largest > 0.1);

    // Below the threshold: the root alone, level 0, no edgefill.
    o.absolute_tolerance = 2 * largest;
    o.weak_transfer = 1;
    const Run weak = run_transfer(squares, o, nullptr);
    CHECK(weak.state.stats.weak);
    CHECK(weak.field.level() == 0);
    CHECK(weak.state.stats.n_leaves == 1);
    CHECK(weak.state.stats.n_boundary_nodes == 0);
    CHECK(weak.state.stats.n_increments == 16);  // the root's m x m samples, taken once
    const ErrorStats full_error = compare_with_exact(full.field, exact_setup, 1, 1, 64);
    const ErrorStats weak_error = compare_with_exact(weak.field, exact_setup, 1, 1, 64);
    // The smooth form factor of parallel squares is nearly a bicubic: the root polynomial is
    // within a few per mille of it (measured: rea 0.37 %, largest 1.7 %; the full pipeline with
    // these small options 0.06 %).
    INFO("weak rea " << weak_error.rea << " max " << weak_error.max_rel << ", full rea "
                     << full_error.rea);
    CHECK(weak_error.rea < 0.005);
    CHECK(weak_error.max_rel < 0.025);
    CHECK(full_error.rea < 0.005);

    // At the threshold (the largest root sample, which the weak run kept) the full pipeline
    // runs.
    o.absolute_tolerance = weak.state.max_sample;
    const Run at = run_transfer(squares, o, nullptr);
    CHECK_FALSE(at.state.stats.weak);
    CHECK(at.field.level() > 0);
}

TEST_CASE("weak transfer: under the paper's shadows the coefficients carry the corner fractions",
          "[weak]") {
    const Pair pair(occluded_squares(0));
    ReceiverOptions o = small_options(ShadowMethod::Fractions);
    o.absolute_tolerance = 10;  // far above F <= 1: every transfer of these squares is weak
    o.weak_transfer = 1;
    const Run clear = run_transfer(pair.setup, o, nullptr);
    const Run shadowed = run_transfer(pair.setup, o, &pair.context);
    REQUIRE(clear.state.stats.weak);
    REQUIRE(shadowed.state.stats.weak);
    CHECK(shadowed.state.stats.n_fractions == 4);  // the four corners, each once
    const int m = o.m, first = first_touching_index(m);
    int shaded = 0;
    for (int k = first; k < first + m; ++k)
        for (int l = first; l < first + m; ++l) {
            const Vec2 p = fraction_point(Fulcrum{0, k, l}, m);
            const auto f = shadowed.state.fractions.find({p.x, p.y});
            REQUIRE(f != shadowed.state.fractions.end());
            const Rgb expected = clear.field.coefficient(k, l) * f->second;
            const Rgb got = shadowed.field.coefficient(k, l);
            CHECK(got.r == Approx(expected.r).margin(1e-15));
            CHECK(got.g == Approx(expected.g).margin(1e-15));
            if (f->second.r < 1) ++shaded;
        }
    // The occluder of side 0.4 halfway up hides part of the shooter from every corner.
    CHECK(shaded == m * m);
}
