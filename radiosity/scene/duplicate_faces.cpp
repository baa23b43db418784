// radiosity/scene/duplicate_faces.cpp - repeated surfaces (duplicate_faces.h): a hash table of
// quantised keys finds the candidates, same_surface decides, the readers' check drops or refuses.
#include "radiosity/scene/duplicate_faces.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <set>
#include <tuple>

#include "math/check.h"
#include "radiosity/scene/mgf_reader.h"

namespace mbr {

namespace {

constexpr int grid_samples = 5;  // the curved kinds' (u,v) grid: 5 x 5 points
// A key cell is this many tolerances wide: a key's tolerance box reaches into a second cell
// along an axis for 1 key in 128, so a look-up visits 1.05 cells on average; distinct surfaces
// share a cell only when all six key numbers agree within 2.6e-7 of the scene's diagonal.
constexpr double cell_tolerances = 256;

bool four_corners(Surface::Kind k) {
    return k == Surface::Kind::PlanarQuad || k == Surface::Kind::BilinearPatch;
}

/// The points a surface is compared by: its four corners, or the (u,v) grid of a curved kind.
std::vector<Vec3> sample_points(const Surface& s) {
    if (four_corners(s.kind())) return {s.corners(), s.corners() + 4};
    std::vector<Vec3> p;
    for (int i = 0; i < grid_samples; ++i)
        for (int j = 0; j < grid_samples; ++j)
            p.push_back(s.point(double(i) / (grid_samples - 1), double(j) / (grid_samples - 1)));
    return p;
}

/// Six numbers that two same_surface surfaces share within the tolerance, whatever corner
/// starts a quad: the point x(1/2,1/2) (the corners' average for a quad) and the lowest corner
/// of the box of the sample points. The box tells apart surfaces that share their centre (a
/// quad turned about it), which would otherwise all fall into one cell.
std::array<double, 6> key_numbers(const Surface& s) {
    const Vec3 c = s.point(0.5, 0.5);
    Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
    if (four_corners(s.kind()))
        for (int i = 0; i < 4; ++i) lo = min(lo, s.corners()[i]);
    else
        for (const Vec3& p : sample_points(s)) lo = min(lo, p);
    return {c.x, c.y, c.z, lo.x, lo.y, lo.z};
}

/// A key's cell: its six numbers in units of the cell's width.
using Cell = std::array<std::int32_t, 6>;

/// A hash of a cell's six indices (a combine step per index, then a multiply-xorshift mix).
std::uint64_t hash_cell(const Cell& c) {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::int32_t x : c) {
        h ^= std::uint64_t(std::uint32_t(x)) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        h *= 0xbf58476d1ce4e5b9ull;
        h ^= h >> 31;
    }
    return h;
}

/// An open-addressing table (linear probing, at most half full) from cells to chains of the
/// surfaces kept so far. A slot holds the high 32 bits of its cell's hash beside the newest
/// surface of the cell, so that a look-up of an absent cell, the common case, reads one slot
/// and no cell.
class CellTable {
public:
    explicit CellTable(size_t n) : next_(n, -1), cells_(n) {
        size_t size = 16;
        while (size < 2 * n) size *= 2;
        slots_.assign(size, 0);
    }

    /// Calls visit(j) for every surface j inserted with cell c.
    template <class Visit>
    void for_each(const Cell& c, Visit&& visit) const {
        const std::uint64_t h = hash_cell(c);
        for (size_t k = slot_of(h); slots_[k] != 0; k = (k + 1) & (slots_.size() - 1)) {
            if (!holds(slots_[k], h, c)) continue;
            for (int j = surface_of(slots_[k]); j >= 0; j = next_[size_t(j)]) visit(j);
            return;
        }
    }

    void insert(int i, const Cell& c) {
        cells_[size_t(i)] = c;
        const std::uint64_t h = hash_cell(c);
        size_t k = slot_of(h);
        while (slots_[k] != 0 && !holds(slots_[k], h, c)) k = (k + 1) & (slots_.size() - 1);
        next_[size_t(i)] = slots_[k] != 0 ? surface_of(slots_[k]) : -1;
        slots_[k] = (h & 0xffffffff00000000ull) | std::uint64_t(std::uint32_t(i) + 1);
    }

private:
    size_t slot_of(std::uint64_t h) const { return size_t(h) & (slots_.size() - 1); }
    static int surface_of(std::uint64_t slot) { return int(std::uint32_t(slot)) - 1; }
    bool holds(std::uint64_t slot, std::uint64_t h, const Cell& c) const {
        return (slot >> 32) == (h >> 32) && cells_[size_t(surface_of(slot))] == c;
    }

    std::vector<std::uint64_t> slots_;  // hash's high half | newest surface + 1; 0: empty
    std::vector<int> next_;             // the next older surface of the same cell, or -1
    std::vector<Cell> cells_;           // each inserted surface's cell
};

/// "'white'", the material's name in quotes, for messages.
std::string material_name(const Scene& scene, int surface) {
    return "'" + scene.material_of(surface).name + "'";
}

/// True when materials a and b are one, or copies of one made for texture coordinates (the OBJ
/// reader names them MATERIAL@LINE.K): the same material in the file's terms.
bool same_family(const Scene& scene, int a, int b) {
    if (a == b) return true;
    const auto family = [&](int m) {
        const std::string& name = scene.materials[size_t(m)].name;
        const size_t at = name.rfind('@');
        return at == std::string::npos ? name : name.substr(0, at);
    };
    return family(a) == family(b);
}

}  // namespace

double duplicate_tolerance(const Box3& bounds) {
    if (bounds.empty()) return 0;
    const double diagonal = length(bounds.extent());
    double largest = 0;
    for (int k = 0; k < 3; ++k)
        largest = std::max({largest, std::fabs(bounds.lo[k]), std::fabs(bounds.hi[k])});
    return std::max(1e-9 * diagonal, 64 * DBL_EPSILON * largest);
}

bool same_surface(const Surface& a, const Surface& b, double tolerance) {
    if (four_corners(a.kind()) != four_corners(b.kind())) return false;
    if (four_corners(a.kind())) {
        const Vec3* p = a.corners();
        const Vec3* q = b.corners();
        for (int shift = 0; shift < 4; ++shift) {
            bool all = true;
            for (int i = 0; i < 4 && all; ++i) all = length(p[i] - q[(i + shift) % 4]) <= tolerance;
            if (all) return true;
        }
        return false;
    }
    if (a.kind() != b.kind()) return false;
    const std::vector<Vec3> p = sample_points(a), q = sample_points(b);
    for (size_t i = 0; i < p.size(); ++i)
        if (!(length(p[i] - q[i]) <= tolerance)) return false;
    return dot(a.normal(0.5, 0.5), b.normal(0.5, 0.5)) > 0;
}

std::vector<DuplicateSurface> find_duplicate_surfaces(const Scene& scene) {
    std::vector<DuplicateSurface> out;
    const int n = int(scene.surfaces.size());
    if (n < 2) return out;
    const Box3 bounds = scene.bounds();
    const double tol = duplicate_tolerance(bounds);
    const double cell = cell_tolerances * tol;
    MBR_CHECK_MSG(cell > 0 && std::isfinite(cell), "cell " << cell);
    // Cells are counted from half a cell below the box's low corner, so that the many key
    // numbers that lie on the box's faces (a floor at its lowest y, a flat scene's one z) sit in
    // the middle of a cell, not on a border where every look-up would visit two. At most
    // diagonal / (256e-9 diagonal), 3.9e6, cells along an axis: well inside int32 (the key
    // points lie in the box, up to rounding).
    const Vec3 o = bounds.lo - Vec3{0.5 * cell, 0.5 * cell, 0.5 * cell};
    const double origin[6] = {o.x, o.y, o.z, o.x, o.y, o.z};
    auto index = [&](double x, int k) {
        const double c = std::floor((x - origin[k]) / cell);
        MBR_CHECK_MSG(std::fabs(c) < 2e9, "cell index " << c);
        return std::int32_t(c);
    };
    auto own_cell = [&](const std::array<double, 6>& x) {
        Cell c;
        for (int k = 0; k < 6; ++k) c[size_t(k)] = index(x[size_t(k)], k);
        return c;
    };
    CellTable table{size_t(n)};
    for (int i = 0; i < n; ++i) {
        const Surface& s = scene.surfaces[size_t(i)].surface;
        const std::array<double, 6> x = key_numbers(s);
        // A repeat's key numbers lie within tol of the original's: the cells that
        // [x - tol, x + tol] meets, one or two along each of the six axes.
        Cell lo, hi;
        int two[6], n_two = 0;  // the axes along which that box meets two cells
        for (int k = 0; k < 6; ++k) {
            lo[size_t(k)] = index(x[size_t(k)] - tol, k);
            hi[size_t(k)] = index(x[size_t(k)] + tol, k);
            if (hi[size_t(k)] != lo[size_t(k)]) two[n_two++] = k;
        }
        int earlier = -1;
        for (int choice = 0; choice < (1 << n_two); ++choice) {
            Cell c = lo;
            for (int b = 0; b < n_two; ++b)
                if (choice & (1 << b)) c[size_t(two[b])] = hi[size_t(two[b])];
            table.for_each(c, [&](int j) {
                if ((earlier < 0 || j < earlier) &&
                    same_surface(scene.surfaces[size_t(j)].surface, s, tol))
                    earlier = j;
            });
        }
        if (earlier >= 0) {
            out.push_back({earlier, i});
            continue;
        }
        table.insert(i, own_cell(x));
    }
    return out;
}

void drop_duplicate_surfaces(Scene& scene, const ImportOptions& options) {
    std::vector<DuplicateSurface> repeats = find_duplicate_surfaces(scene);
    if (repeats.empty()) return;
    auto file_of = [&](int i) {
        const int src = scene.surfaces[size_t(i)].source;
        return src >= 0 && size_t(src) < scene.sources.size() ? scene.sources[size_t(src)]
                                                              : std::string();
    };
    auto name_of = [&](int i) { return "'" + scene.surfaces[size_t(i)].name + "'"; };
    // A repeat with another material is an error before anything changes: which of the two is
    // meant is the user's to say. In a forgiving import (the repeat read from an OBJ file) the
    // first is kept, with a warning of its own.
    const auto same_material = [&](const DuplicateSurface& d) {
        return same_family(scene, scene.surfaces[size_t(d.later)].material,
                           scene.surfaces[size_t(d.earlier)].material);
    };
    std::vector<int> other_material;
    for (const DuplicateSurface& d : repeats)
        if (!same_material(d) && !options.strict && is_import_path(file_of(d.later))) {
            if (other_material.empty()) {
                SceneWarning w;
                w.kind = "duplicate surface with another material";
                w.file = file_of(d.later);
                w.line = scene.surfaces[size_t(d.later)].line;
                w.message = "surface " + name_of(d.later) + " repeats surface " +
                            name_of(d.earlier) + " (" + scene.where(d.earlier) +
                            ") with another material: " + material_name(scene, d.later) +
                            " here, " + material_name(scene, d.earlier) +
                            " there; the first is kept and the repeat dropped";
                w.count = 0;
                scene.warn(w);
            }
            other_material.push_back(d.later);
        }
    if (!other_material.empty()) {
        for (SceneWarning& w : scene.warnings)
            if (w.kind == "duplicate surface with another material")
                w.count += long(other_material.size());
        repeats.erase(std::remove_if(repeats.begin(), repeats.end(),
                                     [&](const DuplicateSurface& d) { return !same_material(d); }),
                      repeats.end());
    }
    for (const DuplicateSurface& d : repeats)
        if (!same_material(d))
            throw InputError(file_of(d.later), scene.surfaces[size_t(d.later)].line,
                             "surface " + name_of(d.later) + " repeats surface " +
                                 name_of(d.earlier) + " (" + scene.where(d.earlier) +
                                 ") with another material: " + material_name(scene, d.later) +
                                 " here, " + material_name(scene, d.earlier) +
                                 " there; surfaces are one-sided and each reflects and emits, "
                                 "so remove one of them");
    std::vector<char> drop(scene.surfaces.size(), 0);
    for (int i : other_material) drop[size_t(i)] = 1;
    if (repeats.empty()) {
        remove_surfaces(scene, drop);
        return;
    }
    // One instance per repeated statement: a statement that makes several surfaces (a box, an
    // OBJ triangle's three quads) and repeats another counts once.
    using Pair = std::tuple<int, int, int, int>;  // later source, line; earlier source, line
    auto pair_of = [&](const DuplicateSurface& d) {
        const SceneSurface& l = scene.surfaces[size_t(d.later)];
        const SceneSurface& e = scene.surfaces[size_t(d.earlier)];
        return Pair{l.source, l.line, e.source, e.line};
    };
    std::set<Pair> pairs;
    for (const DuplicateSurface& d : repeats) pairs.insert(pair_of(d));
    const DuplicateSurface& first = repeats.front();
    long n_first = 0;
    for (const DuplicateSurface& d : repeats) n_first += pair_of(d) == pair_of(first) ? 1 : 0;
    const std::string same =
        ": same place, front side and material " + material_name(scene, first.later);
    SceneWarning w;
    w.kind = "duplicate surface";
    w.file = file_of(first.later);
    w.line = scene.surfaces[size_t(first.later)].line;
    w.count = long(pairs.size());
    if (n_first == 1)
        w.message = "surface " + name_of(first.later) + " repeats surface " +
                    name_of(first.earlier) + " (" + scene.where(first.earlier) + ")" + same +
                    "; the repeat is dropped";
    else
        w.message = std::to_string(n_first) + " surfaces of this statement (the first " +
                    name_of(first.later) + ") repeat those of " + scene.where(first.earlier) +
                    " (the first " + name_of(first.earlier) + ")" + same +
                    "; the repeats are dropped";
    for (const DuplicateSurface& d : repeats) drop[size_t(d.later)] = 1;
    remove_surfaces(scene, drop);
    scene.warn(w);
}

}  // namespace mbr
