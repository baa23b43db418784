// radiosity/solver/resolution.cpp - whether a receiver's finest cells can hold a light's peak.
#include "radiosity/solver/resolution.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "math/check.h"
#include "math/convex2d.h"
#include "radiosity/transfer/form_factor.h"
#include "radiosity/transfer/oracle.h"
#include "radiosity/visibility/visible_parts.h"

namespace mbr {

namespace {

/// What the check measures on a cell of the receiver: its size (its longer side), and the width
/// of the emitter's peak there, max(d, the emitter's narrowest width), d the distance to the
/// emitter from the nearest of the cell's corners, edge midpoints and centre.
struct CellMeasure {
    double size = 0, spot = 0;
};

CellMeasure measure(const Surface& receiver, const ShooterPlane& emitter, double width,
                    const Rect& r) {
    Vec3 p[9];
    int k = 0;
    for (double t : {r.y0, 0.5 * (r.y0 + r.y1), r.y1})
        for (double s : {r.x0, 0.5 * (r.x0 + r.x1), r.x1}) p[k++] = receiver.point(s, t);
    double d = HUGE_VAL;
    for (const Vec3& x : p) d = std::min(d, distance_to_shooter(emitter, x));
    return {std::max(length(p[2] - p[0]), length(p[6] - p[0])), std::max(d, width)};
}

/// A walk down the receiver's quadtree towards the emitter's peak: a cell wider than
/// descent_ratio times the peak's width there splits (the cell under the peak has one of its
/// nine points within 0.36 of its size from the peak's foot, so it keeps splitting while it is
/// wider than about 2.8 peaks); elsewhere the walk stops at once. At every cell where it stops,
/// the finest cell below it (at `depth`) is compared with the peak's width there: the largest
/// ratio, with its sizes.
struct Walk {
    const Surface& receiver;
    const ShooterPlane& emitter;
    double width = 0;  // the emitter's narrowest width
    int depth = 0;
    double ratio = 0, spot = 0, cell = 0;
    long visited = 0;
};

constexpr double descent_ratio = 2;
// DESIGN: a walk visits at most this many cells; beyond, it stops splitting (the cells it did
// not visit count as resolved). It splits only the cells near the peak, a few per level.
constexpr long max_walk_cells = 100000;

void walk(Walk& w, const Rect& r, int level) {
    ++w.visited;
    const CellMeasure m = measure(w.receiver, w.emitter, w.width, r);
    if (level < w.depth && m.size > descent_ratio * m.spot && w.visited < max_walk_cells) {
        const double xm = 0.5 * (r.x0 + r.x1), ym = 0.5 * (r.y0 + r.y1);
        for (const Rect& c : {Rect{r.x0, xm, r.y0, ym}, Rect{xm, r.x1, r.y0, ym},
                              Rect{r.x0, xm, ym, r.y1}, Rect{xm, r.x1, ym, r.y1}})
            walk(w, c, level + 1);
        return;
    }
    const double finest = std::ldexp(m.size, level - w.depth);
    const double ratio = finest / m.spot;
    if (ratio > w.ratio) {
        w.ratio = ratio;
        w.spot = m.spot;
        w.cell = finest;
    }
}

/// True when the emitter stands wholly in front of the receiver's plane. DESIGN: 1e-9 of the
/// coordinates' size: a corner that close to the plane touches it. An emitter that touches the
/// receiver (a lamp on the ceiling it lights) spreads its light from the contact line, which
/// the oracle's contact rule resolves; its peak has no width to check.
bool in_front(const Surface& receiver, const Surface& emitter) {
    const std::optional<Plane> plane = surface_plane(receiver);
    if (!plane) return false;
    double lowest = HUGE_VAL, scale = 0;
    for (int k = 0; k < 4; ++k) {
        const Vec3 x = emitter.corners()[k];
        lowest = std::min(lowest, dot(plane->normal, x) - plane->offset);
        scale = std::max({scale, std::fabs(x.x), std::fabs(x.y), std::fabs(x.z)});
    }
    return lowest > 1e-9 * scale;
}

/// The walk towards the emitter's peak. DESIGN: the peak's width is the emitter's narrowest
/// width, across which a strip's peak is narrow (a 1.4 x 0.08 strip 4 cm under a ceiling: at
/// max_depth 6, cells 5.8 x 8.3 cm, the ceiling read -17 % at the peak's centre and rang from
/// -97 to +687 % beside it, with no word while the check took the square root of the strip's
/// area, 0.33; docs/method.md, "Known wrong answers").
Walk walk_at(const Surface& receiver, const ShooterPlane& emitter, int depth) {
    Walk w{receiver, emitter, narrowest_width(emitter.outline), depth};
    walk(w, Rect{0, 1, 0, 1}, 0);
    return w;
}

/// The share of the emitter's light that reaches the receiver's quad, from the emitter's centre.
double light_share(const Surface& emitter, const Surface& receiver) {
    const SurfacePoint c = emitter.evaluate(0.5, 0.5);
    const Vec3* q = receiver.corners();
    return point_polygon_form_factor(c.position, c.normal, {q[0], q[1], q[2], q[3]});
}

std::string format_length(double x) {
    std::ostringstream os;
    os.precision(3);
    os << x;
    return os.str();
}

}  // namespace

std::vector<UnresolvedLight> unresolved_lights(const Scene& scene, int max_depth) {
    std::vector<UnresolvedLight> out;
    const std::vector<int> emitters = scene.emitters();
    for (int r = 0; r < static_cast<int>(scene.surfaces.size()); ++r) {
        const Surface& receiver = scene.surfaces[r].surface;
        if (receiver.kind() != Surface::Kind::PlanarQuad) continue;
        if (!(max_abs(scene.material_of(r).reflectance.maximum()) > 0)) continue;
        for (int e : emitters) {
            const Surface& emitter = scene.surfaces[e].surface;
            if (e == r || emitter.kind() != Surface::Kind::PlanarQuad) continue;
            if (!in_front(receiver, emitter)) continue;
            const ShooterPlane plane = make_shooter_plane(emitter);
            const Walk w = walk_at(receiver, plane, max_depth);
            if (!(w.ratio > resolution_fraction)) continue;
            const double share = light_share(emitter, receiver);
            if (!(share >= resolution_share)) continue;
            UnresolvedLight u{r, e, w.spot, w.cell, max_depth + 1, share};
            // The least depth that holds the peak (each level halves the finest cell).
            while (u.needed_depth < 60 &&
                   walk_at(receiver, plane, u.needed_depth).ratio > resolution_fraction)
                ++u.needed_depth;
            out.push_back(u);
        }
    }
    return out;
}

void check_resolution(const Scene& scene, int max_depth) {
    const std::vector<UnresolvedLight> found = unresolved_lights(scene, max_depth);
    if (found.empty()) return;
    const UnresolvedLight& u = found.front();
    const SceneSurface& r = scene.surfaces[u.receiver];
    const SceneSurface& e = scene.surfaces[u.emitter];
    // The receiver's longer side: surfaces that much smaller per level short of the need.
    const Vec3* q = r.surface.corners();
    const double side = std::max(length(q[1] - q[0]), length(q[3] - q[0]));
    // DESIGN: a depth is advised up to 10. Fields are full grids at their finest level: a floor
    // under a lamp took 12 s and 590 MB at max_depth 10, 144 s and 2.3 GB at 11, and more than
    // 300 s and 8.8 GB at 12 (`mbr probe`); beyond 10 only splitting the surface is advised.
    constexpr int depth_limit = 10;
    std::ostringstream msg;
    msg << "surface '" << r.name << "' is too coarse for the light of '" << e.name << "' ("
        << scene.where(u.emitter) << "): it takes " << format_length(100 * u.form_factor)
        << " % of that light, in a spot about " << format_length(u.spot)
        << " wide, and its finest cells (max_depth " << max_depth << ") are "
        << format_length(u.cell) << " wide, so the spot would be lost or blurred; ";
    if (u.needed_depth <= depth_limit)
        msg << "set max_depth " << u.needed_depth << " (or --max-depth " << u.needed_depth
            << "), or ";
    msg << "split '" << r.name << "' into surfaces about "
        << format_length(std::ldexp(side, max_depth - u.needed_depth)) << " wide or less";
    if (found.size() > 1) msg << " (and " << found.size() - 1 << " more such pairs)";
    const std::string file = r.source >= 0 ? scene.sources[r.source] : std::string();
    throw InputError(file, r.line, msg.str());
}

}  // namespace mbr
