// radiosity/visibility/hidden_regions.cpp - hidden parts of a surface (hidden_regions.h).
#include "radiosity/visibility/hidden_regions.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/visibility/convex_solids.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

HiddenMask::HiddenMask(int n, std::vector<std::uint8_t> hidden)
    : n_(n), hidden_(std::move(hidden)) {
    MBR_CHECK(n >= 1 && hidden_.size() == size_t(n) * n);
    substitute_.resize(hidden_.size());
    std::vector<int> visible;  // texels that are visible and border a hidden one
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int k = j * n + i;
            substitute_[k] = {(i + 0.5) / n, (j + 0.5) / n};
            if (hidden_[k]) {
                ++n_hidden_;
                continue;
            }
            bool border = false;
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const int a = i + di, b = j + dj;
                    if (a >= 0 && a < n && b >= 0 && b < n && hidden_[b * n + a]) border = true;
                }
            if (border) visible.push_back(k);
        }
    if (n_hidden_ == 0) {  // nothing hidden: keep no texels (a scene's many surfaces)
        hidden_ = {};
        substitute_ = {};
        return;
    }
    if (visible.empty()) return;  // everything hidden
    // The nearest visible texel of each hidden one (Euclidean, over the visible texels that
    // border the hidden region: the nearest visible texel always borders it).
    for (int k = 0; k < n * n; ++k) {
        if (!hidden_[k]) continue;
        const Vec2 c = substitute_[k];
        double best = HUGE_VAL;
        for (int v : visible) {
            const Vec2 d = substitute_[v] - c;
            const double d2 = dot(d, d);
            if (d2 < best) {
                best = d2;
                substitute_[k] = substitute_[v];
            }
        }
    }
    // Each hidden region's thickness (its texels 8-connected): twice the largest distance from
    // one of its texels to its substitute, the nearest visible texel.
    thickness_.assign(hidden_.size(), 0.0f);
    std::vector<int> region, stack;
    std::vector<std::uint8_t> seen(hidden_.size(), 0);
    for (int start = 0; start < n * n; ++start) {
        if (!hidden_[start] || seen[start]) continue;
        region.clear();
        stack.assign(1, start);
        seen[start] = 1;
        double deepest = 0;
        while (!stack.empty()) {
            const int k = stack.back();
            stack.pop_back();
            region.push_back(k);
            const int i = k % n, j = k / n;
            const Vec2 d = substitute_[k] - Vec2{(i + 0.5) / n, (j + 0.5) / n};
            deepest = std::max(deepest, std::sqrt(dot(d, d)));
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const int a = i + di, b = j + dj;
                    if (a < 0 || a >= n || b < 0 || b >= n) continue;
                    const int q = b * n + a;
                    if (hidden_[q] && !seen[q]) {
                        seen[q] = 1;
                        stack.push_back(q);
                    }
                }
        }
        for (int k : region) thickness_[k] = static_cast<float>(2 * deepest);
    }
}

int HiddenMask::texel(double s, double t) const {
    const int i = std::clamp(static_cast<int>(s * n_), 0, n_ - 1);
    const int j = std::clamp(static_cast<int>(t * n_), 0, n_ - 1);
    return j * n_ + i;
}

bool HiddenMask::hidden(double s, double t) const {
    return n_hidden_ > 0 && hidden_[texel(s, t)];
}

bool HiddenMask::mixed(double s0, double s1, double t0, double t1) const {
    if (n_hidden_ == 0) return false;
    const int first = texel(s0, t0), last = texel(s1, t1);
    const int i0 = first % n_, j0 = first / n_, i1 = last % n_, j1 = last / n_;
    bool seen_hidden = false, seen_visible = false;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            (hidden_[size_t(j) * n_ + i] ? seen_hidden : seen_visible) = true;
            if (seen_hidden && seen_visible) return true;
        }
    return false;
}

bool HiddenMask::thin_rim(double s0, double s1, double t0, double t1, double ratio) const {
    if (n_hidden_ == 0 || thickness_.empty()) return false;  // nothing or everything hidden
    const int first = texel(s0, t0), last = texel(s1, t1);
    const int i0 = first % n_, j0 = first / n_, i1 = last % n_, j1 = last / n_;
    const double side = std::min(s1 - s0, t1 - t0);
    bool seen_visible = false, seen_thin = false;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const size_t k = size_t(j) * n_ + i;
            if (!hidden_[k])
                seen_visible = true;
            else if (ratio * thickness_[k] < side)
                seen_thin = true;
            if (seen_visible && seen_thin) return true;
        }
    return false;
}

Vec2 HiddenMask::substitute(double s, double t) const {
    if (n_hidden_ == 0) return {s, t};
    const int k = texel(s, t);
    return hidden_[k] ? substitute_[k] : Vec2{s, t};
}

namespace {

/// The largest signed distance of a polygon's vertices from `plane` (positive in front).
double highest_above(const Polygon& polygon, const Plane& plane) {
    double most = -HUGE_VAL;
    for (const Vec3& v : polygon.vertices()) most = std::max(most, plane.signed_distance(v));
    return most;
}

/// The smallest signed distance of a polygon's vertices from `plane` (negative behind).
double lowest_below(const Polygon& polygon, const Plane& plane) {
    double least = HUGE_VAL;
    for (const Vec3& v : polygon.vertices()) least = std::min(least, plane.signed_distance(v));
    return least;
}

/// Whether p lies inside the convex solid grown by `by` (behind every face's plane, and every
/// opening's).
bool inside_solid(const ConvexSolid& solid, Vec3 p, double by) {
    for (const Plane& f : solid.faces)
        if (f.signed_distance(p) > by) return false;
    for (const SolidOpening& o : solid.openings)
        if (o.plane.signed_distance(p) > by) return false;
    return true;
}

/// Whether a point of `receiver` may see the back of one of the solid's faces: the polygon
/// reaches the outer side of an open solid's opening (or its plane), or it is not wholly
/// outside any of the solid's faces' planes (it may enter the solid).
bool may_enter(const ConvexSolid& solid, const Polygon& receiver, double slack) {
    for (const SolidOpening& o : solid.openings)
        if (highest_above(receiver, o.plane) > -slack) return true;
    for (const Plane& f : solid.faces)
        if (lowest_below(receiver, f) > slack) return false;
    return true;  // (an open solid's openings: every vertex is inside their planes here)
}

/// Whether p lies in front of one of the solid's openings' planes, or behind them all by less
/// than `by` (where the solid's back faces may show).
bool near_an_opening(const ConvexSolid& solid, Vec3 p, double by) {
    for (const SolidOpening& o : solid.openings)
        if (o.plane.signed_distance(p) >= -by) return true;
    return false;
}

Box3 grown_box(Box3 box, double by) {
    box.lo = box.lo - Vec3{by, by, by};
    box.hi = box.hi + Vec3{by, by, by};
    return box;
}

}  // namespace

double contact_reach(const Polygon& occluder) {
    return occluder.diameter() > 0
               ? hidden_contact_reach * occluder.area() / occluder.diameter()
               : 0.0;
}

int hidden_texels(double size, double scene_size) {
    if (!(size > 0) || !(scene_size > 0)) return hidden_resolution;
    const double texels = std::ceil(size / (hidden_min_texel * scene_size));
    return int(std::clamp(texels, double(hidden_min_resolution), double(hidden_resolution)));
}

HiddenMask find_hidden(const Surface& surface, int surface_id, const Octree& octree,
                       const HiddenContacts* contacts) {
    const std::vector<int>* occluders =
        contacts ? &contacts->occluders[size_t(surface_id)] : nullptr;
    const Box3 box = octree.bounds();
    const double scale = box.empty() ? 1.0 : length(box.extent());
    const double slack = 1e-7 * scale;  // find_contacts' "in front" and "behind"
    const int n = hidden_texels(length(surface.bounds().extent()), scale);
    const std::vector<Polygon>& polygons = octree.polygons();
    const bool grow = occluders && int(occluders->size()) <= hidden_max_seed_occluders;
    // A texel's size (about: its diagonal on a parallelogram, more on a curved surface).
    const double texel = length(surface.bounds().extent()) / n;
    // Whether texel k's centre lies behind one of the occluders, within its reach and a texel
    // (a seed: some of the texel comes within reach).
    auto near_a_back = [&](Vec3 p) {
        for (int o : *occluders) {
            const Polygon& occluder = polygons[size_t(o)];
            if (occluder.plane().signed_distance(p) >= -slack) continue;
            const int k = contacts->solids.solid_of[size_t(o)];
            if (k >= 0) {
                const ConvexSolid& solid = contacts->solids.solids[size_t(k)];
                if (inside_solid(solid, p, texel + slack)) return true;
                // Outside, only an open solid's back faces show, through an opening.
                if (!near_an_opening(solid, p, texel + slack)) continue;
            }
            const double reach = contact_reach(occluder) + texel + slack;
            const Box3 b = occluder.bounds();
            if (p.x >= b.lo.x - reach && p.x <= b.hi.x + reach && p.y >= b.lo.y - reach &&
                p.y <= b.hi.y + reach && p.z >= b.lo.z - reach && p.z <= b.hi.z + reach)
                return true;
        }
        return false;
    };
    // The rays of texel k: whether it is hidden.
    auto texel_hidden = [&](int k) {
        const int i = k % n, j = k / n;
        const SurfacePoint p = surface.evaluate((i + 0.5) / n, (j + 0.5) / n);
        if (!(p.area_factor > 0)) return false;  // a degenerate point (a pole): leave it visible
        const CosineFrame frame(p.normal);
        const std::uint64_t key =
            hash_seed(0x6869646465ULL, std::uint64_t(surface_id), std::uint64_t(k));
        // DESIGN: the ray starts 1e-7 of the scene's size in front of the surface, so it does not
        // meet the surface's own polygon at t = 0. It starts on the true surface, so the facets
        // of a curved one near it (its own, a neighbour's across a shared edge) do not count
        // (Polygon::hit_counts): from inside a sphere of 16 x 16 facets, its own facets' backs
        // hid 94 % of its texels (3844 of 4096), which then took the values of the few left.
        const Vec3 origin = p.position + slack * p.normal;
        // Hidden needs the first 4 rays and hidden_back_share of all to meet backs: at most
        // `allowed` visible rays, none among the first 4 (a texel with a front face or an
        // opening in sight is visible). Stop at the first ray that decides it.
        const int allowed =
            hidden_rays - static_cast<int>(std::ceil(hidden_back_share * hidden_rays));
        int visible = 0;
        for (int r = 0; r < hidden_rays; ++r) {
            const Vec3 dir = frame.direction(uniform01(key, 2 * r), uniform01(key, 2 * r + 1));
            const std::optional<Hit> hit =
                octree.closest_hit(Ray{origin, dir, 0, HUGE_VAL}, RayFilter{-1, -1, true});
            const bool back_hit = hit && dot(polygons[size_t(hit->polygon)].normal(), dir) > 0;
            if (!back_hit && (r < 4 || ++visible > allowed)) return false;
        }
        return true;
    };
    std::vector<std::uint8_t> hidden(size_t(n) * n, 0);
    if (!grow) {
        parallel_for(n * n, [&](int k) { hidden[size_t(k)] = texel_hidden(k); });
        return HiddenMask(n, std::move(hidden));
    }
    // Seeds: the texels behind an occluder and within its reach. Then waves: the untested
    // neighbours (8-connected) of the texels found hidden, until none is hidden. A hidden region
    // is reached from any of its texels near the polygons in contact (the footprint's rim under
    // a resting block); texels far from every contact are visible without a ray.
    std::vector<std::uint8_t> queued(size_t(n) * n, 0);
    parallel_for(n * n, [&](int k) {
        const SurfacePoint p = surface.evaluate((k % n + 0.5) / n, (k / n + 0.5) / n);
        queued[size_t(k)] = near_a_back(p.position);
    });
    std::vector<int> wave;
    for (int k = 0; k < n * n; ++k)
        if (queued[size_t(k)]) wave.push_back(k);
    while (!wave.empty()) {
        parallel_for(int(wave.size()), [&](int w) {
            const int k = wave[size_t(w)];
            hidden[size_t(k)] = texel_hidden(k);
        });
        std::vector<int> next;
        for (int k : wave) {
            if (!hidden[size_t(k)]) continue;
            const int i = k % n, j = k / n;
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const int a = i + di, b = j + dj;
                    if (a < 0 || a >= n || b < 0 || b >= n || queued[size_t(b * n + a)]) continue;
                    queued[size_t(b * n + a)] = 1;
                    next.push_back(b * n + a);
                }
        }
        std::sort(next.begin(), next.end());
        wave = std::move(next);
    }
    return HiddenMask(n, std::move(hidden));
}

HiddenContacts find_contacts(const Octree& octree, int n_surfaces) {
    MBR_CHECK(n_surfaces >= 0);
    HiddenContacts contacts;
    contacts.solids = find_convex_solids(octree.polygons());
    const ConvexSolids& solids = contacts.solids;
    const std::vector<Polygon>& polygons = octree.polygons();
    const Box3 scene = octree.bounds();
    const double scale = scene.empty() ? 1.0 : length(scene.extent());
    // DESIGN: "in front" and "behind" by more than 1e-7 of the scene, the offset of
    // find_hidden's ray origins: coplanar polygons and rounding do not count.
    const double slack = 1e-7 * scale;
    // Which surfaces are curved (more than one polygon and not all in one plane): their own
    // polygons may hide each other's points.
    std::vector<int> first_polygon(static_cast<size_t>(n_surfaces), -1);
    std::vector<std::uint8_t> curved(static_cast<size_t>(n_surfaces), 0);
    for (int p = 0; p < int(polygons.size()); ++p) {
        const int s = polygons[size_t(p)].surface();
        if (s < 0 || s >= n_surfaces) continue;
        int& first = first_polygon[size_t(s)];
        if (first < 0) {
            first = p;
        } else if (!curved[size_t(s)]) {
            const Plane& plane = polygons[size_t(first)].plane();
            const Polygon& q = polygons[size_t(p)];
            curved[size_t(s)] = highest_above(q, plane) > slack || lowest_below(q, plane) < -slack;
        }
    }
    // Per occluder P, the surfaces it touches (in the order found); merged in P's order, so the
    // lists do not depend on the thread count.
    std::vector<std::vector<int>> touched(polygons.size());
    parallel_for(int(polygons.size()), [&](int p) {
        const Polygon& occluder = polygons[size_t(p)];
        const Box3 reach = grown_box(occluder.bounds(), contact_reach(occluder) + slack);
        std::vector<int> near;
        octree.append_polygons_near([&](const Box3& cube) { return overlaps(cube, reach); }, near);
        std::vector<int>& out = touched[size_t(p)];
        for (int q : near) {
            if (q == p) continue;
            const Polygon& receiver = polygons[size_t(q)];
            const int s = receiver.surface();
            if (s < 0 || s >= n_surfaces) continue;
            if (s == occluder.surface() && !curved[size_t(s)]) continue;
            if (!overlaps(receiver.bounds(), reach)) continue;
            if (!(highest_above(occluder, receiver.plane()) > slack &&
                  lowest_below(receiver, occluder.plane()) < -slack))
                continue;
            // A face of a convex solid shows its back only inside the solid, or through an
            // open solid's missing face.
            const int k = solids.solid_of[size_t(p)];
            if (k >= 0 && !may_enter(solids.solids[size_t(k)], receiver, slack)) continue;
            out.push_back(s);
        }
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    });
    contacts.occluders.resize(static_cast<size_t>(n_surfaces));
    for (int p = 0; p < int(polygons.size()); ++p)
        for (int s : touched[size_t(p)]) contacts.occluders[size_t(s)].push_back(p);
    return contacts;
}

}  // namespace mbr
