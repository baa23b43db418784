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

/// The faces that use an undirected edge: how many, and the first two.
struct EdgeUses {
    int count = 0;
    int first = -1, second = -1;
};

std::uint64_t edge_key(int a, int b) {
    return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
}

/// The solid the component's faces bound, when they bound a convex one (see the header).
std::optional<ConvexSolid> make_solid(const std::vector<Polygon>& polygons,
                                      const std::vector<int>& faces,
                                      const std::vector<std::vector<int>>& corner_ids,
                                      const std::vector<Vec3>& points) {
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
    // Edges within the solid: each in two of its faces, run in opposite directions, or in one
    // (the missing face's outline); each listed once.
    struct DirectedEdge {
        std::uint64_t key;
        int a, b;  // scene vertex ids, in the face's order
    };
    std::vector<DirectedEdge> directed;
    for (int f : faces) {
        const std::vector<int>& ids = corner_ids[size_t(f)];
        for (size_t k = 0; k < ids.size(); ++k) {
            const int a = ids[k], b = ids[(k + 1) % ids.size()];
            directed.push_back({edge_key(a, b), a, b});
        }
    }
    std::sort(directed.begin(), directed.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
        return x.key < y.key || (x.key == y.key && x.a < y.a);
    });
    std::vector<DirectedEdge> single;  // edges of one face
    for (size_t k = 0; k < directed.size();) {
        size_t end = k + 1;
        while (end < directed.size() && directed[end].key == directed[k].key) ++end;
        if (end - k > 2) return std::nullopt;
        if (end - k == 2 && directed[k].a == directed[k + 1].a) return std::nullopt;  // same way
        const DirectedEdge& e = directed[k];
        solid.edges.push_back({index_of(e.a), index_of(e.b)});
        if (end - k == 1) single.push_back(e);
        k = end;
    }
    // A mesh with T-junctions splits an edge on one side and not on the other: an edge of one
    // face is still inside the surface when edges of others, on its line and run the other way,
    // cover it. The rest are the missing face's outline.
    auto covered = [&](const DirectedEdge& e) {
        const Vec3 a = points[size_t(e.a)], d = points[size_t(e.b)] - a;
        const double len2 = dot(d, d);
        std::vector<std::array<double, 2>> spans;  // parameters along e of the covering edges
        for (const DirectedEdge& f : single) {
            const Vec3 c = points[size_t(f.a)], g = points[size_t(f.b)];
            if (dot(g - c, d) >= 0) continue;  // not run the other way
            if (length(cross(c - a, d)) > tol * std::sqrt(len2) ||
                length(cross(g - a, d)) > tol * std::sqrt(len2))
                continue;  // not on e's line
            const double t0 = dot(g - a, d) / len2, t1 = dot(c - a, d) / len2;
            spans.push_back({t0, t1});
        }
        std::sort(spans.begin(), spans.end());
        const double slack = tol / std::sqrt(len2);
        double reach = 0;
        for (const auto& span : spans) {
            if (span[0] > reach + slack) break;
            reach = std::max(reach, span[1]);
        }
        return reach >= 1 - slack;
    };
    // The edges left are the openings' outlines: one closed loop each, joined through their
    // shared vertices.
    std::vector<DirectedEdge> outline;
    for (const DirectedEdge& e : single)
        if (!covered(e)) outline.push_back(e);
    if (outline.empty()) return solid;  // closed
    std::unordered_map<int, int> loop_of;  // scene vertex id -> union-find node
    std::vector<int> loop_parent;
    auto node_of = [&](int id) {
        const auto it = loop_of.emplace(id, int(loop_parent.size())).first;
        if (it->second == int(loop_parent.size())) loop_parent.push_back(it->second);
        return it->second;
    };
    for (const DirectedEdge& e : outline) {
        const int a = find_root(loop_parent, node_of(e.a));
        const int b = find_root(loop_parent, node_of(e.b));
        loop_parent[size_t(a)] = b;
    }
    std::vector<int> roots;  // one per loop, in the order of their first edge
    std::vector<std::vector<const DirectedEdge*>> loops;
    for (const DirectedEdge& e : outline) {
        const int root = find_root(loop_parent, node_of(e.a));
        const size_t loop = size_t(std::find(roots.begin(), roots.end(), root) - roots.begin());
        if (loop == roots.size()) {
            roots.push_back(root);
            loops.emplace_back();
        }
        loops[loop].push_back(&e);
    }
    if (loops.size() > size_t(max_solid_openings)) return std::nullopt;
    for (const std::vector<const DirectedEdge*>& loop : loops) {
        // The opening: the plane of its outline, which must support the solid.
        Vec3 centre{0, 0, 0};
        for (const DirectedEdge* e : loop) centre = centre + points[size_t(e->a)];
        centre = (1.0 / double(loop.size())) * centre;
        Vec3 normal{0, 0, 0};
        for (const DirectedEdge* e : loop)
            normal = normal + cross(points[size_t(e->a)] - centre, points[size_t(e->b)] - centre);
        if (!(length(normal) > 0)) return std::nullopt;
        normal = normalize(normal);
        Plane plane{normal, dot(normal, centre)};
        for (const DirectedEdge* e : loop)
            if (std::fabs(plane.signed_distance(points[size_t(e->a)])) > tol) return std::nullopt;
        bool behind = false, in_front = false;
        for (const Vec3& v : solid.vertices) {
            const double d = plane.signed_distance(v);
            if (d > tol) in_front = true;
            if (d < -tol) behind = true;
        }
        if (behind == in_front) return std::nullopt;  // it cuts the solid, or the solid is flat
        if (in_front) plane = Plane{-1.0 * normal, -plane.offset};
        SolidOpening opening{plane, {}};
        for (const DirectedEdge* e : loop) opening.outline.push_back(index_of(e->a));
        solid.openings.push_back(std::move(opening));
    }
    return solid;
}

/// The sheet the faces form: a disk (one boundary loop, V - E + F = 1) whose faces meet along
/// whole edges, each edge in at most two faces run opposite ways (the faces turned one way).
std::optional<ConvexSheet> make_sheet(const std::vector<Polygon>& polygons,
                                      const std::vector<int>& faces,
                                      const std::vector<std::vector<int>>& corner_ids,
                                      const std::vector<Vec3>& points) {
    ConvexSheet sheet;
    sheet.polygons = faces;
    std::unordered_map<std::uint64_t, int> way;  // edge key -> a bit per direction run
    std::unordered_map<int, int> next;           // boundary: vertex -> the next one
    std::vector<int> ids;
    Box3 box;
    for (int f : faces) {
        sheet.faces.push_back(polygons[size_t(f)].plane());
        box.extend(polygons[size_t(f)].bounds());
        const std::vector<int>& c = corner_ids[size_t(f)];
        ids.insert(ids.end(), c.begin(), c.end());
        for (size_t k = 0; k < c.size(); ++k) {
            const int a = c[k], b = c[(k + 1) % c.size()];
            int& w = way[edge_key(a, b)];
            const int d = a < b ? 1 : 2;
            if (w & d) return std::nullopt;  // an edge run twice the same way
            w |= d;
        }
    }
    sheet.diameter = length(box.extent());
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (int id : ids) sheet.vertices.push_back(points[size_t(id)]);
    long n_boundary = 0;
    for (int f : faces) {
        const std::vector<int>& c = corner_ids[size_t(f)];
        for (size_t k = 0; k < c.size(); ++k) {
            const int a = c[k], b = c[(k + 1) % c.size()];
            if (way[edge_key(a, b)] != 3) {                           // in this face only
                if (!next.emplace(a, b).second) return std::nullopt;  // a pinched boundary
                ++n_boundary;
            }
        }
    }
    if (n_boundary < 3) return std::nullopt;
    const long n_edges = long(way.size()), n_vertices = long(ids.size());
    if (n_vertices - n_edges + long(faces.size()) != 1) return std::nullopt;  // not a disk
    // One loop through every boundary edge.
    const int first = next.begin()->first;
    int at = first;
    do {
        sheet.boundary.push_back(points[size_t(at)]);
        const auto it = next.find(at);
        if (it == next.end()) return std::nullopt;
        at = it->second;
    } while (at != first && long(sheet.boundary.size()) <= n_boundary);
    if (long(sheet.boundary.size()) != n_boundary) return std::nullopt;
    return sheet;
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
    for (int f = 0; f < n; ++f) {
        const std::vector<int>& ids = corner_ids[size_t(f)];
        for (size_t k = 0; k < ids.size(); ++k) {
            EdgeUses& use = uses[edge_key(ids[k], ids[(k + 1) % ids.size()])];
            (use.count == 0 ? use.first : use.second) = f;
            ++use.count;
        }
    }
    // Faces are joined across an edge they share (with no third face) where it is convex or
    // flat: each face's corners lie behind the other's plane or on it, within 1e-9 of the pair's
    // size. So a block's faces are one set, and a floor meshed together with the blocks on it
    // (a concave edge at every block's foot) is not joined to them.
    auto behind = [&](int f, int g) {
        const Plane& plane = polygons[size_t(f)].plane();
        const double tol =
            1e-9 * std::max(polygons[size_t(f)].diameter(), polygons[size_t(g)].diameter());
        for (const Vec3& v : polygons[size_t(g)].vertices())
            if (plane.signed_distance(v) > tol) return false;
        return true;
    };
    std::vector<int> parent(static_cast<size_t>(n));
    std::iota(parent.begin(), parent.end(), 0);
    for (const auto& entry : uses) {
        const EdgeUses& use = entry.second;
        if (use.count == 2 && behind(use.first, use.second) && behind(use.second, use.first))
            parent[size_t(find_root(parent, use.first))] = find_root(parent, use.second);
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
        std::optional<ConvexSolid> solid = make_solid(polygons, faces, corner_ids, points);
        if (!solid) continue;
        for (int f : faces) out.solid_of[size_t(f)] = int(out.solids.size());
        out.solids.push_back(std::move(*solid));
    }
    // The sheets: the other polygons by surface, in the order of their first polygon.
    std::unordered_map<int, std::vector<int>> by_surface;
    std::vector<int> surfaces;
    for (int f = 0; f < n; ++f) {
        if (out.solid_of[size_t(f)] >= 0) continue;
        std::vector<int>& list = by_surface[polygons[size_t(f)].surface()];
        if (list.empty()) surfaces.push_back(polygons[size_t(f)].surface());
        list.push_back(f);
    }
    out.sheet_of.assign(size_t(n), -1);
    for (int surface : surfaces) {
        const std::vector<int>& faces = by_surface[surface];
        if (faces.size() < 2 || faces.size() > size_t(max_sheet_faces)) continue;
        std::optional<ConvexSheet> sheet = make_sheet(polygons, faces, corner_ids, points);
        if (!sheet) continue;
        for (int f : faces) out.sheet_of[size_t(f)] = int(out.sheets.size());
        out.sheets.push_back(std::move(*sheet));
    }
    return out;
}

void attach_solids(OcclusionContext& context, const ConvexSolids& solids) {
    context.solids = &solids;
    context.solid_ids.clear();
    context.loose.clear();
    const std::vector<Polygon>& polys = context.octree->polygons();
    // How a solid stands to the pair: apart from it (usable as one caster), holding one of the
    // pair's surfaces as one of its face planes (it casts no shadow between them: every segment
    // from a point of that face to a point in front of it lies outside the solid, which is
    // behind the face's plane, and the pair's points see each other only in front), or holding
    // them otherwise (its faces stay loose).
    enum class Stand { apart, on_face, other };
    auto stand = [&](int s) {
        const ConvexSolid& solid = solids.solids[size_t(s)];
        Stand out = Stand::apart;
        for (int surface : {context.shooter_surface, context.receiver_surface}) {
            const Plane* face = nullptr;
            for (size_t k = 0; k < solid.polygons.size(); ++k) {
                if (polys[size_t(solid.polygons[k])].surface() != surface) continue;
                // DESIGN: the same plane to 1e-9 of the solid's size, as make_solid's faces.
                const Plane& plane = solid.faces[k];
                if (!face) {
                    face = &plane;
                    out = out == Stand::apart ? Stand::on_face : out;
                } else if (dot(plane.normal, face->normal) < 1 - 1e-9 ||
                           std::fabs(plane.offset - face->offset) > 1e-9 * solid.diameter) {
                    return Stand::other;  // a curved surface of the solid's (a ball)
                }
            }
        }
        return out;
    };
    std::vector<int> dropped;  // solids on one of the pair's faces
    for (int id : context.candidates) {
        const int s = id < int(solids.solid_of.size()) ? solids.solid_of[size_t(id)] : -1;
        if (s >= 0 && (std::find(context.solid_ids.begin(), context.solid_ids.end(), s) !=
                           context.solid_ids.end() ||
                       std::find(dropped.begin(), dropped.end(), s) != dropped.end()))
            continue;  // taken
        const Stand st = s >= 0 ? stand(s) : Stand::other;
        if (st == Stand::apart)
            context.solid_ids.push_back(s);
        else if (st == Stand::on_face)
            dropped.push_back(s);
        else
            context.loose.push_back(id);
    }
    std::vector<int> surfaces;
    for (int id : context.loose) surfaces.push_back(polys[size_t(id)].surface());
    std::sort(surfaces.begin(), surfaces.end());
    context.loose_surfaces =
        static_cast<int>(std::unique(surfaces.begin(), surfaces.end()) - surfaces.begin());
}

}  // namespace mbr
