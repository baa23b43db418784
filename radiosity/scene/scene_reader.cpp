// radiosity/scene/scene_reader.cpp - the scene format (scene_reader.h; docs/scene-format.md):
// statements line by line (line_reader.h), each checked completely before it changes the scene;
// `obj` statements go through obj_reader.h, `include` reads another file of the format.
#include "radiosity/scene/scene_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <istream>
#include <set>
#include <unordered_map>

#include "math/check.h"
#include "radiosity/scene/faces_to_quads.h"
#include "radiosity/scene/light_sides.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/scene/mgf_reader.h"
#include "radiosity/scene/obj_reader.h"
#include "radiosity/scene/settings.h"

namespace mbr {

using namespace detail;

namespace {

constexpr int max_include_depth = 16;       // nesting of `include`
constexpr double max_angle_degrees = 3600;  // |phi|, |theta| in degrees

// ---------------------------------------------------------------------------------------------
// === Geometry checks

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

/// The optional words after a surface's numbers: `inward` (box, cylinder, sphere) and
/// `order M`, in either order. The numbers end where they begin.
struct SurfaceWords {
    size_t end = 0;       // one past the last number
    bool inward = false;  // the surface faces in
    int order = 0;        // its B-spline order m, 2..8; 0: the scene's (SceneSurface::order)
};

/// "order must be an integer 2..8": one whole number in that range.
int parse_order(const Line& line, const std::string& token) {
    long long m = 0;
    const char* b = token.data();
    const char* e = b + token.size();
    const auto result = std::from_chars(b, e, m);
    if (b == e || result.ec != std::errc() || result.ptr != e || m < 2 || m > 8)
        line.fail("order must be an integer 2..8, found " + in_quotes(token));
    return int(m);
}

/// Takes the optional words off the end of a statement whose numbers (or file name) start at
/// tokens[first]; `has_inward` when it accepts `inward`. Another word at the end is refused,
/// the message naming what it follows (`after`: "the quad's numbers").
SurfaceWords trailing_words(const Line& line, size_t first, bool has_inward,
                            const std::string& after) {
    SurfaceWords w;
    w.end = line.size();
    bool seen_order = false;
    while (w.end > first) {
        const std::string& last = line[w.end - 1];
        if (has_inward && !w.inward && last == "inward") {
            w.inward = true;
            --w.end;
        } else if (has_inward && last == "inward") {
            line.fail("'inward' is given twice");
        } else if (last == "order") {
            line.fail("'order' needs a value: an integer 2..8");
        } else if (w.end >= first + 2 && line[w.end - 2] == "order") {
            if (seen_order) line.fail("'order' is given twice");
            w.order = parse_order(line, last);
            seen_order = true;
            w.end -= 2;
        } else if (!is_number_token(last)) {
            line.fail("unknown word " + in_quotes(last) + " after " + after + " (only " +
                      (has_inward ? "'inward' and 'order M' may" : "'order M' may") + " follow)");
        } else {
            break;
        }
    }
    return w;
}

/// Reads the numbers of `fields` from tokens[first..end). Wrong counts and non-numbers get
/// messages naming the fields.
std::vector<double> read_fields(const Line& line, size_t first, size_t end,
                                const std::string& statement, const std::vector<Field>& fields) {
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
        // Every surface is in now, from this file, its includes and its OBJ and MGF imports:
        // repeats are found across all of them (repair_loaded_scene, light_sides.h).
        repair_loaded_scene(scene_, state_.options());
        scene_.input_files = state_.files();
        return std::move(scene_);
    }

private:
    /// The index of `file` in Scene::sources, added when new.
    int source(const std::string& file) {
        auto [it, is_new] = source_index_.try_emplace(file, int(scene_.sources.size()));
        if (is_new) scene_.sources.push_back(file);
        return it->second;
    }

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
        } else if (key == "obj" || key == "mgf") {
            import(line);
        } else if (key == "include") {
            include(line, depth);
        } else {
            line.fail("unknown keyword " + in_quotes(key) +
                      " (expected material, quad, bilinear, rectangle, box, cylinder, sphere, "
                      "disk, camera, set, obj, mgf or include)");
        }
    }

    // --- material NAME [reflectance TEXTURE] [emission TEXTURE] [two_sided]

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
            if (clause == "two_sided") {
                if (m.two_sided) line.fail("'two_sided' is given twice");
                m.two_sided = true;
                ++t;
                continue;
            }
            bool refl = clause == "reflectance";
            if (!refl && clause != "emission") {
                if (is_number_token(clause))
                    line.fail("unexpected number " + in_quotes(clause) +
                              " (too many numbers for the previous clause)");
                line.fail("unknown material clause " + in_quotes(clause) +
                          " (expected 'reflectance', 'emission' or 'two_sided')");
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
            if (!reflectance && c[i] > max_emission)
                line.fail(what + " " + fmt(c[i]) + " exceeds the limit " + fmt(max_emission));
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

    void add_surface(const Line& line, const std::string& name, int material, Surface s,
                     int order) {
        double area = s.area();
        if (!(area > 0) || !std::isfinite(area))
            line.fail("degenerate surface " + in_quotes(name) + ": its area is " +
                      fmt_approx(area));
        auto [seen, is_new] =
            surface_where_.try_emplace(name, line.file + ":" + std::to_string(line.number));
        if (!is_new)
            line.fail("duplicate surface name " + in_quotes(name) + " (first used at " +
                      seen->second + ")");
        scene_.surfaces.push_back(
            {name, std::move(s), material, source(line.file), line.number, order});
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
        // DESIGN: `order M` may follow any surface's numbers, and `inward` where the kind has
        // it, in either order: per-surface orders are the paper's "different B-spline bases"
        // on different surfaces (section 3); without it the scene's `set order` holds.
        const bool has_inward = kind == "box" || kind == "cylinder" || kind == "sphere";
        const SurfaceWords words =
            trailing_words(line, 3, has_inward, "the " + kind + "'s numbers");
        const auto numbers = [&](const std::vector<Field>& fields) {
            return read_fields(line, 3, words.end, kind, fields);
        };
        if (kind == "quad" || kind == "bilinear") {
            auto x = numbers({{"p00", 3}, {"p10", 3}, {"p11", 3}, {"p01", 3}});
            Quad q = {vec_at(x, 0), vec_at(x, 3), vec_at(x, 6), vec_at(x, 9)};
            if (kind == "quad") {
                add_surface(line, name, material, checked_quad(line, q), words.order);
                return;
            }
            for (int i = 0; i < 4; ++i) check_point(line, q[i], "corner");
            add_surface(line, name, material, checked_bilinear(line, q), words.order);
        } else if (kind == "rectangle") {
            auto x = numbers({{"corner", 3}, {"edge_u", 3}, {"edge_v", 3}});
            Vec3 c = vec_at(x, 0), eu = vec_at(x, 3), ev = vec_at(x, 6);
            check_point(line, c, "corner");
            check_direction(line, eu, "edge_u");
            check_direction(line, ev, "edge_v");
            add_surface(line, name, material, checked_quad(line, {c, c + eu, c + eu + ev, c + ev}),
                        words.order);
        } else if (kind == "box") {
            auto x = numbers({{"lo", 3}, {"hi", 3}});
            box(line, name, material, vec_at(x, 0), vec_at(x, 3), words);
        } else {
            add_surface(line, name, material, curved(line, kind, words, numbers), words.order);
        }
    }

    /// The cylinder, sphere or disk of a statement, checked.
    template <class Numbers>
    Surface curved(const Line& line, const std::string& kind, const SurfaceWords& words,
                   const Numbers& numbers) {
        if (kind == "cylinder") {
            auto x = numbers({{"base", 3},
                              {"axis", 3},
                              {"e1", 3},
                              {"radius", 1},
                              {"height", 1},
                              {"phi0", 1},
                              {"phi1", 1}});
            Vec3 base = vec_at(x, 0), axis = vec_at(x, 3), e1 = vec_at(x, 6);
            check_point(line, base, "base");
            check_direction(line, axis, "axis");
            check_direction(line, e1, "e1");
            check_not_parallel(line, axis, e1, "axis");
            double r = check_length(line, x[9], "radius", false);
            double h = check_length(line, x[10], "height", false);
            check_angle_range(line, x[11], x[12], "phi", 360);
            return Surface::cylinder(base, axis, e1, r, h, radians(x[11]), radians(x[12]),
                                     words.inward);
        }
        if (kind == "sphere") {
            auto x = numbers({{"centre", 3},
                              {"pole", 3},
                              {"e1", 3},
                              {"radius", 1},
                              {"theta0", 1},
                              {"theta1", 1},
                              {"phi0", 1},
                              {"phi1", 1}});
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
            return Surface::sphere(centre, pole, e1, r, radians(x[10]), radians(x[11]),
                                   radians(x[12]), radians(x[13]), words.inward);
        }
        // disk
        auto x = numbers({{"centre", 3},
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
        return Surface::disk(centre, normal, e1, r0, r1, radians(x[11]), radians(x[12]));
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

    /// Six quads of an axis-aligned box, named NAME.xmin ... NAME.zmax, facing out (or in with
    /// `inward`), each of the statement's order.
    void box(const Line& line, const std::string& name, int material, Vec3 lo, Vec3 hi,
             const SurfaceWords& words) {
        const bool inward = words.inward;
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
                add_surface(line, face, material, checked_quad(line, q), words.order);
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
        // The option table (radiosity/scene/settings.h) knows every setting, its range and
        // its messages.
        const OptionSpec* option = find_option(key);
        if (!option) {
            std::string known;
            for (const OptionSpec& o : option_table())
                known += (known.empty() ? "" : ", ") + o.name;
            line.fail("unknown setting " + in_quotes(key) + " (known: " + known + ")");
        }
        apply_setting(scene_.settings, *option, value, key, line.file, line.number);
        if (key == "min_depth" || key == "max_depth") depth_line_ = line;
    }

    // --- obj FILE [order M], mgf FILE [order M], include FILE

    void import(const Line& line) {
        const bool mgf = line[0] == "mgf";
        const std::string kind = mgf ? "MGF" : "OBJ";
        if (line.size() < 2) line.fail(in_quotes(line[0]) + " needs one file name");
        // `order M` gives every surface of the import that order (SceneSurface::order).
        const SurfaceWords words = trailing_words(line, 2, false, "the " + kind + " file's name");
        if (words.end != 2)
            line.fail("unknown word " + in_quotes(line[2]) + " after the " + kind +
                      " file's name (only 'order M' may follow)");
        std::string path = resolve(line.file, line[1]);
        state_.charge(line);
        std::ifstream in;
        open_named(line, kind + " file", path, in);
        state_.record(path);
        Scene part = mgf ? read_mgf(in, path, state_) : read_obj(in, path, state_);
        // Merge: the import's materials join the scene's (names must be new, except the shared
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
            s.order = words.order;
            if (s.source >= 0) s.source = source(part.sources[size_t(s.source)]);
            auto [seen, is_new] = surface_where_.try_emplace(s.name, path);
            if (!is_new)
                line.fail("surface " + in_quotes(s.name) + " of " + in_quotes(path) +
                          " has the name of an earlier surface (at " + seen->second + ")");
            scene_.surfaces.push_back(std::move(s));
        }
        for (const SceneWarning& w : part.warnings) scene_.warn(w);
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
        state_.record(path);
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
    std::unordered_map<std::string, int> source_index_;           // file -> Scene::sources
    std::set<std::string> settings_seen_;
    int camera_line_ = 0;
    Line depth_line_;
};

}  // namespace

Scene parse_scene(std::istream& in, const std::string& name, const ImportOptions& options) {
    LoadState state(options);
    return SceneReader(state).read(in, name);
}

Scene load_scene(const std::string& path, const ImportOptions& options) {
    std::ifstream in;
    open_top(path, in);
    LoadState state(options);
    state.record(path);
    return SceneReader(state).read(in, path);
}

}  // namespace mbr
