// radiosity/scene/mgf_reader.cpp - MGF import (mgf_reader.h): each file's entities read into
// lines, then executed in order with the contexts MGF defines (vertex, colour, material,
// transform, object); an `xf` array executes the lines up to its closing `xf` once per instance.
#include "radiosity/scene/mgf_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <unordered_map>
#include <vector>

#include "math/check.h"
#include "radiosity/scene/faces_to_quads.h"
#include "radiosity/scene/light_sides.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/scene/scene_reader.h"

namespace mbr {

namespace fs = std::filesystem;
using namespace detail;

namespace {

constexpr int max_include_depth = 64;
constexpr long max_instances = 1000000;  // of one xf's arrays together
constexpr long max_surfaces = 10000000;  // made by one load
constexpr int max_face_vertices = 4096;  // faces with holes joined along seams are long
/// The luminous efficacy of equal-energy white light (lm/W), which turns MGF's photometric
/// emittance `ed` (lm/m^2) into the emission E (W/m^2) of eq. (1), as Radiance's mgf2rad does.
constexpr double white_efficacy = 179;
/// The largest reflectance a channel is clamped to (as for OBJ's Kd, obj_reader.cpp).
constexpr double max_clamped_reflectance = 0.99;

using Matrix = std::array<std::array<double, 3>, 3>;

Matrix multiply(const Matrix& a, const Matrix& b) {
    Matrix c{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
                c[size_t(i)][size_t(j)] += a[size_t(i)][size_t(k)] * b[size_t(k)][size_t(j)];
    return c;
}

double determinant(const Matrix& a) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

Matrix inverse(const Matrix& a) {
    const double d = determinant(a);
    Matrix r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            // Cofactor of (j, i), over the determinant.
            const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            r[size_t(i)][size_t(j)] = (a[size_t(r0)][size_t(c0)] * a[size_t(r1)][size_t(c1)] -
                                       a[size_t(r0)][size_t(c1)] * a[size_t(r1)][size_t(c0)]) /
                                      d;
        }
    return r;
}

/// CIE XYZ to linear sRGB with equal-energy white: the BT.709 primaries' chromaticities and
/// white (1/3, 1/3) give the RGB-to-XYZ matrix (the primaries' XYZ scaled so that they sum to
/// white's (1, 1, 1)); this is its inverse.
Matrix xyz_to_rgb() {
    const double xy[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
    Matrix p{};
    for (int c = 0; c < 3; ++c) {
        const double x = xy[c][0], y = xy[c][1];
        p[0][size_t(c)] = x / y;
        p[1][size_t(c)] = 1;
        p[2][size_t(c)] = (1 - x - y) / y;
    }
    const Matrix pi = inverse(p);
    Matrix rgb_to_xyz = p;
    for (int c = 0; c < 3; ++c) {
        const double s = pi[size_t(c)][0] + pi[size_t(c)][1] + pi[size_t(c)][2];  // P^-1 (1,1,1)
        for (int r = 0; r < 3; ++r) rgb_to_xyz[size_t(r)][size_t(c)] *= s;
    }
    return inverse(rgb_to_xyz);
}

/// The chromaticity of a black body at `kelvin` (1667..25000 K): the cubic approximation of the
/// Planckian locus by Kim, Kim, Lee, Lee and Kim (2002).
std::array<double, 2> black_body_xy(double kelvin) {
    const double t = kelvin, t2 = t * t, t3 = t2 * t;
    const double x = t <= 4000 ? -0.2661239e9 / t3 - 0.2343589e6 / t2 + 0.8776956e3 / t + 0.179910
                               : -3.0258469e9 / t3 + 2.1070379e6 / t2 + 0.2226347e3 / t + 0.240390;
    const double x2 = x * x, x3 = x2 * x;
    double y;
    if (t <= 2222)
        y = -1.1063814 * x3 - 1.34811020 * x2 + 2.18555832 * x - 0.20219683;
    else if (t <= 4000)
        y = -0.9549476 * x3 - 1.37418593 * x2 + 2.09137015 * x - 0.16748867;
    else
        y = 3.0817580 * x3 - 5.87338670 * x2 + 3.75112997 * x - 0.37001483;
    return {x, y};
}

/// One `v` entity: its point and normal as given (transforms apply where it is used).
struct MgfVertex {
    Vec3 p, n;
    bool has_p = false;
};

/// One `c` context: a chromaticity (neutral by default).
struct MgfColour {
    double x = 1.0 / 3, y = 1.0 / 3;
};

/// One `m` context: the components mbr uses and what it reports as dropped.
struct MgfMaterial {
    Rgb rd, ed;  // linear sRGB diffuse reflectance, and emission E (W/m^2)
    double rs = 0, ts = 0, td = 0;
    int sides = 0;    // 0: not given (one-sided in mbr), 1 or 2
    int version = 0;  // changes with every component set, so a face takes the state it sees
};

/// An `xf` argument list as maps: the part before the first array, and each array with its
/// count and the map one step of it applies.
struct Transform {
    Affine initial;
    std::vector<std::pair<long, Affine>> arrays;  // (count, step), in argument order
    std::vector<Affine> after;                    // the map after each array (its -i parts)
};

class MgfReader : ImportReader {
public:
    explicit MgfReader(LoadState& state) : ImportReader(state) {}

    Scene read(std::istream& in, const std::string& name) {
        top_ = name;
        read_file(in, name, 0);
        if (scene_.surfaces.empty()) throw InputError(name, 0, "the MGF file has no surfaces");
        return finish();
    }

private:
    /// The file's entities, continued lines (a trailing backslash) joined, then executed.
    void read_file(std::istream& in, const std::string& name, int depth) {
        source_ = source_index(name);
        LineReader reader(in, name);
        std::vector<Line> lines;
        Line line;
        bool continued = false;
        while (reader.next(line)) {
            std::vector<std::string> words(line.tokens.begin(), line.tokens.end());
            bool more = false;
            if (!words.empty() && !words.back().empty() && words.back().back() == '\\') {
                words.back().pop_back();
                if (words.back().empty()) words.pop_back();
                more = true;
            }
            if (continued)
                lines.back().tokens.insert(lines.back().tokens.end(), words.begin(), words.end());
            else if (!words.empty())
                lines.push_back(Line{line.file, line.number, words});
            continued = more && !lines.empty();
        }
        const size_t xf_depth = xf_.size(), o_depth = objects_.size();
        execute(lines, 0, lines.size(), depth);
        // Contexts a file leaves open end with it.
        if (xf_.size() > xf_depth || objects_.size() > o_depth) {
            Line end{name, 0, {}};
            fault(end, "context left open",
                  "the file ends inside " + std::to_string(xf_.size() - xf_depth) + " xf and " +
                      std::to_string(objects_.size() - o_depth) + " o contexts",
                  "they end with it");
            xf_.resize(xf_depth);
            objects_.resize(o_depth);
        }
    }

    int source_index(const std::string& file) {
        for (size_t i = 0; i < scene_.sources.size(); ++i)
            if (scene_.sources[i] == file) return int(i);
        scene_.sources.push_back(file);
        return int(scene_.sources.size()) - 1;
    }

    /// Runs lines [begin, end): an `xf` with arrays runs the lines up to its closing `xf` once
    /// per instance.
    void execute(const std::vector<Line>& lines, size_t begin, size_t end, int depth) {
        for (size_t i = begin; i < end; ++i) {
            const Line& line = lines[i];
            const int source = source_;
            try {
                if (line[0] == "xf" && line.size() > 1) {
                    const Transform t = parse_transform(line, 1);
                    if (t.arrays.empty()) {
                        push_xf(t.initial);
                        continue;
                    }
                    const size_t close = closing_xf(lines, i, end);
                    long n = 1;
                    for (const auto& a : t.arrays) n *= a.first;
                    if (n > max_instances)
                        line.fail("xf makes " + std::to_string(n) + " instances; at most " +
                                  std::to_string(max_instances) + " are accepted");
                    for (long k = 0; k < n; ++k) {
                        push_xf(instance(t, k));
                        execute(lines, i + 1, close, depth);
                        source_ = source;
                        xf_.pop_back();
                    }
                    i = close;
                    continue;
                }
                statement(line, depth);
                source_ = source;
            } catch (const InputError& e) {
                source_ = source;
                if (strict()) throw;
                warn(fault_kind(line[0]), e.file(), e.line(),
                     e.message() + (line[0] == "f" || line[0] == "fh" ? "; the face is dropped"
                                                                      : "; the entity is skipped"));
            }
        }
    }

    static std::string fault_kind(const std::string& key) {
        return key == "f" || key == "fh" ? "face dropped" : "entity skipped";
    }

    /// The index of the `xf` that closes the array `xf` at `open`, nesting counted.
    static size_t closing_xf(const std::vector<Line>& lines, size_t open, size_t end) {
        int depth = 0;
        for (size_t j = open + 1; j < end; ++j) {
            if (lines[j][0] != "xf") continue;
            if (lines[j].size() > 1)
                ++depth;
            else if (depth-- == 0)
                return j;
        }
        lines[open].fail("xf array without its closing 'xf' in this file");
    }

    /// The map of instance k of the arrays of t (the first array's index varies slowest).
    static Affine instance(const Transform& t, long k) {
        std::vector<long> index(t.arrays.size());
        for (size_t a = t.arrays.size(); a-- > 0;) {
            index[a] = k % t.arrays[a].first;
            k /= t.arrays[a].first;
        }
        Affine m = t.initial;
        for (size_t a = 0; a < t.arrays.size(); ++a) {
            for (long s = 0; s < index[a]; ++s) m = t.arrays[a].second.after(m);
            m = t.after[a].after(m);
        }
        return m;
    }

    void push_xf(const Affine& local) {
        // The arguments of a context act before those of the contexts that enclose it.
        xf_.push_back(xf_.empty() ? local : xf_.back().after(local));
    }

    const Affine& world() const {
        static const Affine identity;
        return xf_.empty() ? identity : xf_.back();
    }

    /// xf arguments from token `first` on (docs/scene-format.md, "MGF import").
    static Transform parse_transform(const Line& line, size_t first) {
        Transform t;
        Affine* target = &t.initial;
        for (size_t i = first; i < line.size();) {
            const std::string& a = line[i];
            const auto number = [&](size_t k) {
                if (i + k >= line.size()) line.fail("xf " + a + " needs a number");
                return parse_double(line, line[i + k], "xf " + a);
            };
            Affine step;
            if (a == "-t") {
                step.t = {number(1), number(2), number(3)};
                i += 4;
            } else if (a == "-rx" || a == "-ry" || a == "-rz") {
                const double r = number(1) * Pi / 180, c = std::cos(r), s = std::sin(r);
                const int axis = a[2] - 'x', u = (axis + 1) % 3, v = (axis + 2) % 3;
                step.m[size_t(u)][size_t(u)] = c;
                step.m[size_t(u)][size_t(v)] = -s;
                step.m[size_t(v)][size_t(u)] = s;
                step.m[size_t(v)][size_t(v)] = c;
                i += 2;
            } else if (a == "-s") {
                const double f = number(1);
                if (!(f != 0)) line.fail("xf -s needs a scale factor other than 0");
                for (int k = 0; k < 3; ++k) step.m[size_t(k)][size_t(k)] = f;
                step.scale = std::fabs(f);
                i += 2;
            } else if (a == "-mx" || a == "-my" || a == "-mz") {
                const int axis = a[2] - 'x';
                step.m[size_t(axis)][size_t(axis)] = -1;
                i += 1;
            } else if (a == "-a" || a == "-i") {
                const long n = long(parse_integer(line, i + 1 < line.size() ? line[i + 1] : "",
                                                  "xf " + a + " count", 1, max_instances));
                i += 2;
                if (a == "-a") {
                    t.arrays.push_back({n, Affine()});
                    t.after.push_back(Affine());
                    target = &t.arrays.back().second;
                } else {
                    // -i N: the arguments up to the next -a or -i, N times, after the arrays'.
                    size_t j = i;
                    while (j < line.size() && line[j] != "-a" && line[j] != "-i") ++j;
                    Line part{line.file, line.number, {"xf"}};
                    part.tokens.insert(part.tokens.end(), line.tokens.begin() + long(i),
                                       line.tokens.begin() + long(j));
                    const Affine once = parse_transform(part, 1).initial;
                    Affine& into = t.arrays.empty() ? t.initial : t.after.back();
                    for (long k = 0; k < n; ++k) into = once.after(into);
                    i = j;
                    target = t.arrays.empty() ? &t.initial : &t.after.back();
                }
                continue;
            } else {
                line.fail("unknown xf argument " + in_quotes(a));
            }
            *target = step.after(*target);
        }
        return t;
    }

    // ---- Entities

    void statement(const Line& line, int depth) {
        const std::string& key = line[0];
        if (key == "v") return vertex(line);
        if (key == "p" || key == "n") return vertex_part(line);
        if (key == "c") return colour(line);
        if (key == "cxy" || key == "cct" || key == "cspec" || key == "cmix")
            return colour_part(line);
        if (key == "m") return material(line);
        if (key == "sides" || key == "rd" || key == "ed" || key == "rs" || key == "ts" ||
            key == "td" || key == "ir")
            return material_part(line);
        if (key == "f") return face(line, points_of(line, 1, line.size()));
        if (key == "fh") return face_with_holes(line);
        if (key == "sph") return sphere(line);
        if (key == "cyl") return cylinder(line);
        if (key == "cone") return cone(line);
        if (key == "ring") return ring(line);
        if (key == "torus") return torus(line);
        if (key == "prism") return prism(line);
        if (key == "o") {
            if (line.size() > 2) line.fail("'o' takes at most one name");
            if (line.size() == 2)
                objects_.push_back(line[1]);
            else if (objects_.empty())
                line.fail("'o' ends an object context, but none is open");
            else
                objects_.pop_back();
            return;
        }
        if (key == "xf") {
            if (xf_.empty()) line.fail("'xf' ends a transform context, but none is open");
            xf_.pop_back();
            return;
        }
        if (key == "i") return include(line, depth);
        if (key == "ies") line.fail("IES luminaires ('ies') are not supported");
        line.fail("unknown MGF entity " + in_quotes(key));
    }

    void vertex(const Line& line) {
        if (line.size() < 2 || line.size() > 4 || (line.size() >= 3 && line[2] != "="))
            line.fail("'v' needs a name, then '=' and an optional template: v NAME [= [TEMPLATE]]");
        if (line.size() == 2) {
            vertex_named(line, line[1]);
            vertex_ = line[1];
            return;
        }
        MgfVertex v;
        if (line.size() == 4) v = vertex_named(line, line[3]);
        vertices_[line[1]] = v;
        vertex_ = line[1];
    }

    /// The entry `name` of one of the named contexts (vertices, colours, materials), or an
    /// InputError at `line` ("undefined colour 'x'").
    template <class Map>
    static const typename Map::mapped_type& named(const Map& map, const Line& line,
                                                  const std::string& name, const char* what) {
        auto it = map.find(name);
        if (it == map.end()) line.fail(std::string("undefined ") + what + " " + in_quotes(name));
        return it->second;
    }

    const MgfVertex& vertex_named(const Line& line, const std::string& name) const {
        return named(vertices_, line, name, "vertex");
    }

    void vertex_part(const Line& line) {
        if (line.size() != 4)
            line.fail(in_quotes(line[0]) + " needs 3 numbers, found " +
                      std::to_string(line.size() - 1));
        if (vertex_.empty()) line.fail(in_quotes(line[0]) + " before any 'v'");
        Vec3 x;
        for (int k = 0; k < 3; ++k) x[k] = parse_double(line, line[size_t(1 + k)], line[0]);
        MgfVertex& v = vertices_[vertex_];
        if (line[0] == "p") {
            check_point(line, x, "vertex");
            v.p = x;
            v.has_p = true;
        } else {
            v.n = length(x) > 0 ? normalize(x) : Vec3{};
        }
    }

    void colour(const Line& line) {
        if (line.size() > 4 || (line.size() >= 3 && line[2] != "="))
            line.fail("'c' takes an optional name, '=' and template: c [NAME [= [TEMPLATE]]]");
        if (line.size() == 1) {
            colour_ = MgfColour();
            colour_name_.clear();
            return;
        }
        if (line.size() == 2) {
            colour_ = named(colours_, line, line[1], "colour");
            colour_name_ = line[1];
            return;
        }
        MgfColour c;
        if (line.size() == 4) c = named(colours_, line, line[3], "colour");
        colours_[line[1]] = c;
        colour_ = c;
        colour_name_ = line[1];
    }

    void colour_part(const Line& line) {
        const std::string& key = line[0];
        MgfColour c = colour_;
        if (key == "cxy") {
            if (line.size() != 3) line.fail("'cxy' needs 2 numbers (x y)");
            c.x = parse_double(line, line[1], "cxy x");
            c.y = parse_double(line, line[2], "cxy y");
            if (!(c.x >= 0 && c.y > 0 && c.x + c.y <= 1))
                line.fail("cxy " + fmt(c.x) + " " + fmt(c.y) +
                          " is no chromaticity (x >= 0, y > 0, x + y <= 1)");
        } else if (key == "cct") {
            if (line.size() != 2) line.fail("'cct' needs one temperature (kelvin)");
            double t = parse_double(line, line[1], "cct");
            if (!(t > 0)) line.fail("cct " + fmt(t) + " is not a temperature");
            if (t < 1667 || t > 25000) {
                const double clamped = std::clamp(t, 1667.0, 25000.0);
                fault(line, "value clamped", "cct " + fmt(t) + " is outside [1667, 25000] K",
                      "clamped to " + fmt(clamped));
                t = clamped;
            }
            const auto xy = black_body_xy(t);
            c.x = xy[0];
            c.y = xy[1];
        } else if (key == "cspec") {
            if (line.size() < 4) line.fail("'cspec' needs l_min l_max and the spectrum's values");
            for (size_t i = 1; i < line.size(); ++i) parse_double(line, line[i], "cspec");
            fault(line, "spectrum read as neutral", "spectral colours (cspec) are not supported",
                  "the colour is read as neutral");
            c = MgfColour();
        } else {  // cmix w1 c1 w2 c2 ...: the colours' XYZ (luminance w) summed
            if (line.size() < 3 || line.size() % 2 == 0)
                line.fail("'cmix' needs weight and colour pairs");
            double X = 0, Y = 0, Z = 0;
            for (size_t i = 1; i + 1 < line.size(); i += 2) {
                const double w = parse_double(line, line[i], "cmix weight");
                const MgfColour& m = named(colours_, line, line[i + 1], "colour");
                X += w * m.x / m.y;
                Y += w;
                Z += w * (1 - m.x - m.y) / m.y;
            }
            if (!(X + Y + Z > 0)) line.fail("cmix weights sum to no colour");
            c.x = X / (X + Y + Z);
            c.y = Y / (X + Y + Z);
        }
        colour_ = c;
        if (!colour_name_.empty()) colours_[colour_name_] = c;
    }

    void material(const Line& line) {
        if (line.size() > 4 || (line.size() >= 3 && line[2] != "="))
            line.fail("'m' takes an optional name, '=' and template: m [NAME [= [TEMPLATE]]]");
        if (line.size() == 1) {
            material_ = "";  // the unnamed material, as last set
            return;
        }
        if (line.size() == 2) {
            named(materials_, line, line[1], "material");
            material_ = line[1];
            return;
        }
        MgfMaterial m;
        if (line.size() == 4) m = named(materials_, line, line[3], "material");
        m.version = ++versions_;
        materials_[line[1]] = m;
        material_ = line[1];
    }

    /// The current material's colour component of luminance `value`: linear sRGB, each channel
    /// clamped into [0, limit] (a colour outside the gamut, a reflectance of 1 or more), said.
    Rgb component(const Line& line, double value, double limit) {
        Rgb c = mgf_colour_to_rgb(colour_.x, colour_.y, value);
        for (int k = 0; k < 3; ++k) {
            if (c[k] < 0) {
                warn("colour outside the sRGB gamut", line.file, line.number,
                     "cxy " + fmt_approx(colour_.x) + " " + fmt_approx(colour_.y) +
                         " lies outside the sRGB gamut; its negative channels are clipped to 0");
                for (int j = 0; j < 3; ++j) c[j] = std::max(c[j], 0.0);
                break;
            }
        }
        for (int k = 0; k < 3; ++k)
            if (c[k] > limit) {
                fault(line, "value clamped",
                      line[0] + " " + fmt(value) + " in this colour has a channel of " +
                          fmt_approx(c[k]) + ", beyond " + fmt_approx(limit),
                      "every channel is clamped to [0, " + fmt_approx(limit) + "]");
                for (int j = 0; j < 3; ++j) c[j] = std::min(c[j], limit);
                break;
            }
        return c;
    }

    void material_part(const Line& line) {
        const std::string& key = line[0];
        MgfMaterial& m = materials_[material_];
        m.version = ++versions_;
        const size_t n = key == "rs" || key == "ts" || key == "ir" ? 3 : 2;
        if (line.size() != n)
            line.fail(in_quotes(key) + " needs " + counted(long(n - 1), "number", "numbers") +
                      ", found " + std::to_string(line.size() - 1));
        const double x = parse_double(line, line[1], key);
        if (key == "sides") {
            if (x != 1 && x != 2) line.fail("'sides' is 1 or 2, found " + line[1]);
            m.sides = int(x);
        } else if (key == "rd") {
            if (!(x >= 0 && x <= 1)) line.fail("rd " + fmt(x) + " is outside [0, 1]");
            m.rd = component(line, x, max_clamped_reflectance);
        } else if (key == "ed") {
            if (!(x >= 0)) line.fail("ed " + fmt(x) + " is negative");
            m.ed = component(line, x / white_efficacy, max_emission);
        } else if (key == "rs" || key == "ts" || key == "td") {
            if (!(x >= 0 && x <= 1)) line.fail(key + " " + fmt(x) + " is outside [0, 1]");
            if (n == 3) parse_double(line, line[2], key + " roughness");
            (key == "rs" ? m.rs : key == "ts" ? m.ts : m.td) = x;
        } else {
            parse_double(line, line[2], "ir");  // index of refraction: nothing diffuse to do
        }
    }

    /// The mbr material of the current MGF material as it stands (one per state a face sees).
    int current_material() {
        const MgfMaterial& m = materials_[material_];
        const auto key = std::make_pair(material_, m.version);
        auto it = made_.find(key);
        if (it != made_.end()) return it->second;
        Material out;
        out.name = material_.empty() ? "mgf_default" : material_;
        if (used_names_.count(out.name)) out.name += "#" + std::to_string(m.version);
        used_names_[out.name] = 1;
        out.reflectance = Texture::constant(m.rd);
        out.emission = Texture::constant(m.ed);
        out.two_sided = m.sides == 2;
        const std::string what = "material " + in_quotes(out.name);
        if (m.rs > 0 || m.ts > 0 || m.td > 0)
            warn(
                "specular part dropped", scene_.sources[size_t(source_)], line_,
                what + " has " +
                    (m.rs > 0 ? "a specular reflectance rs " + fmt_approx(m.rs) : std::string()) +
                    (m.ts > 0 ? " a specular transmittance ts " + fmt_approx(m.ts)
                              : std::string()) +
                    (m.td > 0 ? " a diffuse transmittance td " + fmt_approx(m.td) : std::string()) +
                    "; mbr reflects diffusely only and keeps rd");
        scene_.materials.push_back(std::move(out));
        const int index = int(scene_.materials.size()) - 1;
        made_[key] = index;
        return index;
    }

    /// The surfaces' name: the open objects' names joined with '/', or the file's stem.
    std::string surface_name() const {
        std::string name;
        for (const std::string& o : objects_) name += (name.empty() ? "" : "/") + o;
        if (name.empty()) name = fs::path(top_).stem().string();
        return name.empty() ? "mgf" : name;
    }

    void add(const Line& line, const Surface& surface) {
        if (long(scene_.surfaces.size()) >= max_surfaces)
            throw InputError(
                line.file, line.number,
                "the MGF file makes more than " + std::to_string(max_surfaces) + " surfaces");
        SceneSurface s;
        s.name = surface_name();
        s.surface = surface;
        line_ = line.number;
        s.material = current_material();
        s.source = source_;
        s.line = line.number;
        scene_.surfaces.push_back(std::move(s));
    }

    /// The transformed points of the vertices named by tokens [first, end).
    std::vector<Vec3> points_of(const Line& line, size_t first, size_t end) const {
        std::vector<Vec3> p;
        for (size_t i = first; i < end; ++i) p.push_back(point_of(line, line[i]));
        return p;
    }

    Vec3 point_of(const Line& line, const std::string& name) const {
        const MgfVertex& v = vertex_named(line, name);
        if (!v.has_p) line.fail("vertex " + in_quotes(name) + " has no point ('p')");
        return world().point(v.p);
    }

    void face(const Line& line, std::vector<Vec3> p) {
        if (p.size() < 3)
            line.fail(in_quotes(line[0]) + " needs at least 3 vertices, found " +
                      std::to_string(p.size()));
        if (p.size() > size_t(max_face_vertices))
            line.fail("face has " + std::to_string(p.size()) + " vertices; at most " +
                      std::to_string(max_face_vertices) + " are accepted");
        if (world().mirrors()) std::reverse(p.begin(), p.end());  // the same side stays in front
        const std::vector<Quad> quads = face_to_quads(line, p);
        record_face(scene_.surfaces.size(), p, quads.size());
        for (const Quad& q : quads) add(line, Surface::planar_quad(q[0], q[1], q[2], q[3]));
    }

    /// fh v1 ... [- h1 ... [- ...]]: each hole joined to the contour along a seam between their
    /// closest vertices, then a face.
    void face_with_holes(const Line& line) {
        std::vector<std::vector<Vec3>> loops(1);
        for (size_t i = 1; i < line.size(); ++i) {
            if (line[i] == "-")
                loops.emplace_back();
            else
                loops.back().push_back(point_of(line, line[i]));
        }
        std::vector<Vec3> outer = loops[0];
        if (outer.size() < 3) line.fail("'fh' needs a contour of at least 3 vertices");
        Vec3 n;
        for (size_t i = 0; i < outer.size(); ++i)
            n += cross(outer[i], outer[(i + 1) % outer.size()]);
        for (size_t h = 1; h < loops.size(); ++h) {
            std::vector<Vec3> hole = loops[h];
            if (hole.size() < 3) line.fail("a hole of 'fh' needs at least 3 vertices");
            Vec3 hn;
            for (size_t i = 0; i < hole.size(); ++i)
                hn += cross(hole[i], hole[(i + 1) % hole.size()]);
            if (dot(hn, n) > 0) std::reverse(hole.begin(), hole.end());  // opposite to the contour
            size_t bi = 0, bj = 0;
            double best = HUGE_VAL;
            for (size_t i = 0; i < outer.size(); ++i)
                for (size_t j = 0; j < hole.size(); ++j) {
                    const double d = length(outer[i] - hole[j]);
                    if (d < best) best = d, bi = i, bj = j;
                }
            std::vector<Vec3> joined(outer.begin(), outer.begin() + long(bi) + 1);
            for (size_t k = 0; k <= hole.size(); ++k)
                joined.push_back(hole[(bj + k) % hole.size()]);
            joined.insert(joined.end(), outer.begin() + long(bi), outer.end());
            outer = std::move(joined);
        }
        face(line, outer);
    }

    /// A number of an entity, named for messages.
    static double number(const Line& line, size_t i, const std::string& what) {
        return parse_double(line, line[i], what);
    }

    /// Two unit vectors completing `axis` to a right-handed frame.
    static void frame(Vec3 axis, Vec3& e1, Vec3& e2) {
        const Vec3 a = normalize(axis);
        e1 = normalize(std::fabs(a.x) < 0.9 ? cross(a, Vec3{1, 0, 0}) : cross(a, Vec3{0, 1, 0}));
        e2 = cross(a, e1);
    }

    void sphere(const Line& line) {
        if (line.size() != 3) line.fail("'sph' needs a centre vertex and a radius");
        const Vec3 c = point_of(line, line[1]);
        const double r = number(line, 2, "sphere radius") * world().scale;
        if (!(r != 0)) line.fail("sphere radius is 0");
        const Vec3 pole = world().vector({0, 0, 1}), e1 = world().vector({1, 0, 0});
        add(line, Surface::sphere(c, pole, e1, std::fabs(r), 0, Pi, 0, 2 * Pi, r < 0));
    }

    void cylinder(const Line& line) {
        if (line.size() != 4) line.fail("'cyl' needs a vertex, a radius and a vertex");
        const Vec3 a = point_of(line, line[1]), b = point_of(line, line[3]);
        const double r = number(line, 2, "cylinder radius") * world().scale;
        const double h = length(b - a);
        if (!(r != 0) || !(h > 0)) line.fail("degenerate cylinder: zero radius or length");
        Vec3 e1, e2;
        frame(b - a, e1, e2);
        add(line, Surface::cylinder(a, b - a, e1, std::fabs(r), h, 0, 2 * Pi, r < 0));
    }

    /// The side of a cone or cylinder between two circles as `n` planar quads (mbr has no cone).
    void cone_side(const Line& line, Vec3 a, double ra, Vec3 b, double rb) {
        const bool inward = ra < 0 || rb < 0;
        ra = std::fabs(ra);
        rb = std::fabs(rb);
        Vec3 e1, e2;
        frame(b - a, e1, e2);
        const int n = std::max(8, scene_.settings.tessellation);
        for (int k = 0; k < n; ++k) {
            const double p0 = 2 * Pi * k / n, p1 = 2 * Pi * (k + 1) / n;
            const Vec3 d0 = std::cos(p0) * e1 + std::sin(p0) * e2;
            const Vec3 d1 = std::cos(p1) * e1 + std::sin(p1) * e2;
            std::vector<Vec3> q{a + ra * d0, a + ra * d1, b + rb * d1, b + rb * d0};
            if (inward) std::reverse(q.begin(), q.end());
            for (const Quad& x : face_to_quads(line, q))
                add(line, Surface::planar_quad(x[0], x[1], x[2], x[3]));
        }
    }

    void cone(const Line& line) {
        if (line.size() != 5) line.fail("'cone' needs a vertex, a radius, a vertex and a radius");
        const Vec3 a = point_of(line, line[1]), b = point_of(line, line[3]);
        const double ra = number(line, 2, "cone radius") * world().scale;
        const double rb = number(line, 4, "cone radius") * world().scale;
        if (!(length(b - a) > 0) || (ra == 0 && rb == 0) || ra * rb < 0)
            line.fail("degenerate cone: zero length, both radii 0, or radii of both signs");
        if (ra == rb) {
            Vec3 e1, e2;
            frame(b - a, e1, e2);
            add(line,
                Surface::cylinder(a, b - a, e1, std::fabs(ra), length(b - a), 0, 2 * Pi, ra < 0));
            return;
        }
        cone_side(line, a, ra, b, rb);
    }

    void ring(const Line& line) {
        if (line.size() != 4) line.fail("'ring' needs a centre vertex and two radii");
        const MgfVertex& v = vertex_named(line, line[1]);
        if (!(length(v.n) > 0)) line.fail("the ring's centre vertex has no normal ('n')");
        const Vec3 c = point_of(line, line[1]);
        const Vec3 normal = world().vector(v.n);
        double r0 = number(line, 2, "ring radius") * world().scale;
        double r1 = number(line, 3, "ring radius") * world().scale;
        if (r0 > r1) std::swap(r0, r1);
        if (!(r0 >= 0 && r1 > r0)) line.fail("ring radii must satisfy 0 <= r0 < r1");
        Vec3 e1, e2;
        frame(normal, e1, e2);
        add(line, Surface::disk(c, normal, e1, r0, r1, 0, 2 * Pi));
    }

    /// torus centre r_inner r_outer: planar quads around the tube (mbr has no torus). A cell's
    /// corners at two angles around the axis and two around the tube form an isosceles trapezoid
    /// (its two edges along the axis's circles are parallel), so each cell is planar.
    /// DESIGN: planar quads, as the cone's sides, not bilinear patches: the patches were
    /// tessellated 16 x 16 for rays (512 triangles each, 65,536 for corridor.mgf's ring) to
    /// follow a surface that is flat, and a planar receiver or shooter takes the exact clipped
    /// visibility that a curved one does not.
    void torus(const Line& line) {
        if (line.size() != 4) line.fail("'torus' needs a centre vertex and two radii");
        const MgfVertex& v = vertex_named(line, line[1]);
        if (!(length(v.n) > 0)) line.fail("the torus's centre vertex has no normal ('n')");
        const Vec3 c = point_of(line, line[1]);
        const Vec3 axis = normalize(world().vector(v.n));
        const double r0 = number(line, 2, "torus radius") * world().scale;
        const double r1 = number(line, 3, "torus radius") * world().scale;
        const bool inward = r0 < 0 || r1 < 0;
        const double a = std::fabs(r0), b = std::fabs(r1);
        if (!(b > a && a >= 0)) line.fail("torus radii must satisfy 0 <= inner < outer");
        const double major = 0.5 * (a + b), minor = 0.5 * (b - a);
        Vec3 e1, e2;
        frame(axis, e1, e2);
        const int nu = std::max(8, scene_.settings.tessellation), nv = std::max(6, nu / 2);
        auto at = [&](int i, int j) {
            const double u = 2 * Pi * i / nu, w = 2 * Pi * j / nv;
            const Vec3 radial = std::cos(u) * e1 + std::sin(u) * e2;
            return c + (major + minor * std::cos(w)) * radial + minor * std::sin(w) * axis;
        };
        for (int i = 0; i < nu; ++i)
            for (int j = 0; j < nv; ++j) {
                // Corners counter-clockwise seen from outside the tube (at an inner radius of
                // 0 two corners meet at the centre: face_to_quads makes the triangle).
                std::vector<Vec3> q{at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
                if (inward) std::reverse(q.begin(), q.end());
                for (const Quad& x : face_to_quads(line, q))
                    add(line, Surface::planar_quad(x[0], x[1], x[2], x[3]));
            }
    }

    /// prism v1 ... vn length: the face as given, a mirror image of it at `length` on its back
    /// side (MGF extrudes against the face's normal), and the sides between them, all facing
    /// out; a negative length extrudes in front of the face, and all face in.
    void prism(const Line& line) {
        if (line.size() < 5) line.fail("'prism' needs at least 3 vertices and a length");
        std::vector<Vec3> base = points_of(line, 1, line.size() - 1);
        const double len = number(line, line.size() - 1, "prism length") * world().scale;
        if (!(len != 0)) line.fail("prism length is 0");
        if (world().mirrors()) std::reverse(base.begin(), base.end());
        Vec3 n;
        for (size_t i = 0; i < base.size(); ++i) n += cross(base[i], base[(i + 1) % base.size()]);
        if (!(length(n) > 0)) line.fail("degenerate prism: its face has no area");
        const Vec3 d = -len * normalize(n);
        std::vector<Vec3> far;
        for (auto p = base.rbegin(); p != base.rend(); ++p) far.push_back(*p + d);
        std::vector<std::vector<Vec3>> faces{base, far};
        for (size_t i = 0; i < base.size(); ++i) {
            const size_t j = (i + 1) % base.size();
            // Counter-clockwise seen from outside: along the base's edge backwards, then down.
            faces.push_back({base[j], base[i], base[i] + d, base[j] + d});
        }
        for (const std::vector<Vec3>& f : faces)
            for (const Quad& q : face_to_quads(line, f))
                add(line, Surface::planar_quad(q[0], q[1], q[2], q[3]));
    }

    /// i FILE [xf arguments]: the file read in a transform context of its own.
    void include(const Line& line, int depth) {
        if (line.size() < 2) line.fail("'i' needs a file name");
        if (depth + 1 > max_include_depth)
            line.fail("includes are nested more than " + std::to_string(max_include_depth) +
                      " deep");
        const Transform t = parse_transform(line, 2);
        if (!t.arrays.empty()) line.fail("arrays (-a) are not supported on 'i'");
        const std::string path = resolve(line.file, line[1]);
        state_.charge(line);
        std::ifstream in;
        open_named(line, "included file", path, in);
        state_.record(path);
        push_xf(t.initial);
        const size_t depth_xf = xf_.size();
        read_file(in, path, depth + 1);
        xf_.resize(depth_xf - 1);
    }

    std::string top_;
    int source_ = 0;  // the file being executed (Scene::sources)
    int line_ = 0;    // the line of the entity being added (for material warnings)
    std::unordered_map<std::string, MgfVertex> vertices_;
    std::string vertex_;  // the current vertex
    std::unordered_map<std::string, MgfColour> colours_;
    MgfColour colour_;
    std::string colour_name_;  // the current colour's name ("": unnamed)
    std::unordered_map<std::string, MgfMaterial> materials_{{"", MgfMaterial()}};
    std::string material_;  // "": the unnamed material
    int versions_ = 0;
    std::map<std::pair<std::string, int>, int> made_;  // (material, version) -> Scene::materials
    std::unordered_map<std::string, int> used_names_;
    std::vector<Affine> xf_;  // composed maps of the open contexts, innermost last
    std::vector<std::string> objects_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// === Maps

namespace detail {

Vec3 Affine::point(Vec3 p) const {
    return vector(p) + t;
}

Vec3 Affine::vector(Vec3 v) const {
    Vec3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = m[size_t(i)][0] * v.x + m[size_t(i)][1] * v.y + m[size_t(i)][2] * v.z;
    return r;
}

bool Affine::mirrors() const {
    return determinant(m) < 0;
}

Affine Affine::after(const Affine& first) const {
    Affine r;
    r.m = multiply(m, first.m);
    r.t = vector(first.t) + t;
    r.scale = scale * first.scale;
    return r;
}

Scene read_mgf(std::istream& in, const std::string& name, LoadState& state) {
    return MgfReader(state).read(in, name);
}

}  // namespace detail

Rgb mgf_colour_to_rgb(double x, double y, double Y) {
    static const Matrix m = xyz_to_rgb();  // a constant, computed once
    const double X = x * Y / y, Z = (1 - x - y) * Y / y;
    Rgb c;
    for (int i = 0; i < 3; ++i)
        c[i] = m[size_t(i)][0] * X + m[size_t(i)][1] * Y + m[size_t(i)][2] * Z;
    return c;
}

bool is_import_path(const std::string& path) {
    return is_obj_path(path) || is_mgf_path(path);
}

bool is_mgf_path(const std::string& path) {
    return lowercase_extension(path) == ".mgf";
}

Scene parse_mgf(std::istream& in, const std::string& name, const ImportOptions& options) {
    LoadState state(options);
    Scene scene = read_mgf(in, name, state);
    repair_loaded_scene(scene, options);
    return scene;
}

Scene load_mgf(const std::string& path, const ImportOptions& options) {
    std::ifstream in;
    open_top(path, in);
    LoadState state(options);
    state.record(path);
    Scene scene = read_mgf(in, path, state);
    repair_loaded_scene(scene, options);
    return scene;
}

Scene load_scene_file(const std::string& path, const ImportOptions& options) {
    if (is_obj_path(path)) return load_obj(path, options);
    if (is_mgf_path(path)) return load_mgf(path, options);
    return load_scene(path, options);
}

}  // namespace mbr
