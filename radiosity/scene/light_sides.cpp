// radiosity/scene/light_sides.cpp - twins for two-sided materials and back-facing lights turned
// around (light_sides.h).
#include "radiosity/scene/light_sides.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "radiosity/scene/duplicate_faces.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/scene/mgf_reader.h"
#include "radiosity/scene/scene_octree.h"

namespace mbr {

std::vector<int> two_sided_materials(const Scene& scene) {
    std::vector<int> m;
    for (size_t i = 0; i < scene.materials.size(); ++i)
        if (scene.materials[i].two_sided) m.push_back(int(i));
    return m;
}

void add_back_sides(Scene& scene, const std::vector<int>& materials) {
    if (materials.empty()) return;
    std::vector<char> chosen(scene.materials.size(), 0);
    for (int m : materials) {
        chosen[size_t(m)] = 1;
        scene.materials[size_t(m)].two_sided = true;
    }
    std::unordered_set<std::string> names;
    for (const SceneSurface& s : scene.surfaces) names.insert(s.name);
    const size_t n = scene.surfaces.size();
    for (size_t i = 0; i < n; ++i) {
        if (!chosen[size_t(scene.surfaces[i].material)]) continue;
        SceneSurface back = scene.surfaces[i];
        back.surface = scene.surfaces[i].surface.reversed();
        std::string name = back.name + ".back";
        for (int k = 2; names.count(name); ++k) name = back.name + ".back" + std::to_string(k);
        back.name = name;
        names.insert(name);
        scene.surfaces.push_back(std::move(back));
    }
}

namespace {

/// The median of five distances (infinite for a ray that hits nothing).
double median(std::vector<double> d) {
    std::sort(d.begin(), d.end());
    return d[d.size() / 2];
}

}  // namespace

std::vector<BackFacingLight> find_back_facing_lights(const Scene& scene,
                                                     const std::vector<int>& candidates) {
    std::vector<BackFacingLight> found;
    if (candidates.empty()) return found;
    const Octree octree = build_octree(scene);
    const double points[5][2] = {
        {0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.75, 0.75}, {0.25, 0.75}};
    for (int i : candidates) {
        const Surface& s = scene.surfaces[size_t(i)].surface;
        const double size = length(s.bounds().extent());
        if (!(size > 0)) continue;
        const double lights_from = 0.1 * size;  // nearer, the ray lies against what it hits
        std::vector<double> front, back;
        int front_lighting = 0, back_lighting = 0;
        for (const auto& uv : points) {
            const Vec3 p = s.point(uv[0], uv[1]);
            const Vec3 n = s.normal(uv[0], uv[1]);
            for (const double side : {1.0, -1.0}) {
                Ray ray;
                ray.origin = p;
                ray.dir = side * n;
                ray.t_min = 1e-7 * size;
                RayFilter filter;
                filter.skip_surface_a = i;
                const auto hit = octree.closest_hit(ray, filter);
                const double d = hit ? hit->t : HUGE_VAL;
                const bool lights = hit && d >= lights_from;
                (side > 0 ? front : back).push_back(d);
                (side > 0 ? front_lighting : back_lighting) += lights ? 1 : 0;
            }
        }
        if (front_lighting == 0 && back_lighting >= 4)
            found.push_back({i, median(front), median(back)});
    }
    return found;
}

void face_lights_to_the_open_side(Scene& scene, const ImportOptions& options) {
    std::vector<int> candidates;
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        const SceneSurface& s = scene.surfaces[i];
        const Material& m = scene.materials[size_t(s.material)];
        const bool from_obj = s.source >= 0 && size_t(s.source) < scene.sources.size() &&
                              is_import_path(scene.sources[size_t(s.source)]);
        if (from_obj && m.emits() && !m.two_sided) candidates.push_back(int(i));
    }
    const std::vector<BackFacingLight> lights = find_back_facing_lights(scene, candidates);
    if (lights.empty()) return;
    int turned = 0;
    const BackFacingLight* first = nullptr;
    for (const BackFacingLight& l : lights) {
        SceneSurface& s = scene.surfaces[size_t(l.surface)];
        const Material& m = scene.materials[size_t(s.material)];
        const bool plain = m.emission.is_constant() && m.reflectance.is_constant();
        if (options.strict || !plain) continue;
        s.surface = s.surface.reversed();
        ++turned;
        if (!first) first = &l;
    }
    const auto distance = [](double d) {
        return std::isinf(d) ? std::string("nothing")
                             : "a surface " + detail::fmt_approx(d) + " away";
    };
    SceneWarning w;
    const BackFacingLight& l = first ? *first : lights.front();
    const SceneSurface& s = scene.surfaces[size_t(l.surface)];
    w.file = scene.sources[size_t(s.source)];
    w.line = s.line;
    const std::string what = "light '" + s.name + "' faced " + distance(l.front_distance) +
                             " and turned its back on " + distance(l.back_distance);
    if (turned > 0) {
        w.kind = "light turned around";
        w.message = what + " (its face is wound the wrong way): it is turned to shine there";
        w.count = turned;
    } else {
        w.kind = "light faces away";
        w.message = what + " (its face may be wound the wrong way); it is left as it is";
        w.count = long(lights.size());
    }
    scene.warn(w);
}

void repair_loaded_scene(Scene& scene, const ImportOptions& options) {
    drop_duplicate_surfaces(scene, options);
    face_lights_to_the_open_side(scene, options);
    add_back_sides(scene, two_sided_materials(scene));
}

}  // namespace mbr
