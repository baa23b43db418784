// radiosity/reference/path_tracer.cpp - Monte Carlo path tracing of eq. (1) at surface points
// (path_tracer.h): next-event estimation, cosine-weighted bounces, Russian roulette, and a
// counter-based generator per path so that results do not depend on the number of threads.
#include "radiosity/reference/path_tracer.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"
#include "math/parallel.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbr {

namespace {

// ---- Random numbers ------------------------------------------------------------------------

// The output function of splitmix64 (Steele, Lea and Flood 2014): a bijective mix of 64 bits.
std::uint64_t mix64(std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// A counter-based generator: the k-th number of a path is mix64(key + k * golden), so a path's
// numbers depend on (seed, point, path) only, never on which thread draws them or when.
class PathRng {
public:
    PathRng(std::uint64_t seed, std::uint64_t point, std::uint64_t path)
        : state_(mix64(mix64(mix64(seed) ^ point) ^ path)) {}
    /// Uniform in [0, 1), 53 random bits.
    double uniform() {
        state_ += 0x9E3779B97F4A7C15ull;
        return static_cast<double>(mix64(state_) >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t state_;
};

// ---- Geometry ------------------------------------------------------------------------------

// A direction about unit normal n with density cos(theta) / pi (Malley's method: uniform on the
// disk, lifted to the hemisphere). The tangent frame is the branch-free one of Duff et al. 2017.
Vec3 cosine_direction(Vec3 n, double xi_1, double xi_2) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    const Vec3 t_1{1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    const Vec3 t_2{b, sign + n.y * n.y * a, -n.y};
    const double r = std::sqrt(xi_1), phi = 2 * Pi * xi_2;
    const double cos_theta = std::sqrt(std::max(0.0, 1 - xi_1));
    return r * std::cos(phi) * t_1 + r * std::sin(phi) * t_2 + cos_theta * n;
}

// Everything the paths share, computed once.
struct Context {
    const Scene& scene;
    const Octree& octree;
    // DESIGN: a ray leaving a surface ignores hits nearer than self_eps = 1e-7 of the scene's
    // diagonal (t_min for a unit direction; t_min = self_eps / |d| and t_max = 1 - self_eps / |d|
    // for a shadow segment d). The origin lies on its polygon up to rounding (about 1e-16 of the
    // coordinates), so this excludes its own polygon unless the ray grazes it within 1e-9 rad,
    // and misses no occluder thicker than 1e-7 of the scene.
    double self_eps = 0;
    // DESIGN: path vertices lie on the true surfaces, which a curved surface's (or a non-planar
    // quad's) tessellation misses by up to its chord error; on a concave surface they lie behind
    // its facets. Rays leave (and shadow rays arrive at) a point moved off the surface along its
    // normal by gap[surface] = twice the largest distance seen between polygon and surface (at
    // each polygon's (u, v) centroid and edge midpoints), in front of the facets. Measured on a
    // closed inward sphere (tessellation 16) of uniform E and rho, where B = E / (1 - rho):
    // rays from the surface itself, skipping their own facets nearby, were 5-11 % low (grazing
    // chords run between facets and surface and escape); from the moved points every ray meets
    // the closed facets. Zero for exactly tessellated surfaces (planar quads). The price: near
    // a contact with another surface, closer than the gap, shadow rays may start beyond it.
    std::vector<double> gap;
    // Emitters and the cumulative probabilities of choosing each, in proportion to power.
    std::vector<int> emitters;
    std::vector<double> cumulative;
    std::vector<double> probability;
    std::vector<double> choice;  // per surface: probability of choosing it (0: not an emitter)
    bool mis = true;             // PathTracerOptions::multiple_importance
};

std::vector<double> chord_gaps(const Scene& scene, const Octree& octree, double negligible) {
    std::vector<double> gap(scene.surfaces.size(), 0.0);
    for (const Polygon& polygon : octree.polygons()) {
        const int id = polygon.surface();
        MBR_CHECK_MSG(id >= 0 && id < static_cast<int>(scene.surfaces.size()),
                      "octree polygon of surface " << id << ": not built from this scene");
        const Surface& s = scene.surfaces[id].surface;
        const std::vector<Vec3>& x = polygon.vertices();
        const std::vector<Vec2>& uv = polygon.uv();
        const int n = polygon.n_vertices();
        auto deviation = [&](Vec2 q, Vec3 p) { return length(s.point(q.x, q.y) - p); };
        Vec3 centre;
        Vec2 uv_centre;
        double d = 0;
        for (int i = 0; i < n; ++i) {
            const int j = (i + 1) % n;
            centre += x[i] / n;
            uv_centre = uv_centre + (1.0 / n) * uv[i];
            d = std::max(d, deviation(0.5 * (uv[i] + uv[j]), 0.5 * (x[i] + x[j])));
        }
        d = std::max(d, deviation(uv_centre, centre));
        gap[id] = std::max(gap[id], 2 * d);
    }
    for (double& g : gap)
        if (g <= negligible) g = 0;
    return gap;
}

Context make_context(const Scene& scene, const Octree& octree) {
    Context ctx{scene, octree, 0, {}, {}, {}, {}, {}, true};
    const Box3 box = scene.bounds();
    const double diagonal = box.empty() ? 1.0 : length(box.extent());
    ctx.self_eps = 1e-7 * diagonal;
    ctx.gap = chord_gaps(scene, octree, 1e-9 * diagonal);
    // DESIGN: emitters are chosen in proportion to the sum of the channels of their power,
    // mean(E) x area; any positive choice is unbiased, this one puts samples where light is.
    double total = 0;
    for (int id : scene.emitters()) {
        const Rgb power = scene.surfaces[id].surface.area() * scene.material_of(id).emission.mean();
        const double weight = power.r + power.g + power.b;
        if (!(weight > 0)) continue;
        ctx.emitters.push_back(id);
        ctx.probability.push_back(weight);
        total += weight;
    }
    double running = 0;
    for (double& p : ctx.probability) {
        p /= total;
        running += p;
        ctx.cumulative.push_back(running);
    }
    if (!ctx.cumulative.empty()) ctx.cumulative.back() = 1;
    ctx.choice.assign(scene.surfaces.size(), 0.0);
    for (size_t k = 0; k < ctx.emitters.size(); ++k)
        ctx.choice[ctx.emitters[k]] = ctx.probability[k];
    return ctx;
}

// A point of a path: on the true surface (not its tessellation), with its front normal, and
// the origin of the rays that leave it (see Context::gap).
struct Vertex {
    int surface = -1;
    double u = 0, v = 0;
    Vec3 position;
    Vec3 normal;
    Vec3 ray_origin;
};

Vertex vertex_at(const Context& ctx, int surface, double u, double v) {
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    const SurfacePoint sp = ctx.scene.surfaces[surface].surface.evaluate(u, v);
    return {surface, u, v, sp.position, sp.normal, sp.position + ctx.gap[surface] * sp.normal};
}

// The first surface a ray from `from` in unit direction w meets.
std::optional<Hit> first_hit(const Context& ctx, const Vertex& from, Vec3 w) {
    return ctx.octree.closest_hit(Ray{from.ray_origin, w, ctx.self_eps, HUGE_VAL});
}

// Whether the segment between the ray origins of x and y is free of occluders.
bool visible(const Context& ctx, const Vertex& x, Vec3 y_origin) {
    const Vec3 d = y_origin - x.ray_origin;
    const double eps = ctx.self_eps / length(d);
    if (eps >= 0.5) return true;  // closer than the self-hit tolerance: nothing fits between
    return !ctx.octree.any_hit(Ray{x.ray_origin, d, eps, 1 - eps});
}

// The two ways a path finds an emitter point y seen from x, as densities over directions at x:
// light sampling (emitter k with probability P_k, (u, v) uniform, so P_k / A(u, v) per area
// and P_k r^2 / (A cos_y) per solid angle) and the cosine-weighted bounce (cos_x / pi).
double light_density(const Context& ctx, int emitter, double area_factor, double r2, double cos_y) {
    return ctx.choice[emitter] * r2 / (area_factor * cos_y);
}
double bounce_density(double cos_x) {
    return cos_x * InvPi;
}

// The power heuristic (Veach and Guibas 1995, beta = 2): the weight of the strategy with density
// p_a when p_b is the other's.
double power_weight(double p_a, double p_b) {
    const double a2 = p_a * p_a, b2 = p_b * p_b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0;
}

// One sample of D(x) = int over emitters of E(y) / pi cos_x cos_y / r^2 VIS dA_y: one emitter
// by power, (u, v) uniform on its domain, so the density per area is P_k / A(u, v). With MIS,
// weighted against finding y by a bounce.
Rgb direct_light(const Context& ctx, const Vertex& x, PathRng& rng) {
    if (ctx.emitters.empty()) return {};
    const double xi = rng.uniform();
    const size_t k = std::min<size_t>(
        std::upper_bound(ctx.cumulative.begin(), ctx.cumulative.end(), xi) - ctx.cumulative.begin(),
        ctx.emitters.size() - 1);
    const int id = ctx.emitters[k];
    const double u = rng.uniform(), v = rng.uniform();
    const Rgb E_y = ctx.scene.material_of(id).emission.value(u, v);
    if (max_abs(E_y) == 0) return {};
    const SurfacePoint y = ctx.scene.surfaces[id].surface.evaluate(u, v);
    const Vec3 l = y.position - x.position;
    const double r2 = dot(l, l);
    if (!(r2 > 0) || !(y.area_factor > 0)) return {};
    const double r = std::sqrt(r2);
    const double cos_x = dot(l, x.normal) / r;
    const double cos_y = -dot(l, y.normal) / r;
    if (cos_x <= 0 || cos_y <= 0) return {};  // behind x, or y's back (one-sided emitters)
    if (!visible(ctx, x, y.position + ctx.gap[id] * y.normal)) return {};
    const double weight = ctx.mis ? power_weight(light_density(ctx, id, y.area_factor, r2, cos_y),
                                                 bounce_density(cos_x))
                                  : 1.0;
    // kernel cos_x cos_y / (pi r^2) x area factor A(u, v) / probability of the emitter
    return E_y * (weight * cos_x * cos_y / (Pi * r2) * y.area_factor / ctx.probability[k]);
}

// DESIGN: a start point within 1000 self_eps (1e-4 of the scene's diagonal) of the edge of its
// surface is moved inward to that distance (locating clamps points beyond an edge onto it). From
// the edge itself a neighbouring surface that meets it there is hit at t < t_min by every ray
// entering it, and its light would leak; a little inside, the path's next vertices near the edge
// still fall within self_eps of the neighbour too often. Measured at a corner of the emitting
// cube of test_path_tracer: 37 % low at the corner itself (64000 paths), 0.2 % low (8 standard
// errors, 512000 paths) at 10 self_eps, 0.04 % (1.7 standard errors) at 1000 self_eps. The
// radiosity there is the limit from inside the surface. Where a tangent vanishes (a pole, a disk's
// centre) the move along that parameter does not move the point.
Vertex start_vertex(const Context& ctx, const SurfaceLocation& start) {
    const Surface& s = ctx.scene.surfaces[start.surface].surface;
    Vec3 x_u, x_v;
    s.tangents(start.u, start.v, x_u, x_v);
    auto inward = [&](double t, Vec3 x_t) {
        const double margin = std::min(0.5, 1000 * ctx.self_eps / std::max(length(x_t), 1e-300));
        return std::clamp(t, margin, 1 - margin);
    };
    return vertex_at(ctx, start.surface, inward(start.u, x_u), inward(start.v, x_v));
}

// One path's sample of B at the start point (see estimate_radiosity).
Rgb trace_path(const Context& ctx, const SurfaceLocation& start, int min_bounces_before_roulette,
               PathRng& rng) {
    Vertex x = start_vertex(ctx, start);
    const Material& m = ctx.scene.material_of(x.surface);
    Rgb value = m.emission.value(x.u, x.v);
    Rgb beta = m.reflectance.value(x.u, x.v);  // product of the reflectances so far / roulette
    for (int bounce = 0;; ++bounce) {
        if (max_abs(beta) == 0) break;
        value += beta * direct_light(ctx, x, rng);
        // The indirect part: a cosine-weighted direction estimates int L_in cos dw by pi L_in,
        // i.e. by B at the hit y. Its emission E(y) counts with the MIS weight of the bounce
        // (light sampling has the rest), or not at all without MIS.
        const double xi_1 = rng.uniform(), xi_2 = rng.uniform();
        const Vec3 w = cosine_direction(x.normal, xi_1, xi_2);
        const std::optional<Hit> hit = first_hit(ctx, x, w);
        if (!hit) break;
        const Vertex y = vertex_at(ctx, hit->surface, hit->uv.x, hit->uv.y);
        const double cos_y = -dot(w, y.normal);
        if (!(cos_y > 0)) break;  // the back of y: absorbed, no light towards x
        const Material& m_y = ctx.scene.material_of(y.surface);
        if (ctx.mis && ctx.choice[y.surface] > 0) {
            const Rgb E_y = m_y.emission.value(y.u, y.v);
            const double A_y = ctx.scene.surfaces[y.surface].surface.area_factor(y.u, y.v);
            const double r2 = length_squared(y.position - x.position);
            if (max_abs(E_y) > 0 && A_y > 0 && r2 > 0)
                value += beta * (power_weight(bounce_density(dot(w, x.normal)),
                                              light_density(ctx, y.surface, A_y, r2, cos_y)) *
                                 E_y);
        }
        beta = beta * m_y.reflectance.value(y.u, y.v);
        if (bounce + 1 >= min_bounces_before_roulette) {
            // Russian roulette: continue with probability q, weight 1/q keeps the mean.
            const double q = std::min(1.0, std::max({beta.r, beta.g, beta.b}));
            if (!(q > 0) || rng.uniform() >= q) break;
            beta = (1 / q) * beta;
        }
        x = y;
    }
    return value;
}

// Mean and sum of squared deviations of a set of samples, per channel (Welford 1962; blocks are
// merged by Chan, Golub and LeVeque 1979), so the variance does not cancel catastrophically.
struct Moments {
    long n = 0;
    Rgb mean;
    Rgb m2;
    void add(Rgb x) {
        ++n;
        const Rgb delta = x - mean;
        mean += (1.0 / n) * delta;
        m2 += delta * (x - mean);
    }
    void merge(const Moments& other) {
        if (other.n == 0) return;
        const long n_ab = n + other.n;
        const Rgb delta = other.mean - mean;
        mean += (double(other.n) / n_ab) * delta;
        m2 += other.m2 + (double(n) * other.n / n_ab) * (delta * delta);
        n = n_ab;
    }
};

int thread_count(int requested) {
#ifdef _OPENMP
    return requested > 0 ? requested : omp_get_max_threads();
#else
    (void)requested;
    return 1;
#endif
}

}  // namespace

std::vector<RadiosityEstimate> estimate_radiosity(const Scene& scene, const Octree& octree,
                                                  const std::vector<SurfaceLocation>& points,
                                                  const PathTracerOptions& options) {
    MBR_CHECK_MSG(options.paths >= 2, "paths " << options.paths << " (a standard error needs 2)");
    MBR_CHECK_MSG(options.paths_per_block >= 1, "paths_per_block " << options.paths_per_block);
    MBR_CHECK(options.min_bounces_before_roulette >= 0 && options.threads >= 0);
    for (const SurfaceLocation& p : points)
        MBR_CHECK_MSG(p.surface >= 0 && p.surface < static_cast<int>(scene.surfaces.size()) &&
                          p.u >= 0 && p.u <= 1 && p.v >= 0 && p.v <= 1,
                      "point on surface " << p.surface << " at (" << p.u << ", " << p.v << ")");
    Context ctx = make_context(scene, octree);
    ctx.mis = options.multiple_importance;

    // Work items (point, block of paths), each with its own slot: the sums below run in a
    // fixed order whatever the schedule.
    const long n_blocks = (options.paths + options.paths_per_block - 1) / options.paths_per_block;
    const long n_items = static_cast<long>(points.size()) * n_blocks;
    std::vector<Moments> blocks(n_items);
    parallel_for(
        n_items,
        [&](long item) {
            const long point = item / n_blocks, block = item % n_blocks;
            const long first = block * options.paths_per_block;
            const long last = std::min(options.paths, first + options.paths_per_block);
            Moments moments;
            for (long path = first; path < last; ++path) {
                PathRng rng(options.seed, static_cast<std::uint64_t>(point),
                            static_cast<std::uint64_t>(path));
                moments.add(
                    trace_path(ctx, points[point], options.min_bounces_before_roulette, rng));
            }
            blocks[item] = moments;
        },
        thread_count(options.threads));

    std::vector<RadiosityEstimate> estimates(points.size());
    for (size_t point = 0; point < points.size(); ++point) {
        Moments all;
        for (long block = 0; block < n_blocks; ++block) all.merge(blocks[point * n_blocks + block]);
        RadiosityEstimate& e = estimates[point];
        e.mean = all.mean;
        // standard error = sample standard deviation / sqrt(n)
        for (int c = 0; c < 3; ++c)
            e.standard_error[c] = std::sqrt(std::max(0.0, all.m2[c]) / (all.n - 1) / all.n);
    }
    return estimates;
}

}  // namespace mbr
