// math/gauss_legendre.h - Gauss-Legendre quadrature (paper section 6, "Adaptive Quadrature"):
// nodes and weights for any n, the fixed tensor-product 2D rule, and the adaptive 1D and 2D
// rules that compare n against n + 1 points, split the interval (cell) in two (four), and share
// the tolerance among the children. Every adaptive rule counts its integrand evaluations.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "math/check.h"
#include "math/vec3.h"

namespace mbr {

/// The n-point Gauss-Legendre rule on [-1, 1]: nodes ascending, weights summing to 2.
/// Nodes and weights are accurate to about 1e-15 (Newton's method on P_n, with the
/// three-term recurrence), for any n >= 1.
struct GaussLegendre {
    std::vector<double> x;  // nodes in (-1, 1)
    std::vector<double> w;  // weights
    int n() const { return static_cast<int>(x.size()); }
};
GaussLegendre gauss_legendre(int n);

/// sum_i w_i f(x_i) mapped to [a, b].
template <class F>
auto integrate_1d(F&& f, double a, double b, const GaussLegendre& rule) {
    const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
    decltype(f(a)) sum{};
    for (int i = 0; i < rule.n(); ++i) sum += rule.w[i] * f(mid + half * rule.x[i]);
    return sum * half;
}

/// The fixed 2D rule of section 6: sum_i sum_j w_i w_j f(x_i, x_j), mapped to a rectangle
/// (the factor is the Jacobian of the map from [-1,1]^2).
template <class F>
auto integrate_2d(F&& f, const Rect& r, const GaussLegendre& rule) {
    const double hx = 0.5 * r.width(), hy = 0.5 * r.height();
    const double cx = 0.5 * (r.x0 + r.x1), cy = 0.5 * (r.y0 + r.y1);
    decltype(f(cx, cy)) sum{};
    for (int i = 0; i < rule.n(); ++i) {
        decltype(f(cx, cy)) row{};
        for (int j = 0; j < rule.n(); ++j) row += rule.w[j] * f(cx + hx * rule.x[i], cy + hy * rule.x[j]);
        sum += rule.w[i] * row;
    }
    return sum * (hx * hy);
}

/// Options of the adaptive rules (section 6).
struct AdaptiveOptions {
    int n = 4;               // compare the n-point rule with the (n+1)-point rule
    double tolerance = 1e-8; // absolute error allowed on the whole domain
    int max_depth = 12;      // no cell is split more than this many times
    int min_depth = 0;       // cells above this level are split whatever the rules say
    // A cell's share of the tolerance never drops below min_share * tolerance. The paper's
    // halving (quartering in 2D) otherwise asks deep cells near a singularity for agreement
    // far below rounding, which no rule can give; the bound on the accumulated error becomes
    // tolerance * (1 + n_cells * min_share).
    double min_share = 1e-6;
    // Beyond the paper (2D rule only): instead of giving each child a quarter of its parent's
    // tolerance, keep refining the cell with the largest error estimate |F1 - F0| until the
    // estimates sum to at most the tolerance (or max_cells cells exist). The same bound on the
    // accumulated error, reached with far fewer cells where the error is spread thin (a spline
    // integrand whose knots every cell holds).
    bool global = false;
    int max_cells = 20000;   // global strategy: stop refining beyond this many cells (both
                             //   strategies: no forced split beyond it)
};

/// A dyadic cell of the adaptive 2D rule: level, index (i, j) within the domain, its rectangle.
struct QuadCell {
    int level = 0, i = 0, j = 0;
    Rect rect;
};

/// One accepted cell of an adaptive 2D integration and the integral found on it.
template <class V>
struct AcceptedCell {
    QuadCell cell;
    V value{};
};

template <class V>
struct AdaptiveResult {
    V value{};                 // the integral (the n+1 rule, summed over accepted cells)
    long n_evaluations = 0;    // integrand evaluations, both rules, all cells
    int depth = 0;             // deepest level reached
    bool converged = true;     // false when some cell hit max_depth before agreeing
    std::vector<AcceptedCell<V>> cells;  // the partition, when asked for
};

/// Adaptive 1D rule: on [a, b] apply the n- and (n+1)-point rules; if they differ by less than
/// the tolerance keep the (n+1)-point value, otherwise halve the interval and give each half
/// half the tolerance, so the accumulated error stays within the tolerance.
template <class F>
auto adaptive_integrate_1d(F&& f, double a, double b, const AdaptiveOptions& opt) {
    using V = decltype(f(a));
    const GaussLegendre rule_n = gauss_legendre(opt.n), rule_n1 = gauss_legendre(opt.n + 1);
    AdaptiveResult<V> result;
    struct Work { double a, b, tol; int depth; };
    std::vector<Work> stack{{a, b, opt.tolerance, 0}};
    while (!stack.empty()) {
        Work w = stack.back();
        stack.pop_back();
        V f0 = integrate_1d(f, w.a, w.b, rule_n);
        V f1 = integrate_1d(f, w.a, w.b, rule_n1);
        result.n_evaluations += 2 * opt.n + 1;
        if (w.depth > result.depth) result.depth = w.depth;
        bool agree = max_abs(f1 - f0) <= w.tol;
        if (agree || w.depth >= opt.max_depth) {
            if (!agree) result.converged = false;
            result.value += f1;
            continue;
        }
        double mid = 0.5 * (w.a + w.b);
        const double child_tol = std::max(0.5 * w.tol, opt.min_share * opt.tolerance);
        stack.push_back({mid, w.b, child_tol, w.depth + 1});
        stack.push_back({w.a, mid, child_tol, w.depth + 1});
    }
    return result;
}

/// Never split by a geometric rule (the default of adaptive_tensor_rule_2d).
struct NoForcedSplit {
    bool operator()(const QuadCell&) const { return false; }
};

/// The four children of a cell, in (0,0), (1,0), (0,1), (1,1) order.
inline std::array<QuadCell, 4> quad_children(const QuadCell& c) {
    const Rect& r = c.rect;
    const double xm = 0.5 * (r.x0 + r.x1), ym = 0.5 * (r.y0 + r.y1);
    std::array<QuadCell, 4> out;
    for (int q = 0; q < 4; ++q) {
        const int di = q & 1, dj = q >> 1;
        out[q] = {c.level + 1, 2 * c.i + di, 2 * c.j + dj,
                  Rect{di ? xm : r.x0, di ? r.x1 : xm, dj ? ym : r.y0, dj ? r.y1 : ym}};
    }
    return out;
}

/// The global strategy of AdaptiveOptions::global: refine the worst cell first until the error
/// estimates sum to the tolerance. Deterministic: ties go to the coarser, then lower-indexed cell.
template <class CellRule, class ForceSplit>
auto adaptive_tensor_rule_2d_global(CellRule& cell_rule, const Rect& domain, const AdaptiveOptions& opt,
                                    bool keep_cells, ForceSplit& force_split) {
    using V = decltype(cell_rule(QuadCell{}, 1));
    AdaptiveResult<V> result;
    struct Item {
        QuadCell cell;
        V f1;
        double error;
    };
    auto worse = [](const Item& a, const Item& b) {  // heap order: largest error on top
        if (a.error != b.error) return a.error < b.error;
        if (a.cell.level != b.cell.level) return a.cell.level > b.cell.level;
        return a.cell.j != b.cell.j ? a.cell.j > b.cell.j : a.cell.i > b.cell.i;
    };
    std::vector<Item> heap;   // cells that may still be split
    std::vector<Item> done;   // cells at max_depth
    double total = 0;
    const long evals_per_cell = long(opt.n) * opt.n + long(opt.n + 1) * (opt.n + 1);
    std::vector<QuadCell> todo;
    // Room for a typical partition at once (a vector grown by push_back allocates at 1, 2, 4,
    // 8, ... elements: malloc and free were about 6 % of the Cornell box's time).
    heap.reserve(32);
    todo.reserve(16);
    todo.push_back(QuadCell{0, 0, 0, domain});
    auto evaluate = [&]() {
        while (!todo.empty()) {
            const QuadCell c = todo.back();
            todo.pop_back();
            const V f0 = cell_rule(c, opt.n);
            const V f1 = cell_rule(c, opt.n + 1);
            result.n_evaluations += evals_per_cell;
            result.depth = std::max(result.depth, c.level);
            const double error = max_abs(f1 - f0);
            // Cells above min_depth, and cells the caller does not trust, are split at once; the
            // forced splits stop at max_cells cells (a receiving point on a degenerate edge of
            // the shooter, a sphere's pole, is next to every cell along that edge).
            const bool room = long(heap.size() + done.size() + todo.size()) < long(opt.max_cells);
            if (c.level < opt.max_depth && (c.level < opt.min_depth || (room && force_split(c)))) {
                for (const QuadCell& ch : quad_children(c)) todo.push_back(ch);
                continue;
            }
            total += error;
            Item item{c, f1, error};
            if (c.level >= opt.max_depth) {
                done.push_back(item);
            } else {
                heap.push_back(item);
                std::push_heap(heap.begin(), heap.end(), worse);
            }
        }
    };
    evaluate();
    while (total > opt.tolerance && !heap.empty() &&
           long(heap.size() + done.size()) < long(opt.max_cells)) {
        std::pop_heap(heap.begin(), heap.end(), worse);
        const Item worst = heap.back();
        heap.pop_back();
        total -= worst.error;
        for (const QuadCell& ch : quad_children(worst.cell)) todo.push_back(ch);
        evaluate();
    }
    result.converged = total <= opt.tolerance;
    // Sum in a fixed order (by level, j, i), so the value does not depend on the heap's layout.
    std::vector<Item> all = std::move(heap);
    all.insert(all.end(), done.begin(), done.end());
    std::sort(all.begin(), all.end(), [](const Item& a, const Item& b) {
        if (a.cell.level != b.cell.level) return a.cell.level < b.cell.level;
        return a.cell.j != b.cell.j ? a.cell.j < b.cell.j : a.cell.i < b.cell.i;
    });
    for (const Item& it : all) {
        result.value += it.f1;
        if (keep_cells) result.cells.push_back({it.cell, it.f1});
    }
    return result;
}

/// Adaptive 2D rule over dyadic cells of `domain`, with the cell rule supplied by the caller:
/// cell_rule(cell, n) returns the n x n tensor Gauss-Legendre value on cell.rect. (The
/// radiosity kernel uses this form to cache the shooter's points per cell.) Splits a cell into
/// four children with a quarter of its tolerance each (or, with opt.global, refines the
/// worst cell first). Evaluations are counted as n^2 + (n+1)^2
/// per visited cell. force_split(cell) may declare a cell untrustworthy however well the two
/// rules agree (it is then split, up to max_depth).
template <class CellRule, class ForceSplit = NoForcedSplit>
auto adaptive_tensor_rule_2d(CellRule&& cell_rule, const Rect& domain, const AdaptiveOptions& opt,
                             bool keep_cells = false, ForceSplit&& force_split = ForceSplit{}) {
    using V = decltype(cell_rule(QuadCell{}, 1));
    if (opt.global) return adaptive_tensor_rule_2d_global(cell_rule, domain, opt, keep_cells, force_split);
    AdaptiveResult<V> result;
    struct Work { QuadCell cell; double tol; };
    std::vector<Work> stack{{QuadCell{0, 0, 0, domain}, opt.tolerance}};
    const long evals_per_cell = long(opt.n) * opt.n + long(opt.n + 1) * (opt.n + 1);
    long n_cells = 0;
    while (!stack.empty()) {
        Work w = stack.back();
        stack.pop_back();
        V f0 = cell_rule(w.cell, opt.n);
        V f1 = cell_rule(w.cell, opt.n + 1);
        result.n_evaluations += evals_per_cell;
        ++n_cells;
        if (w.cell.level > result.depth) result.depth = w.cell.level;
        // A cell the caller does not trust (force_split) is split whatever the rules say, until
        // max_cells cells have been evaluated (see the global strategy).
        bool agree = max_abs(f1 - f0) <= w.tol && w.cell.level >= opt.min_depth &&
                     !(n_cells < long(opt.max_cells) && force_split(w.cell));
        if (agree || w.cell.level >= opt.max_depth) {
            if (!agree) result.converged = false;
            result.value += f1;
            if (keep_cells) result.cells.push_back({w.cell, f1});
            continue;
        }
        const double child_tol = std::max(0.25 * w.tol, opt.min_share * opt.tolerance);
        const Rect& r = w.cell.rect;
        const double xm = 0.5 * (r.x0 + r.x1), ym = 0.5 * (r.y0 + r.y1);
        // Children pushed in reverse so they are visited in (0,0), (1,0), (0,1), (1,1) order.
        for (int c = 3; c >= 0; --c) {
            int di = c & 1, dj = c >> 1;
            QuadCell child{w.cell.level + 1, 2 * w.cell.i + di, 2 * w.cell.j + dj,
                           Rect{di ? xm : r.x0, di ? r.x1 : xm, dj ? ym : r.y0, dj ? r.y1 : ym}};
            stack.push_back({child, child_tol});
        }
    }
    return result;
}

/// Adaptive 2D rule of section 6 for a plain integrand f(x, y).
template <class F>
auto adaptive_integrate_2d(F&& f, const Rect& domain, const AdaptiveOptions& opt,
                           bool keep_cells = false) {
    std::vector<GaussLegendre> rules;  // rules[n] built on first use
    auto cell_rule = [&](const QuadCell& cell, int n) {
        if (static_cast<int>(rules.size()) <= n) rules.resize(n + 1);
        if (rules[n].n() != n) rules[n] = gauss_legendre(n);
        return integrate_2d(f, cell.rect, rules[n]);
    };
    return adaptive_tensor_rule_2d(cell_rule, domain, opt, keep_cells);
}

}  // namespace mbr
