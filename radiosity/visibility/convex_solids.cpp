// radiosity/visibility/convex_solids.cpp - convex solids among a scene's polygons, and a pair's
// candidates split between them and loose polygons (radiosity/visibility/convex_solids.h).
#include "radiosity/visibility/convex_solids.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <optional>
#include <unordered_map>

#include "radiosity/visibility/occlusion.h"

namespace mbr {

namespace {

/// The bits of a point, for matching the shared corners of neighbouring faces exactly.
struct PointBits {
    std::uint64_t x, y, z;
    bool operator==(const PointBits& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PointBitsHash {
    size_t operator()(const PointBits& p) const {
        return size_t(hash_seed(p.x, p.y, p.z));
    }
};
PointBits bits_of(Vec3 v) {
    PointBits b;
    std::memcpy(&b.x, &v.x, 8);
    std::memcpy(&b.y, &v.y, 8);
    std::memcpy(&b.z, &v.z, 8);
    return b;
}

/// Union-find over polygons (path halving).
int find_root(std::vector<int>& parent, int a) {
    while (parent[size_t(a)] != a) {
        parent[size_t(a)] = parent[size_t(parent[size_t(a)])];
        a = parent[size_t(a)];
    }
    return a;
}

/// One use of an undirected edge by a face: the face and whether it runs from the smaller
/// vertex id to the larger.
struct EdgeUses {
    int count = 0;
    int first_polygon = -1;
    bool first_forward = false;
    bool opposed = true;  // a second use runs the other way
};

std::uint64_t edge_key(int a, int b) {
    return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
}

/// The solid the component's faces bound, when they bound a convex one (see the header).
std::optional<ConvexSolid> make_solid(const std::vector<Polygon>& polygons,
                                      const std::vector<int>& faces,
                                      const std::vector<std::vector<int>>& corner_ids,
                                      const std::vector<Vec3>& points,
                                      const std::unordered_map<std::uint64_t, EdgeUses>& uses) {
    ConvexSolid solid;
    solid.polygons = faces;
    std::vector<int> local;  // scene vertex ids of the solid, sorted
    for (int f : faces) local.insert(local.end(), corner_ids[size_t(f)].begin(), corner_ids[size_t(f)].end());
    std::sort(local.begin(), local.end());
    local.erase(std::unique(local.begin(), local.end()), local.end());
    auto index_of = [&](int id) {
        return int(std::lower_bound(local.begin(), local.end(), id) - local.begin());
    };
    Box3 box;
    for (int id : local) {
        solid.vertices.push_back(points[size_t(id)]);
        box.extend(points[size_t(id)]);
    }
    solid.diameter = length(box.extent());
    // DESIGN: 1e-9 of the solid's size: a corner that far in front of a face's plane still
    // counts as behind it (the faces' own planes are Newell's fits of their corners).
    const double tol = 1e-9 * solid.diameter;
    bool volume = false;
    for (int f : faces) {
        const Plane& plane = polygons[size_t(f)].plane();
        for (const Vec3& v : solid.vertices) {
            const double d = plane.signed_distance(v);
            if (d > tol) return std::nullopt;  // not convex, or a face looking inward
            if (d < -tol) volume = true;
        }
        solid.faces.push_back(plane);
    }
    if (!volume) return std::nullopt;  // flat: coplanar faces bound no solid
    // Edges: each once; those of one face only are the missing face's outline.
    Vec3 centre{0, 0, 0};
    std::vector<std::array<Vec3, 2>> outline;  // directed as their face runs them
    for (int f : faces) {
        const std::vector<int>& ids = corner_ids[size_t(f)];
        for (size_t k = 0; k < ids.size(); ++k) {
            const int a = ids[k], b = ids[(k + 1) % ids.size()];
            const EdgeUses& use = uses.at(edge_key(a, b));
            if (use.count > 2 || !use.opposed) return std::nullopt;
            if (use.count == 2 && use.first_polygon != f) continue;  // listed by its first face
            solid.edges.push_back({index_of(a), index_of(b)});
            if (use.count == 1) {
                outline.push_back({points[size_t(a)], points[size_t(b)]});
                solid.missing_outline.push_back(index_of(a));
                centre = centre + points[size_t(a)];
            }
        }
    }
    if (outline.empty()) return solid;  // closed
    // The missing face: the plane of the outline, which must support the solid.
    centre = (1.0 / double(outline.size())) * centre;
    Vec3 normal{0, 0, 0};
    for (const auto& e : outline) normal = normal + cross(e[0] - centre, e[1] - centre);
    if (!(length(normal) > 0)) return std::nullopt;
    normal = normalize(normal);
    Plane missing{normal, dot(normal, centre)};
    for (const auto& e : outline)
        if (std::fabs(missing.signed_distance(e[0])) > tol) return std::nullopt;
    bool behind = false, in_front = false;
    for (const Vec3& v : solid.vertices) {
        const double d = missing.signed_distance(v);
        if (d > tol) in_front = true;
        if (d < -tol) behind = true;
    }
    if (behind == in_front) return std::nullopt;  // it cuts the solid, or the solid is flat
    if (in_front) missing = Plane{-1.0 * normal, -missing.offset};
    solid.open = true;
    solid.missing = missing;
    return solid;
}

}  // namespace

ConvexSolids find_convex_solids(const std::vector<Polygon>& polygons) {
    ConvexSolids out;
    const int n = static_cast<int>(polygons.size());
    out.solid_of.assign(size_t(n), -1);
    // Corners matched by their bits; faces joined through their shared edges.
    std::unordered_map<PointBits, int, PointBitsHash> vertex_id;
    std::vector<Vec3> points;
    std::vector<std::vector<int>> corner_ids(static_cast<size_t>(n));
    for (int f = 0; f < n; ++f)
        for (const Vec3& v : polygons[size_t(f)].vertices()) {
            const auto it = vertex_id.emplace(bits_of(v), int(points.size())).first;
            if (it->second == int(points.size())) points.push_back(v);
            corner_ids[size_t(f)].push_back(it->second);
        }
    std::unordered_map<std::uint64_t, EdgeUses> uses;
    std::vector<int> parent(static_cast<size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    for (int f = 0; f < n; ++f) {
        const std::vector<int>& ids = corner_ids[size_t(f)];
        for (size_t k = 0; k < ids.size(); ++k) {
            const int a = ids[k], b = ids[(k + 1) % ids.size()];
            EdgeUses& use = uses[edge_key(a, b)];
            if (use.count == 0) {
                use.first_polygon = f;
                use.first_forward = a < b;
            } else {
                if ((a < b) == use.first_forward) use.opposed = false;
                parent[size_t(find_root(parent, f))] = find_root(parent, use.first_polygon);
            }
            ++use.count;
        }
    }
    std::unordered_map<int, std::vector<int>> components;
    for (int f = 0; f < n; ++f) components[find_root(parent, f)].push_back(f);
    std::vector<std::vector<int>> groups;
    for (auto& entry : components)
        if (entry.second.size() >= 3 && entry.second.size() <= size_t(max_solid_faces))
            groups.push_back(std::move(entry.second));
    // A fixed order (the map's is not): by first polygon.
    std::sort(groups.begin(), groups.end(),
              [](const std::vector<int>& a, const std::vector<int>& b) { return a[0] < b[0]; });
    for (const std::vector<int>& faces : groups) {
        std::optional<ConvexSolid> solid = make_solid(polygons, faces, corner_ids, points, uses);
        if (!solid) continue;
        for (int f : faces) out.solid_of[size_t(f)] = int(out.solids.size());
        out.solids.push_back(std::move(*solid));
    }
    return out;
}

void attach_solids(OcclusionContext& context, const ConvexSolids& solids) {
    context.solids = &solids;
    context.solid_ids.clear();
    context.loose.clear();
    const std::vector<Polygon>& polys = context.octree->polygons();
    auto usable = [&](int s) {
        for (int id : solids.solids[size_t(s)].polygons) {
            const int surface = polys[size_t(id)].surface();
            if (surface == context.shooter_surface || surface == context.receiver_surface)
                return false;
        }
        return true;
    };
    for (int id : context.candidates) {
        const int s = id < int(solids.solid_of.size()) ? solids.solid_of[size_t(id)] : -1;
        const bool taken = s >= 0 && std::find(context.solid_ids.begin(), context.solid_ids.end(),
                                               s) != context.solid_ids.end();
        if (taken) continue;
        if (s >= 0 && usable(s))
            context.solid_ids.push_back(s);
        else
            context.loose.push_back(id);
    }
}

}  // namespace mbr
