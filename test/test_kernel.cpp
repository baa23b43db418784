// test/test_kernel.cpp - the kernel F of eq. (3), the analytic point-to-polygon form factor that
// is the exact reference of Tables 1-2 (section 7, "an analytic formula advocated in [7]"), and
// the adaptive quadrature of the sample value (21) over the shooter (section 6, "Adaptive
// Quadrature"; radiosity/transfer/sample_values.h).
//
// Independent references:
// - closed forms of the form factor from a differential area to a rectangle (Siegel and Howell,
//   "Thermal Radiation Heat Transfer", configuration-factor catalogue): a parallel rectangle
//   a x b at distance c with the element's normal through one corner,
//     F = 1/(2 pi) [ A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2)) ],
//   A = a/c, B = b/c; and a rectangle in a perpendicular plane at distance c, width a from the
//   foot of the element along the common direction, height b along the element's normal,
//     F = 1/(2 pi) [ atan(A) - 1/sqrt(1+B^2) atan(A/sqrt(1+B^2)) ]
//   (derived at perpendicular_corner from Lambert's contour integral, edge by edge). Other
//   positions follow by superposition of signed corner rectangles;
// - the area form factors between unit squares (same catalogue: parallel plates, and
//   perpendicular plates with a common edge), to all digits;
// - brute-force tensor Gauss-Legendre quadrature of F over a polygon or a shooter.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "math/gauss_legendre.h"
#include "radiosity/reference/configurations.h"
#include "radiosity/transfer/form_factor.h"
#include "radiosity/transfer/sample_values.h"
#include "test/report.h"

using namespace mbr;

namespace {

/// Parallel rectangle [0,a] x [0,b] at distance c, the element's normal through corner (0,0).
double parallel_corner(double a, double b, double c) {
    const double A = a / c, B = b / c;
    const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
    return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * Pi);
}

/// Signed corner form factor: the cumulative Phi(x, y) over [0,x] x [0,y] (the density is even
/// in x and in y), so that a rectangle [x0,x1] x [y0,y1] has
/// Phi(x1,y1) - Phi(x0,y1) - Phi(x1,y0) + Phi(x0,y0).
double parallel_phi(double x, double y, double c) {
    if (x == 0 || y == 0) return 0;
    const double sign = (x > 0) == (y > 0) ? 1.0 : -1.0;
    return sign * parallel_corner(std::fabs(x), std::fabs(y), c);
}

/// From a point at the origin (normal +z) to the rectangle [x0,x1] x [y0,y1] in z = c.
double parallel_rectangle(double x0, double x1, double y0, double y1, double c) {
    return parallel_phi(x1, y1, c) - parallel_phi(x0, y1, c) - parallel_phi(x1, y0, c) +
           parallel_phi(x0, y0, c);
}

/// Element at the origin with normal +z; rectangle x in [0,a], z in [0,b] in the plane y = c.
/// Lambert's contour sum over the edges (0,c,0) -> (a,c,0) -> (a,c,b) -> (0,c,b): the two edges
/// along z have R_i x R_{i+1} perpendicular to z and give nothing; the bottom edge gives
/// -atan(a/c) (cross product along -z), the top edge c/sqrt(b^2+c^2) atan(a/sqrt(b^2+c^2)).
double perpendicular_corner(double a, double b, double c) {
    const double A = a / c, B = b / c, sb = std::sqrt(1 + B * B);
    return (std::atan(A) - std::atan(A / sb) / sb) / (2 * Pi);
}

/// Area form factor between directly opposed parallel rectangles a x b at distance c
/// (catalogue: "parallel, directly opposed rectangles"), X = a/c, Y = b/c.
double parallel_plates(double a, double b, double c) {
    const double X = a / c, Y = b / c, sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
    return 2 / (Pi * X * Y) *
           (0.5 * std::log((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)) +
            X * sy * std::atan(X / sy) + Y * sx * std::atan(Y / sx) - X * std::atan(X) -
            Y * std::atan(Y));
}

/// Area form factor from a rectangle of width w (perpendicular to the common edge) to one of
/// height h, both along a common edge of length l, at a right angle (catalogue: "perpendicular
/// rectangles with a common edge"), H = h/l, W = w/l.
double perpendicular_plates(double l, double h, double w) {
    const double H = h / l, W = w / l, H2 = H * H, W2 = W * W, R = std::sqrt(H2 + W2);
    const double log_term = std::log((1 + W2) * (1 + H2) / (1 + W2 + H2)) +
                            W2 * std::log(W2 * (1 + W2 + H2) / ((1 + W2) * (W2 + H2))) +
                            H2 * std::log(H2 * (1 + H2 + W2) / ((1 + H2) * (H2 + W2)));
    return (W * std::atan(1 / W) + H * std::atan(1 / H) - R * std::atan(1 / R) + 0.25 * log_term) /
           (Pi * W);
}

/// F from the receiver point at (s, t) of a configuration to its shooter, by the closed forms.
double closed_form_parallel(double s, double t, double h) {
    return parallel_rectangle(-s, 1 - s, -t, 1 - t, h);
}
double closed_form_perpendicular(double s, double t) {
    // Shooter x in [0,1], z in [0,1] in y = 0; the point (s, t, 0) is at distance t from it.
    auto P = [&](double x) {
        return x == 0 ? 0.0 : (x > 0 ? 1 : -1) * perpendicular_corner(std::fabs(x), 1, t);
    };
    return P(1 - s) - P(-s);
}

double relative(double a, double b) {
    return std::fabs(a - b) / std::fabs(b);
}

/// The shooter with constant unshot radiosity 1 (an emitter's first shot).
Shooter unit_shooter(const Surface& surface) {
    Shooter shooter;
    shooter.surface = &surface;
    shooter.unshot = SplineField::constant(4, 0, {1, 1, 1});
    return shooter;
}

/// int over [0,1]^2 of F(p, x(u,v)) B(u,v) A(u,v) du dv by an n x n Gauss-Legendre rule on each
/// cell of a cells x cells grid: the brute-force reference for (21).
template <class B>
double brute_force_increment(const SurfacePoint& p, const Surface& shooter, B&& b, int cells,
                             int n) {
    const GaussLegendre rule = gauss_legendre(n);
    double sum = 0;
    for (int ci = 0; ci < cells; ++ci)
        for (int cj = 0; cj < cells; ++cj) {
            const Rect r{double(ci) / cells, double(ci + 1) / cells, double(cj) / cells,
                         double(cj + 1) / cells};
            sum += integrate_2d(
                [&](double u, double v) {
                    const SurfacePoint x = shooter.evaluate(u, v);
                    return form_factor_kernel(p.position, p.normal, x.position, x.normal) *
                           b(u, v) * x.area_factor;
                },
                r, rule);
        }
    return sum;
}

Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    return normalize(Vec3{g(rng), g(rng), g(rng)});
}

}  // namespace

TEST_CASE("kernel: F is symmetric, non-negative and zero behind either surface", "[kernel]") {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-2, 2);
    int front = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const Vec3 p{u(rng), u(rng), u(rng)}, x{u(rng), u(rng), u(rng)};
        const Vec3 n_p = random_unit(rng), n_x = random_unit(rng);
        CAPTURE(trial, p, n_p, x, n_x);
        const double F = form_factor_kernel(p, n_p, x, n_x);
        CHECK(F >= 0);
        // Swapping the roles of the two points: l -> -l, the two cosines trade places.
        CHECK(form_factor_kernel(x, n_x, p, n_p) == Approx(F).epsilon(1e-14));
        const Vec3 l = x - p;
        const bool facing = dot(l, n_p) > 0 && -dot(l, n_x) > 0;
        if (facing) {
            ++front;
            const double expect = dot(l, n_p) * -dot(l, n_x) / (Pi * std::pow(length(l), 4));
            CHECK(F == Approx(expect).epsilon(1e-13));
            // Turning either surface around puts the other behind it: nothing is received.
            CHECK(form_factor_kernel(p, -n_p, x, n_x) == 0);
            CHECK(form_factor_kernel(p, n_p, x, -n_x) == 0);
        } else {
            CHECK(F == 0);
        }
    }
    CHECK(front > 300);  // about a quarter of random pairs face each other
    // On the axis of facing parallel elements at distance h: 1 / (pi h^2).
    for (double h : {0.1, 1.0, 3.0})
        CHECK(form_factor_kernel({0, 0, 0}, {0, 0, 1}, {0, 0, h}, {0, 0, -1}) ==
              Approx(1 / (Pi * h * h)).epsilon(1e-15));
    // Grazing: a point in the other's plane receives nothing.
    CHECK(form_factor_kernel({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 0, -1}) == 0);
}

TEST_CASE("kernel: the vectorised kernel gives form_factor_kernel's values to the bit",
          "[kernel]") {
    // form_factor_kernels (arrays of points, several per vector instruction, an AVX2 clone
    // where the processor has one) against form_factor_kernel one point at a time: random
    // pairs facing and not, points on p's tangent plane or the node's (zero cosines), a node
    // at p itself (|l| = 0) and at distances from 1e-6 to 1e6, in runs of every length from 0
    // to 37 (the vector loop's remainders).
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-2, 2);
    std::uniform_int_distribution<int> kind(0, 5);
    struct Node {
        Vec3 x, n;
    };
    int facing = 0, zero = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        const Vec3 n_p = random_unit(rng);
        const int count = trial % 38;
        std::vector<Node> nodes;
        for (int i = 0; i < count; ++i) {
            Vec3 x{u(rng), u(rng), u(rng)};
            Vec3 n = random_unit(rng);
            switch (kind(rng)) {
                case 0:  // the node at p
                    x = p;
                    break;
                case 1:  // on p's tangent plane
                    x = x - dot(x - p, n_p) * n_p;
                    break;
                case 2:  // p on the node's tangent plane
                    n = normalize(cross(x - p, random_unit(rng)));
                    break;
                case 3:  // from 1e-6 to 1e6 away
                    x = p + std::pow(10.0, 12 * (u(rng) + 2) / 4 - 6) * random_unit(rng);
                    break;
                default:
                    break;
            }
            nodes.push_back({x, n});
        }
        std::vector<double> block;
        append_shooting_nodes(block, nodes.data(), count);
        std::vector<double> F(size_t(count) + 1, -1.0);
        form_factor_kernels(p, n_p, shooting_nodes(block.data(), count), count, F.data());
        for (int i = 0; i < count; ++i) {
            const double expect = form_factor_kernel(p, n_p, nodes[i].x, nodes[i].n);
            CAPTURE(trial, i, p, n_p, nodes[i].x, nodes[i].n);
            CHECK(std::memcmp(&F[size_t(i)], &expect, sizeof(double)) == 0);
            (expect > 0 ? facing : zero) += 1;
        }
        CHECK(F[size_t(count)] == -1.0);  // nothing written past the run
        // A run that starts inside the block (sum_over's chunks) reads the same nodes.
        if (count > 5) {
            std::vector<double> G(size_t(count) - 5);
            form_factor_kernels(p, n_p, shooting_nodes(block.data(), count, 5), count - 5,
                                G.data());
            for (int i = 5; i < count; ++i) CHECK(G[size_t(i) - 5] == F[size_t(i)]);
        }
    }
    CHECK(facing > 500);
    CHECK(zero > 1000);
}

TEST_CASE("kernel: analytic form factor equals the closed form for a parallel rectangle",
          "[kernel]") {
    // The element's normal through a corner; then any point under or beside the rectangle by
    // signed superposition of four corner rectangles.
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> side(0.05, 3), pos(-0.5, 1.5);
    for (int trial = 0; trial < 300; ++trial) {
        const double a = side(rng), b = side(rng), c = side(rng);
        CAPTURE(trial, a, b, c);
        const std::vector<Vec3> rect{{0, 0, c}, {0, b, c}, {a, b, c}, {a, 0, c}};  // faces -z
        // Lambert's sum of atan2's and the catalogue's atan's: both to rounding.
        CHECK(point_polygon_form_factor({0, 0, 0}, {0, 0, 1}, rect) ==
              Approx(parallel_corner(a, b, c)).epsilon(1e-13));
        const double s = pos(rng), t = pos(rng);
        CAPTURE(s, t);
        const std::vector<Vec3> unit{{0, 0, c}, {0, 1, c}, {1, 1, c}, {1, 0, c}};
        const double F = point_polygon_form_factor({s, t, 0}, {0, 0, 1}, unit);
        // Beside the rectangle the four signed terms cancel to a small value: compare in
        // absolute terms scaled by the largest term (about 1/4).
        CHECK(F == Approx(closed_form_parallel(s, t, c)).margin(1e-14));
    }
    // The centre of the unit square at distance h: 4 corners of a/c = b/c = 1/(2h), each
    // (1/2pi) 2 X/sqrt(1+X^2) atan(X/sqrt(1+X^2)): F = (4/pi) X/sqrt(1+X^2) atan(X/sqrt(1+X^2)).
    for (double h : {1.0, 0.5, 0.1}) {
        CAPTURE(h);
        const TransferSetup setup = parallel_squares(h);
        const double X = 0.5 / h, sx = std::sqrt(1 + X * X);
        const double centre = 4 / Pi * X / sx * std::atan(X / sx);
        CHECK(point_polygon_form_factor({0.5, 0.5, 0}, {0, 0, 1}, setup.shooter_polygon()) ==
              Approx(centre).epsilon(1e-14));
    }
}

TEST_CASE("kernel: analytic form factor equals the closed form for a perpendicular rectangle",
          "[kernel]") {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> side(0.05, 3), unit(0.001, 1);
    for (int trial = 0; trial < 300; ++trial) {
        const double a = side(rng), b = side(rng), c = side(rng);
        CAPTURE(trial, a, b, c);
        // Rectangle x in [0,a], z in [0,b] in the plane y = c, facing -y (towards the point).
        const std::vector<Vec3> rect{{0, c, 0}, {a, c, 0}, {a, c, b}, {0, c, b}};
        // The closed form subtracts two terms of size atan(A) whose difference is O(B^2):
        // relative rounding up to ~1e-16 / B^2 = 4e-13 for the smallest B = 0.05 / 3.
        CHECK(point_polygon_form_factor({0, 0, 0}, {0, 0, 1}, rect) ==
              Approx(perpendicular_corner(a, b, c)).epsilon(1e-12));
        // Table 2's configuration at random receiver points, by superposition of two corners.
        const double s = unit(rng), t = unit(rng);
        CAPTURE(s, t);
        const TransferSetup setup = perpendicular_squares();
        CHECK(point_polygon_form_factor({s, t, 0}, {0, 0, 1}, setup.shooter_polygon()) ==
              Approx(closed_form_perpendicular(s, t)).epsilon(1e-12));
    }
}

TEST_CASE("kernel: analytic form factor is one-sided and clips at the tangent plane", "[kernel]") {
    const std::vector<Vec3> facing{{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}};  // faces -z
    const std::vector<Vec3> away{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};    // faces +z
    const Vec3 p{0.3, 0.6, 0};
    CHECK(point_polygon_form_factor(p, {0, 0, 1}, facing) > 0);
    CHECK(point_polygon_form_factor(p, {0, 0, 1}, away) == 0);
    CHECK(point_polygon_form_factor(p, {0, 0, -1}, facing) == 0);  // p faces away
    CHECK(point_polygon_form_factor(p, {0, 0, 1}, {{0, 0, 1}, {1, 0, 1}}) == 0);
    // A perpendicular plate reaching below the receiver's plane: only the part above counts.
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> unit(0.01, 1);
    for (int trial = 0; trial < 50; ++trial) {
        const double s = unit(rng), t = unit(rng), below = unit(rng);
        CAPTURE(s, t, below);
        const std::vector<Vec3> plate{{0, 0, -below}, {0, 0, 1}, {1, 0, 1}, {1, 0, -below}};
        CHECK(point_polygon_form_factor({s, t, 0}, {0, 0, 1}, plate) ==
              Approx(closed_form_perpendicular(s, t)).epsilon(1e-12));
    }
}

TEST_CASE("kernel: analytic form factor equals brute-force quadrature of F over tilted quads",
          "[kernel]") {
    // Random planar parallelograms in front of a random point: Lambert's contour integral
    // against 16 x 16 cells of 8 x 8 Gauss-Legendre points of eq. (3) times the area factor.
    // The quad stays at least 0.4 above the point's plane (corner heights 1..2 minus two
    // tilts of at most 0.3), so the integrand is smooth on the scale of the cells (1/16 of a
    // side of at most ~1.7): the rule converges to ~1e-13 here.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    int tested = 0;
    for (int trial = 0; trial < 40; ++trial) {
        const Vec3 o{u(rng), u(rng), 1.5 + 0.5 * u(rng)}, e1{u(rng), u(rng), 0.3 * u(rng)},
            e2{u(rng), u(rng), 0.3 * u(rng)};
        const Surface quad = Surface::planar_quad(o, o + e1, o + e1 + e2, o + e2);
        const Vec3 n = quad.normal(0.5, 0.5);
        const SurfacePoint p{
            {0.1 * u(rng), 0.1 * u(rng), 0}, normalize(Vec3{0.3 * u(rng), 0.3 * u(rng), 1}), 1};
        if (dot(o - p.position, n) >= 0) continue;  // the quad must face the point
        if (length(cross(e1, e2)) < 0.2) continue;  // not a sliver
        ++tested;
        CAPTURE(trial, o, e1, e2, p.normal);
        const double exact =
            point_polygon_form_factor(p.position, p.normal, {o, o + e1, o + e1 + e2, o + e2});
        const double brute = brute_force_increment(
            p, quad, [](double, double) { return 1.0; }, 16, 8);
        CHECK(brute == Approx(exact).epsilon(1e-10));
    }
    CHECK(tested >= 10);
}

TEST_CASE("kernel: grid means of the exact values match the area form factors", "[kernel][paper]") {
    // DESIGN.md section 6: the 256 x 256 cell-centre grid of Tables 1-2 averages the exact
    // F(p -> shooter) to the area form factor 0.199825, 0.415253, 0.826995 (h = 1, 0.5, 0.1)
    // and 0.200044 (perpendicular). First the closed forms against those six decimals.
    CHECK(parallel_plates(1, 1, 1.0) == Approx(0.199825).margin(5e-7));
    CHECK(parallel_plates(1, 1, 0.5) == Approx(0.415253).margin(5e-7));
    CHECK(parallel_plates(1, 1, 0.1) == Approx(0.826995).margin(5e-7));
    CHECK(perpendicular_plates(1, 1, 1) == Approx(0.200044).margin(5e-7));

    // The grid mean is the midpoint rule with Delta = 1/256, whose error is, by Euler-Maclaurin,
    // -(Delta^2 / 24) times the flux of grad F out of [0,1]^2 plus O(Delta^4). F falls by up
    // to ~0.3 within ~0.1 of the edges at h = 0.1 (|grad F| <~ 5, perimeter 4): at most ~1.3e-5;
    // at the perpendicular squares' common edge F_t has a log singularity, which adds only a
    // Delta^2 log(Delta) term of the same size. The tolerance 2e-5 covers all four.
    const int n = 256;
    const double delta = 1.0 / n;
    struct Config {
        const char* name;
        TransferSetup setup;
        double exact;
        bool smooth;
    };
    const Config configs[] = {
        {"h = 1.0", parallel_squares(1.0), parallel_plates(1, 1, 1.0), true},
        {"h = 0.5", parallel_squares(0.5), parallel_plates(1, 1, 0.5), true},
        {"h = 0.1", parallel_squares(0.1), parallel_plates(1, 1, 0.1), true},
        {"perpendicular", perpendicular_squares(), perpendicular_plates(1, 1, 1), false}};
    for (const Config& c : configs) {
        CAPTURE(c.name);
        const std::vector<double> grid = exact_grid(c.setup, n);
        double sum = 0;
        for (double v : grid) sum += v;
        const double mean = sum / grid.size();
        CHECK(std::fabs(mean - c.exact) <= 2e-5);
        double predicted = 0;
        if (c.smooth) {
            // The Euler-Maclaurin term itself: flux of grad F through the four edges by
            // central differences of the analytic F (smooth across the edges of the receiver,
            // whose plane extends beyond them) and Gauss-Legendre along each edge.
            const std::vector<Vec3> poly = c.setup.shooter_polygon();
            auto F = [&](double s, double t) {
                return point_polygon_form_factor({s, t, 0}, {0, 0, 1}, poly);
            };
            const double d = 1e-5;
            const GaussLegendre rule = gauss_legendre(20);
            double flux = 0;
            for (int e = 0; e < 4; ++e)
                for (int q = 0; q < 10; ++q)  // 10 pieces of 20 points: F_n varies on scale h
                    flux += integrate_1d(
                        [&](double x) {
                            switch (e) {
                                case 0:
                                    return -(F(x, d) - F(x, -d)) / (2 * d);  // t = 0, outward -t
                                case 1:
                                    return (F(1 + d, x) - F(1 - d, x)) / (2 * d);  // s = 1
                                case 2:
                                    return (F(x, 1 + d) - F(x, 1 - d)) / (2 * d);  // t = 1
                                default:
                                    return -(F(d, x) - F(-d, x)) / (2 * d);  // s = 0
                            }
                        },
                        q / 10.0, (q + 1) / 10.0, rule);
            predicted = -delta * delta / 24 * flux;
            // The next Euler-Maclaurin term is smaller by about (Delta / L)^2 with L = 0.1 the
            // length on which F varies at h = 0.1: 1.5e-3 relative (measured 1.4e-4 there,
            // 1e-6 at h = 1, 0.5); rounding of the 65536-term sum is ~1e-13. 1 % is ample.
            CHECK(mean - c.exact == Approx(predicted).epsilon(0.01).margin(1e-10));
        }
        mbr::test::report() << "kernel grid mean " << c.name << ": mean " << mean
                            << ", area form factor " << c.exact << ", difference " << mean - c.exact
                            << ", Euler-Maclaurin prediction " << predicted << "\n";
    }
}

TEST_CASE("kernel: adaptive quadrature of (21) matches the analytic form factor", "[kernel]") {
    // Tables 1-2's configurations, shooter radiosity 1: I(p) must be F(p -> shooter). The rule
    // asks for 1e-4 relative to a first estimate (floor 1e-4 of max B_h); the n against n + 1
    // comparison with n = 6 over-estimates the error of the kept (n+1)-point value by orders of
    // magnitude, so the result is far better than the tolerance. Points include the receiver's
    // edges and, for the perpendicular squares, points very close to the common edge where the
    // kernel is nearly singular. (The quadrature itself: not the closed form a constant planar
    // shooter gets by default, which "kernel: the closed form for constant shooters" checks.)
    QuadratureOptions options;
    options.analytic = false;
    struct Config {
        const char* name;
        TransferSetup setup;
    };
    const Config configs[] = {{"parallel h = 1.0", parallel_squares(1.0)},
                              {"parallel h = 0.5", parallel_squares(0.5)},
                              {"parallel h = 0.1", parallel_squares(0.1)},
                              {"perpendicular", perpendicular_squares()}};
    std::mt19937 rng(6);
    std::uniform_real_distribution<double> unit(0, 1);
    for (const Config& c : configs) {
        CAPTURE(c.name);
        const Shooter shooter = unit_shooter(c.setup.shooter);
        IncrementIntegrator integrator(shooter, options);
        const std::vector<Vec3> polygon = c.setup.shooter_polygon();
        std::vector<Vec2> points{{0.5, 0.5},     {0, 0},      {1, 1},     {0.5, 0},
                                 {0.001, 0.999}, {0.3, 1e-3}, {0.7, 1e-5}};
        for (int i = 0; i < 25; ++i) points.push_back({unit(rng), unit(rng)});
        double worst = 0, sum = 0;
        int counted = 0;
        long evaluations = 0;
        for (const Vec2& st : points) {
            CAPTURE(st.x, st.y);
            const SurfacePoint p = c.setup.receiver.evaluate(st.x, st.y);
            const double exact = point_polygon_form_factor(p.position, p.normal, polygon);
            if (!(exact > 0)) continue;  // the perpendicular squares' common edge itself
            const IncrementIntegrator::Result r = integrator.integrate(p);
            CHECK(r.converged);
            CHECK(r.value.r == r.value.g);
            CHECK(r.value.r == r.value.b);
            const double rel = relative(r.value.r, exact);
            worst = std::max(worst, rel);
            sum += rel;
            ++counted;
            evaluations += r.n_evaluations;
            CHECK(rel <= 1e-4);  // the requested tolerance, at every point
        }
        // On average well under it: measured means 8e-13, 4e-9, 1.3e-6, 9e-7 and worst points
        // 1.8e-12, 1.2e-8, 1.3e-5, 1.7e-5 for h = 1, 0.5, 0.1 and perpendicular.
        CHECK(sum / counted <= 1e-5);
        mbr::test::report() << "kernel quadrature " << c.name << ": max relative error " << worst
                            << ", mean " << sum / counted << ", kernel evaluations per point "
                            << evaluations / counted << "\n";
    }
}

TEST_CASE("kernel: integrate_on its own partition gives integrate's value", "[kernel]") {
    // integrate_on recomputes the (n+1)-point rule on each accepted cell: the same numbers as the
    // adaptive run summed in another order, so equal to rounding.
    const TransferSetup setup = perpendicular_squares();
    const Shooter shooter = unit_shooter(setup.shooter);
    QuadratureOptions quadrature;
    quadrature.analytic = false;  // the quadrature's own sum, not the closed form
    IncrementIntegrator integrator(shooter, quadrature);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.001, 1);
    for (int trial = 0; trial < 20; ++trial) {
        const double s = unit(rng), t = trial < 5 ? 0.01 * unit(rng) : unit(rng);
        CAPTURE(trial, s, t);
        const SurfacePoint p = setup.receiver.evaluate(s, t);
        const IncrementIntegrator::Result r = integrator.integrate(p, true);
        REQUIRE_FALSE(r.partition.empty());
        double area = 0;
        for (const auto& cell : r.partition) area += cell.cell.rect.area();
        CHECK(area == Approx(1.0).epsilon(1e-14));  // the accepted cells tile the shooter
        long evals = 0;
        const Rgb again = integrator.integrate_on(p, r.partition, &evals);
        CHECK(again.r == Approx(r.value.r).epsilon(1e-14));
        CHECK(evals == long(r.partition.size()) * 7 * 7);  // (n+1)^2 points per cell, n = 6
        // Without keep_partition the value is the same and no partition is returned.
        const IncrementIntegrator::Result plain = integrator.integrate(p);
        CHECK(plain.partition.empty());
        CHECK(plain.value.r == r.value.r);
    }
}

TEST_CASE("kernel: quadrature of (21) weights the shooter's radiosity and area factor",
          "[kernel]") {
    // A tilted 2 x 0.5 rectangle (area factor 1, not the unit square's) above the origin, and a
    // non-constant unshot field B_h(u,v) = u exactly (Greville: sum_k (k + m/2) 2^-j N_m(2^j u - k)
    // = u). Reference: 16 x 16 cells of 8 x 8 Gauss-Legendre points of F B A (smooth integrand:
    // the shooter is at distance >= 0.8, so this is exact to ~1e-13).
    const Surface quad =
        Surface::planar_quad({-1, -0.25, 1}, {-1, 0.25, 1}, {1, 0.25, 0.8}, {1, -0.25, 0.8});
    REQUIRE(quad.area_factor(0.3, 0.3) == Approx(std::sqrt(4 + 0.04) * 0.5).epsilon(1e-14));
    const int m = 4, j = 1;
    SplineField ramp(m, j);
    const int first = first_touching_index(m), n = touching_count(m, j);
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l) {
            const double g = (k + 0.5 * m) / (1 << j);
            ramp.set_coefficient(k, l, {g, 2 * g, 3 * g});
        }
    REQUIRE(ramp.evaluate(0.37, 0.81).r == Approx(0.37).epsilon(1e-14));
    Shooter shooter;
    shooter.surface = &quad;
    shooter.unshot = ramp;
    IncrementIntegrator integrator(shooter, QuadratureOptions{});
    const std::vector<Vec3> polygon{quad.corners()[0], quad.corners()[1], quad.corners()[2],
                                    quad.corners()[3]};
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int trial = 0; trial < 8; ++trial) {
        const SurfacePoint p{
            {u(rng), u(rng), 0}, normalize(Vec3{0.2 * u(rng), 0.2 * u(rng), 1}), 1};
        CAPTURE(trial, p.position, p.normal);
        const double brute = brute_force_increment(
            p, quad, [](double a, double) { return a; }, 16, 8);
        const IncrementIntegrator::Result r = integrator.integrate(p);
        CHECK(r.value.r == Approx(brute).epsilon(1e-5));           // 1e-4 asked; see the test above
        CHECK(r.value.g == Approx(2 * r.value.r).epsilon(1e-14));  // channels are independent
        CHECK(r.value.b == Approx(3 * r.value.r).epsilon(1e-14));
    }
    // A constant B_h = 2 gives exactly twice B_h = 1: the tolerance scales with max B_h, so the
    // same cells are accepted and every product is scaled by a power of two.
    Shooter one = unit_shooter(quad), two = unit_shooter(quad);
    two.unshot = SplineField::constant(4, 0, {2, 2, 2});
    QuadratureOptions quadrature;
    quadrature.analytic = false;  // the same cells of the quadrature, not the closed form
    IncrementIntegrator i1(one, quadrature), i2(two, quadrature);
    const SurfacePoint p{{0.1, -0.2, 0}, {0, 0, 1}, 1};
    const double F = point_polygon_form_factor(p.position, p.normal, polygon);
    const Rgb v1 = i1.integrate(p).value, v2 = i2.integrate(p).value;
    CHECK(v2.r == 2 * v1.r);
    CHECK(v1.r == Approx(F).epsilon(1e-5));
}

TEST_CASE("kernel: the closed form for constant shooters", "[kernel]") {
    // A planar quad shooter of constant radiosity: integrate() uses the contour formula over
    // the visible part (QuadratureOptions::analytic). It must equal the analytic reference
    // point_polygon_form_factor to rounding (1e-12), also where the receiver's tangent plane
    // cuts the shooter (the reference clips there too), and the quadrature at a tight
    // tolerance to that tolerance. It reports no kernel evaluations.
    const double c = std::cos(Pi / 3), s = std::sin(Pi / 3);
    const Surface shooters[] = {
        parallel_squares(0.3).shooter,
        Surface::planar_quad({0, 0, -0.5}, {0, 0, 1}, {1, 0, 1}, {1, 0, -0.5}),  // cut by z = 0
        Surface::planar_quad({0, 0.2, 0.1}, {1, 0.2, 0.1}, {1, 0.2 + c, 0.1 + s}, {0, 0.2 + c, 0.1 + s})};
    const Surface receiver = parallel_squares(1).receiver;
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> unit(0.01, 0.99);
    for (const Surface& quad : shooters) {
        const Shooter shooter = unit_shooter(quad);
        QuadratureOptions closed, tight;
        tight.analytic = false;
        tight.rel_tolerance = 1e-9;
        IncrementIntegrator a(shooter, closed), q(shooter, tight);
        REQUIRE(a.analytic());
        const std::vector<Vec3> polygon{quad.corners()[0], quad.corners()[1], quad.corners()[2],
                                        quad.corners()[3]};
        for (int i = 0; i < 12; ++i) {
            const SurfacePoint p = receiver.evaluate(unit(rng), unit(rng));
            const double F = point_polygon_form_factor(p.position, p.normal, polygon);
            const IncrementIntegrator::Result r = a.integrate(p);
            CAPTURE(p.position, F, r.value.r);
            CHECK(r.n_evaluations == 0);
            CHECK(std::fabs(r.value.r - F) <= 1e-12 * std::max(F, 1e-3));
            CHECK(std::fabs(q.integrate(p).value.r - F) <= 1e-8 * std::max(F, 1e-3));
        }
    }
}

TEST_CASE("kernel: the quadrature's point cache stays within its bound and never changes values",
          "[kernel]") {
    // Receiving points 1e-4 in front of a unit square, each at another place: every point
    // splits the shooter deep around its foot, so the cells seen add up to more points than
    // max_cached_points, and the cache starts over (the bound the memory estimate counts,
    // cost.h). Before the bound was tied to the estimate, the pool grew to 2^20 points and
    // past them by doubling (the room peaked at 195 MiB).
    const Surface quad = Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});
    Shooter shooter;
    shooter.surface = &quad;
    shooter.unshot = SplineField::constant(4, 0, {1, 1, 1});
    QuadratureOptions options;
    options.analytic = false;  // the closed form caches nothing
    IncrementIntegrator warm(shooter, options);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.01, 0.99);
    std::vector<SurfacePoint> points;
    for (int k = 0; k < 600; ++k)
        points.push_back({{u(rng), u(rng), 1e-4}, {0, 0, -1}, 1});
    long evaluations = 0;
    std::vector<Rgb> values;
    for (const SurfacePoint& p : points) {
        const IncrementIntegrator::Result r = warm.integrate(p);
        evaluations += r.n_evaluations;
        values.push_back(r.value);
    }
    test::report() << "cache: " << evaluations << " kernel evaluations, capacity "
                   << warm.cached_point_capacity() << " points\n";
    CHECK(evaluations > long(4 * max_cached_points));  // enough cells to fill it several times
    CHECK(warm.cached_point_capacity() <= max_cached_points);
    // The same points through fresh integrators give the same bits.
    for (size_t k = 0; k < points.size(); k += 149) {
        IncrementIntegrator fresh(shooter, options);
        CHECK(fresh.integrate(points[k]).value == values[k]);
    }
}
