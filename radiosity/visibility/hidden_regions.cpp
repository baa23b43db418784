// radiosity/visibility/hidden_regions.cpp - hidden parts of a surface (hidden_regions.h).
#include "radiosity/visibility/hidden_regions.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"
#include "math/parallel.h"
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
    if (visible.empty()) return;  // nothing hidden, or everything
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
}

int HiddenMask::texel(double s, double t) const {
    const int i = std::clamp(static_cast<int>(s * n_), 0, n_ - 1);
    const int j = std::clamp(static_cast<int>(t * n_), 0, n_ - 1);
    return j * n_ + i;
}

bool HiddenMask::hidden(double s, double t) const {
    return n_hidden_ > 0 && hidden_[texel(s, t)];
}

Vec2 HiddenMask::substitute(double s, double t) const {
    if (n_hidden_ == 0) return {s, t};
    const int k = texel(s, t);
    return hidden_[k] ? substitute_[k] : Vec2{s, t};
}

int hidden_texels(double size, double scene_size) {
    if (!(size > 0) || !(scene_size > 0)) return hidden_resolution;
    const double texels = std::ceil(size / (hidden_min_texel * scene_size));
    return int(std::clamp(texels, double(hidden_min_resolution), double(hidden_resolution)));
}

HiddenMask find_hidden(const Surface& surface, int surface_id, const Octree& octree) {
    const Box3 box = octree.bounds();
    const double scale = box.empty() ? 1.0 : length(box.extent());
    const int n = hidden_texels(length(surface.bounds().extent()), scale);
    std::vector<std::uint8_t> hidden(size_t(n) * n, 0);
    parallel_for(n * n, [&](int k) {
        const int i = k % n, j = k / n;
        const SurfacePoint p = surface.evaluate((i + 0.5) / n, (j + 0.5) / n);
        if (!(p.area_factor > 0)) return;  // a degenerate point (a pole): leave it visible
        const CosineFrame frame(p.normal);
        const std::uint64_t key =
            hash_seed(0x6869646465ULL, std::uint64_t(surface_id), std::uint64_t(k));
        // DESIGN: the ray starts 1e-7 of the scene's size in front of the surface, so it does not
        // meet the surface's own polygon at t = 0. It starts on the true surface, so the facets
        // of a curved one near it (its own, a neighbour's across a shared edge) do not count
        // (Polygon::hit_counts): from inside a sphere of 16 x 16 facets, its own facets' backs
        // hid 94 % of its texels (3844 of 4096), which then took the values of the few left.
        const Vec3 origin = p.position + (1e-7 * scale) * p.normal;
        int back = 0, cast = 0;
        for (int r = 0; r < hidden_rays; ++r) {
            const Vec3 dir = frame.direction(uniform01(key, 2 * r), uniform01(key, 2 * r + 1));
            ++cast;
            const std::optional<Hit> hit =
                octree.closest_hit(Ray{origin, dir, 0, HUGE_VAL}, RayFilter{-1, -1, true});
            const bool back_hit = hit && dot(octree.polygons()[hit->polygon].normal(), dir) > 0;
            if (back_hit) ++back;
            // Four rays first: a texel with a front face or an opening in sight is visible.
            if (r == 3 && back < 4) break;
        }
        hidden[k] = cast == hidden_rays && back >= hidden_back_share * hidden_rays;
    });
    return HiddenMask(n, std::move(hidden));
}

}  // namespace mbr
