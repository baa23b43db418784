// radiosity/solver/ambient_gather.cpp - the ambient correction gathered by rays
// (ambient_gather.h).
#include "radiosity/solver/ambient_gather.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "math/parallel.h"
#include "radiosity/solver/solver.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

namespace {

/// The base-2 radical inverse of i (van der Corput): the bits of i mirrored about the point.
double radical_inverse_2(std::uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i * 0x1.0p-32;
}

/// The fractional part of x.
double wrap01(double x) {
    return x - std::floor(x);
}

bool nonzero(const SplineField& f) {
    if (f.empty()) return false;
    for (int c = 0; c < 3; ++c)
        for (double a : f.channel(c).a)
            if (a != 0) return true;
    return false;
}

/// A kept ray's hit: the front face of `surface` at (u, v).
struct GatherHit {
    int surface;
    float u, v;
};

/// The samples along each direction of a surface of order m gathered at `level`: m Gauss
/// points in each of the 2^level cells.
int sample_side(int m, int level) {
    return m << level;
}

/// Where the samples of all surfaces live in the flat arrays: surface i's side_i^2 samples from
/// first[i], in l2_projection_of_samples' order.
std::vector<int> sample_offsets(const std::vector<int>& order, int level) {
    std::vector<int> first(order.size() + 1, 0);
    for (size_t i = 0; i < order.size(); ++i) {
        const int side = sample_side(order[i], level);
        first[i + 1] = first[i] + side * side;
    }
    return first;
}

/// Sample k of a surface's samples at `level` (l2_projection_of_samples' order, m Gauss points
/// a cell in each direction): its parameters and its weight in the surface's power (the Gauss
/// weight times A).
struct GatherSample {
    double s, t, weight;
};

GatherSample gather_sample(const Surface& surface, int m, int level, int k) {
    const int side = sample_side(m, level), cells = 1 << level;
    const int S = k / side, T = k % side, a = S % m, b = T % m;
    const GaussLegendre rule = gauss_legendre(m);
    const double s = projection_sample_coordinate(rule, S, level);
    const double t = projection_sample_coordinate(rule, T, level);
    return {s, t,
            0.25 * rule.w[a] * rule.w[b] / (double(cells) * cells) * surface.area_factor(s, t)};
}

/// Where a gather sample's rays start: 1e-7 of the scene in front of the true surface at the
/// sample (a hidden point at its substitute, hidden_regions.h, as every sample does), its
/// cosine frame and the shifts of its Hammersley set.
struct GatherOrigin {
    Vec3 origin;
    CosineFrame frame;
    double shift_1, shift_2;
};

/// The origin of the sample at (s, t) of `surface` (nothing for a degenerate point, which
/// gathers nothing); `key` seeds its shifts.
std::optional<GatherOrigin> gather_origin(const Surface& surface, const HiddenMask* hidden,
                                          double s, double t, double scale, std::uint64_t key) {
    const Vec2 q = hidden ? hidden->substitute(s, t) : Vec2{s, t};
    const SurfacePoint p = surface.evaluate(q.x, q.y);
    if (!(p.area_factor > 0)) return std::nullopt;
    // DESIGN: as find_hidden's rays, from the true surface 1e-7 of the scene in front.
    return GatherOrigin{p.position + (1e-7 * scale) * p.normal, CosineFrame(p.normal),
                        uniform01(key, 0), uniform01(key, 1)};
}

/// What ray r of a sample's `rays` meets first: a front face of `surface` at (u, v).
struct RayHit {
    int surface;
    double u, v;
};

/// Ray r of `rays` from a gather origin: the Hammersley point r, shifted (Cranley and
/// Patterson 1976), lifted to the cosine-distributed hemisphere (density cos theta / pi); a
/// back face or nothing counts nothing.
std::optional<RayHit> gather_ray(const Octree& octree, const GatherOrigin& o, int r, int rays) {
    const Vec3 dir = o.frame.direction(wrap01((r + 0.5) / rays + o.shift_1),
                                       wrap01(radical_inverse_2(std::uint32_t(r)) + o.shift_2));
    const std::optional<Hit> hit =
        octree.closest_hit(Ray{o.origin, dir, 0, HUGE_VAL}, RayFilter{-1, -1, true});
    if (!hit || dot(octree.polygons()[hit->polygon].normal(), dir) > 0) return std::nullopt;
    return RayHit{hit->surface, hit->uv.x, hit->uv.y};
}

/// The mean over a sample's `rays` kept hits of what the surfaces hit send: sent[j] at the hit
/// on j where sends[j], nothing for a miss.
Rgb mean_sent(const GatherHit* kept, int rays, const std::vector<PolynomialPatches>& sent,
              const std::vector<bool>& sends) {
    Rgb sum;
    for (int r = 0; r < rays; ++r)
        if (kept[r].surface >= 0 && sends[kept[r].surface])
            sum += sent[kept[r].surface](kept[r].u, kept[r].v);
    return (1.0 / rays) * sum;
}

/// What each surface sends at the gather's level: the field through its samples' rho H
/// (`reflected`, from `first`), as polynomial pieces in sent[j], where any sample is non-zero
/// (sends[j]).
void fields_sent(const std::vector<Rgb>& reflected, const std::vector<int>& first,
                 const std::vector<int>& order, int level, std::vector<PolynomialPatches>& sent,
                 std::vector<bool>& sends) {
    for (size_t j = 0; j < sends.size(); ++j) {
        sends[j] = false;
        for (int item = first[j]; item < first[j + 1]; ++item)
            sends[j] = sends[j] || max_abs(reflected[size_t(item)]) > 0;
        if (sends[j])
            sent[j] = PolynomialPatches(
                l2_projection_of_samples(order[j], level, order[j], &reflected[size_t(first[j])]));
    }
}

/// The memory of `samples` gather points that keep `rays` hits each, `rgb` colours, a weight
/// and a flag.
double gather_points_bytes(double samples, int rays, int rgb) {
    return samples * (double(rays) * sizeof(GatherHit) + rgb * sizeof(Rgb) + sizeof(double) + 1);
}

}  // namespace

int gather_rays_per_point(int rays, double samples) {
    if (!(samples > 0) || double(rays) * samples <= ambient_max_rays) return rays;
    return std::min(rays, std::max(ambient_min_rays, int(ambient_max_rays / samples)));
}

double ambient_gather_bytes(const std::vector<int>& order, int level, int rays) {
    double samples = 0;
    for (int m : order) samples += double(sample_side(m, level)) * sample_side(m, level);
    rays = gather_rays_per_point(rays, samples);
    return gather_points_bytes(samples, rays, 6);
}

double final_gather_bytes(const Scene& scene, const std::vector<int>& order, int level, int rays) {
    const double diagonal = length(scene.bounds().extent());
    double samples = 0;
    for (size_t i = 0; i < scene.surfaces.size() && i < order.size(); ++i) {
        const int l = final_gather_level(scene.surfaces[i].surface, diagonal, level);
        if (l > level) samples += double(sample_side(order[i], l)) * sample_side(order[i], l);
    }
    rays =
        gather_rays_per_point(std::max(ambient_min_rays, rays / final_gather_ray_share), samples);
    return gather_points_bytes(samples, rays, 4);
}

int final_gather_level(const Surface& surface, double diagonal, int level) {
    const double cell = diagonal / final_gather_cells;
    const double size =
        std::max(length(surface.evaluate(1, 0).position - surface.evaluate(0, 1).position),
                 length(surface.evaluate(1, 1).position - surface.evaluate(0, 0).position));
    int l = level;
    while (l < max_ambient_level && size / double(1 << l) > cell) ++l;
    return l;
}

namespace {

/// What the converged first gather hands the final gather: its level, the scene's size, where
/// each surface's samples start, what they reflect (rho H), the share of their first bounce
/// that came from emitting surfaces, and which surfaces hold unshot light or emit.
struct FirstGather {
    int level;
    double scale;
    const std::vector<int>& first;
    const std::vector<Rgb>& reflected;
    const std::vector<Rgb>& lights;
    const std::vector<bool>& has_unshot;
    const std::vector<bool>& emits;
};

/// The surface whose samples hold `item`, from the offsets `start`.
int final_surface_of(const std::vector<int>& start, int item) {
    return int(std::upper_bound(start.begin(), start.end(), item) - start.begin()) - 1;
}

/// The final gather's points (ambient_gather.h): per surface its level (-1: not refined) and
/// where its samples start; per sample its kept hits (`rays` each), the part of H that does not
/// change between passes (the unshot light of the surfaces that do not emit, met by the rays,
/// and the emitters' first bounce as the first gather's field), rho, its power weight and
/// whether it gathered.
struct FinalPoints {
    std::vector<int> level, start;
    int rays = 0;
    std::vector<GatherHit> hits;
    std::vector<Rgb> fixed, rho;
    std::vector<double> weight;
    std::vector<std::uint8_t> gathers;
};

/// The surfaces the final gather refines (their gathered radiosity reaches `threshold` and
/// their final_gather_level is finer than the gather's), their samples, and the rays cast once
/// from each.
FinalPoints final_points(const Scene& scene, const Octree& octree, const AmbientSources& sources,
                         const FirstGather& g, double threshold, std::uint64_t seed,
                         int rays_asked) {
    const int n = static_cast<int>(scene.surfaces.size());
    const int level = g.level;
    const std::vector<int>& first = g.first;
    FinalPoints f;
    f.level.assign(n, -1);
    for (int j = 0; j < n; ++j) {
        double largest = 0;
        for (int item = first[j]; item < first[j + 1]; ++item)
            largest = std::max(largest, max_abs(g.reflected[item]));
        const int l = final_gather_level(scene.surfaces[j].surface, g.scale, level);
        if (largest >= threshold && l > level) f.level[j] = l;  // threshold > 0
    }
    // The light of emitters still unshot stays at the first gather's level: a few rays a point
    // that meet small bright lights are noise at a fine level (corridor.mgf after 3 shots, 54
    // lamps unshot: blotches), and that light is the next shots' to place.
    std::vector<PolynomialPatches> lights(n);
    std::vector<bool> has_lights(n, false);
    for (int i = 0; i < n; ++i) {
        if (f.level[i] < 0) continue;
        for (int item = first[i]; item < first[i + 1]; ++item)
            has_lights[i] = has_lights[i] || max_abs(g.lights[item]) > 0;
        if (has_lights[i])
            lights[i] = PolynomialPatches(l2_projection_of_samples(
                sources.order[i], level, sources.order[i], &g.lights[first[i]]));
    }
    f.start.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) {
        const int side = f.level[i] < 0 ? 0 : sample_side(sources.order[i], f.level[i]);
        f.start[i + 1] = f.start[i] + side * side;
    }
    const int n_samples = f.start[n];
    if (n_samples == 0) return f;
    f.rays = gather_rays_per_point(std::max(ambient_min_rays, rays_asked / final_gather_ray_share),
                                   n_samples);
    f.hits.assign(size_t(n_samples) * f.rays, GatherHit{-1, 0, 0});
    f.fixed.resize(n_samples);
    f.rho.resize(n_samples);
    f.weight.assign(n_samples, 0.0);
    f.gathers.assign(n_samples, 0);
    parallel_for(n_samples, [&](int item) {
        const int i = final_surface_of(f.start, item), k = item - f.start[i];
        const Surface& surface = scene.surfaces[i].surface;
        const GatherSample at = gather_sample(surface, sources.order[i], f.level[i], k);
        f.weight[item] = at.weight;
        f.rho[item] = scene.material_of(i).reflectance.value(at.s, at.t);
        const std::optional<GatherOrigin> o = gather_origin(
            surface, i < int(sources.hidden.size()) ? &sources.hidden[i] : nullptr, at.s, at.t,
            g.scale, hash_seed(seed ^ 0x66696e616cULL, std::uint64_t(i), std::uint64_t(k)));
        if (!o) return;
        GatherHit* kept = &f.hits[size_t(item) * f.rays];
        Rgb sum;
        for (int r = 0; r < f.rays; ++r) {
            const std::optional<RayHit> h = gather_ray(octree, *o, r, f.rays);
            if (!h) continue;
            kept[r] = {h->surface, float(h->u), float(h->v)};
            if (g.has_unshot[h->surface] && !g.emits[h->surface])
                sum += sources.unshot[h->surface].evaluate(h->u, h->v);
        }
        f.fixed[item] = (1.0 / f.rays) * sum + (has_lights[i] ? lights[i](at.s, at.t) : Rgb{});
        f.gathers[item] = 1;
    });
    return f;
}

/// What one pass of the final gather makes of the surfaces it refines: per surface the field
/// to add (H for an irradiance field, else rho H), what the surface sends (rho H) and the
/// power it adds; the rays it counts.
struct FinalGather {
    std::vector<SplineField> added, sent;
    std::vector<double> power;
    long rays = 0;
};

/// One pass of the final gather: H(p) = the fixed part + mean sent_j at the kept hits.
FinalGather final_pass(const Scene& scene, const AmbientSources& sources, const FinalPoints& f,
                       const std::vector<PolynomialPatches>& sent, const std::vector<bool>& sends) {
    const int n = static_cast<int>(scene.surfaces.size());
    FinalGather result{std::vector<SplineField>(n), std::vector<SplineField>(n),
                       std::vector<double>(n, 0.0)};
    const int n_samples = f.start[n];
    if (n_samples == 0) return result;
    std::vector<Rgb> values(n_samples);   // rho H (H for an irradiance field)
    std::vector<Rgb> leaving(n_samples);  // rho H
    parallel_for(n_samples, [&](int item) {
        if (!f.gathers[item]) return;
        const int i = final_surface_of(f.start, item);
        const Rgb H =
            f.fixed[item] + mean_sent(&f.hits[size_t(item) * f.rays], f.rays, sent, sends);
        leaving[item] = f.rho[item] * H;
        values[item] = sources.irradiance[i] ? H : leaving[item];
    });
    for (int i = 0; i < n; ++i) {
        if (f.level[i] < 0) continue;
        for (int item = f.start[i]; item < f.start[i + 1]; ++item) {
            const Rgb& rhoH = leaving[item];
            result.power[size_t(i)] += f.weight[item] * (rhoH.r + rhoH.g + rhoH.b);
            result.rays += f.gathers[item] ? f.rays : 0;
        }
        const int m = sources.order[i];
        result.added[size_t(i)] = l2_projection_of_samples(m, f.level[i], m, &values[f.start[i]]);
        result.sent[size_t(i)] =
            sources.irradiance[i] ? l2_projection_of_samples(m, f.level[i], m, &leaving[f.start[i]])
                                  : result.added[size_t(i)];
    }
    return result;
}

}  // namespace

AmbientGather gather_ambient(const Scene& scene, const Octree& octree,
                             const AmbientSources& sources, int rays_asked, int level,
                             std::uint64_t seed, double final_threshold) {
    const int n = static_cast<int>(scene.surfaces.size());
    MBR_CHECK_MSG(rays_asked >= 1, "ambient gather with " << rays_asked << " rays");
    MBR_CHECK_MSG(level >= 0 && level <= max_ambient_level, "ambient gather at level " << level);
    MBR_CHECK(int(sources.unshot.size()) == n && int(sources.order.size()) == n &&
              int(sources.irradiance.size()) == n);
    // U_j is read once per ray that meets j, by SplineField::evaluate (PolynomialPatches of
    // fields at level 6 would hold 1.5 MiB a surface).
    std::vector<bool> has_unshot(n), emits(n);
    for (int j = 0; j < n; ++j) {
        has_unshot[j] = nonzero(sources.unshot[j]);
        emits[j] = scene.material_of(j).emits();
    }

    const Box3 box = octree.bounds();
    const double scale = box.empty() ? 1.0 : length(box.extent());
    const std::vector<int> first = sample_offsets(sources.order, level);
    const int n_samples = first[n];
    const int rays = gather_rays_per_point(rays_asked, n_samples);
    auto surface_of = [&](int item) {
        return int(std::upper_bound(first.begin(), first.end(), item) - first.begin()) - 1;
    };
    std::vector<GatherHit> hits(size_t(n_samples) * rays, GatherHit{-1, 0, 0});
    std::vector<Rgb> first_bounce(n_samples);    // mean U_j(u, v) over the sample's rays
    std::vector<Rgb> first_lights(n_samples);    //   of which from emitting surfaces
    std::vector<Rgb> rho(n_samples);             // rho(s_a, t_b)
    std::vector<double> weight(n_samples, 0.0);  // Gauss weight x A(s_a, t_b), for the power
    std::vector<std::uint8_t> gathers(n_samples, 0);

    // The rays, cast once: work items are samples, each with its own slots, so every sum below
    // runs in a fixed order for any thread count.
    parallel_for(n_samples, [&](int item) {
        const int i = surface_of(item), k = item - first[i];
        const Material& material = scene.material_of(i);
        const Surface& surface = scene.surfaces[i].surface;
        const GatherSample at = gather_sample(surface, sources.order[i], level, k);
        const double s = at.s, t = at.t;
        weight[item] = at.weight;
        rho[item] = material.reflectance.value(s, t);
        if (max_abs(material.reflectance.maximum()) == 0) return;  // reflects nothing
        const std::optional<GatherOrigin> o = gather_origin(
            surface, i < int(sources.hidden.size()) ? &sources.hidden[i] : nullptr, s, t, scale,
            hash_seed(seed ^ 0x616d6269656e74ULL, std::uint64_t(i), std::uint64_t(k)));
        if (!o) return;  // a degenerate point: nothing gathered
        GatherHit* kept = &hits[size_t(item) * rays];
        Rgb sum, from_lights;
        for (int r = 0; r < rays; ++r) {
            const std::optional<RayHit> h = gather_ray(octree, *o, r, rays);
            if (!h) continue;
            kept[r] = {h->surface, float(h->u), float(h->v)};
            if (!has_unshot[h->surface]) continue;
            const Rgb u = sources.unshot[h->surface].evaluate(h->u, h->v);
            sum += u;
            if (emits[h->surface]) from_lights += u;
        }
        first_bounce[item] = (1.0 / rays) * sum;
        first_lights[item] = (1.0 / rays) * from_lights;
        gathers[item] = 1;
    });

    // Jacobi: H = first bounce + mean R_j at the hits, R_i through rho H, from R = 0.
    AmbientGather out;
    std::vector<Rgb> H = first_bounce, reflected(n_samples);
    auto added_power = [&]() {
        double p = 0;
        for (int item = 0; item < n_samples; ++item) {
            reflected[item] = rho[item] * H[item];
            p += weight[item] * (reflected[item].r + reflected[item].g + reflected[item].b);
        }
        return p;
    };
    double power = added_power();
    out.iterations = 1;
    std::vector<PolynomialPatches> bounce(n);
    std::vector<bool> has_bounce(n, false);
    while (out.iterations < ambient_max_iterations && power > 0) {
        fields_sent(reflected, first, sources.order, level, bounce, has_bounce);
        parallel_for(n_samples, [&](int item) {
            if (!gathers[item]) return;
            H[item] = first_bounce[item] +
                      mean_sent(&hits[size_t(item) * rays], rays, bounce, has_bounce);
        });
        ++out.iterations;
        const double next = added_power();
        const bool settled = std::fabs(next - power) <= ambient_iteration_tolerance * next;
        power = next;
        if (settled) break;
    }

    out.power = power;
    out.added.resize(n);
    // Surface i's field to add at the gather's level: H for an irradiance field, else rho H.
    std::vector<Rgb> samples(n_samples);
    auto added_field = [&](int i) {
        bool any = false;
        for (int item = first[i]; item < first[i + 1]; ++item) {
            samples[item] = sources.irradiance[i] ? H[item] : reflected[item];
            any = any || max_abs(samples[item]) > 0;
        }
        return any ? l2_projection_of_samples(sources.order[i], level, sources.order[i],
                                              &samples[first[i]])
                   : SplineField();
    };
    for (int i = 0; i < n; ++i) {
        for (int item = first[i]; item < first[i + 1]; ++item) out.rays += gathers[item] ? rays : 0;
        out.added[i] = added_field(i);
    }
    if (!(final_threshold > 0)) return out;
    const FirstGather g{level, scale, first, reflected, first_lights, has_unshot, emits};
    const FinalPoints points =
        final_points(scene, octree, sources, g, final_threshold, seed, rays_asked);
    if (points.start[n] == 0) return out;
    // What every surface sends after the converged gather: R_j, its level-`level` field.
    std::vector<PolynomialPatches> sent(n);
    std::vector<bool> sends(n, false);
    fields_sent(reflected, first, sources.order, level, sent, sends);
    FinalGather refined = final_pass(scene, sources, points, sent, sends);
    // A refined surface sends its final pass's field instead.
    auto send_refined = [&](int j) {
        sends[j] = !refined.sent[j].empty();
        if (sends[j]) sent[j] = PolynomialPatches(refined.sent[j]);
    };
    // The final gather once more through the same hits, from what the refined surfaces send
    // after the first pass: a small refined surface beside a large one sees the large one's
    // ambient light at the large one's final level, not spread over its level-`level` cells.
    for (int j = 0; j < n; ++j)
        if (points.level[j] >= 0) send_refined(j);
    refined = final_pass(scene, sources, points, sent, sends);
    out.rays += refined.rays;
    for (int i = 0; i < n; ++i) {
        if (points.level[i] < 0) continue;
        // What the first gather added on i leaves the power, the final gather's enters it.
        for (int item = first[i]; item < first[i + 1]; ++item)
            out.power -= weight[item] * (reflected[item].r + reflected[item].g + reflected[item].b);
        out.power += refined.power[size_t(i)];
        out.added[i] = refined.added[size_t(i)];
        send_refined(i);
    }
    // The last bounce (beyond the final gather): the surfaces it did not refine take one more
    // step of the iteration through their kept hits, from what every surface sends now, the
    // refined ones at their finer level. Without it a small surface beside a large one saw the
    // large one's ambient light spread over its level-`level` cells (a luminaire's housing 4 cm
    // under a ceiling, docs/method.md, "The final gather").
    parallel_for(n_samples, [&](int item) {
        const int i = surface_of(item);
        if (!gathers[item] || points.level[i] >= 0) return;
        H[item] = first_bounce[item] + mean_sent(&hits[size_t(item) * rays], rays, sent, sends);
    });
    for (int i = 0; i < n; ++i) {
        if (points.level[i] >= 0) continue;
        for (int item = first[i]; item < first[i + 1]; ++item) {
            const Rgb old_reflected = reflected[item];
            reflected[item] = rho[item] * H[item];
            out.power += weight[item] * (reflected[item].r + reflected[item].g + reflected[item].b -
                                         old_reflected.r - old_reflected.g - old_reflected.b);
        }
        out.added[i] = added_field(i);
    }
    return out;
}

}  // namespace mbr
