// radiosity/transfer/sample_values.cpp - the adaptive quadrature of (21) over the shooter (paper
// section 6, "Adaptive Quadrature"), with exact visibility when asked.
#include "radiosity/transfer/sample_values.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "math/check.h"

namespace mbr {

namespace {
/// A dyadic cell of the shooter as one integer: level (5 bits), i and j (28 bits each).
std::uint64_t cell_key(const QuadCell& cell) {
    return (std::uint64_t(cell.level) << 56) | (std::uint64_t(cell.i) << 28) |
           std::uint64_t(cell.j);
}
}  // namespace

IncrementIntegrator::IncrementIntegrator(const Shooter& shooter, const QuadratureOptions& options,
                                         const OcclusionContext* occlusion)
    : shooter_(shooter), options_(options) {
    MBR_CHECK(shooter.surface != nullptr && !shooter.unshot.empty());
    MBR_CHECK(options.n >= 1 && options.max_depth >= 0 && options.max_depth <= 28);
    MBR_CHECK(options.n + 1 <= 64);
    unshot_bound_ = shooter.unshot.max_abs_coefficient();  // B-splines sum to one
    unshot_constant_ = shooter.unshot.is_constant();
    unshot_values_.resize(size_t(options.n + 1) * (options.n + 1));
    rules_.resize(options.n + 2);
    for (int n = 1; n <= options.n + 1; ++n) rules_[n] = gauss_legendre(n);
    planar_ = shooter.surface->kind() == Surface::Kind::PlanarQuad;
    if (planar_) {
        plane_ = make_shooter_plane(*shooter.surface);
        const int top = std::max(options.n, options.n_pieces) + 1;
        tri_rules_.resize(top + 1);
        for (int n = 1; n <= top; ++n) tri_rules_[n] = triangle_rule_of_degree_2n_minus_2(n);
    }
    if (occlusion && !occlusion->clear()) occlusion_ = occlusion;
    analytic_ = planar_ && unshot_constant_ && options.analytic;
    if (planar_ && !unshot_constant_)
        unshot_patches_ = shooter.patches
                              ? shooter.patches
                              : std::make_shared<const PolynomialPatches>(shooter.unshot);
}

Rgb IncrementIntegrator::shooter_radiosity(double u, double v) const {
    if (unshot_constant_) return shooter_.unshot.coefficient(0, 0);
    if (planar_) return (*unshot_patches_)(u, v);
    return shooter_.unshot.evaluate(u, v);
}

double IncrementIntegrator::visible_form_factor(const SurfacePoint& p) {
    // The contour formula of the reference (Baum et al. 1989), piece by piece (each convex,
    // counter-clockwise seen from the shooter's front).
    if (view_.behind_all) return 0;
    ++n_analytic_;
    std::vector<Vec3>& polygon = lambert_polygon_;  // its storage reused from point to point
    auto lambert = [&](const ConvexPolygon& piece) {
        polygon.clear();
        for (const Vec2& q : piece) polygon.push_back(plane_.to_space(q));
        return point_polygon_form_factor(p.position, p.normal, polygon);
    };
    if (!options_.shadow_subtraction) {  // the visible pieces themselves
        double F = 0;
        for (const ConvexPolygon& piece : visible_pieces(plane_.outline, view_))
            F += lambert(piece);
        return F;
    }
    // The front part of the outline minus the disjoint parts of the shadows: two or three
    // polygons instead of the pieces the shadows would cut the outline into.
    take_shadows_apart();
    const ConvexPolygon front =
        view_.horizon_cuts ? clip(plane_.outline, view_.front) : plane_.outline;
    double hidden_area = 0;
    for (const ConvexPolygon& region : shadow_regions_) hidden_area += signed_area(region);
    // An umbra: the shadows cover all of it (the regions are disjoint parts of it), exactly 0.
    if (hidden_area >= (1 - 1e-12) * signed_area(front)) return 0;
    double F = lambert(front);
    for (const ConvexPolygon& region : shadow_regions_) F -= lambert(region);
    return std::max(F, 0.0);
}

double cached_points_bytes() {
    // Tensor points: the pool at its bound, and a map entry (about 64 bytes with its bucket)
    // per cell of at least 2 x 2 points. Horizon pieces: their points, and an entry (about 96
    // bytes with its vector) per piece, each counted as at least one point.
    const double point = sizeof(ShooterPoint) + 6 * sizeof(double);  // and its nodes' arrays
    return double(max_cached_points) * (point + 64.0 / 4) +
           double(max_cached_horizon_points) * (point + 96);
}

IncrementIntegrator::PointSpan IncrementIntegrator::points(const QuadCell& cell, int n) {
    // Key: level (5 bits), i and j (28 bits each: cells of [0,1]^2 have non-negative indices
    // below 2^level), and which of the two rules.
    const std::uint64_t key = (std::uint64_t(cell.level) << 57) | (std::uint64_t(cell.i) << 29) |
                              (std::uint64_t(cell.j) << 1) | std::uint64_t(n == options_.n ? 0 : 1);
    auto it = cache_.find(key);
    if (it != cache_.end())
        return {pool_.data() + it->second, n * n, pool_nodes_.data() + 6 * size_t(it->second)};
    // Bound the cache (deep singular corners can make many cells): at most max_cached_points;
    // then it starts over. Values never depend on it. The pool grows as needed, so a transfer
    // that needs few points costs little memory (a span is used before the next call), and by
    // doubling up to the bound, never past it (cached_points_bytes counts the bound).
    if (pool_.size() + size_t(n) * n > max_cached_points) {
        cache_.clear();
        pool_.clear();
        pool_nodes_.clear();
    }
    if (pool_.size() + size_t(n) * n > pool_.capacity()) {
        pool_.reserve(std::min(max_cached_points, std::max<size_t>(1024, 2 * pool_.capacity())));
        pool_nodes_.reserve(6 * pool_.capacity());
    }
    const GaussLegendre& rule = rules_[n];
    const Rect& r = cell.rect;
    const double hx = 0.5 * r.width(), hy = 0.5 * r.height();
    double u[64], v[64];
    for (int a = 0; a < n; ++a) {
        u[a] = r.x0 + hx * (rule.x[a] + 1);
        v[a] = r.y0 + hy * (rule.x[a] + 1);
    }
    Rgb* B = unshot_values_.data();  // n*n values of B_h on the cell's tensor grid
    if (unshot_constant_)
        std::fill(B, B + n * n, shooter_.unshot.coefficient(0, 0));
    else
        shooter_.unshot.evaluate_grid(u, n, v, n, B);
    const std::uint32_t offset = static_cast<std::uint32_t>(pool_.size());
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const SurfacePoint sp = shooter_.surface->evaluate(u[a], v[b]);
            const double w_J_A = rule.w[a] * rule.w[b] * hx * hy * sp.area_factor;
            pool_.push_back({sp.position, sp.normal, w_J_A * B[a * n + b], w_J_A});
        }
    append_shooting_nodes(pool_nodes_, pool_.data() + offset, n * n);
    cache_.emplace(key, offset);
    return {pool_.data() + offset, n * n, pool_nodes_.data() + 6 * size_t(offset)};
}

Rgb IncrementIntegrator::sum_over(const SurfacePoint& p, PointSpan pts) const {
    // The kernel of eq. (3) at a chunk of points at once (form_factor_kernels, vectorised), then
    // the sum in the points' order: the same bits as one point at a time.
    constexpr int chunk = 64;
    double F[chunk];
    Rgb sum;
    for (int start = 0; start < pts.count; start += chunk) {
        const int count = std::min(chunk, pts.count - start);
        form_factor_kernels(p.position, p.normal, shooting_nodes(pts.nodes, pts.count, start),
                            count, F);
        const ShooterPoint* q = pts.first + start;
        for (int i = 0; i < count; ++i)  // b_star_ is zero unless subtracting
            if (F[i] != 0) sum += F[i] * (q[i].e - q[i].a * b_star_);
    }
    return sum;
}

IncrementIntegrator::ShadowTriangleCorners IncrementIntegrator::triangle_corners(Vec2 a, Vec2 b,
                                                                                  Vec2 c) const {
    ShadowTriangleCorners t{a, b, c, {}, {}, {}, std::fabs(cross(b - a, c - a))};
    if (!unshot_constant_) {  // (u, v) at the corners exactly
        t.uv_a = plane_.parameters(a);
        t.uv_b = plane_.parameters(b);
        t.uv_c = plane_.parameters(c);
    }
    return t;
}

Rgb IncrementIntegrator::triangle_value(const SurfacePoint& p, const ShadowTriangleCorners& t,
                                        int n) {
    // The triangle rule of degree 2n - 2 (tri_rules_[n]) on one triangle of the shooter's plane:
    // int F(p, x) (B_h(u(x), v(x)) - b*) dA(x).
    Rgb sum;
    if (t.jacobian <= 0) return sum;
    add_triangle_rule(p, t.a, t.b, t.c, t.jacobian, tri_rules_[n], &t, sum);
    return sum;
}

void IncrementIntegrator::add_triangle_rule(const SurfacePoint& p, Vec2 a, Vec2 b, Vec2 c,
                                            double jacobian, const TriangleRule& rule,
                                            const ShadowTriangleCorners* corners, Rgb& sum) {
    // int F(p, x) (B_h(u(x), v(x)) - b*) dA(x) on the triangle by the rule: each node's term
    // added to `sum` in the nodes' order.
    const Rgb constant_b = unshot_constant_ ? shooter_.unshot.coefficient(0, 0) : Rgb{};
    const Vec2 ab = b - a, ac = c - a;
    const int n_points = static_cast<int>(rule.points.size());
    const Vec2* points = rule.points.data();
    const double* weights = rule.weights.data();
    extra_evaluations_ += long(n_points);
    const Rgb b_star = b_star_;
    // The nodes in passes, each a short loop over independent nodes (the processor overlaps
    // their chains: Newton's divisions or the inverse bilinear map, Horner's rule) instead of
    // one node's whole chain after another; then the sum in the nodes' order, so the value is
    // the same to the bit.
    constexpr int chunk = 32;
    double block[6 * chunk], F[chunk];
    Vec2 X[chunk], uv[chunk];
    Rgb B[chunk];
    for (int start = 0; start < n_points; start += chunk) {
        const int count = std::min(chunk, n_points - start);
        for (int i = 0; i < count; ++i) {  // the nodes in the plane and in space
            const Vec2 node = points[start + i];
            X[i] = a + node.x * ab + node.y * ac;
            const Vec3 x = plane_.to_space(X[i]);
            block[i] = x.x;
            block[count + i] = x.y;
            block[2 * count + i] = x.z;
            block[3 * count + i] = plane_.normal.x;
            block[4 * count + i] = plane_.normal.y;
            block[5 * count + i] = plane_.normal.z;
        }
        form_factor_kernels(p.position, p.normal, shooting_nodes(block, count), count, F);
        if (!unshot_constant_) {
            if (corners) {
                // At a node, the corners' affine blend refined by two Newton steps (the inverse
                // of the bilinear map is nearly affine over one triangle).
                const ShadowTriangleCorners& t = *corners;
                for (int i = 0; i < count; ++i) {
                    if (F[i] == 0) continue;
                    const Vec2 node = points[start + i];
                    const Vec2 guess =
                        t.uv_a + node.x * (t.uv_b - t.uv_a) + node.y * (t.uv_c - t.uv_a);
                    uv[i] = plane_.refine_parameters(X[i], plane_.refine_parameters(X[i], guess));
                }
            } else {
                for (int i = 0; i < count; ++i)
                    if (F[i] != 0) uv[i] = plane_.parameters(X[i]);
            }
            for (int i = 0; i < count; ++i)
                if (F[i] != 0) B[i] = (*unshot_patches_)(uv[i].x, uv[i].y);
        }
        for (int i = 0; i < count; ++i) {
            if (F[i] == 0) continue;
            const Rgb Bi = unshot_constant_ ? constant_b : B[i];
            sum += (weights[start + i] * jacobian * F[i]) * (Bi - b_star);
        }
    }
}

Rgb IncrementIntegrator::shadow_integral(const SurfacePoint& p, double tolerance, double near_field,
                                         std::vector<ShadowTriangle>* kept) {
    // The shadowed part, fan triangles refined worst first (as AdaptiveOptions::global) until
    // the n against n + 1 estimates sum to the tolerance; a triangle too close to p for its
    // size (near_field) is split whatever its estimate.
    struct Item {
        ShadowTriangle t;
        Rgb f1;
        double error;
    };
    auto corner = [&](const ShadowTriangle& t, int k) {
        const ConvexPolygon& piece = shadow_regions_[t.region];
        const Vec2 a = piece[0], b = piece[t.fan], c = piece[t.fan + 1];
        const Vec2 w = t.bary[k];  // weights of b and c
        return a + w.x * (b - a) + w.y * (c - a);
    };
    auto too_near = [&](const Vec2(&v)[3]) {
        if (near_field <= 0) return false;
        Box3 box;
        for (const Vec2& q : v) box.extend(plane_.to_space(q));
        const Vec3 gap = max(max(box.lo - p.position, p.position - box.hi), Vec3{0, 0, 0});
        return length(box.extent()) > near_field * length(gap);
    };
    std::vector<Item> heap, done;
    double total = 0;
    auto worse = [](const Item& x, const Item& y) { return x.error < y.error; };
    const int n_tri = options_.n_pieces > 0 ? options_.n_pieces : options_.n;
    std::vector<ShadowTriangle> todo;
    heap.reserve(32);  // room for a typical refinement at once (as adaptive_tensor_rule_2d's)
    todo.reserve(32);
    for (size_t r = 0; r < shadow_regions_.size(); ++r)
        for (size_t k = 1; k + 1 < shadow_regions_[r].size(); ++k)
            todo.push_back({int(r), int(k), {{0, 0}, {1, 0}, {0, 1}}, 0});
    auto evaluate = [&]() {
        while (!todo.empty()) {
            const ShadowTriangle t = todo.back();
            todo.pop_back();
            const Vec2 v[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
            if (t.level < 12 && too_near(v)) {
                for (const ShadowTriangle& ch : t.children()) todo.push_back(ch);
                continue;
            }
            const ShadowTriangleCorners corners = triangle_corners(v[0], v[1], v[2]);
            const Rgb f0 = triangle_value(p, corners, n_tri);
            const Rgb f1 = triangle_value(p, corners, n_tri + 1);
            const double error = max_abs(f1 - f0);
            total += error;
            Item item{t, f1, error};
            if (t.level >= 12) {
                done.push_back(item);
            } else {
                heap.push_back(item);
                std::push_heap(heap.begin(), heap.end(), worse);
            }
        }
    };
    evaluate();
    while (total > tolerance && !heap.empty() && heap.size() + done.size() < 4000) {
        std::pop_heap(heap.begin(), heap.end(), worse);
        const Item w = heap.back();
        heap.pop_back();
        total -= w.error;
        for (const ShadowTriangle& ch : w.t.children()) todo.push_back(ch);
        evaluate();
    }
    // A fixed order of summation: by region, fan triangle, level and position.
    heap.insert(heap.end(), done.begin(), done.end());
    std::sort(heap.begin(), heap.end(), [](const Item& x, const Item& y) { return x.t < y.t; });
    Rgb sum;
    for (const Item& it : heap) {
        sum += it.f1;
        if (kept) kept->push_back(it.t);
    }
    return sum;
}

Rgb IncrementIntegrator::shadow_on(const SurfacePoint& p,
                                   const std::vector<ShadowTriangle>& triangles) {
    Rgb sum;
    for (const ShadowTriangle& t : triangles) {
        if (t.region >= int(shadow_regions_.size()) ||
            t.fan + 1 >= int(shadow_regions_[t.region].size()))
            continue;  // the shadow's outline changed between the two points: part not found
        const ConvexPolygon& piece = shadow_regions_[t.region];
        const Vec2 a = piece[0], b = piece[t.fan], c = piece[t.fan + 1];
        Vec2 v[3];
        for (int k = 0; k < 3; ++k) v[k] = a + t.bary[k].x * (b - a) + t.bary[k].y * (c - a);
        sum += triangle_value(p, triangle_corners(v[0], v[1], v[2]),
                              (options_.n_pieces > 0 ? options_.n_pieces : options_.n) + 1);
    }
    return sum;
}

void IncrementIntegrator::take_shadows_apart() {
    // Disjoint convex parts of the union of the shadows (each minus the earlier ones), clipped
    // to the front of the horizon; the cells then see the horizon alone. (Once per view: a
    // second call finds no shadows left.)
    // DESIGN: the shadows of adjacent faces of one block share edges, and subtracting one from
    // the other leaves slivers and doubled vertices that rounding makes or unmakes. They carry
    // no area, but they change the regions' vertex counts, and with them the fan triangles
    // shadow_integral refines: between two nearby points (edgefill's divided differences (22)
    // need the same regions at both, shadow_on) and between one scene in two units (the
    // triangles' quadrature errors differ by up to the tolerance). Parts at most 1e-10 of the
    // shooter's size wide or 1e-7 of it across are dropped (is_sliver: the specks rounding
    // leaves where three shadow edges meet are about 1e-9 of it across), and vertices within
    // 1e-10 of its size of the line through their neighbours are removed. (Not parts below a
    // fraction of the shooter's area: that would drop a small shadow which hides most of what
    // a point close to a large shooter sees.) Measured on the Cornell box and test_scale's
    // shadowed floor in decimal units: with 1e-12 instead, rounding still changes the regions
    // (the kernel-evaluation counts of some shots differ between units); with 1e-10 none does.
    const double min_offset = 1e-10 * plane_.size;
    for (size_t s = 0; s < view_.shadows.size(); ++s) {
        std::vector<ConvexPolygon> parts{view_.horizon_cuts ? clip(view_.shadows[s], view_.front)
                                                            : view_.shadows[s]};
        for (size_t t = 0; t < s && !parts.empty(); ++t) {
            std::vector<ConvexPolygon> next;
            for (const ConvexPolygon& part : parts)
                for (ConvexPolygon& rest : subtract(part, view_.shadows[t]))
                    next.push_back(std::move(rest));
            parts = std::move(next);
        }
        for (ConvexPolygon& part : parts) {
            if (is_sliver(part, min_offset, 1e-7 * plane_.size)) continue;
            remove_flat_vertices(part, min_offset);
            start_at_canonical_vertex(part);  // its fan: the same in any unit
            shadow_regions_.push_back(std::move(part));
        }
    }
    view_.shadows.clear();
}

void IncrementIntegrator::set_view(const SurfacePoint& p) {
    b_star_ = Rgb{};
    extra_evaluations_ = 0;
    rays_ = 0;
    mixed_.clear();
    shaft_lists_.clear();
    pieces_key_ = ~0ULL;
    if (planar_ && (options_.clip_horizon || occlusion_))
        view_ = blocked_view(plane_, p.position, p.normal, occlusion_,
                             receiver_plane_ ? &*receiver_plane_ : nullptr);
    else
        view_ = BlockedView{};
    if (!options_.clip_horizon) {  // shadows only: the horizon is left to the clamped cosine
        view_.horizon_cuts = false;
        view_.behind_all = false;
    }
    shadow_regions_.clear();
}

void IncrementIntegrator::cell_image(const QuadCell& cell, ConvexPolygon& image) const {
    // Iso-parameter lines of a bilinear map are straight: a cell's image is the quadrilateral of
    // its corners (counter-clockwise, as the whole quad's). Written into `image`, whose storage
    // is reused from cell to cell.
    const Rect& r = cell.rect;
    image.assign({plane_.at(r.x0, r.y0), plane_.at(r.x1, r.y0), plane_.at(r.x1, r.y1),
                  plane_.at(r.x0, r.y1)});
}

Rgb IncrementIntegrator::pieces_value(const SurfacePoint& p,
                                      const std::vector<ConvexPolygon>& pieces, int n) {
    // The triangle rule of degree 2n - 2 on a fan of triangles of each convex piece, in the
    // shooter's plane: int F(p, x) B_h(u(x), v(x)) dA(x) (dA is the plane's own area element, so
    // the area factor A_h of the parameter map does not appear).
    // The cell's n or n+1 stands for the pieces' pair (n_pieces, n_pieces + 1).
    const int np = options_.n_pieces > 0 ? options_.n_pieces + (n - options_.n) : n;
    const TriangleRule& rule = tri_rules_[np];
    Rgb sum;
    for (const ConvexPolygon& piece : pieces)
        for (size_t k = 1; k + 1 < piece.size(); ++k) {
            const Vec2 a = piece[0], b = piece[k], c = piece[k + 1];
            const double jacobian = std::fabs(cross(b - a, c - a));  // twice the area
            if (jacobian <= 0) continue;
            add_triangle_rule(p, a, b, c, jacobian, rule, nullptr, sum);  // (u, v) exactly
        }
    return sum;
}

IncrementIntegrator::PointSpan IncrementIntegrator::horizon_points(const QuadCell& cell, int n,
                                                                   const ConvexPolygon& image) {
    // The front piece of a cell only the receiver's fixed horizon cuts: its n x n triangle-rule
    // points, with e = w J B_h and a = w J as for the tensor points (the plane's own area
    // element, no A_h), computed once per cell and rule like points().
    const std::uint64_t key = (cell_key(cell) << 1) | std::uint64_t(n == options_.n ? 0 : 1);
    auto it = horizon_cache_.find(key);
    if (it == horizon_cache_.end()) {
        if (horizon_points_ > max_cached_horizon_points) {
            horizon_cache_.clear();  // bound it; values never depend on it
            horizon_points_ = 0;
        }
        HorizonPoints entry;
        std::vector<ShooterPoint>& pts = entry.points;
        ConvexPolygon piece = clip(image, view_.front);
        // A horizon through a corner of the cell leaves a near-repeated vertex where rounding
        // decides, and with it a fan triangle of no area (its points cost evaluations and add
        // nothing): removed, with the other vertices within 1e-9 of the cell's size of flat.
        remove_flat_vertices(piece, 1e-9 * std::sqrt(std::fabs(signed_area(image))));
        start_at_canonical_vertex(piece);
        const TriangleRule& rule = tri_rules_[n];
        const Rgb constant_b = unshot_constant_ ? shooter_.unshot.coefficient(0, 0) : Rgb{};
        for (size_t k = 1; k + 1 < piece.size(); ++k) {
            const Vec2 a = piece[0], b = piece[k], c = piece[k + 1];
            const double jacobian = std::fabs(cross(b - a, c - a));
            if (jacobian <= 0) continue;
            for (size_t q = 0; q < rule.points.size(); ++q) {
                const Vec2 X = a + rule.points[q].x * (b - a) + rule.points[q].y * (c - a);
                const double w = rule.weights[q] * jacobian;
                Rgb B = constant_b;
                if (!unshot_constant_) {
                    const Vec2 uv = plane_.parameters(X);
                    B = (*unshot_patches_)(uv.x, uv.y);
                }
                pts.push_back({plane_.to_space(X), plane_.normal, w * B, w});
            }
        }
        horizon_points_ += pts.size() + 1;  // an empty piece's entry counts as one
        pts.shrink_to_fit();
        append_shooting_nodes(entry.nodes, pts.data(), static_cast<int>(pts.size()));
        it = horizon_cache_.emplace(key, std::move(entry)).first;
    }
    const std::vector<ShooterPoint>& pts = it->second.points;
    extra_evaluations_ += long(pts.size()) - long(n) * n;  // the rule counts n^2 per cell
    return {pts.data(), static_cast<int>(pts.size()), it->second.nodes.data()};
}

void IncrementIntegrator::collect_shaft_occluders(const SurfacePoint& p, const QuadCell& cell,
                                                  const PointSpan& pts) {
    // A polygon whose box misses the box of p and the cell, whose plane has them all on one
    // side, or whose bounding ball misses the capsule around the segment from p to the ball of
    // the nodes, cannot come between p and the cell.
    // DESIGN: on a planar shooter the region is the whole cell (its four corners: the cell is
    // a convex quadrilateral holding every node of both rules and of every cell inside it), so
    // the n and n + 1 rules share one list and a cell's children filter their parent's list
    // instead of the point's (shaft_lists_, kept until the next set_view). On a curved shooter
    // the cell bulges past its corners: its nodes' ball, each rule on its own.
    const std::vector<int>* list = view_.use_rays ? &view_.occluders : &occlusion_->candidates;
    std::uint64_t key = 0;
    if (planar_) {
        key = cell_key(cell);
        const auto it = shaft_lists_.find(key);
        if (it != shaft_lists_.end()) {
            local_ = it->second;
            return;
        }
        // The nearest ancestor's list (every polygon that can meet a segment to the child
        // can meet one to the parent, which holds it).
        for (QuadCell up = cell; up.level > 0;) {
            up = QuadCell{up.level - 1, up.i / 2, up.j / 2, Rect{}};
            const auto parent = shaft_lists_.find(cell_key(up));
            if (parent != shaft_lists_.end()) {
                list = &parent->second;
                break;
            }
        }
    }
    const Rect& r = cell.rect;
    const Vec3 corners[4] = {
        shooter_.surface->point(r.x0, r.y0), shooter_.surface->point(r.x1, r.y0),
        shooter_.surface->point(r.x1, r.y1), shooter_.surface->point(r.x0, r.y1)};
    Box3 shaft, nodes;
    shaft.extend(p.position);
    if (planar_)
        for (const Vec3& c : corners) nodes.extend(c);
    else
        for (int i = 0; i < pts.count; ++i) nodes.extend(pts.first[i].x);
    shaft.extend(nodes);
    for (const Vec3& c : corners) shaft.extend(c);
    const Vec3 c_nodes = nodes.centre();
    double r_nodes = 0;
    if (planar_)
        for (const Vec3& c : corners) r_nodes = std::max(r_nodes, length(c - c_nodes));
    else
        for (int i = 0; i < pts.count; ++i)
            r_nodes = std::max(r_nodes, length(pts.first[i].x - c_nodes));
    // DESIGN: 1e-9 of the coordinates' size: rounding never drops a polygon a ray could meet.
    const double capsule_slack =
        1e-9 * (length(p.position) + length(c_nodes) + length(shaft.extent()));
    const Vec3 axis = c_nodes - p.position;
    const double axis_2 = dot(axis, axis);
    auto outside_capsule = [&](const Box3& box) {
        const Vec3 m = box.centre();
        const double rho = 0.5 * length(box.extent());
        const double s = axis_2 > 0 ? std::clamp(dot(m - p.position, axis) / axis_2, 0.0, 1.0) : 0;
        return length(m - (p.position + s * axis)) > r_nodes + rho + capsule_slack;
    };
    // DESIGN: on a planar shooter the nodes lie in the cell's quadrilateral, so every segment
    // lies in the pyramid from p to it (Shaft); a polygon with every vertex outside one of its
    // planes meets none of them. Counted on corridor.mgf's first 10 shots (7.5 M cells): the
    // box and capsule tests kept 103 of the 223 occluders of a cell on average, each tested by
    // every node's ray.
    std::optional<Shaft> pyramid;
    if (planar_) pyramid.emplace(p.position, corners);
    const std::vector<Polygon>& polys = occlusion_->octree->polygons();
    local_.clear();
    for (int id : *list) {
        const Polygon& poly = polys[id];
        if (!overlaps(poly.bounds(), shaft)) continue;
        if (outside_capsule(poly.bounds())) continue;
        if (pyramid && pyramid->separates(poly.vertices())) continue;
        const Plane& pl = poly.plane();
        // p and the ball of the nodes on one side of the plane: no segment crosses it (inside a
        // sphere, every facet's plane but those next to p).
        const double d_p = pl.signed_distance(p.position), d_c = pl.signed_distance(c_nodes);
        if ((d_p > capsule_slack && d_c > r_nodes + capsule_slack) ||
            (d_p < -capsule_slack && d_c < -r_nodes - capsule_slack))
            continue;
        // A facet of a curved surface near p never blocks its segments (Polygon::hit_counts).
        if (poly.within_thickness(p.position)) continue;
        double lo = HUGE_VAL, hi = -HUGE_VAL;
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3 c{(corner & 1) ? shaft.hi.x : shaft.lo.x,
                         (corner & 2) ? shaft.hi.y : shaft.lo.y,
                         (corner & 4) ? shaft.hi.z : shaft.lo.z};
            const double d = pl.signed_distance(c);
            lo = std::min(lo, d);
            hi = std::max(hi, d);
        }
        if (lo > 0 || hi < 0) continue;
        local_.push_back(id);
    }
    if (planar_) shaft_lists_.emplace(key, local_);
}

Rgb IncrementIntegrator::cell_value(const SurfacePoint& p, const QuadCell& cell, int n) {
    const bool rays = !planar_ || view_.use_rays;  // visibility by one ray per node
    if (planar_ && !view_.trivial() && !view_.use_rays) {
        cell_image(cell, image_);
        const ConvexPolygon& image = image_;
        bool shadowed = false;
        switch (classify_cell(image, view_, &shadowed)) {
            case CellVisibility::hidden:
                return Rgb{};
            case CellVisibility::clear:
                return sum_over(p, points(cell, n));
            case CellVisibility::cut: {
                const std::uint64_t key = cell_key(cell);
                if (cell.level < min_cut_level && cell.level < options_.max_depth) {
                    mixed_.push_back(key);  // split without integrating its pieces
                    return Rgb{};
                }
                if (!shadowed && receiver_plane_)
                    return sum_over(p, horizon_points(cell, n, image));
                if (key != pieces_key_) {  // the n and n+1 rules of one cell share the pieces
                    pieces_ = visible_pieces(image, view_);
                    pieces_key_ = key;
                }
                return pieces_value(p, pieces_, n);
            }
        }
    }
    if (!occlusion_ || !rays) return sum_over(p, points(cell, n));
    // A curved shooter, or too many occluders to project: one visibility ray per node (eq. (21)
    // with VIS), tested against the occluders that can come between p and this cell; none: no
    // rays at all.
    const PointSpan pts = points(cell, n);
    collect_shaft_occluders(p, cell, pts);
    if (local_.empty()) return sum_over(p, pts);
    Rgb sum, unoccluded;
    int n_visible = 0, n_blocked = 0;
    for (int i = 0; i < pts.count; ++i) {
        const ShooterPoint& q = pts.first[i];
        const double F = form_factor_kernel(p.position, p.normal, q.x, q.n);
        if (F == 0) continue;
        unoccluded += F * q.e;
        // The segment between the two true surfaces, tested as the paper's shadow rays are: one
        // by one against the shaft's list, through the octree beyond max_shaft_occluders.
        if (segment_blocked(*occlusion_, local_, p.position, q.x, &rays_, max_shaft_occluders,
                            &recent_blockers_)) {
            ++n_blocked;
            continue;
        }
        ++n_visible;
        sum += F * q.e;
    }
    // A cell whose nodes disagree is split (integrate's `near`) while what its visibility can
    // get wrong, at most its value without occluders, exceeds the tolerance; below, the n
    // against n + 1 estimate decides, like any other cell's.
    if (n_visible > 0 && n_blocked > 0 && max_abs(unoccluded) > mixed_tolerance_)
        mixed_.push_back(cell_key(cell));
    return sum;
}

IncrementIntegrator::Result IncrementIntegrator::integrate(const SurfacePoint& p,
                                                           bool keep_partition, int min_depth,
                                                           bool allow_subtraction) {
    Result result;
    if (analytic_ && !keep_partition) {
        set_view(p);
        if (!view_.use_rays) {  // eq. (21) for a constant B_h: B_h times the form factor to
                                // the part of the shooter p sees (exact visibility)
            result.value = visible_form_factor(p) * shooter_.unshot.coefficient(0, 0);
            return result;
        }
    }
    set_view(p);
    if (view_.behind_all) return result;  // the whole shooter is behind p: nothing arrives
    // The tolerance is relative to the (n+1)-point estimate over the whole shooter, with a
    // floor at 1e-4 of the largest possible value (F integrates to at most 1 over the shooter,
    // so I(p) <= max B_h): a point that sees almost nothing does not ask for endless splitting.
    // (The estimate ignores occluders: a shadowed point keeps the tolerance of a lit one.)
    const QuadCell root{0, 0, 0, Rect{0, 1, 0, 1}};
    const double estimate = max_abs(sum_over(p, points(root, options_.n + 1)));
    const double scale = std::max(estimate, 1e-4 * unshot_bound_);
    // Singularity subtraction (QuadratureOptions::subtract): the constant B_h(x*) at the foot
    // x* of p carries the peak of F exactly; the rule integrates F (B_h - B_h(x*)).
    // DESIGN: no near-field guard where the kernel is bounded (a point on the shooter's own
    // sphere or cylinder: a self-transfer, or a neighbouring piece of one sphere): the guard
    // split the cells around such a point down to max_depth for a kernel that is constant there
    // (inside a sphere, 183 times the evaluations for the same values: docs/method.md).
    const bool bounded = shooter_.surface->bounded_kernel_at(p);
    double near_field = bounded ? 0 : near_field_guard;
    Rgb exact_part;
    if (planar_ && !unshot_constant_ && options_.subtract && allow_subtraction && !view_.use_rays) {
        const Vec2 uv = plane_.parameters(plane_.to_plane(p.position));
        const Rgb b_star =
            shooter_.unshot.evaluate(std::clamp(uv.x, 0.0, 1.0), std::clamp(uv.y, 0.0, 1.0));
        exact_part = visible_form_factor(p) * b_star;
        b_star_ = b_star;
        result.subtracted = b_star;
        near_field = near_field_guard_subtracted;
    }
    AdaptiveOptions opt;
    opt.n = options_.n;
    opt.tolerance = std::max(options_.rel_tolerance * scale, options_.abs_tolerance);
    // Shadow subtraction (QuadratureOptions::shadow_subtraction): the cells below see only the
    // horizon; the part of the shooter the shadows hide (in front of p) is integrated here on
    // its own (shadow_integral: the triangle with the largest error estimate splits first,
    // until the estimates add up to half the tolerance), and subtracted. The rule over the
    // cells gets the other half.
    Rgb shadowed;
    if (planar_ && options_.shadow_subtraction) take_shadows_apart();
    if (!shadow_regions_.empty()) {
        const double share = 0.5 * opt.tolerance;
        opt.tolerance -= share;
        shadowed = shadow_integral(p, share, near_field, &result.shadow_triangles);
        result.shadow_subtracted = true;
        result.shadow_tolerance = share;
        result.shadow_near_field = near_field;
        for (const ConvexPolygon& region : shadow_regions_)
            result.shadow_shape.push_back(int(region.size()));
    }
    opt.max_depth = options_.max_depth;
    // Per-node visibility on a curved shooter: a visibility step never passes the n against
    // n + 1 test, so without this cap its cells would split down to max_depth.
    const bool ray_visibility = occlusion_ && (!planar_ || view_.use_rays);
    if (ray_visibility) opt.max_depth = std::min(opt.max_depth, options_.max_visibility_depth);
    // DESIGN: see mixed_tolerance_ (sample_values.h).
    mixed_tolerance_ = ray_visibility ? opt.tolerance : 0;
    opt.min_depth = min_depth >= 0 ? std::min(min_depth, options_.max_depth) : options_.min_depth;
    opt.min_share = options_.min_share;
    opt.global = options_.global;
    auto cell_rule = [&](const QuadCell& cell, int n) { return cell_value(p, cell, n); };
    // DESIGN: on a single cell the n- and (n+1)-point rules can agree by chance on a peaked
    // integrand, so the whole shooter is never accepted as one cell (min_depth = 1: with n = 6
    // a point of the perpendicular squares at (0.69, 0.24) was accepted at the root 1.3e-3 off,
    // 13 times the tolerance). Moreover, the n against n+1 test can accept a cell whose nodes
    // all miss a peak narrower than their spacing, which is what a receiving point close to
    // the shooter sees. A cell is trusted only when it is well separated from p: its points'
    // extent at most near_field times their distance from p.
    auto near = [&](const QuadCell& cell) {
        if (!mixed_.empty() &&
            std::find(mixed_.begin(), mixed_.end(), cell_key(cell)) != mixed_.end() &&
            (!ray_visibility || cell.level < options_.max_visibility_depth))
            return true;  // its nodes disagree on visibility, or a coarse cut cell: split
        return too_near(p, cell, near_field);
    };
    auto r = adaptive_tensor_rule_2d(cell_rule, root.rect, opt, keep_partition, near);
    result.value = r.value + exact_part - shadowed;
    if (!keep_partition) result.shadow_triangles.clear();
    result.n_evaluations =
        r.n_evaluations + long(options_.n + 1) * (options_.n + 1) + extra_evaluations_;
    result.n_rays = rays_;
    result.converged = r.converged;
    result.partition = std::move(r.cells);
    return result;
}

bool IncrementIntegrator::too_near(const SurfacePoint& p, const QuadCell& cell, double near_field) {
    if (near_field <= 0) return false;
    // The cell's extent: its nodes and its corners (the nodes alone leave a gap along the
    // cell's edges, where a peak between two cells would escape both).
    const PointSpan pts = points(cell, options_.n + 1);
    Box3 box;
    for (int i = 0; i < pts.count; ++i) box.extend(pts.first[i].x);
    const Rect& r = cell.rect;
    for (const Vec2 c : {Vec2{r.x0, r.y0}, Vec2{r.x1, r.y0}, Vec2{r.x0, r.y1}, Vec2{r.x1, r.y1}})
        box.extend(shooter_.surface->point(c.x, c.y));
    const Vec3 gap = max(max(box.lo - p.position, p.position - box.hi), Vec3{0, 0, 0});
    return length(box.extent()) > near_field * length(gap);
}

std::vector<AcceptedCell<Rgb>> IncrementIntegrator::fraction_partition(const SurfacePoint& p,
                                                                       int depth,
                                                                       long* n_evaluations) {
    std::vector<AcceptedCell<Rgb>> out;
    set_view(p);
    if (view_.behind_all) return out;
    const int n = options_.n;
    const bool bounded = shooter_.surface->bounded_kernel_at(p);  // no guard: see integrate
    std::vector<QuadCell> todo;
    const int side = 1 << depth;
    for (int j = side - 1; j >= 0; --j)
        for (int i = side - 1; i >= 0; --i)
            todo.push_back(QuadCell{depth, i, j,
                                    Rect{double(i) / side, double(i + 1) / side, double(j) / side,
                                         double(j + 1) / side}});
    long n_evals = 0;
    while (!todo.empty()) {
        const QuadCell cell = todo.back();
        todo.pop_back();
        const size_t n_mixed = mixed_.size();
        bool split =
            cell.level < max_fraction_depth && !bounded && too_near(p, cell, near_field_guard);
        Rgb value;
        if (!split) {
            value = cell_value(p, cell, n);
            n_evals += long(n) * n;
            // A coarse cut cell is split without a value (cell_value's rule).
            split = mixed_.size() > n_mixed && cell.level < max_fraction_depth;
        }
        if (!split) {
            out.push_back({cell, value});
            continue;
        }
        const std::array<QuadCell, 4> children = quad_children(cell);
        todo.insert(todo.end(), children.rbegin(), children.rend());
    }
    if (n_evaluations) *n_evaluations += n_evals + extra_evaluations_;
    return out;
}

Rgb IncrementIntegrator::integrate_on(const SurfacePoint& p,
                                      const std::vector<AcceptedCell<Rgb>>& partition,
                                      long* n_evaluations, long* n_rays, const Result* made_by) {
    set_view(p);
    Rgb sum;
    if (made_by && max_abs(made_by->subtracted) > 0) {  // the same constant subtracted
        b_star_ = made_by->subtracted;
        sum = visible_form_factor(p) * b_star_;
    }
    if (made_by && made_by->shadow_subtracted) {
        // The shadowed part on the triangles the partition's point kept: the same refinement
        // at both points, so a divided difference (22) of them stays smooth. That needs the
        // same shadow regions with the same vertices at both points; when they differ (an
        // occluder's shadow gained or lost a vertex between the two points) the triangles
        // would land on other parts of the shadow, so it is integrated afresh here.
        take_shadows_apart();
        std::vector<int> shape;
        for (const ConvexPolygon& region : shadow_regions_) shape.push_back(int(region.size()));
        if (shape == made_by->shadow_shape)
            sum -= shadow_on(p, made_by->shadow_triangles);
        else if (!shadow_regions_.empty())
            sum -=
                shadow_integral(p, made_by->shadow_tolerance, made_by->shadow_near_field, nullptr);
    }
    if (!view_.behind_all)
        for (const auto& c : partition) sum += cell_value(p, c.cell, options_.n + 1);
    if (n_evaluations)
        *n_evaluations +=
            long(partition.size()) * (options_.n + 1) * (options_.n + 1) + extra_evaluations_;
    if (n_rays) *n_rays += rays_;
    return sum;
}

}  // namespace mbr
