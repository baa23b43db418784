// radiosity/reference/probe.cpp - probe points (probe.h): the CSV reader, locating world points on
// the parametric surfaces of paper section 2, and the CSV writer of results.
#include "radiosity/reference/probe.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <map>
#include <ostream>
#include <sstream>

#include "math/check.h"
#include "math/gauss_legendre.h"
#include "radiosity/scene/faces_to_quads.h"
#include "radiosity/scene/line_reader.h"

namespace mbr {

namespace {

// ---- CSV reading ---------------------------------------------------------------------------

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// The CSV's lines (radiosity/scene/line_reader.h): fields split at commas and trimmed of spaces
// and tabs, one trailing '\r' dropped, a UTF-8 byte order mark on line 1 dropped, lines of blanks
// skipped; no comments, any bytes inside a field, lines of at most max_probe_line bytes (the
// scene format's limit: a row holds a name and a few numbers).
LineFormat csv_format() {
    LineFormat f;
    f.max_length = max_probe_line;
    f.comments = false;
    f.control_bytes = true;
    f.separator = ',';
    return f;
}

double parse_field(const std::string& field, const std::string& column, const std::string& file,
                   int line) {
    if (field.empty()) throw InputError(file, line, "column '" + column + "' is empty");
    const char* begin = field.c_str();
    char* end = nullptr;
    const double value = std::strtod(begin, &end);
    if (end != begin + field.size())
        throw InputError(file, line, "column '" + column + "': '" + field + "' is not a number");
    if (std::isnan(value)) throw InputError(file, line, "column '" + column + "' is NaN");
    if (!std::isfinite(value))
        throw InputError(file, line, "column '" + column + "': '" + field + "' is not finite");
    return value;
}

std::string format_point(Vec3 p) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "(%g, %g, %g)", p.x, p.y, p.z);
    return buf;
}

std::string format_g(double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", x);
    return buf;
}

// ---- Locating points on surfaces -----------------------------------------------------------

double box_distance(const Box3& box, Vec3 p) {
    if (box.empty()) return HUGE_VAL;
    Vec3 d;
    for (int i = 0; i < 3; ++i) d[i] = std::max({0.0, box.lo[i] - p[i], p[i] - box.hi[i]});
    return length(d);
}

double segment_distance(Vec3 p, Vec3 a, Vec3 b) {
    const Vec3 ab = b - a;
    const double l2 = dot(ab, ab);
    const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
    return length(p - (a + t * ab));
}

double polygon_distance(const Polygon& polygon, Vec3 p) {
    const double h = polygon.plane().signed_distance(p);
    if (polygon.contains(p - h * polygon.normal())) return std::fabs(h);
    double d = HUGE_VAL;
    const std::vector<Vec3>& v = polygon.vertices();
    for (size_t i = 0; i < v.size(); ++i)
        d = std::min(d, segment_distance(p, v[i], v[(i + 1) % v.size()]));
    return d;
}

// The exact inverse of a planar quad's bilinear map at the projection of p onto its plane, with
// (u, v) clamped to [0,1]^2. Of the two roots of the quadratic, the one nearer the domain.
Vec2 invert_planar_quad(const Surface& s, Vec3 p) {
    const Vec3* c = s.corners();
    const Vec3 n = normalize(cross(c[2] - c[0], c[3] - c[1]));
    const Vec3 origin = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    const Vec3 edge = c[1] - c[0];
    const Vec3 axis_a = normalize(edge - dot(edge, n) * n);
    const Vec3 axis_b = cross(n, axis_a);
    auto local = [&](Vec3 x) { return Vec2{dot(x - origin, axis_a), dot(x - origin, axis_b)}; };
    // q = a + u E + v F + u v G, solved for v from cross(H - v F, E + v G) = 0.
    const Vec2 a = local(c[0]), h = local(p) - a;
    const Vec2 e = local(c[1]) - a, f = local(c[3]) - a;
    const Vec2 g = a - local(c[1]) + local(c[2]) - local(c[3]);
    const double k2 = cross(g, f), k1 = cross(e, f) + cross(h, g), k0 = cross(h, e);
    std::vector<double> roots;
    const double disc = std::max(0.0, k1 * k1 - 4 * k2 * k0);
    const double q = -0.5 * (k1 + std::copysign(std::sqrt(disc), k1));
    if (q != 0) roots.push_back(k0 / q);
    if (k2 != 0) roots.push_back(q / k2);
    if (roots.empty()) roots.push_back(0.5);  // h = 0 and a degenerate quad: any start will do
    auto outside = [](Vec2 uv) {
        return std::max({0.0, -uv.x, uv.x - 1}) + std::max({0.0, -uv.y, uv.y - 1});
    };
    Vec2 best{0.5, 0.5};
    double best_out = HUGE_VAL;
    for (double v : roots) {
        if (!std::isfinite(v)) continue;
        const Vec2 w = e + v * g;  // u solves h - v f = u w in the least-squares sense
        const double ww = dot(w, w);
        const double u = ww > 0 ? dot(h - v * f, w) / ww : 0.5;
        const Vec2 uv{u, v};
        if (outside(uv) < best_out) {
            best_out = outside(uv);
            best = uv;
        }
    }
    return {std::clamp(best.x, 0.0, 1.0), std::clamp(best.y, 0.0, 1.0)};
}

// Projected Gauss-Newton on |x(u, v) - p|^2 over [0,1]^2 (Bertsekas 1982): a parameter at a
// bound whose gradient points out of the domain is held there and the other takes the Newton
// step of the reduced problem; steps are clamped to the domain and halved until the distance
// falls. A tiny Levenberg term keeps the 2 x 2 system solvable where x_u or x_v vanishes (a
// sphere's pole, a disk's centre).
Vec2 refine(const Surface& s, Vec3 p, Vec2 uv) {
    double d2 = length_squared(s.point(uv.x, uv.y) - p);
    for (int iteration = 0; iteration < 50 && d2 > 0; ++iteration) {
        Vec3 x_u, x_v;
        s.tangents(uv.x, uv.y, x_u, x_v);
        const Vec3 r = p - s.point(uv.x, uv.y);
        const double a = dot(x_u, x_u), b = dot(x_u, x_v), c = dot(x_v, x_v);
        const double lambda = 1e-12 * (a + c);
        const double g_u = dot(x_u, r), g_v = dot(x_v, r);  // minus half the gradient
        const bool hold_u = (uv.x <= 0 && g_u <= 0) || (uv.x >= 1 && g_u >= 0);
        const bool hold_v = (uv.y <= 0 && g_v <= 0) || (uv.y >= 1 && g_v >= 0);
        Vec2 step;
        if (hold_u && hold_v) break;  // a corner of the domain is the constrained minimum
        if (hold_u) {
            if (!(c + lambda > 0)) break;
            step = {0, g_v / (c + lambda)};
        } else if (hold_v) {
            if (!(a + lambda > 0)) break;
            step = {g_u / (a + lambda), 0};
        } else {
            const double det = (a + lambda) * (c + lambda) - b * b;
            if (!(det > 0)) break;
            step = {((c + lambda) * g_u - b * g_v) / det, ((a + lambda) * g_v - b * g_u) / det};
        }
        bool improved = false;
        for (double scale = 1; scale > 1e-6 && !improved; scale *= 0.5) {
            const Vec2 next{std::clamp(uv.x + scale * step.x, 0.0, 1.0),
                            std::clamp(uv.y + scale * step.y, 0.0, 1.0)};
            const double next_d2 = length_squared(s.point(next.x, next.y) - p);
            if (next_d2 < d2) {
                uv = next;
                d2 = next_d2;
                improved = true;
            }
        }
        if (!improved) break;
    }
    return uv;
}

SurfaceLocation location_at(const Surface& s, int surface, Vec3 p, Vec2 uv) {
    SurfaceLocation loc;
    loc.surface = surface;
    loc.u = uv.x;
    loc.v = uv.y;
    loc.position = s.point(uv.x, uv.y);
    loc.distance = length(loc.position - p);
    return loc;
}

// DESIGN: curved surfaces start from the three nearest of their polygons: one start may sit on
// the wrong side of a seam (u = 0 and u = 1 of a whole cylinder meet) or of a fold, where the
// projected Newton steps stop at the domain's edge.
constexpr int n_starts = 3;

// The nearest point of surface `id` from the (u, v) of the given start polygons.
SurfaceLocation nearest_from(const Scene& scene, const std::vector<Polygon>& polygons, int id,
                             Vec3 p, const std::vector<int>& starts) {
    const Surface& s = scene.surfaces[id].surface;
    std::vector<Vec2> uvs;
    if (s.kind() == Surface::Kind::PlanarQuad) {
        uvs.push_back(invert_planar_quad(s, p));
    } else {
        for (int k : starts) {
            const Vec2 uv = polygons[k].uv_at(p);
            uvs.push_back({std::clamp(uv.x, 0.0, 1.0), std::clamp(uv.y, 0.0, 1.0)});
        }
        if (uvs.empty())  // no polygon of this surface survived tessellation: a coarse grid
            for (double u : {1.0 / 6, 0.5, 5.0 / 6})
                for (double v : {1.0 / 6, 0.5, 5.0 / 6}) uvs.push_back({u, v});
    }
    SurfaceLocation best;
    best.distance = HUGE_VAL;
    for (Vec2 uv : uvs) {
        SurfaceLocation loc = location_at(s, id, p, refine(s, p, uv));
        if (loc.distance < best.distance) best = loc;
    }
    return best;
}

// The n_starts polygons of each surface nearest to p, for the surfaces whose boxes lie within
// `reach` of p.
std::map<int, std::vector<int>> start_polygons(const Scene& scene,
                                               const std::vector<Polygon>& polygons, Vec3 p,
                                               double reach) {
    std::map<int, std::vector<std::pair<double, int>>> near;
    for (int k = 0; k < static_cast<int>(polygons.size()); ++k) {
        const int id = polygons[k].surface();
        if (id < 0 || id >= static_cast<int>(scene.surfaces.size())) continue;
        if (scene.surfaces[id].surface.kind() == Surface::Kind::PlanarQuad) continue;
        if (box_distance(scene.surfaces[id].surface.bounds(), p) > reach) continue;
        near[id].push_back({polygon_distance(polygons[k], p), k});
    }
    std::map<int, std::vector<int>> starts;
    for (auto& [id, list] : near) {
        const size_t n = std::min<size_t>(n_starts, list.size());
        std::partial_sort(list.begin(), list.begin() + n, list.end());
        for (size_t i = 0; i < n; ++i) starts[id].push_back(list[i].second);
    }
    return starts;
}

}  // namespace

// ---- CSV reading ---------------------------------------------------------------------------

std::vector<ProbePoint> parse_probe_points(std::istream& in, const std::string& name) {
    LineReader reader(in, name, csv_format());
    Line line;
    if (!reader.next(line)) throw InputError(name, 0, "the file is empty: expected a header row");
    const int header_line = line.number;

    // Column indices of the known names.
    const std::vector<std::string> header = line.tokens;
    std::map<std::string, int> column;
    for (int i = 0; i < static_cast<int>(header.size()); ++i) {
        const std::string key = lower(header[i]);
        if (key.empty()) continue;
        if (column.count(key))
            throw InputError(name, header_line, "column '" + header[i] + "' appears twice");
        column[key] = i;
    }
    for (const char* required : {"name", "x", "y", "z"})
        if (!column.count(required))
            throw InputError(name, header_line,
                             std::string("missing column '") + required +
                                 "' (the header must name columns name, x, y, z and "
                                 "optionally nx, ny, nz)");
    const int n_normal = int(column.count("nx") + column.count("ny") + column.count("nz"));
    if (n_normal != 0 && n_normal != 3)
        throw InputError(name, header_line,
                         "columns nx, ny, nz must be given all three or none (found " +
                             std::to_string(n_normal) + ")");

    std::vector<ProbePoint> points;
    std::map<std::string, int> first_line;
    while (reader.next(line)) {
        const int line_no = line.number;
        const std::vector<std::string>& fields = line.tokens;
        if (fields.size() != header.size())
            throw InputError(name, line_no,
                             "expected " + std::to_string(header.size()) +
                                 " fields as in the header, found " +
                                 std::to_string(fields.size()));
        ProbePoint point;
        point.line = line_no;
        point.name = fields[column["name"]];
        if (point.name.empty()) throw InputError(name, line_no, "the point has no name");
        auto [it, inserted] = first_line.emplace(point.name, line_no);
        if (!inserted)
            throw InputError(name, line_no,
                             "point name '" + point.name + "' is used before, on line " +
                                 std::to_string(it->second));
        auto number = [&](const char* key) {
            return parse_field(fields[column[key]], header[column[key]], name, line_no);
        };
        // A point lies where the scene's surfaces may lie: within the coordinate limit of the
        // scene format (faces_to_quads.h), beyond which distances to it overflow.
        for (const char* key : {"x", "y", "z"}) {
            const double c = number(key);
            if (!(std::fabs(c) <= max_coordinate))
                throw InputError(name, line_no,
                                 "column '" + header[column[key]] + "': " + detail::fmt(c) +
                                     " exceeds the coordinate limit " +
                                     detail::fmt(max_coordinate));
        }
        point.position = {number("x"), number("y"), number("z")};
        if (n_normal == 3) {
            Vec3 n{number("nx"), number("ny"), number("nz")};
            if (n.x == 0 && n.y == 0 && n.z == 0)
                throw InputError(name, line_no, "the normal (nx, ny, nz) is zero");
            // Only the direction counts: scaled to a largest component of 1 first, so that a
            // normal of huge (or tiny) components neither overflows nor underflows.
            const double big = std::max({std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)});
            n = {n.x / big, n.y / big, n.z / big};
            point.has_normal = true;
            point.normal = normalize(n);
        }
        points.push_back(point);
    }
    if (points.empty()) throw InputError(name, header_line, "the file has a header but no points");
    return points;
}

std::vector<ProbePoint> read_probe_points(const std::string& path) {
    std::ifstream in;
    detail::open_input(path, "probe point file", in);
    return parse_probe_points(in, path);
}

// ---- Locating points on surfaces -----------------------------------------------------------

SurfaceLocation nearest_on_surface(const Scene& scene, const std::vector<Polygon>& polygons,
                                   int surface, Vec3 p) {
    MBR_CHECK_MSG(surface >= 0 && surface < static_cast<int>(scene.surfaces.size()),
                  "surface " << surface);
    const std::map<int, std::vector<int>> starts = start_polygons(scene, polygons, p, HUGE_VAL);
    auto it = starts.find(surface);
    return nearest_from(scene, polygons, surface, p,
                        it == starts.end() ? std::vector<int>{} : it->second);
}

std::optional<SurfaceLocation> locate_on_surface(const Scene& scene,
                                                 const std::vector<Polygon>& polygons, Vec3 p,
                                                 double tolerance,
                                                 const std::optional<Vec3>& normal) {
    MBR_CHECK_MSG(tolerance >= 0, "tolerance " << tolerance);
    const std::map<int, std::vector<int>> starts = start_polygons(scene, polygons, p, tolerance);
    struct Candidate {
        SurfaceLocation location;
        double alignment;  // dot(front normal, given normal); 0 without a normal
    };
    std::vector<Candidate> candidates;
    for (int id = 0; id < static_cast<int>(scene.surfaces.size()); ++id) {
        const Surface& s = scene.surfaces[id].surface;
        if (box_distance(s.bounds(), p) > tolerance) continue;
        auto it = starts.find(id);
        const SurfaceLocation loc = nearest_from(
            scene, polygons, id, p, it == starts.end() ? std::vector<int>{} : it->second);
        if (!(loc.distance <= tolerance)) continue;
        double alignment = 0;
        if (normal) {
            alignment = dot(s.normal(loc.u, loc.v), normalize(*normal));
            if (!(alignment > 0)) continue;  // faces away: the point is on its back
        }
        candidates.push_back({loc, alignment});
    }
    if (candidates.empty()) return std::nullopt;
    // DESIGN: normals agreeing to 1e-3 in their dot product (2.6 degrees) count as the same
    // direction, and then distance decides.
    double best_alignment = -HUGE_VAL;
    for (const Candidate& c : candidates) best_alignment = std::max(best_alignment, c.alignment);
    const Candidate* best = nullptr;
    for (const Candidate& c : candidates)
        if (c.alignment >= best_alignment - 1e-3 &&
            (!best || c.location.distance < best->location.distance))
            best = &c;
    return best->location;
}

double probe_tolerance(const Scene& scene) {
    const Box3 box = scene.bounds();
    return box.empty() ? 0.0 : 1e-3 * length(box.extent());
}

std::vector<SurfaceLocation> locate_probe_points(const Scene& scene,
                                                 const std::vector<Polygon>& polygons,
                                                 const std::vector<ProbePoint>& points,
                                                 const std::string& path, double tolerance) {
    std::vector<SurfaceLocation> locations;
    for (const ProbePoint& point : points) {
        std::optional<Vec3> normal;
        if (point.has_normal) normal = point.normal;
        if (auto loc = locate_on_surface(scene, polygons, point.position, tolerance, normal)) {
            locations.push_back(*loc);
            continue;
        }
        const std::string what =
            "point '" + point.name + "' " + format_point(point.position) + " is not on any surface";
        const auto nearest = locate_on_surface(scene, polygons, point.position, HUGE_VAL);
        if (!nearest) throw InputError(path, point.line, what + ": the scene has no surfaces");
        const std::string surface_name = "'" + scene.surfaces[nearest->surface].name + "'";
        if (nearest->distance <= tolerance) {
            const SurfaceLocation& n = *nearest;
            const Vec3 front = scene.surfaces[n.surface].surface.normal(n.u, n.v);
            throw InputError(path, point.line,
                             what + " facing along its normal " + format_point(point.normal) +
                                 ": the nearest, " + surface_name + " (" + format_g(n.distance) +
                                 " away), faces " + format_point(front));
        }
        throw InputError(path, point.line,
                         what + ": the nearest is " + surface_name + ", " +
                             format_g(nearest->distance) + " away, more than the tolerance " +
                             format_g(tolerance));
    }
    return locations;
}

// ---- Values at located points ---------------------------------------------------------------

namespace {

// The parameter edge of s that the map collapses onto p, if any: axis 0 for an edge u = const, 1
// for v = const, and that constant (0 or 1). Measured, not read from the kind: x at nine points
// of the edge within 1e-9 of the surface's box diagonal of each other and of p.
struct CollapsedEdge {
    int axis = -1;
    double at = 0;
};

CollapsedEdge collapsed_edge_at(const Surface& s, Vec3 p) {
    const double eps = 1e-9 * length(s.bounds().extent());
    for (int axis = 0; axis < 2; ++axis)
        for (double at : {0.0, 1.0}) {
            bool collapses = true;
            for (int k = 0; k <= 8 && collapses; ++k) {
                const double t = k / 8.0;
                const Vec3 x = axis == 0 ? s.point(at, t) : s.point(t, at);
                collapses = length(x - p) <= eps;
            }
            if (collapses) return {axis, at};
        }
    return {};
}

}  // namespace

Rgb radiosity_at(const RadiosityView& view, const Scene& scene, const SurfaceLocation& at) {
    MBR_CHECK(at.surface >= 0 && at.surface < static_cast<int>(scene.surfaces.size()));
    const CollapsedEdge edge = collapsed_edge_at(scene.surfaces[at.surface].surface, at.position);
    if (edge.axis < 0 || view.empty(at.surface)) return view.at(at.surface, at.u, at.v);
    // The mean of B along the edge: Gauss-Legendre on each cell of the field's grid.
    const int cells = 1 << view.surface(at.surface).field->level();
    const GaussLegendre rule = gauss_legendre(8);
    Rgb sum;
    for (int c = 0; c < cells; ++c)
        sum += integrate_1d(
            [&](double t) {
                return edge.axis == 0 ? view.at(at.surface, edge.at, t)
                                      : view.at(at.surface, t, edge.at);
            },
            double(c) / cells, double(c + 1) / cells, rule);
    return sum;
}

// ---- Writing results -----------------------------------------------------------------------

void write_radiosity_csv(std::ostream& os, const std::vector<std::string>& names,
                         const std::vector<Rgb>& radiosity) {
    MBR_CHECK(names.size() == radiosity.size());
    os << "name,B_r,B_g,B_b\n";
    char buf[160];
    for (size_t i = 0; i < names.size(); ++i) {
        const Rgb& b = radiosity[i];
        std::snprintf(buf, sizeof buf, ",%.9g,%.9g,%.9g\n", b.r, b.g, b.b);
        os << names[i] << buf;
    }
}

void write_radiosity_csv(std::ostream& os, const std::vector<std::string>& names,
                         const std::vector<Rgb>& radiosity,
                         const std::vector<Rgb>& standard_error) {
    MBR_CHECK(names.size() == radiosity.size() && names.size() == standard_error.size());
    os << "name,B_r,B_g,B_b,se_r,se_g,se_b\n";
    char buf[320];
    for (size_t i = 0; i < names.size(); ++i) {
        const Rgb& b = radiosity[i];
        const Rgb& se = standard_error[i];
        std::snprintf(buf, sizeof buf, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", b.r, b.g, b.b, se.r,
                      se.g, se.b);
        os << names[i] << buf;
    }
}

}  // namespace mbr
