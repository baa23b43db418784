// radiosity/solver/solution_file.cpp - saving and loading solved fields (docs/solution-format.md),
// so that rendering can be separate from solving.
#include "radiosity/solver/solution_file.h"

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <istream>
#include <ostream>

#include "math/bspline.h"
#include "math/check.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/solver/solver.h"

namespace mbr {

namespace {

constexpr const char* magic = "mbr-solution";
// Version 2 adds `irradiance level J` in place of `radiosity level J` for a field that holds H
// (FieldQuantity::irradiance). Version 3 adds `order m` to each surface line, for a solution
// whose surfaces have different orders (SceneSurface::order); the header's order is then the
// largest. DESIGN: a file is written in the oldest version that holds it (1 without H fields
// and with one order, 2 with H fields and one order, else 3), so that what earlier mbr wrote
// and read stays byte for byte the same; every version is read.
constexpr int format_version = 3;
constexpr int irradiance_version = 2;
constexpr int oldest_version = 1;

bool any_irradiance(const Solution& solution) {
    for (FieldQuantity q : solution.quantity)
        if (q == FieldQuantity::irradiance) return true;
    return false;
}

std::uint64_t mix(std::uint64_t h, std::uint64_t x) {
    h ^= x + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    return h;
}
std::uint64_t mix(std::uint64_t h, double x) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return mix(h, b);
}
std::uint64_t mix(std::uint64_t h, const std::string& s) {
    for (unsigned char c : s) h = mix(h, std::uint64_t(c));
    return mix(h, std::uint64_t(s.size()));
}

void write_field(std::ostream& out, const char* what, const SplineField& f) {
    out << what << " level " << f.level() << "\n";
    char buf[40];
    for (int c = 0; c < 3; ++c) {
        const std::vector<double>& a = f.channel(c).a;
        for (size_t i = 0; i < a.size(); ++i) {
            std::snprintf(buf, sizeof buf, "%.17g", a[i]);
            out << (i ? " " : "") << buf;
        }
        out << "\n";
    }
}

/// Reads the file line by line and reports problems with the file name and line. The lines are
/// read by the scene's line reader (radiosity/scene/line_reader.h) with the solution format's
/// differences: no comments, no byte order mark, no blank lines skipped, any bytes but blanks
/// inside a word, lines of up to 64 MiB.
class Reader {
public:
    Reader(std::istream& in, const std::string& name) : name_(name), lines_(in, name, format()) {}
    std::vector<std::string> words(const char* expecting) {
        Line line;
        if (!lines_.next(line))
            fail("the file ends early (expected " + std::string(expecting) + "): truncated?");
        return std::move(line.tokens);
    }
    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(name_, lines_.number(), message);
    }
    long integer(const std::string& w, long lo, long hi, const char* what) const {
        char* end = nullptr;
        errno = 0;
        const long v = std::strtol(w.c_str(), &end, 10);
        if (w.empty() || *end != '\0' || errno != 0 || v < lo || v > hi)
            fail(std::string("expected ") + what + " in " + std::to_string(lo) + ".." +
                 std::to_string(hi) + ", found '" + w + "'");
        return v;
    }
    double number(const std::string& w) const {
        char* end = nullptr;
        const double v = std::strtod(w.c_str(), &end);
        if (w.empty() || *end != '\0' || !std::isfinite(v))
            fail("expected a finite number, found '" + w + "'");
        return v;
    }
    void expect(const std::vector<std::string>& got, const std::string& first, size_t n) const {
        if (got.empty() || got[0] != first || got.size() != n)
            fail("expected '" + first + "' with " + std::to_string(n - 1) + " values");
    }

private:
    static LineFormat format() {
        LineFormat f;
        f.max_length = size_t(1) << 26;
        f.too_long = "line is too long";
        f.comments = false;
        f.byte_order_mark = false;
        f.control_bytes = true;
        f.skip_blank = false;
        return f;
    }

    std::string name_;
    LineReader lines_;
};

/// A field line `WHAT level J` and its three channel lines; `alternative`, when given, is a
/// second accepted WHAT, and *found_alternative says which one the file has.
SplineField read_field(Reader& r, const char* what, int m, const char* alternative = nullptr,
                       bool* found_alternative = nullptr) {
    std::vector<std::string> head = r.words(what);
    const bool other = alternative && !head.empty() && head[0] == alternative;
    if (found_alternative) *found_alternative = other;
    if (other) head[0] = what;
    r.expect(head, what, 3);
    if (head[1] != "level") r.fail(std::string("expected '") + what + " level J'");
    const int level = int(r.integer(head[2], 0, 14, "a level"));
    // The count is checked against the first line before the field is made: a level-14 field of
    // order 8 holds 3 x 2.7e8 coefficients (6 GiB), which a damaged 20-byte header must not
    // allocate (found by test/fuzz_readers.cpp).
    const size_t n_coefficients = size_t(touching_count(m, level)) * touching_count(m, level);
    std::vector<std::string> values = r.words("coefficients");
    const auto check_count = [&] {
        if (values.size() != n_coefficients)
            r.fail("expected " + std::to_string(n_coefficients) + " coefficients, found " +
                   std::to_string(values.size()));
    };
    check_count();
    SplineField f(m, level);
    for (int c = 0; c < 3; ++c) {
        if (c > 0) {
            values = r.words("coefficients");
            check_count();
        }
        std::vector<double>& a = f.channel(c).a;
        for (size_t i = 0; i < a.size(); ++i) a[i] = r.number(values[i]);
    }
    return f;
}

}  // namespace

std::uint64_t scene_fingerprint(const Scene& scene) {
    std::uint64_t h = 1469598103934665603ULL;
    h = mix(h, std::uint64_t(scene.surfaces.size()));
    for (const SceneSurface& s : scene.surfaces) {
        h = mix(h, s.name);
        h = mix(h, std::uint64_t(s.surface.kind()));
        for (double u : {0.0, 0.5, 1.0})
            for (double v : {0.0, 0.5, 1.0}) {
                const Vec3 p = s.surface.point(u, v);
                h = mix(mix(mix(h, p.x), p.y), p.z);
            }
        const Material& mat = scene.materials[s.material];
        for (const Rgb& c : {mat.reflectance.mean(), mat.emission.mean()})
            h = mix(mix(mix(h, c.r), c.g), c.b);
    }
    return h;
}

void save_solution(std::ostream& out, const Scene& scene, const Solution& solution) {
    MBR_CHECK(solution.radiosity.size() == scene.surfaces.size() &&
              solution.unshot.size() == scene.surfaces.size());
    char fp[32];
    std::snprintf(fp, sizeof fp, "%016" PRIx64, scene_fingerprint(scene));
    // Each surface's fields share its order; the surfaces' orders may differ (version 3).
    int m = 0;
    bool one_order = true;
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        const int mi = solution.radiosity[i].order();
        MBR_CHECK_MSG(solution.unshot[i].order() == mi, "surface " << i << ": B of order " << mi
                                                                   << ", unshot of order "
                                                                   << solution.unshot[i].order());
        one_order = one_order && (i == 0 || mi == m);
        m = std::max(m, mi);
    }
    const bool irradiance = any_irradiance(solution);
    MBR_CHECK(solution.quantity.empty() || solution.quantity.size() == scene.surfaces.size());
    const int version = !one_order   ? format_version
                        : irradiance ? irradiance_version
                                     : oldest_version;
    out << magic << " " << version << "\n"
        << "fingerprint " << fp << "\n"
        << "surfaces " << scene.surfaces.size() << " order " << m << "\n";
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        out << "surface " << i << " " << scene.surfaces[i].name;
        if (!one_order) out << " order " << solution.radiosity[i].order();
        out << "\n";
        const bool holds_h = irradiance && solution.quantity[i] == FieldQuantity::irradiance;
        write_field(out, holds_h ? "irradiance" : "radiosity", solution.radiosity[i]);
        write_field(out, "unshot", solution.unshot[i]);
        const std::vector<DyadicCell> none;
        const std::vector<DyadicCell>& leaves =
            i < solution.leaves.size() ? solution.leaves[i] : none;
        out << "leaves " << leaves.size() << "\n";
        for (size_t k = 0; k < leaves.size(); ++k)
            out << (k ? " " : "") << leaves[k].level << " " << leaves[k].i << " " << leaves[k].j;
        out << "\n";
    }
    out << "end\n";
}

Solution load_solution(std::istream& in, const std::string& name, const Scene& scene) {
    Reader r(in, name);
    const std::vector<std::string> head = r.words("the header");
    if (head.size() != 2 || head[0] != magic)
        r.fail("not an mbr solution file (no 'mbr-solution' header)");
    const long version = r.integer(head[1], 0, 1000000, "a format version");
    if (version < oldest_version || version > format_version)
        r.fail("solution format version " + std::to_string(version) +
               " is not supported (this mbr reads versions " + std::to_string(oldest_version) +
               " to " + std::to_string(format_version) + ")");
    const std::vector<std::string> fp = r.words("the fingerprint");
    r.expect(fp, "fingerprint", 2);
    char expected[32];
    std::snprintf(expected, sizeof expected, "%016" PRIx64, scene_fingerprint(scene));
    if (fp[1] != expected)
        r.fail(
            "the solution was made for another scene (or the scene changed since): fingerprint " +
            fp[1] + ", the scene's is " + expected);
    const std::vector<std::string> sizes = r.words("the surface count");
    r.expect(sizes, "surfaces", 4);
    const long n = r.integer(sizes[1], 0, 100000000, "a surface count");
    if (size_t(n) != scene.surfaces.size())
        r.fail("the solution has " + std::to_string(n) + " surfaces, the scene " +
               std::to_string(scene.surfaces.size()));
    if (sizes[2] != "order") r.fail("expected 'order M'");
    const int m = int(r.integer(sizes[3], 2, 8, "an order"));
    Solution s;
    s.radiosity.resize(n);
    s.quantity.assign(n, FieldQuantity::radiosity);
    s.unshot.resize(n);
    s.leaves.resize(n);
    for (long i = 0; i < n; ++i) {
        const std::vector<std::string> sh = r.words("a surface");
        // Version 3: `surface i NAME order m`, the surface's own order (at most the header's).
        r.expect(sh, "surface", version >= 3 ? 5 : 3);
        if (r.integer(sh[1], 0, n - 1, "a surface index") != i) r.fail("surfaces are out of order");
        if (sh[2] != scene.surfaces[i].name)
            r.fail("surface " + std::to_string(i) + " is '" + sh[2] + "', the scene's is '" +
                   scene.surfaces[i].name + "'");
        int mi = m;
        if (version >= 3) {
            if (sh[3] != "order") r.fail("expected 'surface i NAME order m'");
            mi = int(r.integer(sh[4], 2, 8, "an order"));
            if (mi > m)
                r.fail("surface " + std::to_string(i) + " has order " + std::to_string(mi) +
                       ", above the largest order " + std::to_string(m) + " of the header");
        }
        // Version 2: the field line names what the field holds.
        bool holds_h = false;
        s.radiosity[i] =
            read_field(r, "radiosity", mi, version >= 2 ? "irradiance" : nullptr, &holds_h);
        if (holds_h) s.quantity[i] = FieldQuantity::irradiance;
        s.unshot[i] = read_field(r, "unshot", mi);
        const std::vector<std::string> lh = r.words("leaves");
        r.expect(lh, "leaves", 2);
        const long n_leaves = r.integer(lh[1], 0, 1L << 30, "a leaf count");
        const std::vector<std::string> cells = r.words("leaf cells");
        if (cells.size() != size_t(3 * n_leaves))
            r.fail("expected " + std::to_string(3 * n_leaves) + " numbers of leaf cells");
        for (long k = 0; k < n_leaves; ++k) {
            const int level = int(r.integer(cells[3 * k], 0, 30, "a cell level"));
            const long limit = (1L << level) - 1;
            s.leaves[i].push_back({level,
                                   int(r.integer(cells[3 * k + 1], 0, limit, "a cell index")),
                                   int(r.integer(cells[3 * k + 2], 0, limit, "a cell index"))});
        }
    }
    const std::vector<std::string> end = r.words("'end'");
    if (end.size() != 1 || end[0] != "end") r.fail("expected 'end'");
    return s;
}

Solution load_solution(const std::string& path, const Scene& scene) {
    std::ifstream in;
    detail::open_input(path, "solution file", in);
    return load_solution(in, path, scene);
}

}  // namespace mbr
