// radiosity/scene/scene_io.cpp - the scene text format, OBJ + MTL import and their validation
// (scene_io.h; the format is documented in docs/scene-format.md). Both readers work line by
// line: a line is split into whitespace-separated tokens after '#' comments are removed, and
// each statement is checked completely before it changes the scene.
#include "radiosity/scene/scene_io.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "math/check.h"

namespace mbr {

namespace fs = std::filesystem;

namespace {

constexpr size_t max_line_length = 65536;   // bytes; longer lines are rejected, not read
constexpr int max_include_depth = 16;       // nesting of `include`
constexpr int max_files_read = 1000;        // every `include`, `obj`, `mtllib` and texture
constexpr int max_face_vertices = 256;      // ear clipping below is cubic in this
constexpr double max_angle_degrees = 3600;  // |phi|, |theta| in degrees
const char* const obj_default_material = "obj_default";

// ---------------------------------------------------------------------------------------------
// === Lines and tokens

/// A token for a message: quoted, at most 256 characters, bytes outside printable ASCII as \xHH.
std::string in_quotes(const std::string& s) {
    std::string out = "'";
    size_t n = 0;
    for (unsigned char c : s) {
        if (++n > 256) {
            out += "...";
            break;
        }
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out + "'";
}

/// x for messages about numbers the user wrote, and about limits: the shortest text that reads
/// back as exactly x, so that a value just beyond a limit never prints as the limit itself
/// ("100000000.1 exceeds the limit 100000000"). Positional notation for magnitudes in
/// [1e-5, 1e16), where it is exact and readable; scientific notation outside.
std::string fmt(double x) {
    char buf[64];
    const double a = std::fabs(x);
    const bool positional = a == 0 || (a >= 1e-5 && a < 1e16);
    auto r = positional ? std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed)
                        : std::to_chars(buf, buf + sizeof buf, x);
    return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("?");
}

/// x for messages about derived quantities (a deviation, a percentage, an area), which the user
/// did not write and which need no more than six significant digits.
std::string fmt_approx(double x) {
    std::ostringstream os;
    os.precision(6);
    os << x;
    return os.str();
}

/// "1 word", "3 words": a count with its noun in the right number.
std::string counted(long n, const std::string& singular, const std::string& plural) {
    return std::to_string(n) + " " + (n == 1 ? singular : plural);
}

/// One statement: its file, line number and tokens.
struct Line {
    std::string file;
    int number = 0;
    std::vector<std::string> tokens;

    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(file, number, message);
    }
    size_t size() const { return tokens.size(); }
    const std::string& operator[](size_t i) const { return tokens[i]; }
};

/// Reads statements: skips blank and comment lines, refuses over-long lines and control bytes.
class LineReader {
public:
    LineReader(std::istream& in, std::string file) : in_(in), file_(std::move(file)) {}

    /// The next non-empty statement, or false at the end of the input.
    bool next(Line& line) {
        std::string raw;
        while (read_raw(raw)) {
            line.file = file_;
            line.number = number_;
            line.tokens.clear();
            if (number_ == 1 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0) raw.erase(0, 3);  // BOM
            size_t hash = raw.find('#');
            if (hash != std::string::npos) raw.erase(hash);
            std::string token;
            for (char ch : raw) {
                unsigned char c = static_cast<unsigned char>(ch);
                bool space = c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
                if (!space && (c < 0x20 || c == 0x7f)) {
                    line.fail("unexpected control byte " + in_quotes(std::string(1, ch)) +
                              " (is this a text file?)");
                }
                if (space) {
                    if (!token.empty()) line.tokens.push_back(std::move(token));
                    token.clear();
                } else {
                    token += ch;
                }
            }
            if (!token.empty()) line.tokens.push_back(std::move(token));
            if (!line.tokens.empty()) return true;
        }
        return false;
    }

private:
    /// One physical line without its '\n'; false when the input is exhausted.
    bool read_raw(std::string& raw) {
        raw.clear();
        std::streambuf* buf = in_.rdbuf();
        if (!buf || done_) return false;
        ++number_;
        for (;;) {
            int c = buf->sbumpc();
            if (c == std::char_traits<char>::eof()) {
                done_ = true;
                return !raw.empty();
            }
            if (c == '\n') return true;
            if (raw.size() >= max_line_length)
                throw InputError(
                    file_, number_,
                    "line is longer than " + std::to_string(max_line_length) + " bytes");
            raw += char(c);
        }
    }

    std::istream& in_;
    std::string file_;
    int number_ = 0;
    bool done_ = false;
};

/// Parses a decimal number (no NaN, no infinity, no hex), naming `what` in messages.
double parse_double(const Line& line, const std::string& token, const std::string& what) {
    std::string lower;
    for (char c : token) lower += char(std::tolower(static_cast<unsigned char>(c)));
    size_t start = (!lower.empty() && (lower[0] == '+' || lower[0] == '-')) ? 1 : 0;
    if (lower.compare(start, 3, "nan") == 0 || lower.compare(start, 3, "inf") == 0)
        line.fail(what + " is " + in_quotes(token) + ": NaN and infinity are not allowed");
    const char* b = token.data();
    const char* e = b + token.size();
    if (b != e && *b == '+') ++b;  // from_chars takes '-' but not '+'
    double x = 0;
    auto result = std::from_chars(b, e, x, std::chars_format::general);
    if (b == e || *b == '+' || result.ptr != e ||
        (result.ec != std::errc() && result.ec != std::errc::result_out_of_range))
        line.fail("expected a number for " + what + ", found " + in_quotes(token));
    if (result.ec == std::errc::result_out_of_range || !std::isfinite(x))
        line.fail(what + " " + in_quotes(token) + " is out of range");
    return x;
}

/// Parses an integer in [lo, hi].
long long parse_integer(const Line& line, const std::string& token, const std::string& what,
                        long long lo, long long hi) {
    const char* b = token.data();
    const char* e = b + token.size();
    if (b != e && *b == '+') ++b;
    long long x = 0;
    auto result = std::from_chars(b, e, x);
    if (b == e || *b == '+' || result.ptr != e ||
        (result.ec != std::errc() && result.ec != std::errc::result_out_of_range))
        line.fail("expected an integer for " + what + ", found " + in_quotes(token));
    if (result.ec == std::errc::result_out_of_range || x < lo || x > hi)
        line.fail(what + " " + in_quotes(token) + " is outside [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "]");
    return x;
}

/// True for tokens meant as numbers (including NaN and infinity, which parse_double refuses
/// with their own message).
bool is_number_token(const std::string& t) {
    if (t.empty()) return false;
    char c = t[0];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.')
        return true;
    std::string lower;
    for (char ch : t) lower += char(std::tolower(static_cast<unsigned char>(ch)));
    return lower == "nan" || lower == "inf" || lower == "infinity" ||
           lower.compare(0, 4, "nan(") == 0;
}

// ---------------------------------------------------------------------------------------------
// === Files

/// `file` relative to the folder of `from` (unless absolute).
std::string resolve(const std::string& from, const std::string& file) {
    fs::path p(file);
    if (p.is_absolute()) return p.string();
    return (fs::path(from).parent_path() / p).string();
}

/// Why `path` cannot be read as a regular file, or an empty string.
std::string file_problem(const std::string& path) {
    std::error_code ec;
    fs::file_status st = fs::status(path, ec);
    // Only a missing file is "not found"; anything else (a folder on the way that may not be
    // searched, a file name used as a folder) gets the system's reason, e.g. "Permission denied".
    if (ec && ec != std::errc::no_such_file_or_directory) return ec.message();
    if (ec || !fs::exists(st)) return "file not found";
    if (fs::is_directory(st)) return "is a folder, not a file";
    if (!fs::is_regular_file(st)) return "is not a regular file";
    return "";
}

/// A canonical spelling of `path` for include-cycle detection (lexical when the file system
/// cannot tell).
std::string canonical_name(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::path(path), ec);
    if (ec) p = fs::absolute(fs::path(path), ec).lexically_normal();
    return p.string();
}

/// What the readers of one top-level load share: the count of files opened, which bounds
/// exponential include trees, and the texture images decoded so far.
class LoadState {
public:
    /// Counts one more file read on behalf of `line`.
    void charge(const Line& line) {
        if (++n_files_ > max_files_read)
            line.fail("more than " + std::to_string(max_files_read) +
                      " files are read by this scene (includes, OBJ, MTL, textures)");
    }

    /// The image file at `path` (resolved), unscaled. Each file is read and decoded once per
    /// load, however many materials name it (a big image costs its memory once, not once per
    /// material); later requests share its texels and are not charged as files read.
    Texture image(const Line& line, const std::string& path) {
        const std::string key = canonical_name(path);
        auto cached = textures_.find(key);
        if (cached != textures_.end()) return cached->second;
        charge(line);
        std::string problem = file_problem(path);
        if (!problem.empty()) line.fail("texture " + in_quotes(path) + ": " + problem);
        Texture texture;
        try {
            texture = Texture::image(path);
        } catch (const InputError& e) {
            line.fail("texture " + in_quotes(path) + ": " + e.message());
        }
        textures_.emplace(key, texture);
        return texture;
    }

private:
    int n_files_ = 0;
    std::unordered_map<std::string, Texture> textures_;  // canonical path -> decoded image
};

/// Opens a file named on `line`; the message names the line and the path.
void open_named(const Line& line, const std::string& what, const std::string& path,
                std::ifstream& in) {
    std::string problem = file_problem(path);
    if (!problem.empty()) line.fail(what + " " + in_quotes(path) + ": " + problem);
    errno = 0;
    in.open(path, std::ios::binary);
    if (!in) line.fail(what + " " + in_quotes(path) + ": cannot open it" + system_reason());
}

// ---------------------------------------------------------------------------------------------
// === Geometry checks

double max_pairwise_distance(const std::vector<Vec3>& p) {
    double size = 0;
    for (size_t i = 0; i < p.size(); ++i)
        for (size_t j = i + 1; j < p.size(); ++j) size = std::max(size, length(p[i] - p[j]));
    return size;
}

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

void check_point(const Line& line, Vec3 p, const std::string& what) {
    for (int i = 0; i < 3; ++i)
        if (std::fabs(p[i]) > max_coordinate)
            line.fail(what + " coordinate " + fmt(p[i]) + " exceeds the limit " +
                      fmt(max_coordinate));
}

Vec3 check_direction(const Line& line, Vec3 d, const std::string& what) {
    check_point(line, d, what);
    if (!(length(d) > 1e-100)) line.fail(what + " is the zero vector");
    return d;
}

void check_not_parallel(const Line& line, Vec3 axis, Vec3 e1, const std::string& axis_name) {
    if (length(cross(normalize(axis), normalize(e1))) < 1e-6)
        line.fail("e1 " + fmt(e1.x) + " " + fmt(e1.y) + " " + fmt(e1.z) + " is parallel to the " +
                  axis_name + "; it must give the direction of angle 0");
}

double check_length(const Line& line, double x, const std::string& what, bool allow_zero) {
    if (x < 0 || (!allow_zero && x == 0))
        line.fail(what + " " + fmt(x) + (allow_zero ? " is negative" : " must be positive"));
    if (x > max_coordinate)
        line.fail(what + " " + fmt(x) + " exceeds the limit " + fmt(max_coordinate));
    return x;
}

/// Checks an angle range in degrees: bounded, increasing, spanning at most span_limit.
void check_angle_range(const Line& line, double a0, double a1, const std::string& what,
                       double span_limit) {
    if (std::fabs(a0) > max_angle_degrees || std::fabs(a1) > max_angle_degrees)
        line.fail(what + " angles must lie within +-" + fmt(max_angle_degrees) + " degrees");
    if (!(std::fabs(a1 - a0) >= 1e-6))
        line.fail(what + " range " + fmt(a0) + " .. " + fmt(a1) + " is empty (or below 1e-6)");
    // A decreasing range would turn the surface around (x_u x x_v changes sign); the format
    // keeps one way to say that: `inward`, or the disk's normal.
    if (a1 < a0)
        line.fail(what + " range " + fmt(a0) + " .. " + fmt(a1) +
                  " must increase (turn a surface around with 'inward' or the disk's normal)");
    if (a1 - a0 > span_limit + 1e-9)
        line.fail(what + " range " + fmt(a0) + " .. " + fmt(a1) + " spans more than " +
                  fmt(span_limit) + " degrees");
}

double radians(double degrees) {
    return degrees * (Pi / 180);
}

// ---------------------------------------------------------------------------------------------
// === Numbers of one statement

/// A named group of numbers in a statement: "p00" with 3 numbers, "radius" with 1.
struct Field {
    const char* name;
    int count;
};

std::string describe_fields(const std::vector<Field>& fields) {
    std::string s;
    for (const Field& f : fields) {
        if (!s.empty()) s += ", ";
        s += f.name;
        if (f.count == 3) s += " x y z";
    }
    return s;
}

/// Reads the numbers of `fields` from tokens[first..]; an optional trailing word `flag` (e.g.
/// "inward") sets *flag_set. Wrong counts and non-numbers get messages naming the fields.
std::vector<double> read_fields(const Line& line, size_t first, const std::string& statement,
                                const std::vector<Field>& fields, const char* flag = nullptr,
                                bool* flag_set = nullptr) {
    size_t end = line.size();
    if (flag && end > first && line[end - 1] == flag) {
        *flag_set = true;
        --end;
    }
    int expected = 0;
    for (const Field& f : fields) expected += f.count;
    int found = int(end - first);
    if (found != expected) {
        std::string msg = statement + " needs " + std::to_string(expected) + " numbers (" +
                          describe_fields(fields) + "), found " + std::to_string(found);
        if (found > expected && !is_number_token(line[first + expected]))
            msg += ": unexpected " + in_quotes(line[first + expected]);
        line.fail(msg);
    }
    std::vector<double> x;
    size_t t = first;
    for (const Field& f : fields)
        for (int i = 0; i < f.count; ++i) {
            std::string what = statement + " " + f.name;
            if (f.count == 3) what += std::string(".") + "xyz"[i];
            x.push_back(parse_double(line, line[t++], what));
        }
    return x;
}

Vec3 vec_at(const std::vector<double>& x, size_t i) {
    return {x[i], x[i + 1], x[i + 2]};
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

namespace {

// ---------------------------------------------------------------------------------------------
// === OBJ faces to quads

using Quad = std::array<Vec3, 4>;

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
/// Returns false when no ear exists. Expects a simple polygon (is_simple).
bool triangulate(std::vector<Vec3> p, Vec3 n, std::vector<std::array<Vec3, 3>>& triangles) {
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
                if (j != a && j != i && j != c) blocked = inside(q[a], q[i], q[c], q[j]);
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
    Vec3 n = newell_normal(p);
    if (length(n) <= 1e-9 * size * size)
        line.fail("degenerate face: zero net area (it intersects itself)");
    n = normalize(n);

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
    if (!is_simple(project(p, n)) || !triangulate(p, n, triangles))
        line.fail("face of " + std::to_string(p.size()) +
                  " vertices intersects itself (it cannot be triangulated)");
    for (const auto& t : triangles)
        if (length(cross(t[1] - t[0], t[2] - t[0])) > 1e-12 * size * size)
            triangle_to_quads(t[0], t[1], t[2], quads);
    return quads;
}

/// The quads of one OBJ face (docs/scene-format.md, "OBJ import"): a valid planar quad stays
/// one quad; a planar convex polygon of n != 4 corners becomes n quads around its vertex
/// average; anything else is triangulated (ear clipping) and each triangle becomes three quads.
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

// ---------------------------------------------------------------------------------------------
// === OBJ and MTL

/// A material being read from an MTL file, turned into a Material at its end.
struct MtlEntry {
    std::string name;
    Line newmtl_line;
    Rgb kd{0.5, 0.5, 0.5}, ke{0, 0, 0};
    bool has_kd = false;
    std::string map_kd, map_ke;
    Line map_kd_line, map_ke_line;
};

class ObjReader {
public:
    ObjReader(std::string name, LoadState& state) : name_(std::move(name)), state_(state) {
        group_ = fs::path(name_).stem().string();
        if (group_.empty()) group_ = "obj";
    }

    Scene read(std::istream& in) {
        LineReader reader(in, name_);
        Line line;
        while (reader.next(line)) statement(line);
        if (scene_.surfaces.empty()) throw InputError(name_, 0, "the OBJ file has no faces");
        name_surfaces();
        return std::move(scene_);
    }

private:
    void statement(const Line& line) {
        const std::string& key = line[0];
        if (key == "v") {
            if (line.size() != 4 && line.size() != 5 && line.size() != 7)
                line.fail("'v' needs 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b), found " +
                          std::to_string(line.size() - 1));
            Vec3 p;
            for (int i = 0; i < 3; ++i)
                p[i] = parse_double(line, line[1 + i], std::string("vertex ") + "xyz"[i]);
            for (size_t i = 4; i < line.size(); ++i) parse_double(line, line[i], "vertex w/colour");
            check_point(line, p, "vertex");
            v_.push_back(p);
        } else if (key == "vt" || key == "vp") {
            if (line.size() < 2 || line.size() > 4)
                line.fail("'" + key + "' needs 1 to 3 numbers, found " +
                          std::to_string(line.size() - 1));
            for (size_t i = 1; i < line.size(); ++i) parse_double(line, line[i], key);
            if (key == "vt") ++n_vt_;
        } else if (key == "vn") {
            if (line.size() != 4)
                line.fail("'vn' needs 3 numbers, found " + std::to_string(line.size() - 1));
            for (size_t i = 1; i < 4; ++i) parse_double(line, line[i], "vn");
            ++n_vn_;
        } else if (key == "f") {
            face(line);
        } else if (key == "o" || key == "g") {
            // `g` may list several groups; the first names the surfaces. No name: the default.
            group_ = line.size() >= 2 ? line[1] : fs::path(name_).stem().string();
        } else if (key == "usemtl") {
            if (line.size() != 2) line.fail("'usemtl' needs one material name");
            auto it = material_index_.find(line[1]);
            if (it == material_index_.end())
                line.fail("unknown material " + in_quotes(line[1]) +
                          " (no 'mtllib' before this line defines it)");
            material_ = it->second;
        } else if (key == "mtllib") {
            if (line.size() < 2) line.fail("'mtllib' needs a file name");
            for (size_t i = 1; i < line.size(); ++i) mtllib(line, resolve(name_, line[i]));
        } else if (key == "s") {
            if (line.size() != 2) line.fail("'s' needs one value (a group number or 'off')");
            if (line[1] != "off" && line[1] != "on")
                parse_integer(line, line[1], "smoothing group", 0, 1LL << 40);
        } else if (key == "l" || key == "p") {
            if (line.size() < 2) line.fail("'" + key + "' needs vertex indices");
        } else if (key == "mg" || key == "lod" || key == "bevel" || key == "c_interp" ||
                   key == "d_interp" || key == "shadow_obj" || key == "trace_obj" ||
                   key == "usemap" || key == "maplib") {
            // Display and grouping attributes that do not matter for radiosity.
        } else if (key == "cstype" || key == "deg" || key == "bmat" || key == "step" ||
                   key == "curv" || key == "curv2" || key == "surf" || key == "parm" ||
                   key == "trim" || key == "hole" || key == "scrv" || key == "sp" || key == "end" ||
                   key == "con") {
            line.fail("free-form geometry (" + in_quotes(key) + ") is not supported");
        } else {
            line.fail("unknown OBJ statement " + in_quotes(key));
        }
    }

    /// One index of a face vertex: 1-based, or negative counting back from the last defined.
    long long index(const Line& line, const std::string& text, long long count,
                    const std::string& what, const std::string& what_plural) {
        long long i = parse_integer(line, text, what + " index", -(1LL << 40), 1LL << 40);
        if (i == 0) line.fail(what + " index 0 is not allowed (OBJ indices start at 1)");
        long long k = i > 0 ? i - 1 : count + i;
        if (k < 0 || k >= count)
            line.fail(what + " index " + std::to_string(i) + " is out of range (" +
                      counted(long(count), what, what_plural) + " defined so far)");
        return k;
    }

    void face(const Line& line) {
        if (line.size() < 4)
            line.fail("'f' needs at least 3 vertices, found " + std::to_string(line.size() - 1));
        if (line.size() - 1 > size_t(max_face_vertices))
            line.fail("face has " + std::to_string(line.size() - 1) + " vertices; at most " +
                      std::to_string(max_face_vertices) + " are accepted");
        std::vector<Vec3> p;
        for (size_t t = 1; t < line.size(); ++t) {
            // v, v/vt, v//vn or v/vt/vn.
            const std::string& ref = line[t];
            std::vector<std::string> parts(1);
            for (char c : ref) {
                if (c == '/')
                    parts.emplace_back();
                else
                    parts.back() += c;
            }
            if (parts.size() > 3 || parts[0].empty() || (parts.size() == 2 && parts[1].empty()) ||
                (parts.size() == 3 && parts[2].empty()))
                line.fail("malformed face vertex " + in_quotes(ref) +
                          " (expected v, v/vt, v//vn or v/vt/vn)");
            p.push_back(v_[size_t(index(line, parts[0], long(v_.size()), "vertex", "vertices"))]);
            if (parts.size() >= 2 && !parts[1].empty())
                index(line, parts[1], n_vt_, "texture vertex", "texture vertices");
            if (parts.size() == 3) index(line, parts[2], n_vn_, "normal", "normals");
        }
        if (material_ < 0) material_ = default_material();
        for (const Quad& q : face_to_quads(line, p)) {
            SceneSurface s;
            s.name = group_;
            s.surface = Surface::planar_quad(q[0], q[1], q[2], q[3]);
            s.material = material_;
            scene_.surfaces.push_back(std::move(s));
        }
    }

    int default_material() {
        int m = scene_.find_material(obj_default_material);
        if (m >= 0) return m;
        Material mat;
        mat.name = obj_default_material;
        mat.reflectance = Texture::constant({0.5, 0.5, 0.5});
        scene_.materials.push_back(mat);
        return int(scene_.materials.size()) - 1;
    }

    /// A group that yields one surface gives it its own name; the surfaces of a group that
    /// yields several are NAME.0, NAME.1, ... in file order, skipping every number whose name is
    /// already taken (by a group of that name, say `a.0` next to a group `a` of two faces), so
    /// that every name is unique.
    void name_surfaces() {
        std::unordered_map<std::string, int> count, next;
        for (const SceneSurface& s : scene_.surfaces) ++count[s.name];
        std::unordered_set<std::string> taken;
        for (const auto& [name, n] : count)
            if (n == 1) taken.insert(name);
        for (SceneSurface& s : scene_.surfaces) {
            if (count[s.name] == 1) continue;
            int& k = next[s.name];
            std::string numbered;
            do numbered = s.name + "." + std::to_string(k++);
            while (!taken.insert(numbered).second);
            s.name = std::move(numbered);
        }
    }

    void mtllib(const Line& at, const std::string& path) {
        state_.charge(at);
        std::ifstream in;
        open_named(at, "material library", path, in);
        LineReader reader(in, path);
        Line line;
        MtlEntry entry;
        bool open = false;
        while (reader.next(line)) {
            const std::string& key = line[0];
            if (key == "newmtl") {
                if (open) finish_material(entry, path);
                if (line.size() != 2) line.fail("'newmtl' needs one material name");
                entry = MtlEntry();
                entry.name = line[1];
                entry.newmtl_line = line;
                open = true;
                continue;
            }
            if (!open) line.fail(in_quotes(key) + " before any 'newmtl'");
            mtl_statement(line, entry, path);
        }
        if (open) finish_material(entry, path);
    }

    /// "Kd r g b" or "Kd r" (grey); spectral and CIE XYZ forms are refused.
    static Rgb mtl_colour(const Line& line) {
        if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz"))
            line.fail(in_quotes(line[0]) + " " + line[1] +
                      " colours are not supported; give r g b");
        if (line.size() != 2 && line.size() != 4)
            line.fail(in_quotes(line[0]) + " needs 1 or 3 numbers (r g b), found " +
                      std::to_string(line.size() - 1));
        Rgb c;
        for (int i = 0; i < 3; ++i)
            c[i] = parse_double(line, line[line.size() == 2 ? 1 : 1 + i], line[0]);
        return c;
    }

    static void mtl_statement(const Line& line, MtlEntry& e, const std::string&) {
        const std::string& key = line[0];
        if (key == "Kd") {
            Rgb kd = mtl_colour(line);
            for (int i = 0; i < 3; ++i)
                if (!(kd[i] >= 0 && kd[i] < 1))
                    line.fail("Kd " + fmt(kd[i]) +
                              " is outside [0, 1): a reflectance of 1 or more makes the "
                              "radiosity iteration diverge (scale the colour below 1)");
            e.kd = kd;
            e.has_kd = true;
        } else if (key == "Ke") {
            Rgb ke = mtl_colour(line);
            for (int i = 0; i < 3; ++i)
                if (ke[i] < 0) line.fail("Ke " + fmt(ke[i]) + " is negative");
            if (!std::isfinite(Pi * max_abs(ke))) line.fail("Ke is too large");
            e.ke = ke;
        } else if (key == "map_Kd" || key == "map_Ke") {
            // Options (-s, -o, -bm, ...) come first; the file name is the last token.
            if (line.size() < 2) line.fail(in_quotes(key) + " needs a file name");
            (key == "map_Kd" ? e.map_kd : e.map_ke) = line[line.size() - 1];
            (key == "map_Kd" ? e.map_kd_line : e.map_ke_line) = line;
        } else if (key == "Ka" || key == "Ks" || key == "Tf") {
            if (line.size() >= 2 && (line[1] == "spectral" || line[1] == "xyz")) return;
            mtl_colour(line);
        } else if (key == "Ns" || key == "Ni" || key == "Tr" || key == "illum" ||
                   key == "sharpness" || key == "Pr" || key == "Pm" || key == "Ps" || key == "Pc" ||
                   key == "Pcr" || key == "aniso" || key == "anisor") {
            if (line.size() != 2)
                line.fail(in_quotes(key) + " needs one number, found " +
                          std::to_string(line.size() - 1));
            parse_double(line, line[1], key);
        } else if (key == "d") {
            size_t i = (line.size() == 3 && line[1] == "-halo") ? 2 : 1;
            if (line.size() != i + 1) line.fail("'d' needs one number");
            parse_double(line, line[i], key);
        } else if (key.compare(0, 4, "map_") == 0 || key == "bump" || key == "disp" ||
                   key == "decal" || key == "refl" || key == "norm") {
            if (line.size() < 2) line.fail(in_quotes(key) + " needs a file name");
        } else {
            line.fail("unknown MTL statement " + in_quotes(key));
        }
    }

    Texture mtl_texture(const Line& line, const std::string& file, Rgb scale) {
        return state_.image(line, resolve(line.file, file)).scaled(scale);
    }

    void finish_material(const MtlEntry& e, const std::string&) {
        if (material_index_.count(e.name))
            e.newmtl_line.fail("duplicate material " + in_quotes(e.name));
        Material m;
        m.name = e.name;
        if (!e.map_kd.empty()) {
            Rgb scale = e.has_kd ? e.kd : Rgb{0.9, 0.9, 0.9};
            m.reflectance = mtl_texture(e.map_kd_line, e.map_kd, scale);
        } else {
            m.reflectance = Texture::constant(e.kd);
        }
        // MTL's Ke is emitted radiance (as in the common Cornell box files); E = pi L.
        if (!e.map_ke.empty()) {
            bool any = max_abs(e.ke) > 0;
            m.emission = mtl_texture(e.map_ke_line, e.map_ke, Pi * (any ? e.ke : Rgb{1, 1, 1}));
        } else {
            m.emission = Texture::constant(Pi * e.ke);
        }
        material_index_[e.name] = int(scene_.materials.size());
        scene_.materials.push_back(std::move(m));
    }

    std::string name_;
    LoadState& state_;
    Scene scene_;
    std::vector<Vec3> v_;
    long long n_vt_ = 0, n_vn_ = 0;
    std::unordered_map<std::string, int> material_index_;
    int material_ = -1;
    std::string group_;
};

// ---------------------------------------------------------------------------------------------
// === The scene format

class SceneReader {
public:
    explicit SceneReader(LoadState& state) : state_(state) {}

    Scene read(std::istream& in, const std::string& name) {
        read_file(in, name, 0);
        if (scene_.surfaces.empty()) throw InputError(name, 0, "the scene has no surfaces");
        const SolverSettings& s = scene_.settings;
        if (s.min_depth > s.max_depth) {
            const Line& at = depth_line_.number > 0 ? depth_line_ : Line{name, 0, {}};
            at.fail("min_depth " + std::to_string(s.min_depth) + " exceeds max_depth " +
                    std::to_string(s.max_depth));
        }
        return std::move(scene_);
    }

private:
    void read_file(std::istream& in, const std::string& name, int depth) {
        stack_.push_back(canonical_name(name));
        LineReader reader(in, name);
        Line line;
        while (reader.next(line)) statement(line, depth);
        stack_.pop_back();
    }

    void statement(const Line& line, int depth) {
        const std::string& key = line[0];
        if (key == "material") {
            material(line);
        } else if (key == "quad" || key == "bilinear" || key == "rectangle" || key == "box" ||
                   key == "cylinder" || key == "sphere" || key == "disk") {
            surface(line);
        } else if (key == "camera") {
            camera(line);
        } else if (key == "set") {
            setting(line);
        } else if (key == "obj") {
            obj(line);
        } else if (key == "include") {
            include(line, depth);
        } else {
            line.fail("unknown keyword " + in_quotes(key) +
                      " (expected material, quad, bilinear, rectangle, box, cylinder, sphere, "
                      "disk, camera, set, obj or include)");
        }
    }

    // --- material NAME [reflectance TEXTURE] [emission TEXTURE]

    void material(const Line& line) {
        if (line.size() < 2) line.fail("'material' needs a name");
        const std::string& name = line[1];
        if (is_number_token(name))
            line.fail("material name " + in_quotes(name) + " looks like a number");
        auto seen = materials_.find(name);
        if (seen != materials_.end())
            line.fail("duplicate material " + in_quotes(name) + " (first defined at " +
                      seen->second.where + ")");
        Material m;
        m.name = name;
        bool has_reflectance = false, has_emission = false;
        for (size_t t = 2; t < line.size();) {
            const std::string& clause = line[t];
            bool refl = clause == "reflectance";
            if (!refl && clause != "emission") {
                if (is_number_token(clause))
                    line.fail("unexpected number " + in_quotes(clause) +
                              " (too many numbers for the previous clause)");
                line.fail("unknown material clause " + in_quotes(clause) +
                          " (expected 'reflectance' or 'emission')");
            }
            bool& seen_clause = refl ? has_reflectance : has_emission;
            if (seen_clause) line.fail(in_quotes(clause) + " is given twice");
            seen_clause = true;
            ++t;
            (refl ? m.reflectance : m.emission) = texture(line, t, refl);
        }
        add_material(std::move(m), line.file + ":" + std::to_string(line.number));
    }

    /// Checks a colour against the range of its role.
    static void check_colour(const Line& line, Rgb c, bool reflectance, const std::string& what) {
        for (int i = 0; i < 3; ++i) {
            if (reflectance && !(c[i] >= 0 && c[i] < 1))
                line.fail(what + " " + fmt(c[i]) + " is outside [0, 1)");
            if (!reflectance && c[i] < 0) line.fail(what + " " + fmt(c[i]) + " is negative");
        }
    }

    Rgb colour(const Line& line, size_t& t, const std::string& what, bool reflectance) {
        Rgb c;
        for (int i = 0; i < 3; ++i) {
            if (t >= line.size() || !is_number_token(line[t]))
                line.fail(what + " needs 3 numbers (r g b), found " + std::to_string(i) +
                          (t < line.size() ? ": unexpected " + in_quotes(line[t]) : std::string()));
            c[i] = parse_double(line, line[t++], what);
        }
        check_colour(line, c, reflectance, what);
        return c;
    }

    /// R G B | checker N R G B R G B | image FILE [scale R G B], starting at tokens[t].
    Texture texture(const Line& line, size_t& t, bool reflectance) {
        const std::string role = reflectance ? "reflectance" : "emission";
        if (t >= line.size())
            line.fail(in_quotes(role) + " needs a value (r g b, checker or image)");
        const std::string& kind = line[t];
        if (kind == "checker") {
            ++t;
            if (t >= line.size()) line.fail("checker needs the number of squares per side");
            int n = int(parse_integer(line, line[t++], "checker squares", 1, 4096));
            Rgb a = colour(line, t, role + " checker colour", reflectance);
            Rgb b = colour(line, t, role + " checker colour", reflectance);
            return Texture::checker(a, b, n);
        }
        if (kind == "image") {
            ++t;
            if (t >= line.size()) line.fail("image needs a file name");
            std::string path = resolve(line.file, line[t++]);
            Rgb scale = reflectance ? Rgb{0.9, 0.9, 0.9} : Rgb{1, 1, 1};
            if (t < line.size() && line[t] == "scale") {
                ++t;
                scale = colour(line, t, role + " image scale", reflectance);
            }
            Texture tex = state_.image(line, path).scaled(scale);
            check_colour(line, tex.maximum(), reflectance, role + " image maximum");
            return tex;
        }
        if (!is_number_token(kind))
            line.fail(in_quotes(role) + " expects r g b, 'checker' or 'image', found " +
                      in_quotes(kind));
        return Texture::constant(colour(line, t, role, reflectance));
    }

    // --- surfaces: KIND NAME MATERIAL numbers...

    void add_surface(const Line& line, const std::string& name, int material, Surface s) {
        double area = s.area();
        if (!(area > 0) || !std::isfinite(area))
            line.fail("degenerate surface " + in_quotes(name) + ": its area is " +
                      fmt_approx(area));
        auto [seen, is_new] =
            surface_where_.try_emplace(name, line.file + ":" + std::to_string(line.number));
        if (!is_new)
            line.fail("duplicate surface name " + in_quotes(name) + " (first used at " +
                      seen->second + ")");
        scene_.surfaces.push_back({name, std::move(s), material});
    }

    Surface checked_quad(const Line& line, const Quad& q) {
        for (int i = 0; i < 4; ++i) check_point(line, q[i], "corner");
        std::string problem = planar_quad_problem(q);
        if (!problem.empty()) {
            if (problem.compare(0, 13, "quad is not p") == 0)
                problem += "; use 'bilinear' for a twisted quad";
            line.fail(problem);
        }
        return Surface::planar_quad(q[0], q[1], q[2], q[3]);
    }

    void surface(const Line& line) {
        const std::string& kind = line[0];
        if (line.size() < 3) line.fail(in_quotes(kind) + " needs a name, a material and numbers");
        const std::string& name = line[1];
        const std::string& mat_name = line[2];
        auto found = materials_.find(mat_name);
        if (found == materials_.end())
            line.fail("unknown material " + in_quotes(mat_name) +
                      " (materials must be defined before the surfaces that use them)");
        const int material = found->second.index;
        bool inward = false;
        if (kind == "quad" || kind == "bilinear") {
            auto x = read_fields(line, 3, kind, {{"p00", 3}, {"p10", 3}, {"p11", 3}, {"p01", 3}});
            Quad q = {vec_at(x, 0), vec_at(x, 3), vec_at(x, 6), vec_at(x, 9)};
            if (kind == "quad") {
                add_surface(line, name, material, checked_quad(line, q));
                return;
            }
            for (int i = 0; i < 4; ++i) check_point(line, q[i], "corner");
            add_surface(line, name, material, checked_bilinear(line, q));
        } else if (kind == "rectangle") {
            auto x = read_fields(line, 3, kind, {{"corner", 3}, {"edge_u", 3}, {"edge_v", 3}});
            Vec3 c = vec_at(x, 0), eu = vec_at(x, 3), ev = vec_at(x, 6);
            check_point(line, c, "corner");
            check_direction(line, eu, "edge_u");
            check_direction(line, ev, "edge_v");
            add_surface(line, name, material, checked_quad(line, {c, c + eu, c + eu + ev, c + ev}));
        } else if (kind == "box") {
            auto x = read_fields(line, 3, kind, {{"lo", 3}, {"hi", 3}}, "inward", &inward);
            box(line, name, material, vec_at(x, 0), vec_at(x, 3), inward);
        } else if (kind == "cylinder") {
            auto x = read_fields(line, 3, kind,
                                 {{"base", 3},
                                  {"axis", 3},
                                  {"e1", 3},
                                  {"radius", 1},
                                  {"height", 1},
                                  {"phi0", 1},
                                  {"phi1", 1}},
                                 "inward", &inward);
            Vec3 base = vec_at(x, 0), axis = vec_at(x, 3), e1 = vec_at(x, 6);
            check_point(line, base, "base");
            check_direction(line, axis, "axis");
            check_direction(line, e1, "e1");
            check_not_parallel(line, axis, e1, "axis");
            double r = check_length(line, x[9], "radius", false);
            double h = check_length(line, x[10], "height", false);
            check_angle_range(line, x[11], x[12], "phi", 360);
            add_surface(
                line, name, material,
                Surface::cylinder(base, axis, e1, r, h, radians(x[11]), radians(x[12]), inward));
        } else if (kind == "sphere") {
            auto x = read_fields(line, 3, kind,
                                 {{"centre", 3},
                                  {"pole", 3},
                                  {"e1", 3},
                                  {"radius", 1},
                                  {"theta0", 1},
                                  {"theta1", 1},
                                  {"phi0", 1},
                                  {"phi1", 1}},
                                 "inward", &inward);
            Vec3 centre = vec_at(x, 0), pole = vec_at(x, 3), e1 = vec_at(x, 6);
            check_point(line, centre, "centre");
            check_direction(line, pole, "pole");
            check_direction(line, e1, "e1");
            check_not_parallel(line, pole, e1, "pole");
            double r = check_length(line, x[9], "radius", false);
            for (int i : {10, 11})
                if (!(x[i] >= 0 && x[i] <= 180))
                    line.fail("sphere theta " + fmt(x[i]) + " is outside [0, 180] degrees");
            check_angle_range(line, x[10], x[11], "theta", 180);
            check_angle_range(line, x[12], x[13], "phi", 360);
            add_surface(line, name, material,
                        Surface::sphere(centre, pole, e1, r, radians(x[10]), radians(x[11]),
                                        radians(x[12]), radians(x[13]), inward));
        } else {  // disk
            auto x = read_fields(line, 3, kind,
                                 {{"centre", 3},
                                  {"normal", 3},
                                  {"e1", 3},
                                  {"r0", 1},
                                  {"r1", 1},
                                  {"phi0", 1},
                                  {"phi1", 1}});
            Vec3 centre = vec_at(x, 0), normal = vec_at(x, 3), e1 = vec_at(x, 6);
            check_point(line, centre, "centre");
            check_direction(line, normal, "normal");
            check_direction(line, e1, "e1");
            check_not_parallel(line, normal, e1, "normal");
            double r0 = check_length(line, x[9], "r0", true);
            double r1 = check_length(line, x[10], "r1", false);
            if (!(r1 > r0)) line.fail("disk r1 " + fmt(r1) + " must exceed r0 " + fmt(r0));
            check_angle_range(line, x[11], x[12], "phi", 360);
            add_surface(line, name, material,
                        Surface::disk(centre, normal, e1, r0, r1, radians(x[11]), radians(x[12])));
        }
    }

    /// A bilinear patch must not fold: the normals at the corners agree with the centre's.
    Surface checked_bilinear(const Line& line, const Quad& q) {
        std::vector<Vec3> p(q.begin(), q.end());
        double size = max_pairwise_distance(p);
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j)
                if (!(length(p[i] - p[j]) > 1e-9 * size))
                    line.fail("degenerate bilinear patch: corners " + std::to_string(i + 1) +
                              " and " + std::to_string(j + 1) + " coincide");
        Surface s = Surface::bilinear_patch(q[0], q[1], q[2], q[3]);
        Vec3 n_c = s.normal(0.5, 0.5);
        Vec3 x_u, x_v;
        s.tangents(0.5, 0.5, x_u, x_v);
        if (!(length(cross(x_u, x_v)) > 1e-9 * size * size))
            line.fail("degenerate bilinear patch: zero area at its centre");
        const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int i = 0; i < 4; ++i) {
            s.tangents(uv[i][0], uv[i][1], x_u, x_v);
            Vec3 n = cross(x_u, x_v);
            if (!(dot(n, n_c) > 1e-9 * size * size))
                line.fail("bilinear patch folds over itself at corner " + std::to_string(i + 1) +
                          " (its corners do not form a convex quad seen along its normal)");
        }
        return s;
    }

    /// Six quads of an axis-aligned box, named NAME.xmin ... NAME.zmax, facing out (or in).
    void box(const Line& line, const std::string& name, int material, Vec3 lo, Vec3 hi,
             bool inward) {
        check_point(line, lo, "box lo");
        check_point(line, hi, "box hi");
        for (int a = 0; a < 3; ++a)
            if (!(lo[a] < hi[a]))
                line.fail(std::string("box lo.") + "xyz"[a] + " " + fmt(lo[a]) +
                          " must be below hi." + "xyz"[a] + " " + fmt(hi[a]));
        for (int a = 0; a < 3; ++a)
            for (int side = 0; side < 2; ++side) {
                int b = (a + 1) % 3, c = (a + 2) % 3;
                Vec3 base = lo;
                if (side == 1) base[a] = hi[a];
                Vec3 eb, ec;
                eb[b] = hi[b] - lo[b];
                ec[c] = hi[c] - lo[c];
                // eb x ec points along +axis a: the max side uses (eb, ec), the min side swaps.
                bool plus = (side == 1) != inward;
                Vec3 e_u = plus ? eb : ec, e_v = plus ? ec : eb;
                Quad q = {base, base + e_u, base + e_u + e_v, base + e_v};
                std::string face = name + "." + "xyz"[a] + (side == 1 ? "max" : "min");
                add_surface(line, face, material, checked_quad(line, q));
            }
    }

    // --- camera eye X Y Z look_at X Y Z [up X Y Z] [fov DEGREES] [size W H]

    void camera(const Line& line) {
        if (camera_line_ > 0)
            line.fail("camera is given twice (first at line " + std::to_string(camera_line_) + ")");
        Camera cam;
        std::set<std::string> seen;
        for (size_t t = 1; t < line.size();) {
            const std::string clause = line[t++];
            int n = clause == "eye" || clause == "look_at" || clause == "up" ? 3
                    : clause == "fov"                                        ? 1
                    : clause == "size"                                       ? 2
                                                                             : 0;
            if (n == 0) {
                if (is_number_token(clause))
                    line.fail("unexpected number " + in_quotes(clause) +
                              " (too many numbers for the previous camera clause)");
                line.fail("unknown camera clause " + in_quotes(clause) +
                          " (expected eye, look_at, up, fov or size)");
            }
            if (!seen.insert(clause).second) line.fail("camera " + clause + " is given twice");
            double x[3];
            for (int i = 0; i < n; ++i) {
                if (t >= line.size() || !is_number_token(line[t]))
                    line.fail("camera " + clause + " needs " + std::to_string(n) +
                              " numbers, found " + std::to_string(i));
                if (clause == "size")
                    x[i] = double(parse_integer(line, line[t++], "image size", 1, 16384));
                else
                    x[i] = parse_double(line, line[t++], "camera " + clause);
            }
            if (clause == "eye") cam.eye = {x[0], x[1], x[2]};
            if (clause == "look_at") cam.look_at = {x[0], x[1], x[2]};
            if (clause == "up") cam.up = {x[0], x[1], x[2]};
            if (clause == "fov") cam.fov_degrees = x[0];
            if (clause == "size") {
                cam.width = int(x[0]);
                cam.height = int(x[1]);
            }
        }
        if (!seen.count("eye") || !seen.count("look_at"))
            line.fail("camera needs 'eye' and 'look_at'");
        check_point(line, cam.eye, "camera eye");
        check_point(line, cam.look_at, "camera look_at");
        check_direction(line, cam.up, "camera up");
        Vec3 dir = cam.look_at - cam.eye;
        if (!(length(dir) > 0)) line.fail("camera eye and look_at coincide");
        if (length(cross(normalize(dir), normalize(cam.up))) < 1e-6)
            line.fail("camera up is parallel to the viewing direction");
        if (!(cam.fov_degrees > 0 && cam.fov_degrees < 180))
            line.fail("camera fov " + fmt(cam.fov_degrees) + " is outside (0, 180) degrees");
        scene_.camera = cam;
        scene_.has_camera = true;
        camera_line_ = line.number;
    }

    // --- set NAME VALUE

    void setting(const Line& line) {
        if (line.size() != 3)
            line.fail("'set' needs a name and one value, found " +
                      counted(long(line.size()) - 1, "word", "words"));
        const std::string& key = line[1];
        const std::string& value = line[2];
        if (!settings_seen_.insert(key).second)
            line.fail("setting " + in_quotes(key) + " is given twice");
        SolverSettings& s = scene_.settings;
        auto integer = [&](long long lo, long long hi) {
            return int(parse_integer(line, value, key, lo, hi));
        };
        auto real = [&](double lo, double hi, bool open_lo, bool open_hi) {
            double x = parse_double(line, value, key);
            if (x < lo || x > hi || (open_lo && x == lo) || (open_hi && x == hi))
                line.fail(key + " " + fmt(x) + " is outside " + (open_lo ? "(" : "[") + fmt(lo) +
                          ", " + fmt(hi) + (open_hi ? ")" : "]"));
            return x;
        };
        if (key == "order") {
            s.order = integer(2, 8);
        } else if (key == "min_depth") {
            s.min_depth = integer(0, 12);
            depth_line_ = line;
        } else if (key == "max_depth") {
            s.max_depth = integer(0, 12);
            depth_line_ = line;
        } else if (key == "oracle_tolerance") {
            s.oracle_tolerance = real(0, 1, true, false);
        } else if (key == "truncation_eps") {
            s.truncation_eps = real(0, 1, true, true);
        } else if (key == "rhombus_radius") {
            s.rhombus_radius = real(0, 1000, false, false);
        } else if (key == "extrapolation") {
            if (value != "linear" && value != "higher")
                line.fail("extrapolation " + in_quotes(value) +
                          " is neither 'linear' nor 'higher'");
            s.extrapolation = value;
        } else if (key == "shadow_rays") {
            s.shadow_rays = integer(1, 4096);
        } else if (key == "max_shots") {
            s.max_shots = integer(0, 10000000);
        } else if (key == "convergence") {
            s.convergence = real(0, 1, false, true);
        } else if (key == "self_transfer") {
            if (value != "true" && value != "false")
                line.fail("self_transfer " + in_quotes(value) + " is neither 'true' nor 'false'");
            s.self_transfer = value == "true";
        } else if (key == "tessellation") {
            s.tessellation = integer(1, 1024);
        } else if (key == "shadows") {
            if (value != "exact" && value != "paper" && value != "none")
                line.fail("shadows " + in_quotes(value) + " is not 'exact', 'paper' or 'none'");
            s.shadows = value;
        } else if (key == "tolerance") {
            s.tolerance = real(0, 1, true, true);
        } else if (key == "unify") {
            if (value != "projection" && value != "paper")
                line.fail("unify " + in_quotes(value) + " is neither 'projection' nor 'paper'");
            s.unify = value;
        } else if (key == "shooter_level") {
            s.shooter_level = integer(0, 12);
        } else if (key == "contact_depth") {
            s.contact_depth = integer(0, 12);
        } else if (key == "contact_oracle") {
            if (value != "interpolation" && value != "means")
                line.fail("contact_oracle " + in_quotes(value) +
                          " is neither 'interpolation' nor 'means'");
            s.contact_oracle = value;
        } else if (key == "ambient" || key == "hidden") {
            if (value != "true" && value != "false")
                line.fail(key + " " + in_quotes(value) + " is neither 'true' nor 'false'");
            (key == "ambient" ? s.ambient : s.hidden) = value == "true";
        } else {
            line.fail("unknown setting " + in_quotes(key) +
                      " (known: order, min_depth, max_depth, oracle_tolerance, truncation_eps, "
                      "rhombus_radius, extrapolation, shadow_rays, max_shots, convergence, "
                      "self_transfer, tessellation, shadows, tolerance, unify, ambient, hidden, "
                      "shooter_level, contact_depth, contact_oracle)");
        }
    }

    // --- obj FILE, include FILE

    void obj(const Line& line) {
        if (line.size() != 2) line.fail("'obj' needs one file name");
        std::string path = resolve(line.file, line[1]);
        state_.charge(line);
        std::ifstream in;
        open_named(line, "OBJ file", path, in);
        Scene part = ObjReader(path, state_).read(in);
        // Merge: the OBJ's materials join the scene's (names must be new, except the shared
        // default material), then its surfaces with their material indices moved along.
        std::vector<int> index(part.materials.size());
        for (size_t i = 0; i < part.materials.size(); ++i) {
            Material& m = part.materials[i];
            auto existing = materials_.find(m.name);
            if (existing != materials_.end() && m.name == obj_default_material) {
                index[i] = existing->second.index;
                continue;
            }
            if (existing != materials_.end())
                line.fail("material " + in_quotes(m.name) + " of " + in_quotes(path) +
                          " is already defined (at " + existing->second.where + ")");
            index[i] = add_material(std::move(m), path);
        }
        for (SceneSurface& s : part.surfaces) {
            s.material = index[size_t(s.material)];
            auto [seen, is_new] = surface_where_.try_emplace(s.name, path);
            if (!is_new)
                line.fail("surface " + in_quotes(s.name) + " of " + in_quotes(path) +
                          " has the name of an earlier surface (at " + seen->second + ")");
            scene_.surfaces.push_back(std::move(s));
        }
    }

    void include(const Line& line, int depth) {
        if (line.size() != 2) line.fail("'include' needs one file name");
        std::string path = resolve(line.file, line[1]);
        if (depth + 1 > max_include_depth)
            line.fail("includes are nested more than " + std::to_string(max_include_depth) +
                      " deep");
        std::string canonical = canonical_name(path);
        if (std::find(stack_.begin(), stack_.end(), canonical) != stack_.end())
            line.fail("include cycle: " + in_quotes(path) + " is already being read");
        state_.charge(line);
        std::ifstream in;
        open_named(line, "included file", path, in);
        read_file(in, path, depth + 1);
    }

    /// Appends a material to the scene and indexes it; returns its index.
    int add_material(Material m, const std::string& where) {
        const int index = int(scene_.materials.size());
        materials_[m.name] = {index, where};
        scene_.materials.push_back(std::move(m));
        return index;
    }

    /// Where a material was defined ("file:line", or the OBJ file) and its index in the scene.
    struct MaterialEntry {
        int index = -1;
        std::string where;
    };

    LoadState& state_;
    Scene scene_;
    std::vector<std::string> stack_;  // canonical names of the open files
    // Name look-ups in constant time: a scene of n surfaces is read in O(n), not O(n^2).
    std::unordered_map<std::string, MaterialEntry> materials_;
    std::unordered_map<std::string, std::string> surface_where_;  // name -> "file:line"
    std::set<std::string> settings_seen_;
    int camera_line_ = 0;
    Line depth_line_;
};

/// Opens a top-level file for reading, or throws InputError(path, 0, ...).
void open_top(const std::string& path, std::ifstream& in) {
    std::string problem = file_problem(path);
    if (!problem.empty()) throw InputError(path, 0, problem);
    errno = 0;
    in.open(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "cannot open the file" + system_reason());
}

}  // namespace

Scene parse_scene(std::istream& in, const std::string& name) {
    LoadState state;
    return SceneReader(state).read(in, name);
}

Scene load_scene(const std::string& path) {
    std::ifstream in;
    open_top(path, in);
    return parse_scene(in, path);
}

Scene parse_obj(std::istream& in, const std::string& name) {
    LoadState state;
    return ObjReader(name, state).read(in);
}

Scene load_obj(const std::string& path) {
    std::ifstream in;
    open_top(path, in);
    return parse_obj(in, path);
}

}  // namespace mbr
