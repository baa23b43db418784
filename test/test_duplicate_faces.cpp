// test/test_duplicate_faces.cpp - surfaces that repeat others, found at import
// (radiosity/scene/duplicate_faces.h; docs/scene-format.md, "Duplicate surfaces"): a repeat with
// the same material is dropped with one warning naming both lines, one with another material is
// an InputError naming both lines and both materials, in scene files and OBJ files alike and
// across an `obj` import; a face written the other way round (the other side) is kept; 100,000
// distinct quads are checked in a fraction of a second; and a solve of a box whose wall is
// written twice gives exactly the radiosity of the box written once, where the repeat kept
// brightens it.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "math/check.h"
#include "radiosity/scene/duplicate_faces.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/solver/solution_file.h"
#include "radiosity/solver/solver.h"
#include "test/report.h"
#include "test/solution_text.h"
#ifdef MBR_TOOL
#include "test/run_program.h"
#endif

using namespace mbr;
using Catch::Matchers::Contains;
using mbr::test::saved;

namespace {

Scene scene_text(const std::string& text, const std::string& name = "dup.scene") {
    std::istringstream in(text);
    return parse_scene(in, name);
}

Scene obj_text(const std::string& text, const std::string& name = "dup.obj") {
    std::istringstream in(text);
    return parse_obj(in, name);
}

/// The InputError that `parse` throws (fails the test when there is none).
template <class Parse>
InputError error_of(Parse parse) {
    try {
        parse();
    } catch (const InputError& e) {
        return e;
    }
    FAIL("no InputError");
    return InputError("");
}

const std::string materials =
    "material white reflectance 0.5 0.5 0.5\n"
    "material red reflectance 0.6 0.1 0.1\n";

}  // namespace

// ---------------------------------------------------------------------------------------------
// === Scene files

TEST_CASE("duplicate faces: a repeated quad in a scene file is dropped with one warning",
          "[duplicate_faces]") {
    // Line 3 is the quad of line 2 from its third corner: the same surface, the same front.
    const Scene s = scene_text(materials +
                               "quad a white  0 0 0  1 0 0  1 1 0  0 1 0\n"
                               "quad b white  1 1 0  0 1 0  0 0 0  1 0 0\n"
                               "quad c white  0 0 1  1 0 1  1 1 1  0 1 1\n");
    REQUIRE(s.surfaces.size() == 2);
    CHECK(s.surfaces[0].name == "a");
    CHECK(s.surfaces[1].name == "c");
    REQUIRE(s.warnings.size() == 1);
    const SceneWarning& w = s.warnings[0];
    CHECK(w.kind == "duplicate surface");
    CHECK(w.count == 1);
    CHECK(w.file == "dup.scene");
    CHECK(w.line == 4);
    CHECK_THAT(w.message, Contains("'b'") && Contains("'a'") && Contains("dup.scene:3") &&
                              Contains("'white'") && Contains("dropped"));
    CHECK(w.text() == "dup.scene:4: " + w.message);
    // The kept surfaces know their statements.
    CHECK(s.where(0) == "dup.scene:3");
    CHECK(s.where(1) == "dup.scene:5");
}

TEST_CASE("duplicate faces: the same quad as a rectangle, a bilinear patch or a box face",
          "[duplicate_faces]") {
    // A rectangle and a planar bilinear patch are the bilinear map of the same four corners;
    // box b's zmin face is the quad a (facing -z: corners clockwise seen from +z).
    const Scene s = scene_text(materials +
                               "quad a white  0 0 0  0 1 0  1 1 0  1 0 0\n"
                               "rectangle r white  0 1 0  1 0 0  0 -1 0\n"
                               "bilinear p white  1 0 0  0 0 0  0 1 0  1 1 0\n"
                               "box b white  0 0 0  1 1 1\n");
    CHECK(s.surfaces.size() == 6);
    CHECK(s.find_surface("r") < 0);
    CHECK(s.find_surface("p") < 0);
    CHECK(s.find_surface("b.zmin") < 0);
    REQUIRE(s.warnings.size() == 1);
    CHECK(s.warnings[0].count == 3);  // three statements repeat line 3
    CHECK(s.warnings[0].line == 4);
    CHECK_THAT(s.warnings[0].text(), Contains("(and 2 more like it)"));
}

TEST_CASE("duplicate faces: the other side, a shifted copy and curved kinds", "[duplicate_faces]") {
    SECTION("a quad with its corners in reverse order faces the other way: both are kept") {
        const Scene s = scene_text(materials +
                                   "quad a white  0 0 0  1 0 0  1 1 0  0 1 0\n"
                                   "quad b white  0 0 0  0 1 0  1 1 0  1 0 0\n");
        CHECK(s.surfaces.size() == 2);
        CHECK(s.warnings.empty());
    }
    SECTION("a copy moved by 1e-6 of the scene's size is another surface") {
        const Scene s = scene_text(materials +
                                   "quad a white  0 0 0  1 0 0  1 1 0  0 1 0\n"
                                   "quad b white  0 0 0.000001  1 0 0.000001  1 1 0.000001  "
                                   "0 1 0.000001\n");
        CHECK(s.surfaces.size() == 2);
    }
    SECTION("a copy within 1e-10 of the scene's size is the same surface") {
        const Scene s = scene_text(materials +
                                   "quad a white  0 0 0  1 0 0  1 1 0  0 1 0\n"
                                   "quad b white  0 0 1e-10  1 0 0  1 1 0  0 1 0\n");
        CHECK(s.surfaces.size() == 1);
    }
    SECTION("cylinders: the same parameters, or angle 0 moved, repeat; inward does not") {
        const Scene s = scene_text(materials +
                                   "cylinder a white  0 0 0  0 0 1  1 0 0  1 2  0 90\n"
                                   "cylinder b white  0 0 0  0 0 1  1 0 0  1 2  0 90\n"
                                   "cylinder c white  0 0 0  0 0 1  0 1 0  1 2  -90 0\n"
                                   "cylinder d white  0 0 0  0 0 1  1 0 0  1 2  0 90 inward\n"
                                   "cylinder e white  0 0 0  0 0 1  1 0 0  1 2  0 91\n");
        CHECK(s.surfaces.size() == 3);
        CHECK(s.find_surface("a") >= 0);
        CHECK(s.find_surface("d") >= 0);
        CHECK(s.find_surface("e") >= 0);
        REQUIRE(s.warnings.size() == 1);
        CHECK(s.warnings[0].count == 2);
    }
    SECTION("spheres and disks") {
        const Scene s = scene_text(materials +
                                   "sphere a white  0 0 0  0 1 0  1 0 0  1  0 90  0 360\n"
                                   "sphere b white  0 0 0  0 1 0  1 0 0  1  0 90  0 360\n"
                                   "sphere c white  0 0 0  0 1 0  1 0 0  1.5  0 90  0 360\n"
                                   "disk d white  0 3 0  0 1 0  1 0 0  0 1  0 360\n"
                                   "disk e white  0 3 0  0 1 0  1 0 0  0 1  0 360\n"
                                   "disk f white  0 3 0  0 -1 0  1 0 0  0 1  0 360\n");
        CHECK(s.surfaces.size() == 4);
        CHECK(s.find_surface("b") < 0);
        CHECK(s.find_surface("e") < 0);
        CHECK(s.find_surface("f") >= 0);  // the disk's other side
    }
    SECTION("a scene without repeats is unchanged and has no warnings") {
        for (const std::string name : {"cornell_box.scene", "room.scene", "cornell_box.obj"}) {
            const std::string path = std::string(MBR_SOURCE_DIR) + "/examples/scenes/" + name;
            const bool obj = name.size() > 4 && name.substr(name.size() - 4) == ".obj";
            const Scene s = obj ? load_obj(path) : load_scene(path);
            CAPTURE(name);
            CHECK(s.warnings.empty());
            CHECK(find_duplicate_surfaces(s).empty());
        }
    }
}

TEST_CASE("duplicate faces: a repeat with another material is an error naming both",
          "[duplicate_faces]") {
    const InputError e = error_of([] {
        scene_text(materials +
                   "quad a white  0 0 0  1 0 0  1 1 0  0 1 0\n"
                   "# a comment between them\n"
                   "quad b red  0 1 0  0 0 0  1 0 0  1 1 0\n");
    });
    CHECK(e.file() == "dup.scene");
    CHECK(e.line() == 5);
    CHECK_THAT(e.message(), Contains("'b'") && Contains("'a'") && Contains("dup.scene:3") &&
                                Contains("'red' here") && Contains("'white' there"));
}

// ---------------------------------------------------------------------------------------------
// === OBJ files

namespace {

// A unit square (1 2 3 4, front +z) and a triangle; 8 9 10 is the triangle of 5 6 7 from
// another vertex, written again with other vertices at the same places.
const std::string obj_vertices =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "v 2 0 0\nv 3 0 0\nv 2 1 0\n"
    "v 3 0 0\nv 2 1 0\nv 2 0 0\n";

}  // namespace

TEST_CASE("duplicate faces: a repeated OBJ face is dropped, the reverse winding kept",
          "[duplicate_faces]") {
    const Scene s = obj_text(obj_vertices +
                             "o square\n"
                             "f 1 2 3 4\n"  // line 12
                             "f 3 4 1 2\n"  // line 13: the same face from vertex 3
                             "f 1 4 3 2\n"  // line 14: the other side
                             "o tri\n"
                             "f 5 6 7\n"     // line 16: three quads
                             "f 8 9 10\n");  // line 17: the same three quads
    // square.0 and square.2 (the back side), tri's first three quads.
    CHECK(s.surfaces.size() == 5);
    REQUIRE(s.warnings.size() == 1);
    const SceneWarning& w = s.warnings[0];
    CHECK(w.file == "dup.obj");
    CHECK(w.line == 13);
    CHECK(w.count == 2);  // two repeated faces: line 13 and line 17
    CHECK_THAT(w.message, Contains("dup.obj:12") && Contains("'obj_default'"));
    for (const SceneSurface& x : s.surfaces) CHECK(x.line != 13);
    for (const SceneSurface& x : s.surfaces) CHECK(x.line != 17);
}

TEST_CASE("duplicate faces: one warning for many repeats, naming the first", "[duplicate_faces]") {
    std::string text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    for (int i = 0; i < 1000; ++i) text += "f 1 2 3 4\n";
    const Scene s = obj_text(text);
    CHECK(s.surfaces.size() == 1);
    REQUIRE(s.warnings.size() == 1);
    CHECK(s.warnings[0].count == 999);
    CHECK(s.warnings[0].line == 6);
    CHECK_THAT(s.warnings[0].text(),
               Contains("dup.obj:6: ") && Contains("dup.obj:5") && Contains("(and 998 more"));
}

TEST_CASE("duplicate faces: an OBJ repeat with another material is an error when strict",
          "[duplicate_faces]") {
    mbr::test::TempFolder dir;
    dir.write("m.mtl", "newmtl white\nKd 0.5 0.5 0.5\nnewmtl red\nKd 0.6 0.1 0.1\n");
    const std::string obj = dir.write("m.obj",
                                      "mtllib m.mtl\n"
                                      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                      "usemtl white\nf 1 2 3 4\n"
                                      "usemtl red\nf 2 3 4 1\n");
    const InputError e = error_of([&] { load_obj(obj, ImportOptions{true}); });
    CHECK(e.file() == obj);
    CHECK(e.line() == 9);
    CHECK_THAT(e.message(),
               Contains(obj + ":7") && Contains("'red' here") && Contains("'white' there"));
    // Forgiving (the default): the first kept, the repeat dropped, with a warning of its own.
    const Scene s = load_obj(obj);
    CHECK(s.surfaces.size() == 1);
    CHECK(s.material_of(0).name == "white");
    REQUIRE(s.warnings.size() == 1);
    CHECK(s.warnings[0].kind == "duplicate surface with another material");
    CHECK(s.warnings[0].line == 9);
    CHECK_THAT(s.warnings[0].message, Contains("the first is kept and the repeat dropped"));
}

TEST_CASE("duplicate faces: an OBJ face that repeats a scene surface", "[duplicate_faces]") {
    mbr::test::TempFolder dir;
    const std::string obj =
        dir.write("part.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 2 3 4 1\n");
    SECTION("the same material (obj_default): dropped, naming both files' lines") {
        const std::string scene = dir.write("s.scene",
                                            "material obj_default reflectance 0.5 0.5 0.5\n"
                                            "quad floor obj_default  0 0 0  1 0 0  1 1 0  0 1 0\n"
                                            "obj part.obj\n");
        const Scene s = load_scene(scene);
        CHECK(s.surfaces.size() == 1);
        REQUIRE(s.warnings.size() == 1);
        CHECK(s.warnings[0].file == obj);
        CHECK(s.warnings[0].line == 5);
        CHECK_THAT(s.warnings[0].message, Contains(scene + ":2"));
    }
    SECTION("another material: an error at the OBJ's line when strict, else dropped") {
        const std::string scene = dir.write(
            "t.scene", materials + "quad floor red  0 0 0  1 0 0  1 1 0  0 1 0\nobj part.obj\n");
        const Scene s = load_scene(scene);
        CHECK(s.surfaces.size() == 1);
        CHECK(s.surfaces[0].name == "floor");
        const InputError e = error_of([&] { load_scene(scene, ImportOptions{true}); });
        CHECK(e.file() == obj);
        CHECK(e.line() == 5);
        CHECK_THAT(e.message(), Contains(scene + ":3") && Contains("'obj_default' here") &&
                                    Contains("'red' there"));
    }
}

// ---------------------------------------------------------------------------------------------
// === Cost

TEST_CASE("duplicate faces: 100,000 distinct quads are checked in well under a second",
          "[duplicate_faces]") {
    Scene s;
    s.materials.push_back({"white", Texture::constant({0.5, 0.5, 0.5}), Texture()});
    const int nx = 400, ny = 250;  // 100,000 unit quads in a plane, sharing corners
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j) {
            const double x = i, y = j;
            s.surfaces.push_back(
                {"q",
                 Surface::planar_quad({x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}),
                 0});
        }
    // The first quad again from its second corner, last.
    s.surfaces.push_back(
        {"again", Surface::planar_quad({1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}), 0});
    const auto start = std::chrono::steady_clock::now();
    const std::vector<DuplicateSurface> d = find_duplicate_surfaces(s);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    test::report() << "find_duplicate_surfaces: " << s.surfaces.size() << " quads in " << seconds
                   << " s\n";
    REQUIRE(d.size() == 1);
    CHECK(d[0].earlier == 0);
    CHECK(d[0].later == nx * ny);
    CHECK(seconds < 0.5);
}

// ---------------------------------------------------------------------------------------------
// === Through a solve

namespace {

// A closed room of inward faces with a light under its ceiling; `extra` adds statements.
std::string room(const std::string& extra) {
    return "material white reflectance 0.7 0.7 0.7\n"
           "material light reflectance 0.5 0.5 0.5 emission 10 10 10\n"
           "box room white  0 0 0  2 2 2  inward\n"
           "quad lamp light  0.8 1.99 0.8  1.2 1.99 0.8  1.2 1.99 1.2  0.8 1.99 1.2\n" +
           extra;
}

SolverOptions quick(const Scene& scene) {
    SolverOptions o = solver_options(scene.settings);
    o.receiver.min_depth = 1;
    o.receiver.max_depth = 3;
    o.tolerance = 1e-2;
    o.max_shots = 8;
    o.convergence = 0;
    return o;
}

Solution solved(const Scene& scene) {
    const Octree octree = build_octree(scene);
    return solve(scene, octree, quick(scene));
}

}  // namespace

TEST_CASE("duplicate faces: a wall written twice no longer brightens the room",
          "[duplicate_faces]") {
    const Scene once = scene_text(room(""));
    // The back wall (room.zmax, facing -z) again, as a quad from another corner.
    const Scene twice = scene_text(room("quad back white  2 2 2  2 0 2  0 0 2  0 2 2\n"));
    REQUIRE(once.surfaces.size() == 7);
    REQUIRE(twice.surfaces.size() == 7);
    REQUIRE(twice.warnings.size() == 1);
    const Solution a = solved(once), b = solved(twice);
    // Every coefficient, leaf and name, to 17 digits: the same radiosity.
    CHECK(saved(once, a) == saved(twice, b));
    // What the repeat did when kept (added after the reader, as the readers had kept it): the
    // floor's centre is brighter.
    Scene kept = once;
    kept.surfaces.push_back(once.surfaces[size_t(once.find_surface("room.zmax"))]);
    kept.surfaces.back().name = "back";
    const Solution c = solved(kept);
    const int floor = once.find_surface("room.ymin");
    const double b_once = a.radiosity[size_t(floor)].evaluate(0.5, 0.5)[0];
    const double b_kept = c.radiosity[size_t(floor)].evaluate(0.5, 0.5)[0];
    test::report() << "floor centre B: once " << b_once << ", twice (dropped) "
                   << b.radiosity[size_t(floor)].evaluate(0.5, 0.5)[0] << ", twice (kept) "
                   << b_kept << "\n";
    CHECK(b_kept > 1.02 * b_once);
}

// ---------------------------------------------------------------------------------------------
// === The warning channel

TEST_CASE("duplicate faces: Scene::warn keeps one warning per kind", "[duplicate_faces]") {
    Scene s;
    s.warn({"clamped value", "a.obj", 3, "Kd 1.2 clamped to 0.999", 1});
    s.warn({"skipped statement", "a.obj", 4, "unknown statement 'foo' skipped", 1});
    s.warn({"clamped value", "a.obj", 9, "Kd 1.5 clamped to 0.999", 2});
    REQUIRE(s.warnings.size() == 2);
    CHECK(s.warnings[0].count == 3);
    CHECK(s.warnings[0].text() == "a.obj:3: Kd 1.2 clamped to 0.999 (and 2 more like it)");
    CHECK(s.warnings[1].text() == "a.obj:4: unknown statement 'foo' skipped");
    CHECK(SceneWarning{"k", "", 0, "no place", 1}.text() == "no place");
    CHECK(SceneWarning{"k", "f.obj", 0, "the file", 1}.text() == "f.obj: the file");
}

#ifdef MBR_TOOL
TEST_CASE("duplicate faces: mbr prints the warning once, with --quiet too", "[duplicate_faces]") {
    test::TempFolder dir;
    const std::string scene = dir / "twice.scene";
    std::ofstream(scene) << room(
        "quad back white  2 2 2  2 0 2  0 0 2  0 2 2\n"
        "set max_depth 2\nset max_shots 2\n");
    const std::string points = dir / "p.csv";
    std::ofstream(points) << "name,x,y,z,nx,ny,nz\nfloor,1,0,1,0,1,0\n";
    for (const bool quiet : {false, true}) {
        std::vector<std::string> args{"probe", scene, "--points", points};
        if (quiet) args.push_back("--quiet");
        const test::ProgramRun run = test::run_program(MBR_TOOL, args);
        CAPTURE(quiet, run);
        REQUIRE(run.status == 0);
        // One line: "warning: FILE:5: surface 'back' repeats surface 'room.zmax' (FILE:3) ...".
        // Lines of duplicate warnings (two shots leave power unshot, and the summary's own
        // warning about that is not counted).
        size_t n = 0;
        for (size_t at = run.err.find("warning: "); at != std::string::npos;
             at = run.err.find("warning: ", at + 1))
            if (run.err.find("repeats surface", at) < run.err.find('\n', at)) ++n;
        CHECK(n == 1);
        CHECK_THAT(run.err, Contains("warning: " + scene +
                                     ":5: surface 'back' repeats surface "
                                     "'room.zmax' (" +
                                     scene + ":3)"));
    }
}
#endif
