// radiosity/output/export.h - the solved scene as triangle meshes for viewers (Blender, three.js,
// MeshLab): every surface tessellated on a regular grid of its parameter domain at its field's
// resolution, with the radiosity B_i(u, v) (eq. (20), radiosity_view) at each vertex, written as
// glTF 2.0 binary (.glb, optionally with a baked lightmap atlas) or as binary PLY. Radiosity is
// view-independent: solve once, look from anywhere. docs/export.md describes the files.
//
// The colour rule, the same as the renderer's (render.h): what a viewer shows is the radiance
// B / pi times an exposure, clipped to [0, 1]; glTF's COLOR_0 holds that linear value (the
// viewer encodes it to sRGB), PLY's red/green/blue and the lightmap's texels hold its 8-bit sRGB
// encoding (tone_map), so all three show mbr render's picture. The unclipped linear B itself is
// in every file too (glTF: the _RADIOSITY attribute; PLY: radiosity_r/g/b), for analysis.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/geometry/radiosity_view.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/output/image.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// The largest grid an exported surface gets: n intervals along u and along v.
constexpr int max_export_resolution = 256;

/// One vertex of an exported surface.
struct ExportVertex {
    Vec3 position;  // x(u, v)
    Vec3 normal;    // the unit normal n(u, v), towards the front
    Vec2 uv;        // (u, v) on the surface's domain [0,1]^2
    Rgb radiosity;  // B(u, v), linear, emission included (black without a field)
};

/// One surface as a triangle mesh of its own: its vertices are not shared with (welded to) any
/// other surface's, since the radiosity is discontinuous from one surface to the next.
struct ExportSurface {
    std::string name;      // the surface's name (SceneSurface::name)
    std::string material;  // its material's name
    int surface = -1;      // its index in Scene::surfaces (and in the RadiosityView)
    int resolution = 0;    // n: the vertices form the (n+1) x (n+1) grid (u, v) = (a/n, b/n)
    std::vector<ExportVertex> vertices;                   // vertex (a, b) at index b (n+1) + a
    std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from the
                                                          // front; zero-area ones left out
};

/// Every surface of a scene, in scene order.
struct ExportMesh {
    std::vector<ExportSurface> surfaces;
    /// Vertices and triangles of all surfaces together.
    long vertex_count() const;
    long triangle_count() const;
};

/// The grid size n of a surface's export: twice the knot intervals 2^level of its field along
/// each direction (a cubic's shape shows between knots), at least 2; for a surface that is not
/// a planar quad (a bilinear patch, cylinder, sphere or disk: curved, or bounded by an arc) at
/// least `tessellation` (the scene's ray-casting tessellation); at most max_resolution. `field`
/// may be null or empty (no field: level 0).
int export_resolution(const Surface& surface, const SplineField* field, int tessellation,
                      int max_resolution = max_export_resolution);

/// Every surface tessellated for export: the (n+1) x (n+1) grid of export_resolution (with the
/// scene's settings.tessellation), positions Surface::point, normals Surface::normal, B =
/// view.at(i, u, v) (black where view.empty(i)). Each grid cell gives two triangles,
/// (a,b) (a+1,b) (a+1,b+1) and (a,b) (a+1,b+1) (a,b+1), turned where needed so that their
/// winding is counter-clockwise seen from the side the vertex normals point to; triangles of
/// zero area (their float positions, as at a sphere's pole) are dropped. Parallel over surfaces.
ExportMesh tessellate_for_export(const Scene& scene, const RadiosityView& view,
                                 int max_resolution = max_export_resolution);

/// What a viewer should show for radiosity B: per channel exposure x B / pi (the radiance of a
/// Lambertian surface), clipped to [0, 1] (NaN to 0): linear, not yet sRGB-encoded. glTF's
/// COLOR_0; tone_map (render.h) then encodes it, for PNG texels and PLY's 8-bit colours.
Rgb display_colour(Rgb radiosity, double exposure);

/// The same as 8-bit sRGB codes, lround(255 linear_to_srgb(display_colour)): the pixel mbr
/// render's PNG gives for that radiosity.
std::array<std::uint8_t, 3> display_colour_srgb8(Rgb radiosity, double exposure);

// ---- Lightmaps: every surface's B baked into one square texture atlas ----------------------

/// The sizes --lightmaps accepts: powers of two in this range.
constexpr int min_lightmap_size = 16, max_lightmap_size = 4096;
/// True for a power of two in [min_lightmap_size, max_lightmap_size].
bool valid_lightmap_size(int size);

/// Where each surface's square tile lies in a size x size atlas, in texels, row 0 at the top.
/// Tiles of `tile` x `tile` texels sit on a grid of `columns` x `columns`, surface k at column
/// k % columns, row k / columns (columns = ceil(sqrt(surfaces))). The outer `gutter` texels of a
/// tile repeat its edge texels (so that bilinear filtering at the edge does not blend in a
/// neighbour); the `inner` x `inner` texels inside sample the surface at their centres:
/// inner texel (a, r) at (u, v) = ((a + 0.5) / inner, 1 - (r + 0.5) / inner): u to the right,
/// v upwards, as image textures are read (texture.h).
struct LightmapLayout {
    int size = 0;      // the atlas is size x size texels
    int surfaces = 0;  // tiles
    int columns = 0;   // tiles per row (and at most that many rows)
    int tile = 0;      // tile side, texels, gutter included: size / columns, rounded down
    int gutter = 0;    // 2 when tile >= 16, else 1
    int inner = 0;     // tile - 2 gutter, at least 2
    /// The top-left texel (x, y) of tile k.
    int tile_x(int k) const { return (k % columns) * tile; }
    int tile_y(int k) const { return (k / columns) * tile; }
    /// glTF's TEXCOORD_0 of surface k's point (u, v): (0, 0) the atlas's top-left corner,
    /// (1, 1) its bottom-right one; u = 0..1 spans the inner texels' outer edges.
    Vec2 texcoord(int k, Vec2 uv) const;
};

/// The layout for `surfaces` tiles in a size x size atlas. Throws std::invalid_argument when
/// the size is not valid_lightmap_size or the tiles would have fewer than 2 x 2 inner texels
/// (smallest_lightmap_size says the least size that works).
LightmapLayout lightmap_layout(int surfaces, int size);

/// The least valid size whose layout gives `surfaces` tiles at least 2 x 2 inner texels, or 0
/// when even max_lightmap_size does not.
int smallest_lightmap_size(int surfaces);

/// The atlas as linear radiance B / pi (Image values, unclipped): surface k's tile holds
/// view.at(k, u, v) / pi at its inner texels' centres (LightmapLayout), the gutter repeats the
/// nearest inner texel, texels outside every tile are black. layout.surfaces must equal
/// view.size(). Parallel over rows of tiles.
Image bake_lightmap(const RadiosityView& view, const LightmapLayout& layout);

/// A baked lightmap, ready for the GLB: its layout and the PNG of tone_map(bake_lightmap,
/// exposure).
struct Lightmap {
    LightmapLayout layout;
    std::string png;
};

/// bake_lightmap, tone-mapped with `exposure` (8-bit sRGB, as mbr render's PNG) and encoded.
Lightmap make_lightmap(const RadiosityView& view, int size, double exposure);

/// An upper bound of the memory of an export beside the solve, before it is solved: every
/// surface at the largest grid export_resolution can give it under the scene's settings (a
/// field's level at most max_depth, or 5 for a textured emission), its vertices, triangles and
/// encoded file, and with lightmap_size > 0 the atlas's texels and PNG. For the memory check of
/// `mbr export` (radiosity/solver/cost.h's estimate of the solve plus this).
double export_bytes(const Scene& scene, int lightmap_size = 0);

// ---- The files ------------------------------------------------------------------------------

/// Options of encode_glb.
struct GlbOptions {
    double exposure = 1;                 // the colour rule's multiplier (display_colour)
    const Lightmap* lightmap = nullptr;  // with one: TEXCOORD_0 and a baseColorTexture instead
                                         // of COLOR_0
    std::string scene_name;              // the glTF scene's name (e.g. the scene file's)
};

/// The bytes of a glTF 2.0 binary file (GLB): the 12-byte header ("glTF", version 2, length), the
/// JSON chunk (padded with spaces to 4 bytes) and the BIN chunk (padded with zeros). One mesh
/// and one node per surface with triangles, both named after the surface (its material in the
/// node's extras), one scene. Each primitive: POSITION (float VEC3, exact min/max), NORMAL
/// (float VEC3, unit), _RADIOSITY (float VEC3: B, linear, unclipped), indices (UNSIGNED_SHORT
/// below 65536 vertices, else UNSIGNED_INT), and without a lightmap COLOR_0 (float VEC3:
/// display_colour), with one TEXCOORD_0 (float VEC2: LightmapLayout::texcoord) and no COLOR_0,
/// since glTF multiplies the base colour texture by COLOR_0. One material, unlit
/// (KHR_materials_unlit), baseColorFactor 1, its baseColorTexture the lightmap's PNG (embedded
/// through a bufferView, linear filtering, clamped to the edge). asset.extras records the colour
/// rule and the exposure. Coordinates as in the scene (glTF reads them as metres, Y up).
/// Throws std::length_error when the file would exceed GLB's 4 GiB.
std::string encode_glb(const ExportMesh& mesh, const GlbOptions& options = {});

/// The bytes of a binary little-endian PLY 1.0 file: per vertex float x y z nx ny nz, uchar
/// red green blue (display_colour_srgb8), float radiosity_r radiosity_g radiosity_b (B, linear,
/// unclipped); per face `list uchar int vertex_indices` (triangles, indices into all vertices,
/// surface after surface). Comment lines give the colour rule, the exposure and each surface's
/// name, material and range of vertices and faces.
std::string encode_ply(const ExportMesh& mesh, double exposure = 1);

}  // namespace mbr
