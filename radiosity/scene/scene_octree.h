// radiosity/scene/scene_octree.h - from a scene to the paper's octree (section 6, "Octree";
// DESIGN.md section 5): every surface tessellated into planar polygons that carry the surface's
// index and the (u, v) of their vertices, so that a ray's hit names a point of a surface, and the
// octree built over them for the shadow rays of eq. (28) and for rendering.
#pragma once

#include <vector>

#include "octree/octree.h"
#include "octree/polygon.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// What scene_polygons made of the surfaces' facets.
struct ScenePolygonStats {
    int n_facets = 0;          // facets of all the surfaces' tessellations
    int n_polygons = 0;        // polygons made of them
    int n_split = 0;           // facets refused whole by Polygon, replaced by two triangles
    int n_dropped = 0;         // degenerate pieces refused even as triangles, left out
    double dropped_area = 0;   // their total area (slivers: next to nothing)
    int n_empty_surfaces = 0;  // surfaces left without a single polygon
};

/// Every surface's facets, Surface::tessellate(tessellation), as polygons: surface by surface in
/// scene order, facets in tessellation order; the surface id of a polygon is the index of its
/// surface in scene.surfaces and its vertices carry the facets' (u, v), so that a hit maps back
/// through scene.surfaces[hit.surface].surface.point(hit.uv). A planar quad stays one polygon,
/// exact (Polygon's inverse bilinear (u, v) is the quad's own map), if Polygon accepts it.
/// Facets the Polygon constructor refuses do not stop the build: vertices closer than 1e-8 of the
/// facet's size are merged and the facet is tried again; a facet still refused (a quad beyond
/// Polygon's planarity tolerance of 1e-6, such as the Cornell box's red wall at 1e-3, which the
/// scene format allows; rounding on small facets far from the origin) becomes two triangles along a
/// diagonal, which keeps its edges and corners, so neighbours still meet without a crack; a
/// triangle refused even so (zero area, an angle below 1e-7 rad) covers next to nothing and is left
/// out. Limits of Polygon, not of the surfaces: facets thinner than about 1e-8 of their length, or
/// smaller than about 1e-10 of their distance from the origin (where rounding of the coordinates
/// beats Polygon's planarity tolerance, even for triangles), are partly or wholly lost. *stats, if
/// given, counts all this; n_dropped and n_empty_surfaces are zero for any reasonable scene.
std::vector<Polygon> scene_polygons(const Scene& scene, int tessellation,
                                    ScenePolygonStats* stats = nullptr);

/// The paper's octree over scene_polygons(scene, scene.settings.tessellation), built with
/// `options`; *stats, if given, receives scene_polygons' counts.
Octree build_octree(const Scene& scene, const OctreeOptions& options = {},
                    ScenePolygonStats* stats = nullptr);

}  // namespace mbr
