// radiosity/reference/probe.h - probe points: world points where a user wants the radiosity B of
// eq. (1), to check mbr against an independent estimate (path_tracer.h) or against other renderers.
// A CSV of named points is read, each point is located on the nearest surface as (surface, u, v) of
// the parametric map of paper section 2, and results are written back as CSV.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "octree/polygon.h"
#include "radiosity/geometry/radiosity_view.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// One named world point of a probe file, with the normal of the face it is meant to lie on
/// when the file gives one (it decides between surfaces that meet at the point).
struct ProbePoint {
    std::string name;
    Vec3 position;
    bool has_normal = false;
    Vec3 normal;   // unit length when has_normal
    int line = 0;  // line of the file it came from, for messages
};

/// The longest line of a probe CSV, in bytes; a longer one is refused as soon as it passes this.
constexpr size_t max_probe_line = 65536;

/// Reads probe points from a CSV file: a header row, then one point per row. Columns `name`,
/// `x`, `y`, `z` are required, `nx`, `ny`, `nz` optional (all three or none), in any order;
/// other columns are ignored. Header names are matched without regard to case or surrounding
/// blanks; fields are trimmed; blank lines are skipped; `\r\n` line ends and a UTF-8 byte order
/// mark are accepted. Throws InputError(path, line, ...) for a missing or empty file, a folder,
/// device or FIFO (refused before it is read), a line longer than max_probe_line, a missing,
/// duplicate or half-given (normal) column, a row with the wrong number of fields, an empty or
/// repeated name, a field that is not a finite number, a coordinate beyond the scene format's
/// limit max_coordinate (1e8), a zero normal, or a file without points.
std::vector<ProbePoint> read_probe_points(const std::string& path);

/// The same from a stream; `name` is used in messages as the file name.
std::vector<ProbePoint> parse_probe_points(std::istream& in, const std::string& name);

/// A point of a surface: its index in Scene::surfaces, its parameters (u, v) in [0,1]^2, the
/// point x(u, v), and its distance from the world point that was located.
struct SurfaceLocation {
    int surface = -1;
    double u = 0, v = 0;
    Vec3 position;
    double distance = 0;
};

/// The point of surface `surface` nearest to p (a local minimum of the distance, found as
/// follows). Planar quads: p is projected onto the quad's plane (the plane through the
/// corners' mean normal to cross(p11 - p00, p01 - p10)), the bilinear map is inverted exactly
/// there and (u, v) clamped to [0,1]^2. Other kinds: the start is Polygon::uv_at on each of the
/// three `polygons` of that surface nearest to p. Every start is then refined by Gauss-Newton
/// steps on |x(u, v) - p|^2 projected onto [0,1]^2 (a no-op for a point inside a planar quad;
/// it finishes the clamped case and non-planar "planar" quads such as the Cornell box's red
/// wall) and the nearest result kept. `polygons` are the scene's tessellation (scene_polygons or
/// Octree::polygons()); planar quads do not need them.
SurfaceLocation nearest_on_surface(const Scene& scene, const std::vector<Polygon>& polygons,
                                   int surface, Vec3 p);

/// The point of any surface nearest to p, if one lies within `tolerance` (callers use 1e-3 of
/// the scene's bounding-box diagonal: probe_tolerance). Without a normal the nearest surface
/// wins (the lower index at equal distances). With a normal only surfaces whose front normal at
/// the found point faces the same way (positive dot product) count, and among those within
/// tolerance the one whose normal is closest to it wins, the nearer one when the dot products
/// agree to 1e-3 (a light just below a parallel ceiling, or one face split in two surfaces).
std::optional<SurfaceLocation> locate_on_surface(const Scene& scene,
                                                 const std::vector<Polygon>& polygons, Vec3 p,
                                                 double tolerance,
                                                 const std::optional<Vec3>& normal = {});

/// The default tolerance of locate_on_surface: 1e-3 of the scene's bounding-box diagonal.
double probe_tolerance(const Scene& scene);

/// Locates every point (with its normal when it has one) within `tolerance`. Throws
/// InputError(path, point.line, "point 'NAME' (x, y, z) is not on any surface: ...") naming the
/// nearest surface and its distance when no surface is close enough, or saying which surface is
/// close but faces away from the given normal.
std::vector<SurfaceLocation> locate_probe_points(const Scene& scene,
                                                 const std::vector<Polygon>& polygons,
                                                 const std::vector<ProbePoint>& points,
                                                 const std::string& path, double tolerance);

/// B at a located point, eq. (2): view.at(surface, u, v), except where the point is the image of
/// a whole parameter edge (a disk's centre, a sphere's pole: the edge u = 0 of a disk with r0 =
/// 0). There a field's value depends on the direction the point is approached from (on the room's
/// stool the values around its underside's centre spread by 9 % of their mean), and the located
/// (u, v) picks one direction arbitrarily; the mean along that edge is returned instead, the
/// limit of B's means over small circles around the point (8-point Gauss-Legendre on each of the
/// field's 2^level cells along the edge: exact for orders up to 16).
Rgb radiosity_at(const RadiosityView& view, const Scene& scene, const SurfaceLocation& at);

/// Writes `name,B_r,B_g,B_b` and one row per point (%.9g: doubles' values to 9 digits).
void write_radiosity_csv(std::ostream& os, const std::vector<std::string>& names,
                         const std::vector<Rgb>& radiosity);

/// Writes `name,B_r,B_g,B_b,se_r,se_g,se_b`: the values and their standard errors.
void write_radiosity_csv(std::ostream& os, const std::vector<std::string>& names,
                         const std::vector<Rgb>& radiosity, const std::vector<Rgb>& standard_error);

}  // namespace mbr
