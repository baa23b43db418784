// radiosity/scene/faces_to_quads.cpp - planar quads (faces_to_quads.h): planar_quad_problem and
// OBJ faces to quads by fans around the centre or ear clipping.
#include "radiosity/scene/faces_to_quads.h"

#include <algorithm>
#include <cmath>

namespace mbr {

using namespace detail;

namespace {

// ---------------------------------------------------------------------------------------------
// === Polygon measures

/// Newell's vector area: twice the area vector of a closed polygon (exact for planar ones).
Vec3 newell_normal(const std::vector<Vec3>& p) {
    Vec3 n;
    for (size_t i = 0; i < p.size(); ++i) n += cross(p[i], p[(i + 1) % p.size()]);
    return n;
}

/// Largest distance of a corner from the plane through the corners' average with normal n.
double plane_deviation(const std::vector<Vec3>& p, Vec3 n) {
    Vec3 c;
    for (const Vec3& q : p) c += q;
    c = c / double(p.size());
    double dev = 0;
    for (const Vec3& q : p) dev = std::max(dev, std::fabs(dot(q - c, n)));
    return dev;
}

/// Sine of the turn at corner i (positive: a left turn seen from the side n points to).
double turn_sine(const std::vector<Vec3>& p, size_t i, Vec3 n) {
    size_t k = p.size();
    Vec3 e1 = p[i] - p[(i + k - 1) % k], e2 = p[(i + 1) % k] - p[i];
    double l = length(e1) * length(e2);
    return l > 0 ? dot(cross(e1, e2), n) / l : 0;
}

// ---------------------------------------------------------------------------------------------
// === Faces: triangles, fans and ear clipping

/// A triangle as three quads (corner, edge midpoint, centroid, edge midpoint), same orientation.
void triangle_to_quads(Vec3 a, Vec3 b, Vec3 c, std::vector<Quad>& out) {
    Vec3 g = (a + b + c) / 3.0;
    Vec3 m_ab = 0.5 * (a + b), m_bc = 0.5 * (b + c), m_ca = 0.5 * (c + a);
    out.push_back({a, m_ab, g, m_ca});
    out.push_back({b, m_bc, g, m_ab});
    out.push_back({c, m_ca, g, m_bc});
}

/// Projects a polygon onto the plane normal to the unit vector n (counter-clockwise about n).
std::vector<Vec2> project(const std::vector<Vec3>& p, Vec3 n) {
    Vec3 t1 = normalize(std::fabs(n.x) < 0.9 ? cross(n, Vec3{1, 0, 0}) : cross(n, Vec3{0, 1, 0}));
    Vec3 t2 = cross(n, t1);
    std::vector<Vec2> q;
    for (const Vec3& x : p) q.push_back({dot(x, t1), dot(x, t2)});
    return q;
}

/// True when no two edges of the closed 2D polygon meet except adjacent ones at their shared
/// corner (touching counts as meeting).
bool is_simple(const std::vector<Vec2>& q) {
    auto orient = [](Vec2 a, Vec2 b, Vec2 c) {
        double d = cross(b - a, c - a);
        return d > 0 ? 1 : (d < 0 ? -1 : 0);
    };
    auto on_segment = [](Vec2 a, Vec2 b, Vec2 c) {  // c collinear with a, b: within the box?
        return std::min(a.x, b.x) <= c.x && c.x <= std::max(a.x, b.x) &&
               std::min(a.y, b.y) <= c.y && c.y <= std::max(a.y, b.y);
    };
    auto meet = [&](Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
        int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
        if (o1 != o2 && o3 != o4) return true;
        return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) ||
               (o3 == 0 && on_segment(c, d, a)) || (o4 == 0 && on_segment(c, d, b));
    };
    size_t k = q.size();
    for (size_t i = 0; i < k; ++i)
        for (size_t j = i + 2; j < k; ++j) {
            if (i == 0 && j == k - 1) continue;  // adjacent through the wrap
            if (meet(q[i], q[(i + 1) % k], q[j], q[(j + 1) % k])) return false;
        }
    return true;
}

/// Ear clipping in the plane normal to n, choosing the ear with the shortest new diagonal.
/// Returns false when no ear exists. Expects a simple polygon (is_simple) or a weakly simple one:
/// a face with holes joined to its outline along seams, each seam an edge walked there and back
/// (MGF writes holes so; docs/scene-format.md, "MGF import"). A vertex that coincides with one of
/// the ear's corners (the other end of a seam) does not block the ear; the caller checks the result
/// covers the face's net area once (covers_net_area).
bool triangulate(std::vector<Vec3> p, Vec3 n, std::vector<std::array<Vec3, 3>>& triangles) {
    const double size = max_pairwise_distance(p);
    auto same = [&](size_t j, size_t k) { return length(p[j] - p[k]) <= 1e-9 * size; };
    std::vector<Vec2> q = project(p, n);
    auto inside = [](Vec2 a, Vec2 b, Vec2 c, Vec2 x) {
        // Closed triangle test (points on the edges count as inside, which blocks the ear).
        return cross(b - a, x - a) >= 0 && cross(c - b, x - b) >= 0 && cross(a - c, x - c) >= 0;
    };
    while (p.size() > 3) {
        size_t k = p.size(), best = k;
        double best_len = HUGE_VAL;
        for (size_t i = 0; i < k; ++i) {
            size_t a = (i + k - 1) % k, c = (i + 1) % k;
            double turn = cross(q[i] - q[a], q[c] - q[i]);
            double scale = length(p[i] - p[a]) * length(p[c] - p[i]);
            if (!(turn > 1e-12 * scale)) continue;  // reflex or straight: not an ear
            bool blocked = false;
            for (size_t j = 0; j < k && !blocked; ++j)
                if (j != a && j != i && j != c && !same(j, a) && !same(j, i) && !same(j, c))
                    blocked = inside(q[a], q[i], q[c], q[j]);
            if (blocked) continue;
            double len = length(p[c] - p[a]);
            if (len < best_len) {
                best_len = len;
                best = i;
            }
        }
        if (best == k) return false;
        size_t a = (best + k - 1) % k, c = (best + 1) % k;
        triangles.push_back({p[a], p[best], p[c]});
        p.erase(p.begin() + long(best));
        q.erase(q.begin() + long(best));
    }
    triangles.push_back({p[0], p[1], p[2]});
    return true;
}

/// True when the triangles' areas add up to the net area of the polygon with unit normal n
/// (Newell's vector `newell`, twice the area vector): a triangulation of a simple or weakly
/// simple face covers it once, while ears cut from a face whose edges cross overlap or stick out.
bool covers_net_area(const std::vector<std::array<Vec3, 3>>& triangles, Vec3 newell, Vec3 n) {
    double sum = 0;
    for (const auto& t : triangles) sum += std::fabs(dot(cross(t[1] - t[0], t[2] - t[0]), n));
    const double net = dot(newell, n);
    return std::fabs(sum - net) <= 1e-7 * std::fabs(net);
}

/// face_to_quads for a face given relative to one of its vertices.
std::vector<Quad> local_face_to_quads(const Line& line, std::vector<Vec3> p) {
    double size = max_pairwise_distance(p);
    if (!(size > 0)) line.fail("degenerate face: all its vertices coincide");
    // Drop repeated vertices, then corners that do not turn (straight or folded back).
    for (size_t i = 0; p.size() > 1 && i < p.size();) {
        if (length(p[i] - p[(i + 1) % p.size()]) <= 1e-9 * size)
            p.erase(p.begin() + long(i));
        else
            ++i;
    }
    for (bool changed = true; changed && p.size() >= 3;) {
        changed = false;
        for (size_t i = 0; i < p.size() && p.size() >= 3; ++i) {
            size_t k = p.size();
            Vec3 e1 = p[i] - p[(i + k - 1) % k], e2 = p[(i + 1) % k] - p[i];
            if (length(cross(e1, e2)) <= 1e-9 * length(e1) * length(e2)) {
                p.erase(p.begin() + long(i));
                changed = true;
                break;
            }
        }
    }
    if (p.size() < 3) line.fail("degenerate face: zero area (its vertices are collinear)");
    const Vec3 newell = newell_normal(p);
    if (length(newell) <= 1e-9 * size * size)
        line.fail("degenerate face: zero net area (it intersects itself)");
    const Vec3 n = normalize(newell);

    std::vector<Quad> quads;
    if (p.size() == 3) {
        triangle_to_quads(p[0], p[1], p[2], quads);
        return quads;
    }
    if (p.size() == 4 && planar_quad_problem({p[0], p[1], p[2], p[3]}).empty()) {
        quads.push_back({p[0], p[1], p[2], p[3]});
        return quads;
    }
    if (p.size() > 4) {
        // Planar, convex and simple (total turning one full turn): quads around the centre.
        bool convex = plane_deviation(p, n) <= planarity_tolerance * max_pairwise_distance(p);
        double turning = 0;
        for (size_t i = 0; convex && i < p.size(); ++i) {
            double s = turn_sine(p, i, n);
            size_t k = p.size();
            Vec3 e1 = p[i] - p[(i + k - 1) % k], e2 = p[(i + 1) % k] - p[i];
            convex = s > 1e-9;
            turning += std::atan2(s, dot(normalize(e1), normalize(e2)));
        }
        if (convex && std::fabs(turning - 2 * Pi) < 1e-6) {
            Vec3 c;
            for (const Vec3& x : p) c += x;
            c = c / double(p.size());
            size_t k = p.size();
            for (size_t i = 0; i < k; ++i) {
                Vec3 m_next = 0.5 * (p[i] + p[(i + 1) % k]);
                Vec3 m_prev = 0.5 * (p[(i + k - 1) % k] + p[i]);
                quads.push_back({p[i], m_next, c, m_prev});
            }
            bool all_valid = true;
            for (const Quad& q : quads) all_valid = all_valid && planar_quad_problem(q).empty();
            if (all_valid) return quads;
            quads.clear();  // the vertex average sits too near a corner: triangulate instead
        }
    }
    std::vector<std::array<Vec3, 3>> triangles;
    // A face whose edges touch may still be weakly simple (holes joined along seams): its ears
    // must then cover its net area exactly once.
    const bool simple = is_simple(project(p, n));
    if (!triangulate(p, n, triangles) || (!simple && !covers_net_area(triangles, newell, n)))
        line.fail("face of " + std::to_string(p.size()) +
                  " vertices intersects itself (it cannot be triangulated)");
    for (const auto& t : triangles)
        if (length(cross(t[1] - t[0], t[2] - t[0])) > 1e-12 * size * size)
            triangle_to_quads(t[0], t[1], t[2], quads);
    return quads;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// === Quads

std::string planar_quad_problem(const std::array<Vec3, 4>& corners) {
    for (const Vec3& q : corners)
        if (!is_finite(q)) return "a corner is not finite";
    // Every test below works on the corners relative to corner 0 and divided by the largest
    // coordinate difference, so that its numbers are of order 1 wherever the quad lies and
    // however large or small it is. In absolute coordinates a quad near 1e8 loses its area to
    // cancellation in Newell's sum (cross products of 1e8-sized position vectors) and its squared
    // sizes can overflow. Subtracting corner 0 is exact for corners within a factor 2 of each
    // other (Sterbenz), which covers a small quad far from the origin.
    double scale = 0;
    for (const Vec3& q : corners)
        for (int k = 0; k < 3; ++k) scale = std::max(scale, std::fabs(q[k] - corners[0][k]));
    if (!std::isfinite(scale)) return "corners are too far apart to compute with";
    if (!(scale > 0)) return "degenerate quad: all corners coincide";
    std::vector<Vec3> p;
    for (const Vec3& q : corners) p.push_back((q - corners[0]) / scale);
    const double size = max_pairwise_distance(p);  // in units of scale: in [1, 2 sqrt(3)]
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
            if (length(p[i] - p[j]) <= 1e-9 * size)
                return "degenerate quad: corners " + std::to_string(i + 1) + " and " +
                       std::to_string(j + 1) + " coincide";
    // Spread of the corner triangles: zero exactly when all four corners are collinear.
    double spread = 0;
    for (int i = 0; i < 4; ++i)
        spread = std::max(spread, length(cross(p[(i + 1) % 4] - p[i], p[(i + 2) % 4] - p[i])));
    if (spread <= 1e-12 * size * size) return "degenerate quad: zero area (collinear corners)";
    Vec3 n = newell_normal(p);
    if (length(n) <= 1e-9 * size * size)
        return "quad intersects itself (its edges cross, so its net area is zero)";
    n = normalize(n);
    double dev = plane_deviation(p, n);
    if (dev > planarity_tolerance * size)
        return "quad is not planar: a corner lies " + fmt_approx(dev * scale) +
               " off the corners' mean plane, " + fmt_approx(100 * dev / size) +
               "% of its size (the limit is " + fmt_approx(100 * planarity_tolerance) + "%)";
    for (size_t i = 0; i < 4; ++i)
        if (turn_sine(p, i, n) <= 1e-9)
            return "quad is not convex at corner " + std::to_string(i + 1) +
                   " (a non-convex or self-intersecting quad folds its bilinear map)";
    return "";
}

namespace detail {

// ---------------------------------------------------------------------------------------------
// === Shared checks

double max_pairwise_distance(const std::vector<Vec3>& p) {
    double size = 0;
    for (size_t i = 0; i < p.size(); ++i)
        for (size_t j = i + 1; j < p.size(); ++j) size = std::max(size, length(p[i] - p[j]));
    return size;
}

void check_point(const Line& line, Vec3 p, const std::string& what) {
    for (int i = 0; i < 3; ++i)
        if (std::fabs(p[i]) > max_coordinate)
            line.fail(what + " coordinate " + fmt(p[i]) + " exceeds the limit " +
                      fmt(max_coordinate));
}

// ---------------------------------------------------------------------------------------------
// === OBJ faces to quads

std::vector<Quad> face_to_quads(const Line& line, std::vector<Vec3> p) {
    // The work is done relative to vertex 0, as in planar_quad_problem: Newell's sum and the
    // turn tests of a small face far from the origin would otherwise drown in cancellation. For
    // a face small against its distance from the origin the subtraction and the addition back
    // are both exact, so its vertices come back unchanged.
    const Vec3 origin = p[0];
    for (Vec3& x : p) x = x - origin;
    std::vector<Quad> quads = local_face_to_quads(line, std::move(p));
    for (Quad& q : quads)
        for (Vec3& x : q) x = x + origin;
    return quads;
}

namespace {

/// The largest interior angle of a planar quad, in degrees.
double largest_angle(const Quad& q) {
    double largest = 0;
    for (size_t i = 0; i < 4; ++i) {
        const Vec3 a = q[(i + 3) % 4] - q[i], b = q[(i + 1) % 4] - q[i];
        const double l = length(a) * length(b);
        if (l <= 0) return 180;
        largest = std::max(largest, std::acos(std::clamp(dot(a, b) / l, -1.0, 1.0)));
    }
    return largest * 180 / M_PI;
}

/// A directed edge by its ends' exact coordinates, and the triangle and corner it starts at.
struct Edge {
    std::array<double, 6> key;
    int triangle = 0, corner = 0;
    bool operator<(const Edge& o) const { return key < o.key; }
};
std::array<double, 6> edge_key(Vec3 from, Vec3 to) {
    return {from.x, from.y, from.z, to.x, to.y, to.z};
}

}  // namespace

TrianglePairs pair_triangles(const std::vector<Triangle>& triangles) {
    const int n = static_cast<int>(triangles.size());
    TrianglePairs pairs;
    pairs.partner.assign(size_t(n), -1);
    pairs.quad.resize(size_t(n));
    // Every directed edge, sorted by its ends (a triangle's edge k runs from corner k to k + 1).
    std::vector<Edge> edges;
    edges.reserve(3 * size_t(n));
    for (int t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            const auto& c = triangles[size_t(t)].corner;
            edges.push_back({edge_key(c[size_t(k)], c[size_t((k + 1) % 3)]), t, k});
        }
    std::stable_sort(edges.begin(), edges.end());
    for (int t = 0; t < n; ++t) {
        if (pairs.partner[size_t(t)] >= 0) continue;
        const Triangle& a = triangles[size_t(t)];
        int best = -1;
        double best_angle = 0;
        Quad best_quad{};
        for (int k = 0; k < 3; ++k) {
            // Edge k runs from corner k to corner k + 1; a partner walks it back.
            const Vec3 from = a.corner[size_t(k)], to = a.corner[size_t((k + 1) % 3)];
            const auto [begin, end] =
                std::equal_range(edges.begin(), edges.end(), Edge{edge_key(to, from)});
            for (auto e = begin; e != end; ++e) {
                const int u = e->triangle, j = e->corner;
                if (u <= t || pairs.partner[size_t(u)] >= 0) continue;
                const Triangle& b = triangles[size_t(u)];
                if (b.group != a.group) continue;
                const Vec3 third = b.corner[size_t((j + 2) % 3)];
                // a's corners from the one after the edge: k + 2, k, then b's third, k + 1.
                const Quad q{a.corner[size_t((k + 2) % 3)], from, third, to};
                if (!planar_quad_problem(q).empty()) continue;
                const double angle = largest_angle(q);
                if (angle > max_pair_angle) continue;
                if (best < 0 || angle < best_angle) {
                    best = u;
                    best_angle = angle;
                    best_quad = q;
                }
            }
        }
        if (best < 0) continue;
        pairs.partner[size_t(t)] = best;
        pairs.partner[size_t(best)] = t;
        pairs.quad[size_t(t)] = best_quad;
    }
    return pairs;
}

}  // namespace detail

}  // namespace mbr
