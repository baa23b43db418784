// test/test_ambient_gather.cpp - the ambient correction gathered by rays (ambient_gather.h):
// exact where the answer is known (a closed box of uniform unshot radiosity, a square's form
// factor), independent of the thread count, and nearer the converged solution than the constant
// per surface on the Cornell box stopped early.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "radiosity/geometry/radiosity_view.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/ambient_gather.h"
#include "radiosity/solver/solver.h"
#include "radiosity/transfer/form_factor.h"
#include "test/report.h"

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mbr;

namespace {

Scene scene_from(const std::string& text) {
    std::istringstream in(text);
    return parse_scene(in, "test.scene");
}

/// Sources for gather_ambient: every surface of order 4, holding B, nothing hidden, and the
/// unshot radiosity `unshot` (a constant) on the surfaces named in `shooting`.
struct TestSources {
    std::vector<SplineField> unshot;
    std::vector<int> order;
    std::vector<bool> irradiance;
    std::vector<HiddenMask> hidden;
    AmbientSources sources() const { return {unshot, order, irradiance, hidden}; }
};
TestSources sources_for(const Scene& scene, Rgb unshot, const std::vector<std::string>& shooting) {
    TestSources s;
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        bool shoots = false;
        for (const std::string& name : shooting) shoots = shoots || scene.surfaces[i].name == name;
        s.unshot.push_back(shoots ? SplineField::constant(4, 0, unshot) : SplineField());
        s.order.push_back(4);
        s.irradiance.push_back(false);
    }
    return s;
}

/// A unit cube seen from inside, reflectance 0.5.
Scene closed_box() {
    return scene_from(
        "material white reflectance 0.5 0.5 0.5\n"
        "box cube white  0 0 0  1 1 1  inward\n");
}

std::vector<std::string> surface_names(const Scene& scene) {
    std::vector<std::string> all;
    for (const SceneSurface& s : scene.surfaces) all.push_back(s.name);
    return all;
}

/// The m-point Gauss-Legendre nodes of [0,1] for m = 4, where the added field interpolates its
/// samples.
std::vector<double> gauss_nodes_01() {
    const GaussLegendre rule = gauss_legendre(4);
    std::vector<double> x;
    for (int a = 0; a < 4; ++a) x.push_back(0.5 * (rule.x[a] + 1));
    return x;
}

}  // namespace

TEST_CASE("ambient gather: a closed box of uniform unshot radiosity gains U rho / (1 - rho)",
          "[ambient]") {
    // Every ray from inside a closed box meets a front face, all of them leaving U + R: the
    // Jacobi iteration sums the geometric series rho + rho^2 + ... = rho / (1 - rho) = 1.
    const Scene scene = closed_box();
    const Octree octree = build_octree(scene);
    const TestSources held = sources_for(scene, {1, 1, 1}, surface_names(scene));
    for (int level : {0, 1, 2}) {
        const AmbientGather g = gather_ambient(scene, octree, held.sources(), 16, level);
        REQUIRE(g.added.size() == 6);
        for (size_t i = 0; i < 6; ++i) {
            CHECK(g.added[i].level() == level);
            for (double s : {0.1, 0.5, 0.9})
                for (double t : {0.2, 0.7}) {
                    CAPTURE(level, scene.surfaces[i].name, s, t);
                    CHECK(g.added[i].evaluate(s, t).g == Approx(1).epsilon(1e-3));
                }
        }
        CHECK(g.power == Approx(6 * 3).epsilon(1e-3));  // six unit faces, three channels
        CHECK(g.rays == 6 * (16 << (2 * level)) * 16);  // 4^level x 16 points a face
        CHECK(g.iterations > 5);
        CHECK(g.iterations < ambient_max_iterations);
    }
}

TEST_CASE("ambient gather: under an unshot square, rho times its point form factor", "[ambient]") {
    // A black square of unshot radiosity 1 at height 1 above a receiver: one bounce only, the
    // gathered H at each Gauss point is the point-to-square form factor.
    const Scene scene = scene_from(
        "material grey  reflectance 0.5 0.5 0.5\n"
        "material black reflectance 0 0 0\n"
        "rectangle floor grey    0 0 0   0 0 1   1 0 0\n"
        "rectangle top   black   0 1 0   1 0 0   0 0 1\n");
    const Octree octree = build_octree(scene);
    const int floor = scene.find_surface("floor"), top = scene.find_surface("top");
    REQUIRE(scene.surfaces[floor].surface.evaluate(0.5, 0.5).normal.y == Approx(1));
    REQUIRE(scene.surfaces[top].surface.evaluate(0.5, 0.5).normal.y == Approx(-1));
    const AmbientGather g =
        gather_ambient(scene, octree, sources_for(scene, {1, 1, 1}, {"top"}).sources(), 4096);
    CHECK(g.added[top].empty());  // black: gathers nothing
    CHECK(g.iterations == 2);     // nothing reflected comes back
    const std::vector<Vec3> square{{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}};
    double worst = 0;
    for (double s : gauss_nodes_01())
        for (double t : gauss_nodes_01()) {
            const SurfacePoint p = scene.surfaces[floor].surface.evaluate(s, t);
            const double exact = 0.5 * point_polygon_form_factor(p.position, p.normal, square);
            const double got = g.added[floor].evaluate(s, t).g;
            worst = std::max(worst, std::fabs(got / exact - 1));
        }
    test::report() << "ambient gather, 4096 rays under a square: largest error " << 100 * worst
                   << " %\n";
    CHECK(worst < 0.015);  // 0.78 %
}

#ifdef _OPENMP
TEST_CASE("ambient gather: results do not depend on the thread count", "[ambient]") {
    const Scene scene =
        load_scene(std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    const Octree octree = build_octree(scene);
    const TestSources held = sources_for(scene, {1, 0.5, 0.25}, {"light", "floor", "short_top"});
    const AmbientSources sources = held.sources();
    const int before = omp_get_max_threads();
    // With the final gather too (a threshold every lit surface reaches: the walls gather again
    // at level 3 or 4).
    for (double final_threshold : {0.0, 1e-6}) {
        CAPTURE(final_threshold);
        omp_set_num_threads(1);
        const AmbientGather one = gather_ambient(scene, octree, sources, 32, 1, 1, final_threshold);
        omp_set_num_threads(2);
        const AmbientGather two = gather_ambient(scene, octree, sources, 32, 1, 1, final_threshold);
        omp_set_num_threads(before);
        CHECK(one.power == two.power);
        CHECK(one.rays == two.rays);
        CHECK(one.iterations == two.iterations);
        int finer = 0;
        for (size_t i = 0; i < one.added.size(); ++i) {
            CAPTURE(scene.surfaces[i].name);
            REQUIRE(one.added[i].empty() == two.added[i].empty());
            if (!one.added[i].empty() && one.added[i].level() > 1) ++finer;
            for (int c = 0; c < 3 && !one.added[i].empty(); ++c)
                CHECK(one.added[i].channel(c).a == two.added[i].channel(c).a);
        }
        CHECK((finer > 0) == (final_threshold > 0));
    }
}
#endif

TEST_CASE("ambient gather: the Cornell box stopped early lands nearer its converged solution",
          "[ambient][solver]") {
    // Stopped after a few shots, much of the power is unshot: the constant per surface restores
    // its total, the gather puts it where it falls (the floor's shadows, the walls' corners).
    const Scene scene =
        load_scene(std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    const Octree octree = build_octree(scene);
    SolverOptions o = solver_options(scene.settings);
    o.receiver.max_depth = 4;
    const RadiosityView converged = radiosity_view(scene, solve(scene, octree, o));
    o.max_shots = 6;
    o.ambient_rays = 0;
    const Solution constant = solve(scene, octree, o);
    o.ambient_rays = 64;
    const Solution gathered = solve(scene, octree, o);
    const double unshot = constant.stats.unshot_power / constant.stats.emitted_power;
    const RadiosityView constant_view = radiosity_view(scene, constant);
    const RadiosityView gathered_view = radiosity_view(scene, gathered);
    double e_constant = 0, e_gathered = 0, max_gathered = 0;
    int count = 0;
    for (size_t i = 0; i < scene.surfaces.size(); ++i)
        for (int a = 0; a < 5; ++a)
            for (int b = 0; b < 5; ++b) {
                const double s = (a + 0.5) / 5, t = (b + 0.5) / 5;
                const double ref = converged.at(int(i), s, t).g;
                if (!(ref > 0)) continue;
                e_constant += std::fabs(constant_view.at(int(i), s, t).g / ref - 1);
                const double e = std::fabs(gathered_view.at(int(i), s, t).g / ref - 1);
                e_gathered += e;
                max_gathered = std::max(max_gathered, e);
                ++count;
            }
    e_constant /= count;
    e_gathered /= count;
    test::report() << "Cornell box after 6 shots (" << 100 * unshot << " % unshot), mean error "
                   << "against converged at " << count << " points: constant " << 100 * e_constant
                   << " %, gathered " << 100 * e_gathered << " % (max " << 100 * max_gathered
                   << " %), gathered power " << gathered.stats.ambient_power << " against "
                   << constant.stats.ambient_power << "\n";
    CHECK(unshot > 0.05);
    CHECK(gathered.stats.ambient_rays > 0);
    CHECK(e_gathered < 0.5 * e_constant);
}

TEST_CASE("ambient gather: the final gather level follows the surface's size", "[ambient]") {
    // Cells no wider than 1/16 of the scene's diagonal: a 10 x 10 square (diagonal 14.1) in a
    // scene of diagonal 17.3 needs 14.1 / 2^l <= 1.08, level 4; a unit square stays at level 1;
    // nothing goes past max_ambient_level however large.
    const Scene scene = scene_from(
        "material grey reflectance 0.5 0.5 0.5\n"
        "rectangle big   grey  0 0 0   0 0 10   10 0 0\n"
        "rectangle small grey  0 1 0   0 0 1    1 0 0\n"
        "rectangle huge  grey  0 2 0   0 0 1000 1000 0 0\n");
    const double diagonal = std::sqrt(300.0);
    CHECK(final_gather_level(scene.surfaces[scene.find_surface("big")].surface, diagonal, 1) == 4);
    CHECK(final_gather_level(scene.surfaces[scene.find_surface("small")].surface, diagonal, 1) ==
          1);
    CHECK(final_gather_level(scene.surfaces[scene.find_surface("huge")].surface, diagonal, 1) ==
          max_ambient_level);
    CHECK(final_gather_level(scene.surfaces[scene.find_surface("small")].surface, diagonal, 3) ==
          3);  // never coarser than the gather's own level
}

TEST_CASE("ambient gather: the final gather keeps a closed box exact at its finer level",
          "[ambient]") {
    // Unit cube (diagonal 1.73, cells of 0.108): each face (diagonal 1.41) gathers once more at
    // level 4, one bounce from U + R with R converged: rho (U + R) = 0.5 (1 + 1) = 1 again.
    const Scene scene = closed_box();
    const Octree octree = build_octree(scene);
    const TestSources held = sources_for(scene, {1, 1, 1}, surface_names(scene));
    const AmbientGather plain = gather_ambient(scene, octree, held.sources(), 64, 1);
    const AmbientGather g = gather_ambient(scene, octree, held.sources(), 64, 1, 1, 0.5);
    REQUIRE(g.added.size() == 6);
    for (size_t i = 0; i < 6; ++i) {
        CHECK(g.added[i].level() == 4);
        for (double s : {0.1, 0.5, 0.9})
            for (double t : {0.2, 0.7}) {
                CAPTURE(scene.surfaces[i].name, s, t);
                CHECK(g.added[i].evaluate(s, t).g == Approx(1).epsilon(1e-3));
            }
    }
    CHECK(g.power == Approx(6 * 3).epsilon(1e-3));
    // The first gather's rays (16 points a level-1 cell, 64 rays) and the final gather's (16
    // points a level-4 cell, a quarter of the rays; its second pass reuses them).
    CHECK(plain.rays == 6 * (16 << 2) * 64);
    CHECK(g.rays == plain.rays + 6 * (16 << 8) * (64 / final_gather_ray_share));
    // Nothing reaches a threshold above every value: the plain gather.
    const AmbientGather high = gather_ambient(scene, octree, held.sources(), 64, 1, 1, 10);
    CHECK(high.rays == plain.rays);
    CHECK(high.power == plain.power);
}

TEST_CASE("ambient gather: the final gather resolves the gap under a block beside a wall",
          "[ambient]") {
    // A 10 x 10 wall, a black block 0.3 in front of its middle, a black square of unshot
    // radiosity 1 facing the wall from 8 away: the wall's one bounce is dark under the block
    // and bright around it. At level 1 one cell covers half the wall and its field cannot dip
    // under the block; the final gather (level 4) can. Reference: the plain gather at level 4
    // with 1024 rays a point. Error: the mean of |B - B_ref| over a 20 x 20 grid of the wall,
    // over the largest B_ref (measured: level 1 9.1 %, the final gather 2.1 %).
    const Scene scene = scene_from(
        "material grey  reflectance 0.5 0.5 0.5\n"
        "material black reflectance 0 0 0\n"
        "rectangle wall  grey   0 0 0   0 0 10   10 0 0\n"
        "rectangle top   black  0 8 0   10 0 0   0 0 10\n"
        "box block black  3 0.3 3  7 4.3 7\n");
    const Octree octree = build_octree(scene);
    const int wall = scene.find_surface("wall");
    REQUIRE(scene.surfaces[wall].surface.evaluate(0.5, 0.5).normal.y == Approx(1));
    const TestSources held = sources_for(scene, {1, 1, 1}, {"top"});
    const AmbientGather reference = gather_ambient(scene, octree, held.sources(), 1024, 4);
    const AmbientGather plain = gather_ambient(scene, octree, held.sources(), 256, 1);
    const AmbientGather final = gather_ambient(scene, octree, held.sources(), 256, 1, 1, 1e-3);
    REQUIRE(final.added[wall].level() == 4);
    double largest = 0, e_plain = 0, e_final = 0;
    for (int a = 0; a < 20; ++a)
        for (int b = 0; b < 20; ++b) {
            const double s = (a + 0.5) / 20, t = (b + 0.5) / 20;
            const double ref = reference.added[wall].evaluate(s, t).g;
            largest = std::max(largest, ref);
            e_plain += std::fabs(plain.added[wall].evaluate(s, t).g - ref) / 400;
            e_final += std::fabs(final.added[wall].evaluate(s, t).g - ref) / 400;
        }
    REQUIRE(largest > 0);
    e_plain /= largest;
    e_final /= largest;
    test::report() << "wall beside a block: level 1 mean error " << 100 * e_plain
                   << " % of the largest, final gather " << 100 * e_final << " %\n";
    CHECK(e_final < 0.4 * e_plain);
}

TEST_CASE("ambient gather: surfaces beside a refined one see its final field", "[ambient]") {
    // A 10 x 10 wall; a black square of unshot radiosity 1 facing it from 0.1 away lights a
    // spot about its size; two grey squares 0.1 from the wall just beside the spot, facing it,
    // take the spot's bounce from close by: a 2 x 2 one, which the final gather refines (level
    // 2), and a 0.5 x 0.5 one, which it does not. The wall's level-1 field spreads the spot
    // over cells of 5, so a square that gathers from it reads a fraction of that light; the
    // final gather's second pass (for the 2 x 2 square) and the last bounce (for the small one)
    // read the wall's level-4 field. Reference: the plain gather at level 4 with 1024 rays a
    // point; the squares' means over a 6 x 6 grid. Measured: the 2 x 2 square 0.0181 with the
    // final gather of one pass (level 1 alone: 0.0181) against 0.00589, with the second pass
    // 0.00868 (the rest: the wall's level-4 cells, 0.625 wide, cannot follow the spot's edge
    // 0.1 from the wall); the small square 0.0202 without the last bounce, 0.0293 with it,
    // against 0.0313.
    const Scene scene = scene_from(
        "material grey  reflectance 0.5 0.5 0.5\n"
        "material black reflectance 0 0 0\n"
        "rectangle wall  grey   0 0 0   0 0 10   10 0 0\n"
        "rectangle spot  black  4 0.1 4   1 0 0   0 0 1\n"
        "rectangle big   grey   5.02 0.1 3.5   2 0 0   0 0 2\n"
        "rectangle small grey   3.48 0.1 4.25   0.5 0 0   0 0 0.5\n");
    const Octree octree = build_octree(scene);
    const int big = scene.find_surface("big"), small = scene.find_surface("small");
    for (int i : {scene.find_surface("spot"), big, small})
        REQUIRE(scene.surfaces[i].surface.evaluate(0.5, 0.5).normal.y == Approx(-1));
    const TestSources held = sources_for(scene, {1, 1, 1}, {"spot"});
    const AmbientGather reference = gather_ambient(scene, octree, held.sources(), 1024, 4);
    const AmbientGather plain = gather_ambient(scene, octree, held.sources(), 256, 1);
    const AmbientGather final = gather_ambient(scene, octree, held.sources(), 256, 1, 1, 1e-3);
    REQUIRE(final.added[scene.find_surface("wall")].level() == 4);
    REQUIRE(final.added[big].level() == 2);
    REQUIRE(final.added[small].level() == 1);
    for (int i : {big, small}) {
        double ref = 0, got = 0, level_1 = 0;
        for (int a = 0; a < 6; ++a)
            for (int b = 0; b < 6; ++b) {
                const double s = (a + 0.5) / 6, t = (b + 0.5) / 6;
                ref += reference.added[i].evaluate(s, t).g / 36;
                got += final.added[i].evaluate(s, t).g / 36;
                level_1 += plain.added[i].evaluate(s, t).g / 36;
            }
        test::report() << scene.surfaces[i].name << " square beside the spot: reference " << ref
                       << ", final gather " << got << ", level 1 alone " << level_1 << "\n";
        CAPTURE(scene.surfaces[i].name, ref, got, level_1);
        REQUIRE(ref > 0);
        CHECK(std::fabs(got - ref) < 0.35 * std::fabs(level_1 - ref));
        if (i == small) CHECK(std::fabs(got / ref - 1) < 0.1);
    }
}

TEST_CASE(
    "ambient gather: the final gather leaves an unshot light's first bounce at the gather's "
    "level",
    "[ambient]") {
    // A small light still unshot above a 10 x 10 floor: its first bounce is direct light, which
    // a few rays a point turn into noise at a fine level (blotches under 54 small lamps), so the
    // final gather keeps it as the level-1 field of the first gather. Nothing else bounces here,
    // so the final field (level 4) is that level-1 field, re-projected exactly (the level-4
    // splines hold the level-1 ones and the Gauss rule integrates their products exactly).
    const Scene scene = scene_from(
        "material grey reflectance 0.5 0.5 0.5\n"
        "material lamp reflectance 0 0 0 emission 1 1 1\n"
        "rectangle floor grey  0 0 0   0 0 10   10 0 0\n"
        "rectangle light lamp  4.5 3 4.5   1 0 0   0 0 1\n");
    const Octree octree = build_octree(scene);
    const int floor = scene.find_surface("floor");
    REQUIRE(scene.surfaces[scene.find_surface("light")].surface.evaluate(0.5, 0.5).normal.y ==
            Approx(-1));
    const TestSources held = sources_for(scene, {1, 1, 1}, {"light"});
    const AmbientGather plain = gather_ambient(scene, octree, held.sources(), 64, 1);
    const AmbientGather final = gather_ambient(scene, octree, held.sources(), 64, 1, 1, 1e-12);
    REQUIRE(plain.added[floor].level() == 1);
    REQUIRE(final.added[floor].level() == 4);
    CHECK(final.rays > plain.rays);
    for (double s : {0.1, 0.37, 0.5, 0.81})
        for (double t : {0.05, 0.5, 0.66}) {
            CAPTURE(s, t);
            CHECK(final.added[floor].evaluate(s, t).g ==
                  Approx(plain.added[floor].evaluate(s, t).g).epsilon(1e-9));
        }
    CHECK(final.power == Approx(plain.power).epsilon(1e-9));
}
