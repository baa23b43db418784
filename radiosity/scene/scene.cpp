// radiosity/scene/scene.cpp - helpers of the scene model (scene.h).
#include "radiosity/scene/scene.h"

#include "math/check.h"

namespace mbr {

int Scene::find_material(const std::string& name) const {
    for (size_t i = 0; i < materials.size(); ++i)
        if (materials[i].name == name) return int(i);
    return -1;
}

int Scene::find_surface(const std::string& name) const {
    for (size_t i = 0; i < surfaces.size(); ++i)
        if (surfaces[i].name == name) return int(i);
    return -1;
}

const Material& Scene::material_of(int surface) const {
    MBR_CHECK_MSG(surface >= 0 && size_t(surface) < surfaces.size(), "surface " << surface);
    int m = surfaces[surface].material;
    MBR_CHECK_MSG(m >= 0 && size_t(m) < materials.size(), "material " << m);
    return materials[m];
}

std::vector<int> Scene::emitters() const {
    std::vector<int> out;
    for (size_t i = 0; i < surfaces.size(); ++i)
        if (material_of(int(i)).emits()) out.push_back(int(i));
    return out;
}

double Scene::total_area() const {
    double sum = 0;
    for (const SceneSurface& s : surfaces) sum += s.surface.area();
    return sum;
}

Rgb Scene::emitted_power() const {
    Rgb sum;
    for (int i : emitters()) sum += surfaces[i].surface.area() * material_of(i).emission.mean();
    return sum;
}

Box3 Scene::bounds() const {
    Box3 box;
    for (const SceneSurface& s : surfaces) box.extend(s.surface.bounds());
    return box;
}

std::string Scene::where(int surface) const {
    MBR_CHECK_MSG(surface >= 0 && size_t(surface) < surfaces.size(), "surface " << surface);
    const SceneSurface& s = surfaces[size_t(surface)];
    if (s.source < 0 || size_t(s.source) >= sources.size()) return "'" + s.name + "'";
    return sources[size_t(s.source)] + ":" + std::to_string(s.line);
}

int surface_order(const Scene& scene, int surface, int global_order) {
    MBR_CHECK_MSG(surface >= 0 && size_t(surface) < scene.surfaces.size(), "surface " << surface);
    const int own = scene.surfaces[size_t(surface)].order;
    return own > 0 ? own : global_order;
}

int surface_order(const Scene& scene, int surface) {
    return surface_order(scene, surface, scene.settings.order);
}

void remove_surfaces(Scene& scene, const std::vector<char>& drop) {
    size_t kept = 0;
    for (size_t i = 0; i < scene.surfaces.size(); ++i)
        if (!drop[i]) {
            if (kept != i) scene.surfaces[kept] = std::move(scene.surfaces[i]);
            ++kept;
        }
    scene.surfaces.resize(kept);
}

void Scene::warn(const SceneWarning& w) {
    for (SceneWarning& x : warnings)
        if (x.kind == w.kind) {
            x.count += w.count;
            return;
        }
    warnings.push_back(w);
}

std::string SceneWarning::text() const {
    std::string s;
    if (!file.empty()) s = file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": ";
    s += message;
    if (count > 1) s += " (and " + std::to_string(count - 1) + " more like it)";
    return s;
}

}  // namespace mbr
