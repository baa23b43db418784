// math/convex2d.cpp - clipping of convex polygons and the collapsed Gauss rule on triangles.
#include "math/convex2d.h"

#include <algorithm>
#include <cmath>

namespace mbr {

double signed_area(const ConvexPolygon& polygon) {
    double a = 0;
    const size_t n = polygon.size();
    for (size_t i = 0; i < n; ++i) a += cross(polygon[i], polygon[(i + 1) % n]);
    return 0.5 * a;
}

HalfPlane left_of(Vec2 a, Vec2 b) {
    const Vec2 d = b - a;
    const Vec2 normal{-d.y, d.x};
    return {normal, -dot(normal, a)};
}

namespace {
/// clip() into `out` (whose capacity is reused).
void clip_into(const ConvexPolygon& polygon, const HalfPlane& h, ConvexPolygon& out) {
    out.clear();
    const size_t n = polygon.size();
    if (n < 3) return;
    // Each vertex's value once, and the next index without a division (the same values).
    double vb = h.value(polygon[0]);
    for (size_t i = 0; i < n; ++i) {
        const size_t next = i + 1 == n ? 0 : i + 1;
        const Vec2 a = polygon[i], b = polygon[next];
        const double va = vb;
        vb = h.value(b);
        if (va >= 0) out.push_back(a);
        // The edge crosses the line strictly (an end on the line is kept as a vertex already,
        // or is the next edge's start): add the crossing point, measured from the end nearer
        // the line. A shadow's vertex can lie 1e7 times further out than the shooter (an
        // occluder at nearly the height of the receiving point): from there, the crossing
        // would carry that vertex's rounding, 1e7 times the shooter's.
        if ((va > 0 && vb < 0) || (va < 0 && vb > 0))
            out.push_back(std::fabs(va) <= std::fabs(vb) ? a + (va / (va - vb)) * (b - a)
                                                         : b + (vb / (vb - va)) * (a - b));
    }
    // Vertices on the line can still meet at one point (a polygon touching the line): drop
    // repeated consecutive vertices, so every edge has a length.
    size_t k = 0;
    for (size_t i = 0; i < out.size(); ++i)
        if (k == 0 || out[i].x != out[k - 1].x || out[i].y != out[k - 1].y) out[k++] = out[i];
    while (k > 1 && out[k - 1].x == out[0].x && out[k - 1].y == out[0].y) --k;
    out.resize(k);
    if (out.size() < 3 || signed_area(out) <= 0) out.clear();
}
}  // namespace

ConvexPolygon clip(const ConvexPolygon& polygon, const HalfPlane& h) {
    ConvexPolygon out;
    out.reserve(polygon.size() + 1);
    clip_into(polygon, h, out);
    return out;
}

ConvexPolygon intersect(const ConvexPolygon& a, const ConvexPolygon& b) {
    // Two buffers in turn: one allocation each, not one per clipping line.
    ConvexPolygon out, next;
    out.reserve(a.size() + b.size());
    next.reserve(a.size() + b.size());
    out.assign(a.begin(), a.end());
    const size_t n = b.size();
    for (size_t i = 0; i < n && !out.empty(); ++i) {
        clip_into(out, left_of(b[i], b[(i + 1) % n]), next);
        out.swap(next);
    }
    if (!out.empty() && signed_area(out) <= 0) out.clear();
    return out;
}

std::vector<ConvexPolygon> subtract(const ConvexPolygon& a, const ConvexPolygon& b,
                                    double min_area) {
    std::vector<ConvexPolygon> pieces;
    if (b.size() < 3) {
        if (!a.empty()) pieces.push_back(a);
        return pieces;
    }
    // The part of a still inside every edge line of b seen so far, in two buffers in turn, and
    // a piece's buffer that is handed over only when the piece is kept (allocations per call,
    // not per edge).
    const size_t n = b.size();
    ConvexPolygon rest, next, piece;
    rest.reserve(a.size() + n);
    next.reserve(a.size() + n);
    piece.reserve(a.size() + n);
    rest.assign(a.begin(), a.end());
    for (size_t i = 0; i < n && !rest.empty(); ++i) {
        const HalfPlane inside = left_of(b[i], b[(i + 1) % n]);
        const HalfPlane outside{-1.0 * inside.normal, -inside.offset};
        clip_into(rest, outside, piece);
        if (!piece.empty() && signed_area(piece) > min_area) {
            pieces.push_back(std::move(piece));
            piece = ConvexPolygon();
            piece.reserve(a.size() + n);
        }
        clip_into(rest, inside, next);
        rest.swap(next);
    }
    // What is left of a lies inside b: removed.
    return pieces;
}

Rect bounding_rect(const ConvexPolygon& polygon) {
    Rect r{HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL};
    for (const Vec2& q : polygon) {
        r.x0 = std::min(r.x0, q.x);
        r.x1 = std::max(r.x1, q.x);
        r.y0 = std::min(r.y0, q.y);
        r.y1 = std::max(r.y1, q.y);
    }
    return r;
}

double narrowest_width(const ConvexPolygon& polygon) {
    const size_t n = polygon.size();
    double narrowest = HUGE_VAL;
    for (size_t i = 0; i < n; ++i) {
        const Vec2 a = polygon[i], edge = polygon[(i + 1) % n] - a;
        const double len = std::hypot(edge.x, edge.y);
        if (!(len > 0)) continue;
        double farthest = 0;
        for (const Vec2& q : polygon) farthest = std::max(farthest, std::fabs(cross(edge, q - a)));
        narrowest = std::min(narrowest, farthest / len);
    }
    return narrowest;
}

bool is_sliver(const ConvexPolygon& polygon, double min_width, double min_extent) {
    if (polygon.size() < 3) return true;
    const Rect box = bounding_rect(polygon);
    const double diagonal = std::sqrt(box.width() * box.width() + box.height() * box.height());
    return diagonal <= min_extent || std::fabs(signed_area(polygon)) <= min_width * diagonal;
}

void remove_flat_vertices(ConvexPolygon& polygon, double tolerance) {
    for (size_t i = 0; polygon.size() > 3 && i < polygon.size();) {
        const size_t n = polygon.size();
        const Vec2 a = polygon[(i + n - 1) % n], b = polygon[i], c = polygon[(i + 1) % n];
        // b's distance from the line a c, times |c - a|
        if (std::fabs(cross(b - a, c - a)) <= tolerance * std::sqrt(dot(c - a, c - a)))
            polygon.erase(polygon.begin() + long(i));
        else
            ++i;
    }
}

void start_at_canonical_vertex(ConvexPolygon& polygon) {
    // Not an axis: the sides of axis-aligned scenes would tie (two vertices equally low, and
    // rounding choosing between them).
    const Vec2 direction{0.54030230586813977, 0.84147098480789650};  // (cos 1, sin 1)
    size_t first = 0;
    for (size_t i = 1; i < polygon.size(); ++i)
        if (dot(direction, polygon[i]) < dot(direction, polygon[first])) first = i;
    std::rotate(polygon.begin(), polygon.begin() + long(first), polygon.end());
}

ConvexPolygon convex_hull(std::vector<Vec2> points) {
    std::sort(points.begin(), points.end(),
              [](Vec2 a, Vec2 b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    points.erase(std::unique(points.begin(), points.end(),
                             [](Vec2 a, Vec2 b) { return a.x == b.x && a.y == b.y; }),
                 points.end());
    if (points.size() < 3) return {};
    ConvexPolygon hull(2 * points.size());
    size_t k = 0;
    for (size_t i = 0; i < points.size(); ++i) {  // lower hull
        while (k >= 2 && cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0) --k;
        hull[k++] = points[i];
    }
    for (size_t i = points.size() - 1, t = k + 1; i-- > 0;) {  // upper hull
        while (k >= t && cross(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0) --k;
        hull[k++] = points[i];
    }
    hull.resize(k - 1);
    if (hull.size() < 3) hull.clear();
    return hull;
}

ConvexPolygon convex_union(const ConvexPolygon& a, const ConvexPolygon& b, double rel_tolerance) {
    std::vector<Vec2> points(a.begin(), a.end());
    points.insert(points.end(), b.begin(), b.end());
    ConvexPolygon hull = convex_hull(points);
    if (hull.empty()) return hull;
    const ConvexPolygon common = intersect(a, b);
    const double covered = signed_area(a) + signed_area(b) - (common.empty() ? 0.0 : signed_area(common));
    const double area = signed_area(hull);
    if (area - covered > rel_tolerance * area) hull.clear();  // the hull holds more: not convex
    return hull;
}

Overlap classify(const ConvexPolygon& a, const ConvexPolygon& b) {
    if (a.size() < 3 || b.size() < 3) return Overlap::disjoint;
    // Separating axis: an edge line of either polygon with the other wholly outside it.
    bool a_inside_b = true;
    for (size_t i = 0; i < b.size(); ++i) {
        const HalfPlane h = left_of(b[i], b[(i + 1) % b.size()]);
        double lo = HUGE_VAL;
        for (Vec2 x : a) lo = std::min(lo, h.value(x));
        double hi = -HUGE_VAL;
        for (Vec2 x : a) hi = std::max(hi, h.value(x));
        if (hi <= 0) return Overlap::disjoint;
        if (lo < 0) a_inside_b = false;
    }
    for (size_t i = 0; i < a.size(); ++i) {
        const HalfPlane h = left_of(a[i], a[(i + 1) % a.size()]);
        double hi = -HUGE_VAL;
        for (Vec2 x : b) hi = std::max(hi, h.value(x));
        if (hi <= 0) return Overlap::disjoint;
    }
    return a_inside_b ? Overlap::inside : Overlap::partial;
}

bool contains(const ConvexPolygon& polygon, Vec2 x) {
    const size_t n = polygon.size();
    if (n < 3) return false;
    for (size_t i = 0; i < n; ++i)
        if (left_of(polygon[i], polygon[(i + 1) % n]).value(x) < 0) return false;
    return true;
}

bool contains(const ConvexPolygon& polygon, Vec2 x, double slack) {
    const size_t n = polygon.size();
    if (n < 3) return false;
    for (size_t i = 0; i < n; ++i) {
        const Vec2 d = polygon[(i + 1) % n] - polygon[i];
        // left_of's value is the distance from the edge's line times the edge's length.
        if (left_of(polygon[i], polygon[(i + 1) % n]).value(x) < -slack * std::sqrt(dot(d, d)))
            return false;
    }
    return true;
}

Vec2 inverse_bilinear(Vec2 q0, Vec2 q1, Vec2 q2, Vec2 q3, Vec2 q) {
    // P(s,t) = q0 + s e + t f + s t g. Eliminating s from q - q0 - t f = s (e + t g) leaves
    // k2 t^2 + k1 t + k0 = 0 (as in Quilez's inverse bilinear interpolation).
    const Vec2 e = q1 - q0, f = q3 - q0, g = q0 - q1 + q2 - q3, h = q - q0;
    const double k2 = cross(g, f);
    const double k1 = cross(h, g) + cross(e, f);
    const double k0 = cross(h, e);
    // Stable roots q_r / k2 and k0 / q_r; for a parallelogram k2 = 0 and only k0 / q_r is finite.
    const double disc = std::max(0.0, k1 * k1 - 4 * k0 * k2);  // < 0 only outside
    const double q_r = -0.5 * (k1 + std::copysign(std::sqrt(disc), k1));
    double t = 0;
    if (q_r != 0) {
        const double r1 = k0 / q_r;
        const double r2 = k2 != 0 ? q_r / k2 : HUGE_VAL;
        // The root in [0, 1], or the one nearer to that interval when extrapolating.
        auto off = [](double r) { return r < 0 ? -r : (r > 1 ? r - 1 : 0.0); };
        t = off(r1) <= off(r2) ? r1 : r2;
    }
    const Vec2 d = e + t * g;
    double s = dot(h - t * f, d) / dot(d, d);
    // Two Newton steps on P(s,t) = q polish the rounding of the closed form.
    for (int it = 0; it < 2; ++it) {
        const Vec2 r = q0 + s * e + t * f + (s * t) * g - q;
        const Vec2 ps = e + t * g, pt = f + s * g;
        const double det = cross(ps, pt);
        if (det == 0) break;
        s -= cross(r, pt) / det;
        t -= cross(ps, r) / det;
    }
    return {s, t};
}

TriangleRule triangle_rule(int n) {
    // Duffy's map (xi, eta) -> (xi (1 - eta), xi eta) of [0,1]^2 onto the triangle, Jacobian xi.
    const GaussLegendre g = gauss_legendre(n);
    TriangleRule rule;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const double xi = 0.5 * (g.x[a] + 1), eta = 0.5 * (g.x[b] + 1);
            rule.points.push_back({xi * (1 - eta), xi * eta});
            rule.weights.push_back(0.25 * g.w[a] * g.w[b] * xi);
        }
    return rule;
}

TriangleRule symmetric_triangle_rule(int degree) {
    // Orbits in barycentric coordinates (a, a, 1 - 2a) (three points) and (a, b, 1 - a - b)
    // (six points), with their weights for the unit-area triangle (they sum to 1).
    struct Orbit {
        double a, b, weight;  // b < 0: the three-point orbit (a, a, 1 - 2a)
    };
    static const Orbit degree2[] = {{1.0 / 6, -1, 1.0 / 3}};
    static const Orbit degree4[] = {{0.445948490915965, -1, 0.223381589678011},
                                    {0.091576213509771, -1, 0.109951743655322}};
    static const Orbit degree6[] = {{0.249286745170910, -1, 0.116786275726379},
                                    {0.063089014491502, -1, 0.050844906370207},
                                    {0.053145049844817, 0.310352451033784, 0.082851075618374}};
    MBR_CHECK_MSG(degree == 2 || degree == 4 || degree == 6,
                  "no symmetric triangle rule of degree " << degree);
    const Orbit* first = degree == 2 ? degree2 : (degree == 4 ? degree4 : degree6);
    const int n_orbits = degree / 2;
    TriangleRule rule;
    auto add = [&](double l1, double l2, double weight) {
        rule.points.push_back({l1, l2});  // (x, y) = the weights of corners (1,0) and (0,1)
        rule.weights.push_back(0.5 * weight);
    };
    for (int k = 0; k < n_orbits; ++k) {
        const Orbit& o = first[k];
        if (o.b < 0) {
            const double c = 1 - 2 * o.a;
            add(o.a, o.a, o.weight);
            add(o.a, c, o.weight);
            add(c, o.a, o.weight);
        } else {
            const double c = 1 - o.a - o.b;
            add(o.a, o.b, o.weight);
            add(o.b, o.a, o.weight);
            add(o.a, c, o.weight);
            add(c, o.a, o.weight);
            add(o.b, c, o.weight);
            add(c, o.b, o.weight);
        }
    }
    return rule;
}

TriangleRule triangle_rule_of_degree_2n_minus_2(int n) {
    return n >= 2 && n <= 4 ? symmetric_triangle_rule(2 * n - 2) : triangle_rule(n);
}

}  // namespace mbr
