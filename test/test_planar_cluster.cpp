// test/test_planar_cluster.cpp - planar clusters (beyond the paper; radiosity/solver/solver.h,
// planar_cluster): coplanar neighbours that face alike shoot together; a receiver at least the
// cluster's diagonal away takes one transfer of their summed fields (transfer() with several
// ShooterParts), a nearer one a transfer from each.
//
// Independent references: the same light as one surface (a lamp whole against the lamp in
// pieces), the sum of the members' own transfers, and the power balance of a closed box.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solver.h"
#include "radiosity/transfer/transfer.h"
#include "radiosity/visibility/occlusion.h"
#include "test/report.h"

using namespace mbr;

namespace {

Scene scene_from(const std::string& text) {
    std::istringstream in(text);
    return parse_scene(in, "cluster.scene");
}

/// A grey room of 4 x 3 x 4 (y up) with a block on its floor, lit by a 2 x 2 lamp 1 cm under the
/// ceiling: whole, or as `nx` x `nz` coplanar pieces of the same emission. The walls are nearer
/// the lamp than its diagonal (a transfer from each piece), the floor is not (one transfer).
Scene lamp_room(int nx, int nz) {
    std::string text =
        "material grey reflectance 0.5 0.5 0.5\n"
        "material glow reflectance 0 0 0 emission 3 3 3\n"
        "box room grey  0 0 0  4 3 4  inward\n"
        "box block grey  1.2 0 1.2  2 0.8 2\n";
    const double x0 = 1, z0 = 1, y = 2.99;
    for (int i = 0; i < nx; ++i)
        for (int k = 0; k < nz; ++k) {
            const double a = x0 + 2.0 * i / nx, b = x0 + 2.0 * (i + 1) / nx;
            const double c = z0 + 2.0 * k / nz, d = z0 + 2.0 * (k + 1) / nz;
            // Facing down (-y): corners counter-clockwise seen from below.
            std::ostringstream q;
            q << "quad lamp" << i << k << " glow  " << a << ' ' << y << ' ' << c << "  " << b << ' '
              << y << ' ' << c << "  " << b << ' ' << y << ' ' << d << "  " << a << ' ' << y << ' '
              << d << "\n";
            text += q.str();
        }
    return scene_from(text);
}

SolverOptions quick(const Scene& scene, int max_shots, bool clusters) {
    SolverOptions o = solver_options(scene.settings);
    o.receiver.shadows.method = ShadowMethod::Exact;
    o.receiver.min_depth = 1;
    o.receiver.max_depth = 4;
    o.tolerance = 5e-3;
    o.max_shots = max_shots;
    o.convergence = 0;
    o.cluster_shots = clusters;
    return o;
}

}  // namespace

TEST_CASE(
    "planar cluster: coplanar neighbours that face alike, with a tenth of the power, join "
    "within twice the lead's size",
    "[cluster]") {
    const Scene scene = scene_from(
        "material grey reflectance 0.5 0.5 0.5\n"
        "rectangle a grey  0 0 0  1 0 0  0 1 0\n"                 // z = 0, facing +z: the lead
        "rectangle b grey  1 0 0  1 0 0  0 1 0\n"                 // beside a
        "rectangle c grey  0 1 0  0 1 0  1 0 0\n"                 // beside a, facing -z
        "rectangle d grey  0 0 0.01  1 0 0  0 1 0\n"              // a parallel plane 1 cm above
        "rectangle e grey  0 -1.2 0  1 0 0  0 1 0\n"              // 0.2 below a: too little power
        "rectangle f grey  2.1 0 0  0.5 0 0  0 0.4 0\n"           // 0.1 beside b, exactly a tenth
        "rectangle g grey  6 0 0  1 0 0  0 1 0\n"                 // coplanar, far from the others
        "cylinder k grey  0 0 0  0 0 1  1 0 0  0.5 1  0 360\n");  // curved
    std::vector<double> unshot = {10, 3, 10, 10, 0.99, 1.0, 10, 20};
    // f joins through b (0.1 is within a quarter of the smaller diagonal, f's 0.64); a, b and f
    // span 2.6 x 1, within twice a's diagonal (2.83).
    CHECK(planar_cluster(scene, 0, unshot) == std::vector<int>{0, 1, 5});
    // A tenth of 3 is 0.3, but e would make the cluster 2.6 x 2.2, wider than twice b's
    // diagonal.
    CHECK(planar_cluster(scene, 1, unshot) == std::vector<int>{1, 0, 5});
    unshot[1] = 0.5;  // b too weak: f has no way to a
    CHECK(planar_cluster(scene, 0, unshot) == std::vector<int>{0});
    CHECK(planar_cluster(scene, 6, unshot) == std::vector<int>{6});  // nobody near
    CHECK(planar_cluster(scene, 7, unshot) == std::vector<int>{7});  // not planar
    unshot[0] = 0;
    CHECK(planar_cluster(scene, 0, unshot) == std::vector<int>{0});  // nothing to shoot
}

TEST_CASE("planar cluster: at most max_cluster_members surfaces", "[cluster]") {
    // An 8 x 8 lead and 10 x 7 tiles of 0.25 beside it (all within twice its diagonal).
    std::string text =
        "material grey reflectance 0.5 0.5 0.5\n"
        "rectangle lead grey  0 0 0  8 0 0  0 8 0\n";
    for (int ix = 0; ix < 10; ++ix)
        for (int iy = 0; iy < 7; ++iy) {
            std::ostringstream r;
            r << "rectangle t" << ix << '_' << iy << " grey  " << 8 + 0.25 * ix << ' ' << 0.25 * iy
              << " 0  0.25 0 0  0 0.25 0\n";
            text += r.str();
        }
    const Scene scene = scene_from(text);
    const int n = int(scene.surfaces.size());
    const std::vector<int> members = planar_cluster(scene, 0, std::vector<double>(size_t(n), 1.0));
    REQUIRE(int(members.size()) == max_cluster_members);  // the first tiles met, in order
    for (int k = 0; k < max_cluster_members; ++k) CHECK(members[size_t(k)] == k);
}

TEST_CASE("planar cluster: a cluster's transfer is the sum of its members' transfers",
          "[cluster][transfer]") {
    // Two coplanar lamps of different emission over a floor, a block between them and the
    // floor: exact visibility, one transfer of the two against two transfers added. Each is a
    // fit within the tolerance; the sum agrees with the cluster's within a few of them.
    const Scene scene = scene_from(
        "material grey reflectance 0.5 0.5 0.5\n"
        "material glow reflectance 0 0 0 emission 4 4 4\n"
        "material dim reflectance 0 0 0 emission 1 2 3\n"
        "rectangle floor grey  0 0 0  0 0 3  3 0 0\n"
        "rectangle lamp1 glow  0.5 2 0.5  0.6 0 0  0 0 0.6\n"
        "rectangle lamp2 dim  1.8 2 1.6  0.8 0 0  0 0 0.5\n"
        "box block grey  1 0.6 1  1.6 0.8 1.8\n");
    const Octree octree = build_octree(scene);
    const int floor = scene.find_surface("floor");
    const int l1 = scene.find_surface("lamp1"), l2 = scene.find_surface("lamp2");
    ReceiverOptions options;
    options.min_depth = 1;
    options.max_depth = 4;
    options.absolute_tolerance = 2e-3;
    options.quadrature.abs_tolerance = 2e-3;
    options.shadows.method = ShadowMethod::Exact;
    const ReceiverSurface receiver{&scene.surfaces[size_t(floor)].surface,
                                   [](double, double) {
                                       return Rgb{0.5, 0.5, 0.5};
                                   },
                                   nullptr};
    auto shooter_of = [&](int i) {
        const Texture& e = scene.material_of(i).emission;
        return make_shooter(scene.surfaces[size_t(i)].surface,
                            SplineField::constant(4, 0, e.mean()), 1);
    };
    const Shooter s1 = shooter_of(l1), s2 = shooter_of(l2);
    const OcclusionContext c1 = make_occlusion_context(octree, scene.surfaces[size_t(l1)].surface,
                                                       l1, *receiver.surface, floor, 1);
    const OcclusionContext c2 = make_occlusion_context(octree, scene.surfaces[size_t(l2)].surface,
                                                       l2, *receiver.surface, floor, 1);
    REQUIRE(!c1.clear());
    REQUIRE(!c2.clear());
    const SplineField both = transfer({{&s1, &c1}, {&s2, &c2}}, receiver, options);
    const SplineField one = transfer(s1, receiver, options, nullptr, nullptr, &c1);
    const SplineField two = transfer(s2, receiver, options, nullptr, nullptr, &c2);
    // The reference: the two transfers at a twentieth of the tolerance, depth 6, added.
    ReceiverOptions fine = options;
    fine.max_depth = 6;
    fine.absolute_tolerance /= 20;
    fine.quadrature.abs_tolerance /= 20;
    const SplineField ref1 = transfer(s1, receiver, fine, nullptr, nullptr, &c1);
    const SplineField ref2 = transfer(s2, receiver, fine, nullptr, nullptr, &c2);
    double cluster_error = 0, sum_error = 0, largest = 0;
    for (int a = 0; a <= 40; ++a)
        for (int b = 0; b <= 40; ++b) {
            const double s = a / 40.0, t = b / 40.0;
            const Rgb ref = ref1.evaluate(s, t) + ref2.evaluate(s, t);
            const Rgb sum = one.evaluate(s, t) + two.evaluate(s, t);
            cluster_error = std::max(cluster_error, max_abs(both.evaluate(s, t) - ref));
            sum_error = std::max(sum_error, max_abs(sum - ref));
            largest = std::max(largest, max_abs(ref));
        }
    test::report() << "two lamps over a floor: largest error of the cluster's transfer "
                   << cluster_error << ", of the two transfers added " << sum_error
                   << " (absolute tolerance 2e-3, largest value " << largest << ")\n";
    CHECK(largest > 0.05);
    // One fit for the sum: within its tolerance's few multiples, and no worse than two fits.
    CHECK(cluster_error < 4 * options.absolute_tolerance);
    CHECK(cluster_error < 1.5 * sum_error);
}

TEST_CASE("planar cluster: a lamp in pieces shoots once and lights the room like the lamp whole",
          "[cluster][solver]") {
    const Scene whole = lamp_room(1, 1), pieces = lamp_room(1, 3);
    const Octree octree_whole = build_octree(whole), octree_pieces = build_octree(pieces);
    const Solution a = solve(whole, octree_whole, quick(whole, 6, true));
    const Solution b = solve(pieces, octree_pieces, quick(pieces, 6, true));
    REQUIRE(b.stats.per_shot.size() == 6);
    CHECK(b.stats.per_shot[0].members == 3);  // the three pieces in the first shot
    CHECK(b.stats.clustered_shots >= 1);
    // Without clusters the pieces take the first three shots.
    ProgressiveSolver apart(pieces, octree_pieces, quick(pieces, 3, false));
    for (int k = 0; k < 3; ++k) CHECK(apart.shoot().members == 1);
    CHECK(apart.solution().stats.unshot_power > 0);
    // The lit room agrees: the same light, one transfer per receiver for the pieces' sum.
    const RadiosityView va = radiosity_view(whole, a), vb = radiosity_view(pieces, b);
    double worst = 0;
    for (const char* name :
         {"room.ymin", "room.xmin", "room.zmax", "block.ymax", "block.xmax", "room.ymax"}) {
        const int ia = whole.find_surface(name), ib = pieces.find_surface(name);
        REQUIRE(ia >= 0);
        REQUIRE(ib >= 0);
        for (double u = 0.1; u < 1; u += 0.2)
            for (double v = 0.1; v < 1; v += 0.2) {
                const double x = luminance(va.at(ia, u, v)), y = luminance(vb.at(ib, u, v));
                worst = std::max(worst, std::fabs(x / y - 1));
            }
    }
    test::report() << "lamp in 3 pieces against the lamp whole, 6 shots: largest difference "
                   << 100 * worst << " %\n";
    CHECK(worst < 0.03);
}

TEST_CASE(
    "planar cluster: a closed box's split light is absorbed or still unshot after every "
    "shot",
    "[cluster][solver]") {
    // The top face of a closed unit box as three coplanar emitting strips (one cluster).
    std::string text =
        "material white reflectance 0.5 0.5 0.5\n"
        "material glow reflectance 0.5 0.5 0.5 emission 1 1 1\n"
        "quad bottom white  0 0 0  0 0 1  1 0 1  1 0 0\n"
        "quad x0 white  0 0 0  0 1 0  0 1 1  0 0 1\n"
        "quad x1 white  1 0 0  1 0 1  1 1 1  1 1 0\n"
        "quad z0 white  0 0 0  1 0 0  1 1 0  0 1 0\n"
        "quad z1 white  0 0 1  0 1 1  1 1 1  1 0 1\n";
    for (int k = 0; k < 3; ++k) {  // three strips of 1 x 1/3
        const double c = k / 3.0, d = (k + 1) / 3.0;
        std::ostringstream q;
        q << "quad top" << k << " glow  0 1 " << c << "  1 1 " << c << "  1 1 " << d << "  0 1 "
          << d << "\n";
        text += q.str();
    }
    const Scene scene = scene_from(text);
    const Octree octree = build_octree(scene);
    SolverOptions options = quick(scene, 10, true);
    options.receiver.max_depth = 3;
    options.tolerance = 1e-2;
    ProgressiveSolver solver(scene, octree, options);
    const double emitted = solver.solution().stats.emitted_power;
    REQUIRE(emitted == Approx(3.0));
    double absorbed = 0;
    int clustered = 0;
    while (!solver.done()) {
        const ShotStats shot = solver.shoot();
        CAPTURE(shot.shot, shot.shooter, shot.members);
        clustered += shot.members > 1 ? 1 : 0;
        // The loop's bookkeeping: the members' unshot power leaves, the reflected power joins.
        CHECK(shot.unshot_after ==
              Approx(shot.unshot_before - shot.shooter_power + shot.reflected).epsilon(1e-10));
        // Everything the cluster sends arrives on the faces it sees (as in test_solver.cpp's
        // closed box: within the transfers' accuracy).
        CHECK(shot.incident == Approx(shot.shooter_power).epsilon(2e-2));
        absorbed += shot.incident - shot.reflected;
        CHECK(absorbed + shot.unshot_after == Approx(emitted).epsilon(1e-2));
    }
    CHECK(solver.solution().stats.per_shot[0].members == 3);
    CHECK(clustered >= 1);
}
