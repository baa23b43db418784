// test/test_scene_io.cpp - the scene format and OBJ/MTL import of radiosity/scene/scene_io.h: every
// example scene loads with the expected counts and orientations, each class of bad input gets
// its message at the right line, and OBJ faces become the quads docs/scene-format.md promises.
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "math/check.h"
#include "radiosity/scene/line_reader.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/solver/solver.h"

using namespace mbr;
using Catch::Matchers::Contains;

namespace {

const std::string scenes_dir = std::string(MBR_SOURCE_DIR) + "/examples/scenes/";
// Parsed text pretends to live beside the example scenes, so relative textures resolve there.
const std::string text_name = scenes_dir + "inline.scene";
const std::string obj_name = scenes_dir + "inline.obj";

Scene parse_text(const std::string& text) {
    std::istringstream in(text);
    return parse_scene(in, text_name);
}

Scene parse_obj_text(const std::string& text) {
    std::istringstream in(text);
    return parse_obj(in, obj_name);
}

/// OBJ text read strictly (ImportOptions::strict): every fault refused.
Scene parse_obj_strict(const std::string& text) {
    std::istringstream in(text);
    return parse_obj(in, obj_name, ImportOptions{true});
}

/// The InputError that parsing `text` throws (fails the test when there is none).
template <class Parse>
InputError error_of(Parse parse, const std::string& text) {
    try {
        parse(text);
    } catch (const InputError& e) {
        return e;
    }
    FAIL("no InputError for:\n" << text);
    return InputError("");
}

/// Checks that `text` fails at `line` with a message containing `part`.
void check_error(const std::string& text, int line, const std::string& part) {
    InputError e = error_of(parse_text, text);
    CAPTURE(text, e.what());
    CHECK(e.file() == text_name);
    CHECK(e.line() == line);
    CHECK_THAT(e.message(), Contains(part));
}

void check_obj_error(const std::string& text, int line, const std::string& part) {
    InputError e = error_of(parse_obj_strict, text);
    CAPTURE(text, e.what());
    CHECK(e.line() == line);
    CHECK_THAT(e.message(), Contains(part));
}

const std::string white = "material white reflectance 0.5 0.5 0.5\n";
const std::string square = "quad sq white 0 0 0  1 0 0  1 1 0  0 1 0\n";

double total_area(const Scene& s) {
    return s.total_area();
}

/// A folder of scratch files, removed at the end of the test.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        path = std::filesystem::temp_directory_path() /
               ("mbr_test_scene_io_" + std::to_string(long(getpid())));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string write(const std::string& name, const std::string& text) const {
        std::string p = (path / name).string();
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
};

}  // namespace

// === Example scenes

TEST_CASE("scene_io: every example scene loads with the expected counts", "[scene_io]") {
    struct Expected {
        const char* file;
        size_t n_materials, n_surfaces, n_emitters;
    };
    for (Expected x :
         {Expected{"parallel_squares.scene", 2, 2, 1},
          Expected{"perpendicular_squares.scene", 2, 2, 1}, Expected{"three_strips.scene", 2, 4, 1},
          Expected{"room.scene", 11, 27, 1}, Expected{"cornell_box.scene", 4, 16, 1},
          Expected{"cornell_box.obj", 4, 16, 1}}) {
        CAPTURE(x.file);
        std::string path = scenes_dir + x.file;
        Scene s = std::string(x.file).find(".obj") != std::string::npos ? load_obj(path)
                                                                        : load_scene(path);
        CHECK(s.materials.size() == x.n_materials);
        CHECK(s.surfaces.size() == x.n_surfaces);
        CHECK(s.emitters().size() == x.n_emitters);
        CHECK(s.has_camera == (std::string(x.file).find(".obj") == std::string::npos));
        for (const SceneSurface& surface : s.surfaces) {
            CAPTURE(surface.name);
            CHECK(surface.material >= 0);
            CHECK(size_t(surface.material) < s.materials.size());
            CHECK(surface.surface.area() > 0);
        }
        if (s.has_camera) {
            // The camera looks at the scene: the bounding box centre is within its field of view.
            const Camera& c = s.camera;
            Vec3 dir = normalize(c.look_at - c.eye);
            Vec3 to_centre = normalize(s.bounds().centre() - c.eye);
            CHECK(dot(dir, to_centre) > std::cos(c.fov_degrees * Pi / 360));
        }
    }
}

TEST_CASE("scene_io: example scenes' settings and textures", "[scene_io]") {
    Scene squares = load_scene(scenes_dir + "parallel_squares.scene");
    CHECK(squares.settings.min_depth == 3);
    CHECK(squares.settings.max_depth == 3);
    CHECK(squares.materials[size_t(squares.find_material("receiver"))].reflectance.mean().r ==
          0.999);
    Scene room = load_scene(scenes_dir + "room.scene");
    const Material& floor = room.materials[size_t(room.find_material("floor"))];
    CHECK(floor.reflectance.kind() == Texture::Kind::Checker);
    CHECK(floor.reflectance.checker_squares() == 10);
    const Material& picture = room.materials[size_t(room.find_material("picture"))];
    CHECK(picture.reflectance.kind() == Texture::Kind::Image);
    CHECK(picture.reflectance.maximum().r <= 0.85);
    CHECK(!picture.reflectance.is_constant());
    CHECK(room.surfaces[size_t(room.find_surface("table_top.ymax"))].surface.normal(0.5, 0.5).y ==
          Approx(1));
    CHECK(room.surfaces[size_t(room.find_surface("table_top.ymin"))].surface.normal(0.5, 0.5).y ==
          Approx(-1));
    CHECK(room.surfaces[size_t(room.find_surface("floor"))].surface.normal(0.5, 0.5).y ==
          Approx(1));
    CHECK(room.surfaces[size_t(room.find_surface("ceiling"))].surface.normal(0.5, 0.5).y ==
          Approx(-1));
    CHECK(room.surfaces[size_t(room.find_surface("lamp"))].surface.normal(0.5, 0.5).y ==
          Approx(-1));
}

TEST_CASE("scene_io: the Cornell box faces the right way", "[scene_io]") {
    for (const char* file : {"cornell_box.scene", "cornell_box.obj"}) {
        CAPTURE(file);
        std::string path = scenes_dir + file;
        Scene s =
            std::string(file).find(".obj") != std::string::npos ? load_obj(path) : load_scene(path);
        const Vec3 room_centre{278, 274, 280};
        const Vec3 short_centre{185, 82.5, 169}, tall_centre{368.5, 165, 351.25};
        for (const SceneSurface& x : s.surfaces) {
            CAPTURE(x.name);
            Vec3 p = x.surface.point(0.5, 0.5), n = x.surface.normal(0.5, 0.5);
            if (x.name.compare(0, 5, "short") == 0)
                CHECK(dot(n, p - short_centre) > 0);  // block faces look out of the block
            else if (x.name.compare(0, 4, "tall") == 0)
                CHECK(dot(n, p - tall_centre) > 0);
            else
                CHECK(dot(n, room_centre - p) > 0);  // room faces look into the room
        }
        // The camera at z = -800 sees the back wall's front.
        Vec3 n_back = s.surfaces[size_t(s.find_surface("back_wall"))].surface.normal(0.5, 0.5);
        CHECK(n_back.z == Approx(-1));
    }
}

TEST_CASE("scene_io: the Cornell box scene and OBJ files describe the same box", "[scene_io]") {
    Scene a = load_scene(scenes_dir + "cornell_box.scene");
    Scene b = load_obj(scenes_dir + "cornell_box.obj");
    REQUIRE(a.surfaces.size() == b.surfaces.size());
    for (size_t i = 0; i < a.surfaces.size(); ++i) {
        CAPTURE(a.surfaces[i].name);
        CHECK(a.surfaces[i].name == b.surfaces[i].name);
        for (int k = 0; k < 4; ++k)
            CHECK(length(a.surfaces[i].surface.corners()[k] - b.surfaces[i].surface.corners()[k]) ==
                  0);
        const Material& ma = a.material_of(int(i));
        const Material& mb = b.material_of(int(i));
        CHECK(ma.name == mb.name);
        for (int c = 0; c < 3; ++c) {
            CHECK(ma.reflectance.mean()[c] == mb.reflectance.mean()[c]);
            // The scene file gives E = pi L rounded to 4 decimals; the MTL gives L exactly.
            CHECK(ma.emission.mean()[c] == Approx(mb.emission.mean()[c]).epsilon(1e-5));
        }
    }
    Camera c = a.camera;
    CHECK(c.fov_degrees == 39.3077);
    CHECK(c.eye == Vec3{278, 273, -800});
}

// === Planar quads

TEST_CASE("scene_io: planarity is relative to the quad's size", "[scene_io]") {
    // The Cornell red wall: 3.2 mm off over 550 mm passes (1.02e-3 < 2.5e-3).
    CHECK(planar_quad_problem(
              {Vec3{552.8, 0, 0}, {549.6, 0, 559.2}, {556, 548.8, 559.2}, {556, 548.8, 0}})
              .empty());
    // The same shape a thousand times smaller or larger is judged the same.
    for (double scale : {1e-3, 1.0, 1e3}) {
        CAPTURE(scale);
        double w = 0.02;  // one corner lifted 2% of the side: 0.35% of the diagonal, > 0.25%
        std::array<Vec3, 4> q = {
            Vec3{0, 0, 0}, {scale, 0, 0}, {scale, scale, w * scale}, {0, scale, 0}};
        CHECK_THAT(planar_quad_problem(q), Contains("not planar"));
        q[2].z = 0.005 * scale;  // 0.09% of the diagonal: planar enough
        CHECK(planar_quad_problem(q).empty());
    }
}

TEST_CASE("scene_io: triangles that share an edge join into one quad", "[scene_io]") {
    using detail::pair_triangles;
    using detail::Triangle;
    const Vec3 a{0, 0, 0}, b{2, 0, 0}, c{2, 1, 0}, d{0, 1, 0};
    SECTION("a rectangle's two halves, the diagonal walked both ways") {
        const auto pairs = pair_triangles({Triangle{{a, b, c}, 0}, Triangle{{a, c, d}, 0}});
        REQUIRE(pairs.partner == std::vector<int>{1, 0});
        const detail::Quad& q = pairs.quad[0];
        const Surface quad = Surface::planar_quad(q[0], q[1], q[2], q[3]);
        CHECK(quad.area() == Approx(2));
        CHECK(quad.normal(0.5, 0.5).z == Approx(1));  // the triangles' front
        for (Vec3 corner : {a, b, c, d}) CHECK(std::count(q.begin(), q.end(), corner) == 1);
    }
    SECTION("not joined: another group, the other front, a fold, a flat corner, no shared edge") {
        CHECK(pair_triangles({Triangle{{a, b, c}, 0}, Triangle{{a, c, d}, 1}}).partner ==
              std::vector<int>{-1, -1});
        CHECK(pair_triangles({Triangle{{a, b, c}, 0}, Triangle{{a, d, c}, 0}}).partner ==
              std::vector<int>{-1, -1});
        const Vec3 up{0, 1, 1};  // the second half bent up about the diagonal
        CHECK(pair_triangles({Triangle{{a, b, c}, 0}, Triangle{{a, c, up}, 0}}).partner ==
              std::vector<int>{-1, -1});
        // A third corner nearly on the line through c and a: the quad's corner at a is 162
        // degrees, more than max_pair_angle.
        const Vec3 flat{-2, -0.65, 0};
        CHECK(pair_triangles({Triangle{{a, b, c}, 0}, Triangle{{a, c, flat}, 0}}).partner ==
              std::vector<int>{-1, -1});
        CHECK(pair_triangles(
                  {Triangle{{a, b, c}, 0}, Triangle{{d, Vec3{0, 2, 0}, Vec3{-1, 1, 0}}, 0}})
                  .partner == std::vector<int>{-1, -1});
    }
    SECTION("a strip of three squares, each cut along a diagonal: each square's halves join") {
        // Triangle 0 could also join triangle 3 across the edge p1-q1 (a parallelogram whose
        // largest angle is 135 degrees); its own square's other half (90) is taken instead.
        const Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
        const Vec3 q[4] = {{0, 1, 0}, {1, 1, 0}, {2, 1, 0}, {3, 1, 0}};
        std::vector<Triangle> strip;
        for (int k = 0; k < 3; ++k) {
            strip.push_back(Triangle{{p[k], p[k + 1], q[k + 1]}, 0});
            strip.push_back(Triangle{{p[k], q[k + 1], q[k]}, 0});
        }
        const auto pairs = pair_triangles(strip);
        CHECK(pairs.partner == std::vector<int>{1, 0, 3, 2, 5, 4});
        for (int t : {0, 2, 4}) {
            const detail::Quad& x = pairs.quad[size_t(t)];
            CHECK(Surface::planar_quad(x[0], x[1], x[2], x[3]).area() == Approx(1));
        }
    }
    SECTION("a square cut along both diagonals stays four triangles") {
        // Two neighbours' union is a triangle with the centre on its edge: a corner of 180.
        const Vec3 m{1, 0.5, 0};
        const auto pairs = pair_triangles({Triangle{{a, b, m}, 0}, Triangle{{b, c, m}, 0},
                                           Triangle{{c, d, m}, 0}, Triangle{{d, a, m}, 0}});
        CHECK(pairs.partner == std::vector<int>{-1, -1, -1, -1});
    }
}

// === One test per class of bad input

TEST_CASE("scene_io: unknown keyword", "[scene_io][errors]") {
    check_error(white + "materail red reflectance 1 0 0\n", 2, "unknown keyword 'materail'");
    check_error(white + square + "set colour blue\n", 3, "unknown setting 'colour'");
    check_error(white + "material m reflectance 0.1 0.1 0.1 shine 3\n", 2,
                "unknown material clause 'shine'");
    check_error(white + square + "camera eye 0 0 5 look_at 0 0 0 zoom 2\n", 3,
                "unknown camera clause 'zoom'");
}

TEST_CASE("scene_io: missing numbers", "[scene_io][errors]") {
    check_error(white + "quad q white 0 0 0  1 0 0  1 1 0  0 1\n", 2,
                "quad needs 12 numbers (p00 x y z, p10 x y z, p11 x y z, p01 x y z), found 11");
    check_error("material m reflectance 0.5 0.5\n", 1,
                "reflectance needs 3 numbers (r g b), found 2");
    check_error(white + "sphere s white 0 0 0  0 0 1  1 0 0  1  0 180  0\n", 2,
                "sphere needs 14 numbers");
    check_error(white + square + "camera eye 0 0 look_at 0 0 0\n", 3, "camera eye needs 3 numbers");
    check_error(white + square + "set order\n", 3, "'set' needs a name and one value");
}

TEST_CASE("scene_io: extra numbers", "[scene_io][errors]") {
    check_error(white + "quad q white 0 0 0  1 0 0  1 1 0  0 1 0  7\n", 2,
                "quad needs 12 numbers (p00 x y z, p10 x y z, p11 x y z, p01 x y z), found 13");
    check_error("material m reflectance 0.5 0.5 0.5 0.5\n", 1, "unexpected number '0.5'");
    check_error(white + "disk d white 0 0 0  0 0 1  1 0 0  0 1  0 360 inward\n", 2,
                "unknown word 'inward' after the disk's numbers (only 'order M' may follow)");
    check_error(white + square + "camera eye 0 0 5 1 look_at 0 0 0\n", 3, "unexpected number '1'");
}

TEST_CASE("scene_io: NaN and infinity", "[scene_io][errors]") {
    check_error(white + "quad q white 0 0 0  1 0 nan  1 1 0  0 1 0\n", 2,
                "quad p10.z is 'nan': NaN and infinity are not allowed");
    check_error("material m emission inf 1 1\n", 1, "NaN and infinity are not allowed");
    check_error("material m emission -Infinity 1 1\n", 1, "NaN and infinity are not allowed");
    check_error(white + "quad q white 0 0 0  1e400 0 0  1 1 0  0 1 0\n", 2,
                "quad p10.x '1e400' is out of range");
    check_error(white + "quad q white 0 0 0  1 0 0  1 1 0  0 1 0x10\n", 2,
                "expected a number for quad p01.z, found '0x10'");
    check_error(white + "quad q white 0 0 0  1e300 0 0  1 1 0  0 1 0\n", 2,
                "coordinate 1e+300 exceeds the limit 100000000");
}

TEST_CASE("scene_io: reflectance out of range", "[scene_io][errors]") {
    check_error("material m reflectance 0.5 1.2 0.5\n", 1, "reflectance 1.2 is outside [0, 1)");
    check_error("material m reflectance 1 1 1\n", 1, "reflectance 1 is outside [0, 1)");
    check_error("material m reflectance -0.1 0 0\n", 1, "reflectance -0.1 is outside [0, 1)");
    check_error("material m reflectance checker 4 0.5 0.5 0.5 1.5 0 0\n", 1,
                "reflectance checker colour 1.5 is outside [0, 1)");
    check_error("material m reflectance image picture.png scale 1 1 1\n", 1,
                "reflectance image scale 1 is outside [0, 1)");
}

TEST_CASE("scene_io: negative emission", "[scene_io][errors]") {
    check_error("# a light\nmaterial m emission 1 -2 1\n", 2, "emission -2 is negative");
    check_error("material m emission checker 2 1 1 1 0 -1 0\n", 1, "checker colour -1 is negative");
}

TEST_CASE("scene_io: degenerate quads", "[scene_io][errors]") {
    check_error(white + "quad q white 0 0 0  1 0 0  1 0 0  0 1 0\n", 2,
                "degenerate quad: corners 2 and 3 coincide");
    check_error(white + "quad q white 0 0 0  1 0 0  2 0 0  3 0 0\n", 2,
                "degenerate quad: zero area (collinear corners)");
    check_error(white + "rectangle r white 0 0 0  1 0 0  2 0 0\n", 2, "zero area");
    check_error(white + "rectangle r white 0 0 0  0 0 0  0 1 0\n", 2, "edge_u is the zero vector");
    check_error(white + "box b white 0 0 0  1 0 1\n", 2, "box lo.y 0 must be below hi.y 0");
    check_error(white + "bilinear b white 0 0 0  1 0 0  1 0 0  0 1 1\n", 2,
                "degenerate bilinear patch: corners 2 and 3 coincide");
    check_error(white + "cylinder c white 0 0 0  0 0 1  1 0 0  0 1  0 360\n", 2,
                "radius 0 must be positive");
    check_error(white + "disk d white 0 0 0  0 0 1  1 0 0  0.5 0.5  0 360\n", 2,
                "disk r1 0.5 must exceed r0 0.5");
    check_error(white + "sphere s white 0 0 0  0 0 1  1 0 0  1  30 30  0 360\n", 2,
                "theta range 30 .. 30 is empty");
    check_error(white + "cylinder c white 0 0 0  0 0 1  0 0 2  1 1  0 360\n", 2,
                "is parallel to the axis");
    check_error(white + "cylinder c white 0 0 0  0 0 1  1 0 0  1 1  90 -45\n", 2,
                "phi range 90 .. -45 must increase");
    check_error(white + "disk d white 0 0 0  0 0 1  1 0 0  0 1  0 400\n", 2,
                "phi range 0 .. 400 spans more than 360 degrees");
}

TEST_CASE("scene_io: non-planar quad", "[scene_io][errors]") {
    check_error(white + "quad q white 0 0 0  1 0 0  1 1 0.1  0 1 0\n", 2,
                "quad is not planar: a corner lies 0.0249377 off the corners' mean plane, 1.75897% "
                "of its size");
    check_error(white + "quad q white 0 0 0  1 0 0  1 1 0.1  0 1 0\n", 2,
                "use 'bilinear' for a twisted quad");
    // The same corners as a bilinear patch are fine.
    CHECK(parse_text(white + "bilinear q white 0 0 0  1 0 0  1 1 0.1  0 1 0\n").surfaces.size() ==
          1);
}

TEST_CASE("scene_io: non-convex quad", "[scene_io][errors]") {
    // A dart: corner 3 points back inside.
    check_error(white + "quad q white 0 0 0  2 0 0  0.5 0.5 0  0 2 0\n", 2,
                "quad is not convex at corner 3");
    // A bow tie: its edges cross.
    check_error(white + "quad q white 0 0 0  1 1 0  1 0 0  0 1 0\n", 2, "quad intersects itself");
    // A bilinear patch over a dart folds.
    check_error(white + "bilinear q white 0 0 0  2 0 0  0.5 0.5 0.1  0 2 0\n", 2,
                "bilinear patch folds over itself");
}

TEST_CASE("scene_io: unknown material", "[scene_io][errors]") {
    check_error(white + "quad q grey 0 0 0  1 0 0  1 1 0  0 1 0\n", 2, "unknown material 'grey'");
    // Materials must come before their use.
    check_error(square + white, 1, "unknown material 'white'");
}

TEST_CASE("scene_io: duplicate material and surface names", "[scene_io][errors]") {
    check_error(white + "\n\nmaterial white reflectance 0.1 0.1 0.1\n", 4,
                "duplicate material 'white' (first defined at " + text_name + ":1)");
    check_error(white + square + square, 3, "duplicate surface name 'sq'");
    check_error(white + "material m reflectance 0.1 0.1 0.1 reflectance 0.2 0.2 0.2\n", 2,
                "'reflectance' is given twice");
    check_error(white + square + "set order 3\nset order 4\n", 4, "setting 'order' is given twice");
}

TEST_CASE("scene_io: missing or unreadable texture", "[scene_io][errors]") {
    check_error("material m reflectance image no_such_picture.png\n", 1,
                "texture '" + scenes_dir + "no_such_picture.png': file not found");
    check_error("material m reflectance image cornell_box.mtl\n", 1,
                "cannot read the texture image");
    check_error("material m reflectance image .\n", 1, "is a folder, not a file");
    check_error("material m reflectance image\n", 1, "image needs a file name");
}

TEST_CASE("scene_io: bad OBJ index", "[scene_io][errors][obj]") {
    const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    check_obj_error(v3 + "f 1 2 4\n", 4, "vertex index 4 is out of range (3 vertices defined");
    check_obj_error(v3 + "f 1 2 0\n", 4, "vertex index 0 is not allowed");
    check_obj_error(v3 + "f -1 -2 -4\n", 4, "vertex index -4 is out of range");
    check_obj_error(v3 + "f 1/1 2/1 3/1\n", 4, "texture vertex index 1 is out of range");
    check_obj_error(v3 + "vn 0 0 1\nf 1//1 2//1 3//2\n", 5, "normal index 2 is out of range");
    check_obj_error(v3 + "f 1/ 2 3\n", 4, "malformed face vertex '1/'");
    check_obj_error(v3 + "f 1 2 x\n", 4, "expected an integer for vertex index, found 'x'");
    check_obj_error(v3 + "f 1 2 99999999999999999999\n", 4, "is outside");
    check_obj_error(v3 + "f 1 2\n", 4, "'f' needs at least 3 vertices, found 2");
}

TEST_CASE("scene_io: file not found", "[scene_io][errors]") {
    InputError e =
        error_of([](const std::string& p) { return load_scene(p); }, scenes_dir + "no_such.scene");
    CHECK(e.file() == scenes_dir + "no_such.scene");
    CHECK(e.line() == 0);
    CHECK(e.message() == "file not found");
    e = error_of([](const std::string& p) { return load_obj(p); }, scenes_dir + "no_such.obj");
    CHECK(e.message() == "file not found");
    e = error_of([](const std::string& p) { return load_scene(p); }, scenes_dir);
    CHECK(e.message() == "is a folder, not a file");
    check_error(white + square + "obj missing.obj\n", 3,
                "OBJ file '" + scenes_dir + "missing.obj': file not found");
    check_error(white + square + "include missing.scene\n", 3,
                "included file '" + scenes_dir + "missing.scene': file not found");
}

TEST_CASE("scene_io: a file that cannot be read gives the system's reason", "[scene_io][errors]") {
    // Only a missing file is "file not found": a file name used as a folder (ENOTDIR, which
    // root meets too) and a file or folder without permission are reported as the system says.
    TempDir dir;
    const std::string plain = dir.write("plain", "not a folder\n");
    const std::string not_dir = std::strerror(ENOTDIR);
    InputError e =
        error_of([](const std::string& p) { return load_scene(p); }, plain + "/x.scene");
    CHECK(e.message() == not_dir);
    const std::string top = dir.write("top.scene", white + square + "obj plain/x.obj\n");
    e = error_of([](const std::string& p) { return load_scene(p); }, top);
    CHECK(e.line() == 3);
    CHECK(e.message() == "OBJ file '" + plain + "/x.obj': " + not_dir);

    if (::geteuid() == 0) {
        WARN("skipped the permission cases: root may read any file");
        return;
    }
    const std::string locked = dir.write("locked.scene", white + square);
    std::filesystem::permissions(locked, std::filesystem::perms::none);
    e = error_of([](const std::string& p) { return load_scene(p); }, locked);
    CHECK(e.message() == std::string("cannot open the file: ") + std::strerror(EACCES));
    const std::filesystem::path closed = dir.path / "closed";
    std::filesystem::create_directory(closed);
    const std::string inside = (closed / "x.scene").string();
    std::ofstream(inside) << white + square;
    std::filesystem::permissions(closed, std::filesystem::perms::none);
    e = error_of([](const std::string& p) { return load_scene(p); }, inside);
    CHECK(e.message() == std::strerror(EACCES));
    std::filesystem::permissions(closed, std::filesystem::perms::owner_all);  // let TempDir clean
}

TEST_CASE("scene_io: includes, their cycles and their depth", "[scene_io][errors]") {
    TempDir dir;
    std::string base = dir.write("base.scene", white + "set order 3\n");
    std::string top = dir.write("top.scene", "include base.scene\n" + square);
    Scene s = load_scene(top);
    CHECK(s.settings.order == 3);
    CHECK(s.surfaces.size() == 1);
    // A file including itself, and a cycle of two, are refused at the including line.
    std::string self = dir.write("self.scene", white + square + "include self.scene\n");
    InputError e = error_of([](const std::string& p) { return load_scene(p); }, self);
    CHECK(e.line() == 3);
    CHECK_THAT(e.message(), Contains("include cycle"));
    dir.write("a.scene", white + "include b.scene\n");
    dir.write("b.scene", "\ninclude a.scene\n");
    e = error_of([](const std::string& p) { return load_scene(p); },
                 (dir.path / "a.scene").string());
    CHECK_THAT(e.file(), Contains("b.scene"));
    CHECK(e.line() == 2);
    CHECK_THAT(e.message(), Contains("include cycle"));
    // A chain deeper than 16 is refused.
    for (int i = 0; i < 20; ++i)
        dir.write("chain" + std::to_string(i) + ".scene",
                  "include chain" + std::to_string(i + 1) + ".scene\n");
    dir.write("chain20.scene", white + square);
    e = error_of([](const std::string& p) { return load_scene(p); },
                 (dir.path / "chain0.scene").string());
    CHECK_THAT(e.message(), Contains("nested more than 16 deep"));
    // A tree of includes that would read 2^12 files stops at the budget.
    for (int i = 0; i < 12; ++i)
        dir.write("tree" + std::to_string(i) + ".scene", "include tree" + std::to_string(i + 1) +
                                                             ".scene\ninclude tree" +
                                                             std::to_string(i + 1) + ".scene\n");
    dir.write("tree12.scene", "# a leaf\n");
    e = error_of([](const std::string& p) { return load_scene(p); },
                 (dir.path / "tree0.scene").string());
    CHECK_THAT(e.message(), Contains("more than 1000 files"));
    (void)base;
}

TEST_CASE("scene_io: binary garbage and long lines", "[scene_io][errors]") {
    check_error(white + std::string("quad q\0 white", 14) + "\n", 2,
                "unexpected control byte '\\x00'");
    check_error("\x89PNG\r\n\x1a\n", 1, "unknown keyword '\\x89PNG'");
    check_error(white + "material m\x1a reflectance 0 0 0\n", 2, "unexpected control byte '\\x1a'");
    check_error(white + std::string(100000, 'x') + "\n", 2, "line is longer than 65536 bytes");
    check_error("", 0, "the scene has no surfaces");
    check_error("# only a comment\n" + white, 0, "the scene has no surfaces");
}

TEST_CASE("scene_io: settings and camera are checked", "[scene_io][errors]") {
    check_error(white + square + "set order 1\n", 3, "order '1' is outside [2, 8]");
    check_error(white + square + "set order 4.5\n", 3, "expected an integer for order");
    check_error(white + square + "set truncation_eps 0\n", 3, "truncation_eps 0 is outside (0, 1)");
    check_error(white + square + "set extrapolation cubic\n", 3, "neither 'linear' nor 'higher'");
    check_error(white + square + "set self_transfer yes\n", 3, "neither 'true' nor 'false'");
    check_error(white + square + "set contact_oracle mean\n", 3,
                "contact_oracle 'mean' is not 'hybrid', 'interpolation' or 'means'");
    check_error(white + square + "set min_depth 5\nset max_depth 3\n", 4,
                "min_depth 5 exceeds max_depth 3");
    check_error(white + square + "camera eye 0 0 1 look_at 0 0 1\n", 3, "eye and look_at coincide");
    check_error(white + square + "camera eye 0 0 1 look_at 0 0 0 up 0 0 2\n", 3,
                "up is parallel to the viewing direction");
    check_error(white + square + "camera eye 0 0 1 look_at 0 0 0 fov 180\n", 3,
                "fov 180 is outside (0, 180)");
    check_error(white + square + "camera eye 0 0 1 look_at 0 0 0 size 0 10\n", 3,
                "image size '0' is outside [1, 16384]");
    check_error(white + square + "camera look_at 0 0 0\n", 3, "camera needs 'eye' and 'look_at'");
    check_error(white + square + "camera eye 0 0 1 look_at 0 0 0\ncamera eye 0 0 1 look_at 0 0 0\n",
                4, "camera is given twice");
}

TEST_CASE("scene_io: every statement of the format", "[scene_io]") {
    Scene s = parse_text(
        "material plain reflectance 0.2 0.3 0.4\n"
        "material chk reflectance checker 3 0.1 0.1 0.1 0.7 0.7 0.7 emission 0 0 0\n"
        "material img reflectance image picture.png emission image picture.png scale 2 2 2\n"
        "material lamp emission 5 5 5   # a comment after a statement\n"
        "quad q plain 0 0 0  1 0 0  1 1 0  0 1 0\n"
        "bilinear b plain 0 0 0  1 0 0  1 1 1  0 1 0\n"
        "rectangle r chk 0 0 2  1 0 0  0 1 0\n"
        "box x img 0 0 3  1 1 4\n"
        "box room img -5 -5 -5  5 5 5 inward\n"
        "cylinder c plain 0 0 0  0 0 1  1 0 0  0.5 2  0 180\n"
        "cylinder ci plain 0 0 0  0 0 1  1 0 0  0.5 2  0 360 inward\n"
        "sphere s lamp 3 3 3  0 0 1  1 0 0  0.5  0 180  0 360\n"
        "sphere si lamp 3 3 3  0 0 1  1 0 0  0.6  0 90  0 360 inward\n"
        "disk d plain 0 0 0  0 0 1  1 0 0  0 1  0 360\n"
        "disk a plain 0 0 0  0 0 -1  1 0 0  0.5 1  -90 90\n"
        "obj cornell_box.obj\n"
        "camera eye 0 -10 0 look_at 0 0 0 up 0 0 1 fov 60 size 320 200\n"
        "set order 3\nset min_depth 2\nset max_depth 5\nset oracle_tolerance 1e-4\n"
        "set truncation_eps 1e-7\nset rhombus_radius 20\nset extrapolation higher\n"
        "set shadow_rays 8\nset max_shots 10\nset convergence 0.01\nset self_transfer true\n"
        "set tessellation 8\nset contact_oracle means\n");
    CHECK(s.materials.size() == 4 + 4);
    CHECK(s.surfaces.size() == 3 + 12 + 6 + 16);
    CHECK(s.emitters().size() == 12 + 2 + 1);  // the img boxes, the lamp spheres, the OBJ light
    CHECK(s.materials[1].reflectance.kind() == Texture::Kind::Checker);
    CHECK(s.materials[2].emission.maximum().r <= 2);
    CHECK(s.materials[2].emission.maximum().r > 1);
    CHECK(s.find_surface("room.xmin") >= 0);
    CHECK(s.surfaces[size_t(s.find_surface("room.xmin"))].surface.normal(0.5, 0.5).x == Approx(1));
    CHECK(s.surfaces[size_t(s.find_surface("x.xmin"))].surface.normal(0.5, 0.5).x == Approx(-1));
    CHECK(s.surfaces[size_t(s.find_surface("ci"))].surface.area() == Approx(2 * Pi * 0.5 * 2));
    CHECK(s.surfaces[size_t(s.find_surface("a"))].surface.area() == Approx(0.5 * Pi * (1 - 0.25)));
    CHECK(s.has_camera);
    CHECK(s.camera.width == 320);
    CHECK(s.camera.height == 200);
    const SolverSettings& o = s.settings;
    CHECK(o.order == 3);
    CHECK(o.min_depth == 2);
    CHECK(o.max_depth == 5);
    CHECK(o.oracle_tolerance == 1e-4);
    CHECK(o.truncation_eps == 1e-7);
    CHECK(o.rhombus_radius == 20);
    CHECK(o.extrapolation == ExtrapolationSetting::Higher);
    CHECK(o.shadow_rays == 8);
    CHECK(o.max_shots == 10);
    CHECK(o.convergence == 0.01);
    CHECK(o.self_transfer);
    CHECK(o.tessellation == 8);
    CHECK(o.contact_oracle == OracleSetting::Means);
    CHECK(solver_options(o).receiver.contact_oracle_test == OracleTest::Means);
    // Defaults when nothing is set.
    Scene d = parse_text(white + square);
    CHECK(d.settings.order == 4);
    CHECK(d.settings.oracle == OracleSetting::Hybrid);
    CHECK(d.settings.contact_oracle == OracleSetting::Interpolation);
    CHECK(solver_options(d.settings).receiver.oracle_test == OracleTest::Hybrid);
    CHECK(solver_options(d.settings).receiver.contact_oracle_test == OracleTest::Interpolation);
    CHECK(d.settings.extrapolation == ExtrapolationSetting::Linear);
    CHECK(!d.has_camera);
}

// === OBJ import

namespace {

/// Sum of the areas of all surfaces.
double area_sum(const Scene& s) {
    return total_area(s);
}

/// Every surface is a valid planar quad facing along n.
void check_quads_face(const Scene& s, Vec3 n) {
    for (const SceneSurface& x : s.surfaces) {
        CAPTURE(x.name);
        const Vec3* c = x.surface.corners();
        CHECK(planar_quad_problem({c[0], c[1], c[2], c[3]}).empty());
        CHECK(dot(x.surface.normal(0.5, 0.5), n) > 0.99);
    }
}

}  // namespace

TEST_CASE("scene_io: OBJ quad becomes one planar quad", "[scene_io][obj]") {
    Scene s = parse_obj_text("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4\n");
    REQUIRE(s.surfaces.size() == 1);
    CHECK(s.surfaces[0].surface.kind() == Surface::Kind::PlanarQuad);
    CHECK(area_sum(s) == Approx(2));
    CHECK(s.surfaces[0].name == "inline");  // no o/g: the file's stem
    CHECK(s.materials[size_t(s.surfaces[0].material)].name == "obj_default");
    check_quads_face(s, {0, 0, 1});
    // A vertex in the middle of an edge is dropped: still one quad.
    s = parse_obj_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4 5\n");
    CHECK(s.surfaces.size() == 1);
    CHECK(area_sum(s) == Approx(2));
}

TEST_CASE("scene_io: OBJ triangle becomes three quads with the triangle's area",
          "[scene_io][obj]") {
    Scene s = parse_obj_text("v 0 0 0\nv 3 0 0\nv 1 2 0\nf 1 2 3\n");
    REQUIRE(s.surfaces.size() == 3);
    CHECK(area_sum(s) == Approx(3.0).epsilon(1e-14));
    check_quads_face(s, {0, 0, 1});
    // Every quad has a triangle corner, two edge midpoints and the centroid.
    Vec3 g{4.0 / 3, 2.0 / 3, 0};
    for (const SceneSurface& x : s.surfaces) CHECK(length(x.surface.corners()[2] - g) < 1e-15);
    // The reverse order faces the other way.
    s = parse_obj_text("v 0 0 0\nv 3 0 0\nv 1 2 0\nf 3 2 1\n");
    check_quads_face(s, {0, 0, -1});
}

TEST_CASE("scene_io: OBJ polygons are split", "[scene_io][obj]") {
    // A convex planar pentagon: five quads around the vertex average.
    Scene s = parse_obj_text("v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n");
    CHECK(s.surfaces.size() == 5);
    // Shoelace: (0,0) (2,0) (3,1) (1,2) (-1,1).
    CHECK(area_sum(s) == Approx(0.5 * (0 + 2 + 5 + 3 + 0)).epsilon(1e-14));
    check_quads_face(s, {0, 0, 1});
    // A non-convex quad (dart): two triangles, six quads, same area.
    s = parse_obj_text("v 0 0 0\nv 2 0 0\nv 0.5 0.5 0\nv 0 2 0\nf 1 2 3 4\n");
    CHECK(s.surfaces.size() == 6);
    CHECK(area_sum(s) == Approx(1.0).epsilon(1e-14));
    check_quads_face(s, {0, 0, 1});
    // A non-planar quad: two triangles along the shorter diagonal, six planar quads.
    s = parse_obj_text("v 0 0 0\nv 1 0 0\nv 1 1 0.5\nv 0 1 0\nf 1 2 3 4\n");
    CHECK(s.surfaces.size() == 6);
    for (const SceneSurface& x : s.surfaces) {
        const Vec3* c = x.surface.corners();
        CHECK(planar_quad_problem({c[0], c[1], c[2], c[3]}).empty());
    }
    // A non-convex L-shaped hexagon: four triangles, twelve quads.
    s = parse_obj_text("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n");
    CHECK(s.surfaces.size() == 12);
    CHECK(area_sum(s) == Approx(3.0).epsilon(1e-14));
    check_quads_face(s, {0, 0, 1});
    // A pentagram intersects itself.
    check_obj_error(
        "v 0 1 0\nv 0.951 0.309 0\nv 0.588 -0.809 0\nv -0.588 -0.809 0\nv -0.951 0.309 0\n"
        "f 1 3 5 2 4\n",
        6, "intersects itself");
    check_obj_error("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", 4, "degenerate face: zero area");
}

TEST_CASE("scene_io: OBJ negative indices and v/vt/vn forms", "[scene_io][obj]") {
    const std::string v = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n";
    Scene a = parse_obj_text(v + "f 1 2 3 4\n");
    for (const char* face : {"f -4 -3 -2 -1\n", "f 1/1 2/2 3/1 4/2\n", "f 1//1 2//1 3//-1 4//1\n",
                             "f 1/1/1 -3/-1/-1 3/2/1 4/1/1\n"}) {
        CAPTURE(face);
        Scene b = parse_obj_text(v + face);
        REQUIRE(b.surfaces.size() == 1);
        for (int k = 0; k < 4; ++k)
            CHECK(a.surfaces[0].surface.corners()[k] == b.surfaces[0].surface.corners()[k]);
    }
    // Negative indices count back from the last vertex defined before the face.
    Scene c =
        parse_obj_text(v + "f -4 -3 -2 -1\nv 5 5 5\nv 6 5 5\nv 6 6 5\nv 5 6 5\nf -4 -3 -2 -1\n");
    REQUIRE(c.surfaces.size() == 2);
    CHECK(c.surfaces[1].surface.corners()[0] == Vec3{5, 5, 5});
}

TEST_CASE("scene_io: OBJ materials, names and ignored statements", "[scene_io][obj]") {
    TempDir dir;
    dir.write("m.mtl",
              "newmtl wall\nKa 0.1 0.1 0.1\nKd 0.5 0.6 0.7\nKs 0 0 0\nNs 10\nd 1\nillum 2\n"
              "newmtl lamp\nKd 0.8\nKe 1 2 3\n");
    std::string obj = dir.write(
        "t.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\ns off\ns 1\n"
        "o box\ng panel\nusemtl wall\nf 1 2 3 4\nf 1 2 3\nusemtl lamp\ng\nf 4 3 2 1\nl 1 2\n");
    Scene s = load_obj(obj);
    REQUIRE(s.surfaces.size() == 5);
    CHECK(s.surfaces[0].name == "panel.0");
    CHECK(s.surfaces[3].name == "panel.3");
    CHECK(s.surfaces[4].name == "t");
    const Material& wall = s.material_of(0);
    CHECK(wall.name == "wall");
    CHECK(wall.reflectance.mean().b == 0.7);
    CHECK(!wall.emits());
    const Material& lamp = s.material_of(4);
    CHECK(lamp.reflectance.mean().g == 0.8);          // one number: grey
    CHECK(lamp.emission.mean().g == Approx(2 * Pi));  // Ke is radiance: E = pi Ke
    CHECK(s.emitters() == std::vector<int>{4});
}

TEST_CASE("scene_io: OBJ and MTL errors", "[scene_io][obj][errors]") {
    TempDir dir;
    const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    auto obj_error = [&](const std::string& mtl, const std::string& obj) {
        dir.write("e.mtl", mtl);
        std::string path = dir.write("e.obj", obj);
        return error_of([](const std::string& p) { return load_obj(p, ImportOptions{true}); },
                        path);
    };
    // A missing material library.
    InputError e = obj_error("", quad + "mtllib nothere.mtl\nf 1 2 3 4\n");
    CHECK(e.line() == 5);
    CHECK_THAT(e.message(), Contains("material library '"));
    CHECK_THAT(e.message(), Contains("nothere.mtl': file not found"));
    // usemtl of a name no library defines.
    e = obj_error("newmtl a\nKd 0.5 0.5 0.5\n", "mtllib e.mtl\n" + quad + "usemtl b\nf 1 2 3 4\n");
    CHECK(e.line() == 6);
    CHECK_THAT(e.message(), Contains("unknown material 'b'"));
    // Kd of 1 or more is refused, not clamped.
    e = obj_error("newmtl a\nKd 1 1 1\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK_THAT(e.file(), Contains("e.mtl"));
    CHECK(e.line() == 2);
    CHECK_THAT(e.message(), Contains("Kd 1 is outside [0, 1)"));
    e = obj_error("newmtl a\nKe 1 -1 1\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK_THAT(e.message(), Contains("Ke -1 is negative"));
    e = obj_error("newmtl a\nnewmtl a\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK(e.line() == 2);
    CHECK_THAT(e.message(), Contains("duplicate material 'a'"));
    e = obj_error("Kd 0.5 0.5 0.5\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK_THAT(e.message(), Contains("'Kd' before any 'newmtl'"));
    e = obj_error("newmtl a\nKd 0.5 nan 0.5\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK_THAT(e.message(), Contains("NaN and infinity are not allowed"));
    e = obj_error("newmtl a\nmap_Kd -s 1 1 1 nothere.png\n",
                  "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK(e.line() == 2);
    CHECK_THAT(e.message(), Contains("nothere.png': file not found"));
    e = obj_error("newmtl a\nshininess 3\n", "mtllib e.mtl\n" + quad + "f 1 2 3 4\n");
    CHECK_THAT(e.message(), Contains("unknown MTL statement 'shininess'"));
    // OBJ statements.
    check_obj_error(quad + "vx 1 2\n", 5, "unknown OBJ statement 'vx'");
    check_obj_error("v 1 2\n", 1, "'v' needs 3 numbers");
    check_obj_error("v 1 2 inf\n", 1, "NaN and infinity are not allowed");
    check_obj_error("vn 1 2\n", 1, "'vn' needs 3 numbers");
    check_obj_error("s smooth\n", 1, "expected an integer for smoothing group");
    check_obj_error("cstype bspline\n", 1, "free-form geometry ('cstype') is not supported");
    check_obj_error(quad, 0, "the OBJ file has no faces");
}

TEST_CASE("scene_io: textures decode sRGB and look up bilinearly", "[scene_io][texture]") {
    CHECK(srgb_to_linear(0) == 0);
    CHECK(srgb_to_linear(1) == Approx(1).epsilon(1e-15));
    CHECK(srgb_to_linear(0.5) == Approx(0.214041).epsilon(1e-5));
    // 2 x 1 image: left texel 0, right texel 1; centres at u = 0.25 and 0.75.
    Texture t = Texture::from_pixels(2, 1, {{0, 0, 0}, {1, 1, 1}}, {0.5, 0.5, 0.5});
    CHECK(t.value(0.0, 0.5).r == 0);  // clamped to the edge texel
    CHECK(t.value(0.25, 0.5).r == 0);
    CHECK(t.value(0.5, 0.5).r == Approx(0.25));
    CHECK(t.value(0.75, 0.5).r == Approx(0.5));
    CHECK(t.value(1.0, 0.5).r == Approx(0.5));
    CHECK(t.mean().r == Approx(0.25));
    CHECK(t.maximum().r == 0.5);
    CHECK(!t.is_constant());
    // Row 0 of the file is v = 1.
    Texture tall = Texture::from_pixels(1, 2, {{1, 1, 1}, {0, 0, 0}}, {1, 1, 1});
    CHECK(tall.value(0.5, 1.0).r == 1);
    CHECK(tall.value(0.5, 0.0).r == 0);
    // Checker: (0,0) holds the first colour; mean counts the squares.
    Texture c = Texture::checker({1, 1, 1}, {0, 0, 0}, 3);
    CHECK(c.value(0.1, 0.1).r == 1);
    CHECK(c.value(0.4, 0.1).r == 0);
    CHECK(c.value(1.0, 1.0).r == 1);
    CHECK(c.mean().r == Approx(5.0 / 9));
    CHECK(Texture::checker({0.3, 0.3, 0.3}, {0.3, 0.3, 0.3}, 4).is_constant());
    // The mean of an image equals the integral of its bilinear lookup over [0,1]^2.
    Texture img = Texture::image(scenes_dir + "picture.png", {0.9, 0.9, 0.9});
    const int n = 400;
    Rgb sum;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) sum += img.value((i + 0.5) / n, (j + 0.5) / n);
    CHECK(sum.g / (n * n) == Approx(img.mean().g).epsilon(1e-3));
    CHECK(img.maximum().r <= 0.9);
}

// === Scenes of any size, bounded texture memory, clear messages

TEST_CASE("scene_io: many surfaces keep unique names; duplicates name the first use",
          "[scene_io][errors]") {
    // 3000 surfaces (the name look-up is a hash map; this checks that it still finds every
    // duplicate, whether the first use is early, late, in a box or in an OBJ import).
    std::string text = white;
    for (int i = 0; i < 3000; ++i)
        text += "rectangle r" + std::to_string(i) + " white " + std::to_string(i) +
                " 0 0  1 0 0  0 1 0\n";
    CHECK(parse_text(text).surfaces.size() == 3000);
    check_error(text + "rectangle r0 white 0 0 5  1 0 0  0 1 0\n", 3002,
                "duplicate surface name 'r0' (first used at " + text_name + ":2)");
    check_error(text + "rectangle r2999 white 0 0 5  1 0 0  0 1 0\n", 3002,
                "(first used at " + text_name + ":3001)");
    check_error(text + "box r17 white 0 0 0 1 1 1\nbox b white 0 0 0 1 1 1\nquad b.ymax white " +
                    "0 0 0  1 0 0  1 1 0  0 1 0\n",
                3004, "duplicate surface name 'b.ymax' (first used at " + text_name + ":3003)");
    TempDir dir;
    dir.write("one.obj", "g r5\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    const std::string scene = dir.write("s.scene", text + "obj one.obj\n");
    try {
        load_scene(scene);
        FAIL("no error for an OBJ surface named like an earlier one");
    } catch (const InputError& e) {
        CHECK(e.line() == 3002);
        CHECK_THAT(e.message(), Contains("surface 'r5' of '"));
        CHECK_THAT(e.message(),
                   Contains("has the name of an earlier surface (at " + scene + ":7)"));
    }
}

TEST_CASE("scene_io: quads near the coordinate limit or far from the origin are judged alike",
          "[scene_io]") {
    // The same unit square, with and without a twist, at the origin and translated by t: the
    // verdicts must agree. Relative to corner 0 the corners are exact (Sterbenz), so even a
    // quad of size 1e-3 at 99999999 is judged as at the origin; in absolute coordinates, its
    // Newell normal drowned in cancellation and convex quads were called non-convex.
    for (double t : {0.0, 1e4, 99999999.0, -99999999.0})
        for (double size : {1.0, 1e-3}) {
            CAPTURE(t, size);
            const Vec3 o{t, t, t};
            std::array<Vec3, 4> flat = {o, o + Vec3{size, 0, 0}, o + Vec3{size, size, 0},
                                        o + Vec3{0, size, 0}};
            CHECK(planar_quad_problem(flat).empty());
            // A square rotated out of the axis planes (its corners round at 1e8).
            const Vec3 eu = Vec3{0.6, 0.8, 0} * size, ev = Vec3{0, 0, 1} * size;
            CHECK(planar_quad_problem({o, o + eu, o + eu + ev, o + ev}).empty());
            // Twisted by 10% of its size: refused, with a finite deviation in the message.
            std::array<Vec3, 4> twisted = flat;
            twisted[2].z += 0.1 * size;
            const std::string problem = planar_quad_problem(twisted);
            CHECK_THAT(problem, Contains("quad is not planar: a corner lies "));
            CHECK_THAT(problem, !Contains("inf") && !Contains("nan"));
            // 1.75897% at the origin. At 1e8 the corners themselves round to 1.5e-8, 1.5e-5 of
            // the smaller size, which moves the percentage in its fourth digit at most.
            const size_t end = problem.find("% of its size");
            const size_t begin = problem.rfind(' ', end) + 1;
            REQUIRE(end != std::string::npos);
            CHECK(std::stod(problem.substr(begin, end - begin)) == Approx(1.75897).epsilon(1e-3));
            // A dart stays non-convex, a bow tie self-intersecting, wherever they are.
            CHECK_THAT(
                planar_quad_problem({o, o + Vec3{2, 0, 0} * size, o + Vec3{0.5, 0.5, 0} * size,
                                     o + Vec3{0, 2, 0} * size}),
                Contains("not convex at corner 3"));
            CHECK_THAT(planar_quad_problem({o, o + Vec3{1, 1, 0} * size, o + Vec3{1, 0, 0} * size,
                                            o + Vec3{0, 1, 0} * size}),
                       Contains("intersects itself"));
        }
    // Far beyond the file limit (the function is public): squared sizes of 1e400 no longer
    // overflow into "zero area".
    const double big = 1e200;
    CHECK(planar_quad_problem({Vec3{0, 0, 0}, Vec3{big, 0, 0}, Vec3{big, big, 0}, Vec3{0, big, 0}})
              .empty());
    CHECK(planar_quad_problem(
              {Vec3{0, 0, 0}, Vec3{1e-200, 0, 0}, Vec3{1e-200, 1e-200, 0}, Vec3{0, 1e-200, 0}})
              .empty());
    CHECK_THAT(planar_quad_problem({Vec3{1, 2, 3}, Vec3{1, 2, 3}, Vec3{1, 2, 3}, Vec3{1, 2, 3}}),
               Contains("all corners coincide"));
    // Through the reader: a quad spanning the whole allowed range and a tiny tilted rectangle at
    // the limit both load.
    CHECK(parse_text(white +
                     "quad q white 1e8 1e8 -1e8  -1e8 1e8 1e8  -1e8 -1e8 1e8  1e8 -1e8 -1e8\n")
              .surfaces.size() == 1);
    CHECK(parse_text(white + "rectangle r white 99999999 99999999 99999999  0.0006 0.0008 0  "
                             "0 0 0.001\n")
              .surfaces.size() == 1);
}

TEST_CASE("scene_io: OBJ faces far from the origin keep their vertices", "[scene_io][obj]") {
    // A small planar quad and a triangle at 99999999: the quad stays one quad with exactly the
    // given corners, the triangle becomes three quads of its area.
    Scene s = parse_obj_text(
        "v 99999999 99999999 99999999\nv 99999999.001 99999999 99999999\n"
        "v 99999999.001 99999999.001 99999999.0005\nv 99999999 99999999.001 99999999.0005\n"
        "g quad\nf 1 2 3 4\ng tri\nf 1 2 3\n");
    REQUIRE(s.surfaces.size() == 4);
    CHECK(s.surfaces[0].name == "quad");
    const Vec3* c = s.surfaces[0].surface.corners();
    CHECK(c[0] == Vec3{99999999, 99999999, 99999999});
    CHECK(c[2] == Vec3{99999999.001, 99999999.001, 99999999.0005});
    double tri_area = 0;
    for (int i = 1; i < 4; ++i) tri_area += s.surfaces[i].surface.area();
    // 1/2 |e1 x e2| with the parsed corner differences. The quads' new corners (midpoints and
    // centroid) round to the spacing of doubles near 1e8, 1.5e-8, which is 1.5e-5 of the
    // triangle's 1e-3 edges: their areas may differ by a few times that.
    const Vec3 e1 = Vec3{99999999.001, 99999999, 99999999} - Vec3{99999999, 99999999, 99999999};
    const Vec3 e2 =
        Vec3{99999999.001, 99999999.001, 99999999.0005} - Vec3{99999999, 99999999, 99999999};
    CHECK(tri_area == Approx(0.5 * length(cross(e1, e2))).epsilon(1e-4));
}

TEST_CASE("scene_io: messages print numbers that read back as themselves", "[scene_io][errors]") {
    check_error(white + "quad q white 100000000.1 0 0  1 0 0  1 1 0  0 1 0\n", 2,
                "corner coordinate 100000000.1 exceeds the limit 100000000");
    check_error(white + "cylinder c white 0 0 0  0 0 1  1 0 0  100000000.5 1  0 360\n", 2,
                "radius 100000000.5 exceeds the limit 100000000");
    check_error("material m reflectance 0.5 1.0000000000000002 0.5\n", 1,
                "reflectance 1.0000000000000002 is outside [0, 1)");
    check_error("set oracle_tolerance 1.00000000001\n", 1,
                "oracle_tolerance 1.00000000001 is outside (0, 1]");
    check_error(white + "quad q white 1e-320 0 0  1 0 0  1 1 0  0 1 0\n" + square +
                    "disk d white 0 0 0  0 0 1  1 0 0  0.30000000000000004 0.3  0 360\n",
                4, "disk r1 0.3 must exceed r0 0.30000000000000004");
}

TEST_CASE("scene_io: OBJ group names never collide", "[scene_io][obj]") {
    // Four unit squares side by side: faces 1 2 3 4, 5 6 7 8, 9 10 11 12 and 13 14 15 16 (one
    // face written twice would be dropped as a repeat, docs/scene-format.md).
    const std::string v4 =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "v 2 0 0\nv 3 0 0\nv 3 1 0\nv 2 1 0\n"
        "v 4 0 0\nv 5 0 0\nv 5 1 0\nv 4 1 0\n"
        "v 6 0 0\nv 7 0 0\nv 7 1 0\nv 6 1 0\n";
    auto names = [&](const std::string& groups) {
        std::vector<std::string> out;
        for (const SceneSurface& s : parse_obj_text(v4 + groups).surfaces) out.push_back(s.name);
        return out;
    };
    using V = std::vector<std::string>;
    // A group 'a' of two faces and a group named 'a.0': the numbering skips the taken 'a.0',
    // whichever comes first in the file.
    CHECK(names("g a\nf 1 2 3 4\nf 5 6 7 8\ng a.0\nf 9 10 11 12\n") == V{"a.1", "a.2", "a.0"});
    CHECK(names("g a.0\nf 1 2 3 4\ng a\nf 5 6 7 8\nf 9 10 11 12\n") == V{"a.0", "a.1", "a.2"});
    // A group 'a.1' of several faces is numbered in its own right; 'a' may then use 'a.1'.
    CHECK(names("g a\nf 1 2 3 4\nf 5 6 7 8\ng a.1\nf 9 10 11 12\nf 13 14 15 16\n") ==
          V{"a.0", "a.1", "a.1.0", "a.1.1"});
    // A triangle is three surfaces of its group; the file's stem names faces without a group.
    CHECK(names("f 1 2 3\ng inline.1\nf 1 2 3 4\n") ==
          V{"inline.0", "inline.2", "inline.3", "inline.1"});
    // And the unique names go through an `obj` statement into a scene without complaint.
    TempDir dir;
    dir.write("g.obj", v4 + "g a\nf 1 2 3 4\nf 5 6 7 8\ng a.0\nf 9 10 11 12\n");
    CHECK(load_scene(dir.write("g.scene", "obj g.obj\n")).surfaces.size() == 3);
}

TEST_CASE("scene_io: counts in messages agree with their nouns", "[scene_io][errors]") {
    check_error("set order\n", 1, "'set' needs a name and one value, found 1 word");
    check_error("set order 3 4\n", 1, "'set' needs a name and one value, found 3 words");
    check_obj_error("v 0 0 0\nf 1 2 3\n", 2, "vertex index 2 is out of range (1 vertex defined");
    check_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n", 5,
                    "texture vertex index 2 is out of range (1 texture vertex defined");
    check_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nf 1/1 2/3 3/1\n", 6,
                    "(2 texture vertices defined");
    check_obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n", 4,
                    "normal index 1 is out of range (0 normals defined");
}

TEST_CASE("scene_io: the scene records every file its readers opened, in order", "[scene_io]") {
    // The scene, its includes, OBJ files, MTL libraries and textures, each once (a texture named
    // twice is read once), as the paths opened; text parsed from a stream is no file opened.
    TempDir dir;
    std::filesystem::copy_file(scenes_dir + "picture.png", dir.path / "a.png",
                               std::filesystem::copy_options::overwrite_existing);
    std::filesystem::copy_file(scenes_dir + "picture.png", dir.path / "b.png",
                               std::filesystem::copy_options::overwrite_existing);
    const std::string p = dir.path.string() + "/";
    dir.write("t.mtl", "newmtl poster\nKd 0.5 0.5 0.5\nmap_Kd b.png\n");
    // The OBJ's quad lies above the rectangle r (the same place with another material would be
    // an error, docs/scene-format.md).
    dir.write("t.obj",
              "mtllib t.mtl\nusemtl poster\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
              "f 1 2 3 4\n");
    dir.write("inc.scene", "material c reflectance image a.png\n");
    const std::string top = dir.write("top.scene",
                                      "material a reflectance image a.png\n"
                                      "include inc.scene\n"
                                      "rectangle r a 0 0 0  1 0 0  0 1 0\n"
                                      "obj t.obj\n");
    Scene s = load_scene(top);
    CHECK(s.input_files == std::vector<std::string>{top, p + "a.png", p + "inc.scene", p + "t.obj",
                                                    p + "t.mtl", p + "b.png"});
    Scene o = load_obj(p + "t.obj");
    CHECK(o.input_files == std::vector<std::string>{p + "t.obj", p + "t.mtl", p + "b.png"});
    std::ifstream in(top);
    Scene streamed = parse_scene(in, top);
    CHECK(streamed.input_files == std::vector<std::string>{p + "a.png", p + "inc.scene",
                                                           p + "t.obj", p + "t.mtl", p + "b.png"});
}

TEST_CASE("scene_io: an image named by several materials is decoded once", "[scene_io][texture]") {
    // Four materials of one scene and one material of an imported OBJ name the same file (once
    // through a different spelling of its path): all five share one decoded image.
    TempDir dir;
    std::filesystem::copy_file(scenes_dir + "picture.png", dir.path / "big.png");
    std::filesystem::create_directories(dir.path / "sub");
    dir.write("t.mtl", "newmtl poster\nKd 0.5 0.5 0.5\nmap_Kd big.png\n");
    // The OBJ's quad lies above the rectangle r (the same place with another material would be
    // an error, docs/scene-format.md).
    dir.write("t.obj",
              "mtllib t.mtl\nusemtl poster\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
              "f 1 2 3 4\n");
    const std::string text =
        "material a reflectance image big.png\n"
        "material b reflectance image big.png scale 0.3 0.6 0.45\n"
        "material c emission image sub/../big.png scale 20 20 20\n"
        "material d reflectance 0.5 0.5 0.5 emission image big.png\n"
        "rectangle r a 0 0 0  1 0 0  0 1 0\n"
        "obj t.obj\n";
    Scene s = load_scene(dir.write("t.scene", text));
    REQUIRE(s.materials.size() == 5);
    const Texture& first = s.materials[0].reflectance;
    REQUIRE(first.kind() == Texture::Kind::Image);
    CHECK(first.shares_texels(s.materials[1].reflectance));
    CHECK(first.shares_texels(s.materials[2].emission));
    CHECK(first.shares_texels(s.materials[3].emission));
    CHECK(first.shares_texels(s.materials[4].reflectance));
    CHECK(!first.shares_texels(s.materials[3].reflectance));  // a constant has no texels
    // Each keeps its own scale: b = a x (0.3 0.6 0.45) / 0.9 at every point; the OBJ's map_Kd
    // is scaled by its Kd.
    for (Vec2 uv : {Vec2{0.1, 0.2}, Vec2{0.5, 0.5}, Vec2{0.93, 0.7}}) {
        const Rgb a = first.value(uv.x, uv.y) * (1 / 0.9);
        const Rgb b = s.materials[1].reflectance.value(uv.x, uv.y);
        const Rgb c = s.materials[2].emission.value(uv.x, uv.y);
        const Rgb p = s.materials[4].reflectance.value(uv.x, uv.y);
        // Products of the same doubles in a different order: a few ulps apart.
        CHECK(b.g == Approx(0.6 * a.g).epsilon(1e-14));
        CHECK(b.b == Approx(0.45 * a.b).epsilon(1e-14));
        CHECK(c.r == Approx(20 * a.r).epsilon(1e-14));
        CHECK(p.r == Approx(0.5 * a.r).epsilon(1e-14));
    }
    // A memory-independent check that the file is read once: the scene's budget of 1000 files
    // read counts it once, so 1500 materials may name it.
    std::string many;
    for (int i = 0; i < 1500; ++i)
        many += "material m" + std::to_string(i) + " reflectance image big.png\n";
    Scene m = load_scene(dir.write("many.scene", many + "rectangle r m7 0 0 0  1 0 0  0 1 0\n"));
    CHECK(m.materials.size() == 1500);
    CHECK(m.materials[0].reflectance.shares_texels(m.materials[1499].reflectance));
}

TEST_CASE("texture: scaled copies share the texels and scale every statistic",
          "[scene_io][texture]") {
    Texture t = Texture::from_pixels(2, 1, {{0.2, 0.4, 0.8}, {0.6, 0.1, 0.0}}, {1, 1, 1});
    Texture s = t.scaled({2, 1, -1});
    CHECK(s.shares_texels(t));
    CHECK(s.value(0.25, 0.5).r == 0.4);
    CHECK(s.value(0.75, 0.5).b == 0);
    CHECK(s.mean().r == Approx(0.8));  // 2 x mean 0.4
    CHECK(s.maximum().r == 1.2);
    // A negative scale turns the range around: minimum -0.8, maximum -0 for blue.
    CHECK(s.minimum().b == -0.8);
    CHECK(s.maximum().b == 0);
    CHECK(Texture::constant({0.5, 0.5, 0.5}).scaled({0.5, 1, 2}).value(0.3, 0.3).b == 1);
    Texture c = Texture::checker({1, 1, 1}, {0.5, 0.5, 0.5}, 2).scaled({0.5, 0.5, 0.5});
    CHECK(c.value(0.1, 0.1).r == 0.5);
    CHECK(c.value(0.6, 0.1).r == 0.25);
    CHECK(!c.shares_texels(c));  // procedural: no texels
}

TEST_CASE("line_reader: the formats of scenes, solution files and probe CSVs",
          "[scene_io][line_reader]") {
    // Scenes (the defaults): blank-separated tokens, '#' comments, blank lines skipped.
    {
        std::istringstream in(std::string("\xEF\xBB\xBF") + "a b\t# note\n\n  \r\nc\n");
        LineReader reader(in, "s");
        Line line;
        REQUIRE(reader.next(line));
        CHECK(line.number == 1);
        CHECK(line.tokens == std::vector<std::string>{"a", "b"});
        REQUIRE(reader.next(line));
        CHECK(line.number == 4);
        CHECK(line.tokens == std::vector<std::string>{"c"});
        CHECK(!reader.next(line));
        CHECK(reader.number() == 4);  // the end leaves the last line's number
    }
    // Solution files: every line returned, '#' and control bytes are part of words, a limit with
    // its own message.
    {
        LineFormat f;
        f.max_length = 4;
        f.too_long = "line is too long";
        f.comments = false;
        f.control_bytes = true;
        f.skip_blank = false;
        std::istringstream in("a#b\n\n\x01\nabcde\n");
        LineReader reader(in, "f", f);
        Line line;
        REQUIRE(reader.next(line));
        CHECK(line.tokens == std::vector<std::string>{"a#b"});
        REQUIRE(reader.next(line));
        CHECK(line.number == 2);
        CHECK(line.tokens.empty());
        REQUIRE(reader.next(line));
        CHECK(line.tokens == std::vector<std::string>{"\x01"});
        try {
            reader.next(line);
            FAIL("no InputError for a line beyond the limit");
        } catch (const InputError& e) {
            CHECK(e.line() == 4);
            CHECK(e.message() == "line is too long");
        }
    }
    // Probe CSVs: fields at commas, trimmed of spaces and tabs (not of other bytes), empty
    // fields kept, one trailing '\r' dropped, lines of blanks skipped.
    {
        LineFormat f;
        f.max_length = 0;
        f.comments = false;
        f.control_bytes = true;
        f.separator = ',';
        std::istringstream in(" a ,,\tb#\r\n \t\r\n\v\n");
        LineReader reader(in, "p", f);
        Line line;
        REQUIRE(reader.next(line));
        CHECK(line.tokens == std::vector<std::string>{"a", "", "b#"});
        REQUIRE(reader.next(line));
        CHECK(line.number == 3);
        CHECK(line.tokens == std::vector<std::string>{"\v"});
        CHECK(!reader.next(line));
    }
}
