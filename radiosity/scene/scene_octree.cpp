// radiosity/scene/scene_octree.cpp - the scene's surfaces as the octree's polygons (section 6,
// "Octree"; DESIGN.md section 5), robust to facets the Polygon constructor refuses.
#include "radiosity/scene/scene_octree.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "math/check.h"

namespace mbr {

namespace {

// DESIGN: vertices of one facet closer than this fraction of its size are one vertex. Polygon
// refuses edges below 1e-12 of the size, and the direction of an edge of relative length e is
// uncertain by about 1e-16 / e rad, which must stay below its convexity tolerance of 1e-7 rad.
constexpr double merge_tol = 1e-8;

// Vertices and (u, v) of one polygon-to-be.
struct Piece {
    std::vector<Vec3> vertices;
    std::vector<Vec2> uv;
};

double piece_area(const Piece& piece) {
    Vec3 sum;
    for (size_t i = 1; i + 1 < piece.vertices.size(); ++i)
        sum +=
            cross(piece.vertices[i] - piece.vertices[0], piece.vertices[i + 1] - piece.vertices[0]);
    return 0.5 * length(sum);
}

// DESIGN: whether a piece makes a valid Polygon is the Polygon constructor's own decision (its
// planarity, convexity and degeneracy checks, with their tolerances); asking it is the one way to
// stay in step with it, so a refusal (CheckFailure) is caught here and only here.
std::optional<Polygon> try_polygon(const Piece& piece, int surface) {
    try {
        return Polygon(piece.vertices, piece.uv, surface);
    } catch (const CheckFailure&) {
        return std::nullopt;
    }
}

// The facet without repeated vertices (closer than merge_tol of its size, also last to first).
Piece merged(const Facet& facet) {
    double size = 0;
    for (const Vec3& a : facet.vertices)
        for (const Vec3& b : facet.vertices) size = std::max(size, length(b - a));
    const double tol = merge_tol * size;
    Piece piece;
    for (size_t i = 0; i < facet.vertices.size(); ++i) {
        if (!piece.vertices.empty() && length(facet.vertices[i] - piece.vertices.back()) <= tol)
            continue;
        piece.vertices.push_back(facet.vertices[i]);
        piece.uv.push_back(facet.uv[i]);
    }
    while (piece.vertices.size() > 1 &&
           length(piece.vertices.back() - piece.vertices.front()) <= tol) {
        piece.vertices.pop_back();
        piece.uv.pop_back();
    }
    return piece;
}

// The triangles of a split of `piece` along the diagonals from vertex `apex` (a fan).
std::vector<Piece> fan(const Piece& piece, int apex) {
    const int n = static_cast<int>(piece.vertices.size());
    std::vector<Piece> triangles;
    for (int k = 1; k + 1 < n; ++k) {
        Piece t;
        for (int i : {apex, (apex + k) % n, (apex + k + 1) % n}) {
            t.vertices.push_back(piece.vertices[i]);
            t.uv.push_back(piece.uv[i]);
        }
        triangles.push_back(std::move(t));
    }
    return triangles;
}

// The polygons of one split and what it leaves out.
struct Split {
    std::vector<Polygon> polygons;
    int n_dropped = 0;
    double dropped_area = 0;
    double diagonal = 0;  // length of the first diagonal (a quad has one)
};

Split split(const Piece& piece, int apex, int surface) {
    Split result;
    const int n = static_cast<int>(piece.vertices.size());
    result.diagonal = length(piece.vertices[(apex + 2) % n] - piece.vertices[apex]);
    for (const Piece& t : fan(piece, apex)) {
        if (std::optional<Polygon> p = try_polygon(t, surface)) {
            result.polygons.push_back(std::move(*p));
        } else {
            ++result.n_dropped;
            result.dropped_area += piece_area(t);
        }
    }
    return result;
}

// DESIGN: the thickness of a facet of a curved surface (Polygon::thickness) is measured, not
// derived: the surface is evaluated on a grid over the facet's (u, v) polygon scaled by
// thickness_reach about its centroid (reaching a quarter further out than each vertex, where a
// neighbour continues the surface), and the largest distance from the facet's plane, times
// thickness_safety (for the maximum between the grid's points and neighbours that bend a little
// more), is the thickness. thickness_grid + 1 points along each side of the fan's triangles: the
// distance is smooth (quadratic over a chord), so the grid misses little of its maximum.
constexpr double thickness_reach = 1.25;
constexpr double thickness_safety = 2;
constexpr int thickness_grid = 8;

/// How far `surface` stands off the plane of `polygon` (one of its facets) over the polygon's
/// (u, v) polygon and just beyond, with the safety factor; zero for the surfaces whose facets
/// are exact (planar quads and disks), and where the distance is only rounding.
double facet_thickness(const Surface& surface, const Polygon& polygon) {
    if (surface.is_planar()) return 0;
    const std::vector<Vec2>& uv = polygon.uv();
    const int n = static_cast<int>(uv.size());
    Vec2 centre;
    for (const Vec2& q : uv) centre = centre + (1.0 / n) * q;
    double largest = 0;
    // The fan of triangles (centre, vertex k, vertex k+1) covers the convex (u, v) polygon.
    for (int k = 0; k < n; ++k) {
        const Vec2 a = thickness_reach * (uv[k] - centre),
                   b = thickness_reach * (uv[(k + 1) % n] - centre);
        for (int i = 0; i <= thickness_grid; ++i)
            for (int j = 0; i + j <= thickness_grid; ++j) {
                const Vec2 q =
                    centre + (double(i) / thickness_grid) * a + (double(j) / thickness_grid) * b;
                const double d = polygon.plane().signed_distance(surface.point(q.x, q.y));
                largest = std::max(largest, std::fabs(d));
            }
    }
    // DESIGN: a distance below 1e-9 of the facet's diameter is the rounding of an exact facet
    // (a flat bilinear patch): zero, so such facets keep the plain ray-polygon test.
    if (largest <= 1e-9 * polygon.diameter()) return 0;
    return thickness_safety * largest;
}

}  // namespace

std::vector<Polygon> scene_polygons(const Scene& scene, int tessellation,
                                    ScenePolygonStats* stats) {
    MBR_CHECK_MSG(tessellation >= 1, "tessellation " << tessellation);
    ScenePolygonStats s;
    std::vector<Polygon> polygons;
    for (int id = 0; id < static_cast<int>(scene.surfaces.size()); ++id) {
        const size_t first = polygons.size();
        for (const Facet& facet : scene.surfaces[id].surface.tessellate(tessellation)) {
            ++s.n_facets;
            if (facet.vertices.size() >= 3)
                if (std::optional<Polygon> p = try_polygon(Piece{facet.vertices, facet.uv}, id)) {
                    polygons.push_back(std::move(*p));
                    continue;
                }
            // Refused (or fewer than three vertices): merge near-duplicates and try again. Only
            // now, as merging changes the (u, v) map of the cell (a quad with a tiny edge is
            // a triangle in space but not in (u, v)).
            Piece piece = merged(facet);
            if (piece.vertices.size() < 3) {
                // Collapsed to a point or a segment: a sliver thinner than merge_tol.
                ++s.n_dropped;
                s.dropped_area += piece_area(Piece{facet.vertices, facet.uv});
                continue;
            }
            if (piece.vertices.size() < facet.vertices.size())
                if (std::optional<Polygon> p = try_polygon(piece, id)) {
                    polygons.push_back(std::move(*p));
                    continue;
                }
            if (piece.vertices.size() == 3) {
                ++s.n_dropped;
                s.dropped_area += piece_area(piece);
                continue;
            }
            // Refused whole: triangles keep the facet's edges (no crack towards neighbours). A
            // quad has two diagonals: take the split that leaves out less, else the shorter
            // diagonal (the better-shaped triangles).
            ++s.n_split;
            Split best = split(piece, 0, id);
            if (piece.vertices.size() == 4) {
                Split other = split(piece, 1, id);
                if (other.n_dropped < best.n_dropped ||
                    (other.n_dropped == best.n_dropped && other.diagonal < best.diagonal))
                    best = std::move(other);
            }
            s.n_dropped += best.n_dropped;
            s.dropped_area += best.dropped_area;
            for (Polygon& p : best.polygons) polygons.push_back(std::move(p));
        }
        if (polygons.size() == first) ++s.n_empty_surfaces;
        for (size_t k = first; k < polygons.size(); ++k)
            polygons[k].set_thickness(facet_thickness(scene.surfaces[id].surface, polygons[k]));
    }
    s.n_polygons = static_cast<int>(polygons.size());
    if (stats) *stats = s;
    return polygons;
}

Octree build_octree(const Scene& scene, const OctreeOptions& options, ScenePolygonStats* stats) {
    return Octree(scene_polygons(scene, scene.settings.tessellation, stats), options);
}

}  // namespace mbr
