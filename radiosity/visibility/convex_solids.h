// radiosity/visibility/convex_solids.h - occluders that are faces of one convex solid (a block of
// the Cornell box, a table top, a tessellated ball), found once per scene, and their silhouette
// seen from a receiving point: the shadow of the whole solid on a planar shooter's plane in one
// convex hull, instead of one projection per face and pairwise merges (paper section 6,
// "Shadow", with exact visibility; issue 20, "one silhouette per occluder").
//
// A solid here is a set of polygons, connected through shared edges (the same two vertices, to
// the bit) that are convex or flat (a floor meshed with the block on it is not joined to it),
// that bounds a convex polyhedron K: every vertex lies behind every face's plane (the faces look
// outward), each edge belongs to two faces or is covered by edges of others on its line (a
// T-junction), except the edges of at most two missing faces, the openings (a block standing on
// the floor has no bottom; a table leg tessellated as an open tube has neither top nor bottom),
// each in one plane that supports K.
// Seen from a point p outside K, every ray through K crosses a face of the set, unless it enters
// through an opening and ends inside K or leaves through the other opening (checked per point:
// solid_shadow), so the union of the faces' shadows is the shadow of K: the convex hull of the
// projected corners of K cut to the slab between the shooter's plane and p (solid_shadow,
// radiosity/visibility/visible_parts.h).
//
// A sheet is the other kind of caster found here: the polygons of one surface, not part of a
// solid, that form one disk with its faces turned one way (each edge in at most two of them,
// run opposite ways; one boundary loop; V - E + F = 1): a disk's sectors, a gently curved cloth.
// Seen from a point that sees every face from the same side, its projection is the region its
// projected boundary encloses; when that is convex, the shadow is one polygon (sheet_shadow,
// visible_parts.h) instead of one per face.
#pragma once

#include <array>
#include <vector>

#include "octree/polygon.h"

namespace mbr {

struct OcclusionContext;

/// A face a convex solid lacks (not in the scene): its plane, facing outward, and its outline.
struct SolidOpening {
    Plane plane;
    std::vector<int> outline;  // the vertices on its outline (indices into the solid's)
};

/// At most this many openings a solid (an open tube has two). DESIGN: two; with three (a box
/// without a top and two sides) rays pass through the solid along many more paths.
constexpr int max_solid_openings = 2;

/// One convex solid of a scene's polygons.
struct ConvexSolid {
    std::vector<int> polygons;              // polygon indices, increasing
    std::vector<Vec3> vertices;             // its corners (each once)
    std::vector<std::array<int, 2>> edges;  // vertex index pairs, each edge once
    std::vector<Plane> faces;               // the planes of its polygons, facing outward
    std::vector<SolidOpening> openings;     // its missing faces (none: closed)
    double diameter = 0;                    // of its bounding box
    bool open() const { return !openings.empty(); }
};

/// One sheet: the polygons of one surface forming a disk, faces turned one way.
struct ConvexSheet {
    std::vector<int> polygons;   // polygon indices, increasing
    std::vector<Vec3> vertices;  // every corner (each once)
    std::vector<Vec3> boundary;  // the corners along its boundary loop, in order
    std::vector<Plane> faces;    // the planes of its polygons
    double diameter = 0;         // of its bounding box
};

/// Sheets with more faces than this are not looked for (each receiving point tests every face).
/// DESIGN: 4096, above the room's cloth (1,152 triangles).
constexpr int max_sheet_faces = 4096;

/// The convex solids and sheets of a scene's polygons, and for each polygon its solid or sheet.
struct ConvexSolids {
    std::vector<ConvexSolid> solids;
    std::vector<int> solid_of;  // per polygon: the index of its solid, or -1
    std::vector<ConvexSheet> sheets;
    std::vector<int> sheet_of;  // per polygon: the index of its sheet, or -1 (never both)
};

/// Solids with more faces than this are not looked for (a silhouette's cost grows with the
/// solid's corners, its hull's with their logarithm too).
/// DESIGN: 1024, so that a tessellated sphere (256 facets at the default tessellation 16, 576 at
/// the room's 24) is one caster: at 64 its facets were loose, each counted against exact_limit,
/// and a point that saw the sphere cast one ray per quadrature node. corridor.mgf's sphere: 89.6
/// -> 68.3 s at the defaults, 137 -> 53 M rays (docs/method.md, "Shadows").
constexpr int max_solid_faces = 1024;

/// The convex solids among `polygons`, and the sheets among the others (linear in their
/// number: vertices matched by their bits).
ConvexSolids find_convex_solids(const std::vector<Polygon>& polygons);

/// Splits a pair's occluder candidates between whole solids and loose polygons: a solid with at
/// least one candidate face and no face on the pair's own two surfaces stands for all its faces
/// (a face of it that is no candidate cannot come between the pair: its shadow from a point of
/// the receiver misses the shooter). Sets context.solids, context.solid_ids and context.loose.
void attach_solids(OcclusionContext& context, const ConvexSolids& solids);

}  // namespace mbr
