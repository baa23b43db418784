// test/test_mgf.cpp - MGF import (radiosity/scene/mgf_reader.h; docs/scene-format.md, "MGF
// import") on small files of our own: colours and materials, faces and the curved entities, xf
// transforms with arrays, objects, includes, faces with holes (fh and seams, OBJ too), the
// forgiving and the strict import, and the mbr tool reading an MGF file directly.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "radiosity/scene/scene_io.h"
#include "test/run_program.h"

using namespace mbr;
using Catch::Matchers::Contains;
using mbr::test::TempFolder;

namespace {

Scene mgf(const std::string& text, bool strict = false) {
    std::istringstream in(text);
    ImportOptions o;
    o.strict = strict;
    return parse_mgf(in, "t.mgf", o);
}

/// The four vertices of the unit square in z = 0, and a material of reflectance 0.5.
const char* square_vertices =
    "m grey =\n  c\n  rd 0.5\n"
    "v a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\nv d =\n p 0 1 0\n";

const SceneWarning* warning_of(const Scene& scene, const std::string& kind) {
    for (const SceneWarning& w : scene.warnings)
        if (w.kind == kind) return &w;
    return nullptr;
}

double total_area(const Scene& s) {
    double a = 0;
    for (const SceneSurface& x : s.surfaces) a += x.surface.area();
    return a;
}

/// The area-weighted mean normal of the scene's surfaces (each over a 4 x 4 grid).
Vec3 mean_normal(const Scene& s) {
    Vec3 n;
    for (const SceneSurface& x : s.surfaces)
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const SurfacePoint p = x.surface.evaluate((i + 0.5) / 4, (j + 0.5) / 4);
                n += (p.area_factor / 16) * p.normal;
            }
    return n;
}

}  // namespace

TEST_CASE("mgf: CIE xy and Y to linear sRGB with equal-energy white", "[mgf]") {
    // Neutral grey is grey: (Y, Y, Y).
    const Rgb grey = mgf_colour_to_rgb(1.0 / 3, 1.0 / 3, 0.4);
    CHECK(grey.r == Approx(0.4));
    CHECK(grey.g == Approx(0.4));
    CHECK(grey.b == Approx(0.4));
    // Each primary's chromaticity gives that channel alone; the three channels' luminances
    // (Y of a unit channel) sum to white's Y, 1.
    const double xy[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
    double luminance_sum = 0;
    for (int c = 0; c < 3; ++c) {
        const Rgb p = mgf_colour_to_rgb(xy[c][0], xy[c][1], 1);
        CAPTURE(c);
        for (int k = 0; k < 3; ++k)
            if (k != c) CHECK(std::abs(p[k]) < 1e-9);
        REQUIRE(p[c] > 0);
        luminance_sum += 1 / p[c];
    }
    CHECK(luminance_sum == Approx(1));
    // Linear in Y.
    const Rgb a = mgf_colour_to_rgb(0.4, 0.35, 0.2), b = mgf_colour_to_rgb(0.4, 0.35, 0.6);
    for (int k = 0; k < 3; ++k) CHECK(b[k] == Approx(3 * a[k]));
}

TEST_CASE("mgf: materials from c, cxy, cct, cmix, rd and ed; templates and named colours",
          "[mgf]") {
    const Scene s = mgf(std::string(square_vertices) +
                        "c warm =\n cxy 0.4 0.35\n"
                        "m painted =\n c warm\n rd 0.3\n"
                        "m lamp =\n c\n ed 179\n rd 0\n"
                        "m hot = painted\n c\n cct 2800\n ed 358\n"
                        "m mixed =\n c red =\n cxy 0.64 0.33\n c blue =\n cxy 0.15 0.06\n"
                        "  c\n  cmix 1 red 1 blue\n rd 0.2\n"
                        // Each face in a place of its own (a repeat would be dropped).
                        "m grey\nf a b c d\nm painted\nxf -t 2 0 0\nf a b c d\nxf\n"
                        "m lamp\nxf -t 4 0 0\nf a b c d\nxf\n"
                        "m hot\nxf -t 6 0 0\nf a b c d\nxf\n"
                        "m mixed\nxf -t 8 0 0\nf a b c d\nxf\n");
    REQUIRE(s.surfaces.size() == 5);
    auto material = [&](int i) -> const Material& { return s.material_of(i); };
    // rd of neutral grey: rho = (0.5, 0.5, 0.5).
    CHECK(material(0).reflectance.mean().g == Approx(0.5));
    CHECK(material(0).reflectance.mean().r == Approx(0.5));
    // rd in a named colour: the colour's sRGB with luminance 0.3.
    const Rgb warm = mgf_colour_to_rgb(0.4, 0.35, 0.3);
    for (int k = 0; k < 3; ++k) CHECK(material(1).reflectance.mean()[k] == Approx(warm[k]));
    CHECK(warm.r > warm.b);
    // ed 179 lm/m^2 of white: E = 1 W/m^2 in each channel.
    CHECK(material(2).emits());
    CHECK(material(2).emission.mean().r == Approx(1));
    CHECK(material(2).emission.mean().b == Approx(1));
    // A template copies rd; a black body of 2800 K is reddish; ed 358: twice the lamp's Y.
    for (int k = 0; k < 3; ++k) CHECK(material(3).reflectance.mean()[k] == Approx(warm[k]));
    const Rgb e = material(3).emission.mean();
    CHECK(e.r > e.g);
    CHECK(e.g > e.b);
    // Its luminance: each channel weighted by the luminance of a unit of it (the primaries').
    const double xy[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
    double Y = 0;
    for (int c = 0; c < 3; ++c) Y += e[c] / mgf_colour_to_rgb(xy[c][0], xy[c][1], 1)[c];
    CHECK(Y == Approx(2));
    // cmix of red and blue primaries: a purple with no green.
    const Rgb m = material(4).reflectance.mean();
    CHECK(m.r > 0);
    CHECK(m.b > 0);
    CHECK(m.g == Approx(0).margin(1e-9));
}

TEST_CASE("mgf: faces, objects' names and the faces' sides", "[mgf]") {
    const Scene s =
        mgf(std::string(square_vertices) +
            "o room\n o floor\n  f a b c d\n o\n o wall\n  f a b c\n  f d c b a\n o\no\n");
    // The square is one planar quad; the triangle three quads; the reversed square one more.
    REQUIRE(s.surfaces.size() == 5);
    CHECK(s.surfaces[0].name == "room/floor");
    CHECK_THAT(s.surfaces[1].name, Contains("room/wall"));
    CHECK(s.surfaces[0].surface.kind() == Surface::Kind::PlanarQuad);
    CHECK(s.surfaces[0].surface.area() == Approx(1));
    CHECK(s.surfaces[0].surface.normal(0.5, 0.5).z == Approx(1));  // counter-clockwise: +z
    CHECK(s.surfaces[4].surface.normal(0.5, 0.5).z == Approx(-1));
    double triangle = 0;
    for (int i = 1; i <= 3; ++i) triangle += s.surfaces[size_t(i)].surface.area();
    CHECK(triangle == Approx(0.5));
    // One-sided unless `sides 2`: the material is two-sided and each face gets a twin.
    const Scene two =
        mgf("m g =\n sides 2\n rd 0.5\n"
            "v a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\nv d =\n p 0 1 0\n"
            "f a b c d\n");
    REQUIRE(two.surfaces.size() == 2);
    CHECK(two.materials[size_t(two.surfaces[0].material)].two_sided);
    CHECK(two.surfaces[1].surface.normal(0.5, 0.5).z == Approx(-1));
}

TEST_CASE("mgf: a quad written as two triangles is one surface (MGF and OBJ)", "[mgf][obj]") {
    // The unit square's halves, the diagonal a-c walked both ways; then the same halves in two
    // materials, which stay three quads each.
    const Scene s = mgf(std::string(square_vertices) + "f a b c\nf a c d\n");
    REQUIRE(s.surfaces.size() == 1);
    CHECK(s.surfaces[0].surface.area() == Approx(1));
    CHECK(s.surfaces[0].surface.normal(0.5, 0.5).z == Approx(1));
    const Scene two =
        mgf(std::string(square_vertices) + "f a b c\nm white =\n c\n rd 0.8\nf a c d\n");
    CHECK(two.surfaces.size() == 6);
    CHECK(total_area(two) == Approx(1));
    // A cube's face of two triangles, repeated as the quad itself: the repeat is found.
    const Scene again = mgf(std::string(square_vertices) + "f a b c\nf a c d\nf b c d a\n");
    CHECK(again.surfaces.size() == 1);
    // --keep-triangles: each half stays three quads.
    std::istringstream kept_text(std::string(square_vertices) + "f a b c\nf a c d\n");
    ImportOptions keep;
    keep.join_triangles = false;
    CHECK(parse_mgf(kept_text, "t.mgf", keep).surfaces.size() == 6);
    std::istringstream obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
    const Scene o = parse_obj(obj, "t.obj");
    REQUIRE(o.surfaces.size() == 1);
    CHECK(o.surfaces[0].surface.area() == Approx(1));
}

TEST_CASE("mgf: xf moves, turns, scales and mirrors; arrays repeat their lines", "[mgf]") {
    SECTION("translation, rotation and scale") {
        const Scene s = mgf(std::string(square_vertices) +
                            "xf -s 2 -rz 90 -t 10 0 0\nf a b c d\nxf\nf a b c d\n");
        REQUIRE(s.surfaces.size() == 2);
        // Scaled by 2 (area 4), turned a quarter about z (x -> y), then moved by 10 along x.
        const Surface& q = s.surfaces[0].surface;
        CHECK(q.area() == Approx(4));
        CHECK(q.point(0, 0).x == Approx(10));
        const Vec3 p10 =
            q.point(1, 0);  // the image of b = (1, 0, 0) or d, by the quad's corner order
        CHECK(std::abs(p10.x - 10) + std::abs(p10.y) == Approx(2));
        const Box3 box = s.surfaces[0].surface.bounds();
        CHECK(box.lo.x == Approx(8));
        CHECK(box.hi.x == Approx(10));
        CHECK(box.lo.y == Approx(0).margin(1e-12));
        CHECK(box.hi.y == Approx(2));
        CHECK(s.surfaces[0].surface.normal(0.5, 0.5).z == Approx(1));
        CHECK(s.surfaces[1].surface.area() == Approx(1));  // the context ended
    }
    SECTION("a mirror keeps the front on the mirrored side") {
        const Scene s = mgf(std::string(square_vertices) + "xf -mz\nf a b c d\nxf\n");
        REQUIRE(s.surfaces.size() == 1);
        // The face's front (+z) seen in a mirror across z = 0 is -z.
        CHECK(s.surfaces[0].surface.normal(0.5, 0.5).z == Approx(-1));
    }
    SECTION("arrays: 3 along x times 2 along y, nested contexts inside") {
        const Scene s = mgf(std::string(square_vertices) +
                            "xf -t 0 0 5 -a 3 -t 2 0 0 -a 2 -t 0 3 0\n"
                            " xf -t 0.5 0 0\n  f a b c d\n xf\n"
                            "xf\n");
        REQUIRE(s.surfaces.size() == 6);
        std::vector<std::pair<double, double>> corners;
        for (const SceneSurface& x : s.surfaces) {
            const Box3 b = x.surface.bounds();
            CHECK(b.lo.z == Approx(5));
            corners.push_back({b.lo.x, b.lo.y});
        }
        std::sort(corners.begin(), corners.end());
        const double want[6][2] = {{0.5, 0}, {0.5, 3}, {2.5, 0}, {2.5, 3}, {4.5, 0}, {4.5, 3}};
        for (int i = 0; i < 6; ++i) {
            CHECK(corners[size_t(i)].first == Approx(want[i][0]));
            CHECK(corners[size_t(i)].second == Approx(want[i][1]).margin(1e-12));
        }
    }
    SECTION("an array without its closing xf, and one too large, are refused") {
        REQUIRE_THROWS_WITH(
            mgf(std::string(square_vertices) + "xf -a 3 -t 1 0 0\nf a b c d\n", true),
            Contains("without its closing 'xf'"));
        REQUIRE_THROWS_WITH(mgf(std::string(square_vertices) +
                                    "xf -a 1000 -t 1 0 0 -a 1001 -t 0 1 0\nf a b c d\nxf\n",
                                true),
                            Contains("instances"));
    }
}

TEST_CASE(
    "mgf: spheres, cylinders and rings are mbr's curved surfaces; cones, tori and prisms "
    "quads",
    "[mgf]") {
    const Scene s = mgf(
        "m w =\n rd 0.5\n"
        "v o =\n p 0 0 0\n n 0 0 1\nv top =\n p 0 0 2\nv far =\n p 5 0 0\n n 1 0 0\n"
        "sph o 1.5\nsph far -0.5\ncyl o 0.5 top\nring o 1 2\ncone o 1 top 0.5\ncone o 1 top 1\n");
    REQUIRE(s.surfaces.size() >= 6);
    CHECK(s.surfaces[0].surface.kind() == Surface::Kind::Sphere);
    CHECK(s.surfaces[0].surface.area() == Approx(4 * Pi * 1.5 * 1.5));
    CHECK_FALSE(s.surfaces[0].surface.is_concave());
    CHECK(s.surfaces[1].surface.is_concave());  // a negative radius: the inside faces out
    CHECK(s.surfaces[2].surface.kind() == Surface::Kind::Cylinder);
    CHECK(s.surfaces[2].surface.area() == Approx(2 * Pi * 0.5 * 2));
    CHECK(s.surfaces[3].surface.kind() == Surface::Kind::Disk);
    CHECK(s.surfaces[3].surface.area() == Approx(Pi * (4 - 1)));
    CHECK(s.surfaces[3].surface.normal(0.5, 0.5).z == Approx(1));
    // The cone of radii 1 and 0.5 over height 2: a band of planar quads of nearly its area
    // (the inscribed polygon's), then the cone of equal radii is a cylinder.
    double cone = 0;
    size_t i = 4;
    for (; s.surfaces[i].surface.kind() == Surface::Kind::PlanarQuad; ++i)
        cone += s.surfaces[i].surface.area();
    const double slant = std::sqrt(4 + 0.25);
    CHECK(cone == Approx(Pi * (1 + 0.5) * slant).epsilon(0.03));
    CHECK(cone < Pi * (1 + 0.5) * slant);
    REQUIRE(i + 1 == s.surfaces.size());
    CHECK(s.surfaces[i].surface.kind() == Surface::Kind::Cylinder);

    // A torus of radii 1 and 2 about z: planar quads of nearly 4 pi^2 R r, facing out (and in
    // with negative radii). Each is one facet for rays: its cell of the torus is a trapezoid.
    for (const char* radii : {"1 2", "-1 -2"}) {
        CAPTURE(radii);
        const Scene t = mgf(std::string("m w =\n rd 0.5\nv o =\n p 0 0 0\n n 0 0 1\ntorus o ") +
                            radii + "\n");
        CHECK(t.surfaces.size() >= 48);
        CHECK(total_area(t) == Approx(4 * Pi * Pi * 1.5 * 0.5).epsilon(0.05));
        const bool inward = radii[0] == '-';
        for (const SceneSurface& x : t.surfaces) {
            REQUIRE(x.surface.kind() == Surface::Kind::PlanarQuad);
            CHECK(x.surface.tessellate(16).size() == 1);
            // Out of the tube (or into it): the normal points away from the tube's circle.
            const SurfacePoint q = x.surface.evaluate(0.5, 0.5);
            const Vec3 radial = normalize(Vec3{q.position.x, q.position.y, 0});
            CHECK(dot(q.normal, q.position - 1.5 * radial) * (inward ? -1 : 1) > 0);
        }
    }
    // An inner radius of 0: the cells at the centre are triangles, nothing is refused.
    const Scene t0 = mgf("m w =\n rd 0.5\nv o =\n p 0 0 0\n n 0 0 1\ntorus o 0 2\n");
    CHECK(total_area(t0) == Approx(4 * Pi * Pi * 1 * 1).epsilon(0.05));

    // A prism, the MGF manual's example: the face (0 0 0) (0 1 0) (1 1 0) (1 0 0) looks down
    // (-z), and a positive length extrudes it the other way: the unit cube, every side out.
    const std::string cube_face =
        "m w =\n rd 0.5\nv c0 =\n p 0 0 0\nv c1 =\n p 0 1 0\nv c2 =\n p 1 1 0\n"
        "v c3 =\n p 1 0 0\n";
    for (const double len : {1.0, -1.0}) {
        CAPTURE(len);
        const Scene p = mgf(cube_face + "prism c0 c1 c2 c3 " + std::to_string(len) + "\n");
        CHECK(total_area(p) == Approx(6));
        CHECK(length(mean_normal(p)) == Approx(0).margin(1e-9));  // closed: the normals cancel
        Box3 box;
        for (const SceneSurface& x : p.surfaces) box.extend(x.surface.bounds());
        const Vec3 centre{0.5, 0.5, 0.5 * len};
        CHECK(box.lo.z == Approx(std::min(0.0, len)));
        CHECK(box.hi.z == Approx(std::max(0.0, len)));
        for (const SceneSurface& x : p.surfaces) {
            const SurfacePoint q = x.surface.evaluate(0.5, 0.5);
            CHECK(dot(q.normal, q.position - centre) * len >
                  0);  // out, or in for a negative length
        }
    }
}

TEST_CASE("mgf: faces with holes, by fh and along seams (MGF and OBJ)", "[mgf]") {
    // A 4 x 4 square with a 2 x 2 hole in the middle: area 12.
    const std::string v =
        "m w =\n rd 0.5\n"
        "v o1 =\n p 0 0 0\nv o2 =\n p 4 0 0\nv o3 =\n p 4 4 0\nv o4 =\n p 0 4 0\n"
        "v h1 =\n p 1 1 0\nv h2 =\n p 3 1 0\nv h3 =\n p 3 3 0\nv h4 =\n p 1 3 0\n";
    SECTION("fh: the hole in either winding") {
        for (const char* hole : {"h1 h2 h3 h4", "h4 h3 h2 h1"}) {
            const Scene s = mgf(v + "fh o1 o2 o3 o4 - " + hole + "\n", true);
            CHECK(total_area(s) == Approx(12));
            CHECK(mean_normal(s).z == Approx(12));
        }
    }
    SECTION("a seam: the outline, back to its first vertex, the hole reversed, back again") {
        const Scene s = mgf(v + "f o1 o2 o3 o4 o1 h1 h4 h3 h2 h1\n", true);
        CHECK(total_area(s) == Approx(12));
        CHECK(mean_normal(s).z == Approx(12));
        // The MGF manual's way: the seam from the outline's last vertex into the hole and back.
        const Scene manual = mgf(v + "f o1 o2 o3 o4 h4 h3 h2 h1 h4 o4\n", true);
        CHECK(total_area(manual) == Approx(12));
        // Nothing of the scene covers the hole's centre.
        for (const SceneSurface& x : s.surfaces) {
            const Box3 b = x.surface.bounds();
            CHECK_FALSE((b.lo.x > 1.5 && b.hi.x < 2.5 && b.lo.y > 1.5 && b.hi.y < 2.5));
        }
    }
    SECTION("the same seam face in OBJ") {
        std::istringstream in(
            "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 1 1 0\nv 3 1 0\nv 3 3 0\nv 1 3 0\n"
            "f 1 2 3 4 1 5 8 7 6 5\n");
        ImportOptions strict;
        strict.strict = true;
        const Scene s = parse_obj(in, "seam.obj", strict);
        CHECK(total_area(s) == Approx(12));
    }
    SECTION("a face whose edges cross is still refused (strict) or dropped") {
        const std::string bow = v + "f o1 o3 o2 o4 h1\n";
        REQUIRE_THROWS_WITH(mgf(bow, true), Contains("intersects itself"));
        const std::string bad = v + "f o1 o2 o3 o4\nf o1 o3 o2 o4 h1\n";
        const Scene s = mgf(bad);
        CHECK(total_area(s) == Approx(16));
        const SceneWarning* w = warning_of(s, "face dropped");
        REQUIRE(w != nullptr);
        CHECK(w->line > 0);
    }
}

TEST_CASE("mgf: includes, the mgf statement and load_scene_file", "[mgf][scene_io]") {
    TempFolder dir;
    std::filesystem::create_directory(dir.path() / "parts");
    dir.write("parts/square.mgf", square_vertices + std::string("f a b c d\n"));
    const std::string top =
        dir.write("top.MGF", "i parts/square.mgf\ni parts/square.mgf -t 0 0 3\n");
    const Scene s = load_scene_file(top);
    REQUIRE(s.surfaces.size() == 2);
    CHECK(s.surfaces[1].surface.bounds().lo.z == Approx(3));
    CHECK(s.input_files.size() == 2);  // top and the included file, once
    CHECK_FALSE(s.has_camera);
    // Read by a scene file's `mgf` statement, with the scene's own camera and settings.
    const std::string scene =
        dir.write("a.scene", "mgf top.MGF\ncamera eye 0.5 0.5 9 look_at 0.5 0.5 0 up 0 1 0\n");
    const Scene t = load_scene_file(scene);
    CHECK(t.surfaces.size() == 2);
    CHECK(t.has_camera);
    // A missing include: refused where it was asked for (strict), or skipped with a warning.
    dir.write("broken.mgf", "i nothere.mgf\ni parts/square.mgf\n");
    ImportOptions strict;
    strict.strict = true;
    REQUIRE_THROWS_WITH(load_scene_file(dir / "broken.mgf", strict),
                        Contains("broken.mgf:1") && Contains("nothere.mgf"));
    const Scene forgiven = load_scene_file(dir / "broken.mgf");
    CHECK(forgiven.surfaces.size() == 1);
    REQUIRE(warning_of(forgiven, "entity skipped") != nullptr);
    CHECK_THAT(warning_of(forgiven, "entity skipped")->message, Contains("nothere.mgf"));
}

TEST_CASE("mgf: the forgiving import warns once per kind; strict refuses at the line", "[mgf]") {
    const std::string text = std::string(square_vertices) +
                             "m shiny =\n rd 0.4\n rs 0.3 0.05\n"
                             "f a b c d\n"
                             "frobnicate 1 2\nfrobnicate 3\n"
                             "f a b nowhere\n"
                             "m bright =\n c\n  cxy 0.15 0.06\n rd 0.5\n"
                             "xf -t 0 0 1\nf a b c d\nxf\n";
    const Scene s = mgf(text);
    CHECK(s.surfaces.size() == 2);
    const SceneWarning* skipped = warning_of(s, "entity skipped");
    REQUIRE(skipped != nullptr);
    CHECK(skipped->count == 2);
    CHECK(skipped->line == 16);  // the first of them
    CHECK_THAT(skipped->message, Contains("frobnicate"));
    REQUIRE(warning_of(s, "face dropped") != nullptr);
    CHECK_THAT(warning_of(s, "face dropped")->message, Contains("nowhere"));
    REQUIRE(warning_of(s, "specular part dropped") != nullptr);
    CHECK_THAT(warning_of(s, "specular part dropped")->message, Contains("rs 0.3"));
    // rd 0.5 of the blue primary needs a blue channel near 7: clamped, said.
    REQUIRE(warning_of(s, "value clamped") != nullptr);
    CHECK(s.material_of(1).reflectance.maximum().b < 1);
    REQUIRE_THROWS_WITH(mgf(text, true), Contains("t.mgf:16") && Contains("frobnicate"));
    REQUIRE_THROWS_WITH(mgf("ies lamp.ies\n", true), Contains("not supported"));
    // Names of the contexts that were never defined.
    REQUIRE_THROWS_WITH(mgf("m a =\n c nope\n", true),
                        Contains("t.mgf:2: undefined colour 'nope'"));
    REQUIRE_THROWS_WITH(mgf("m a = zz\n", true), Contains("t.mgf:1: undefined material 'zz'"));
    REQUIRE_THROWS_WITH(mgf("v q\n", true), Contains("t.mgf:1: undefined vertex 'q'"));
    REQUIRE_THROWS_WITH(mgf("c\n cmix 1 red\n", true), Contains("undefined colour 'red'"));
    REQUIRE_THROWS_WITH(mgf("m w =\n rd 0.5\n"), Contains("no surfaces"));
}

#ifdef MBR_TOOL
TEST_CASE("mgf: mbr renders an MGF file directly, with the automatic camera", "[mgf][tool]") {
    // A small closed box, z up, with a light in its ceiling facing down.
    TempFolder dir;
    const std::string box =
        dir.write("box.mgf",
                  "m wall =\n rd 0.6\nm lamp =\n ed 1000\n rd 0\n"
                  "v a =\n p 0 0 0\nv b =\n p 2 0 0\nv c =\n p 2 2 0\nv d =\n p 0 2 0\n"
                  "v e =\n p 0 0 2\nv f =\n p 2 0 2\nv g =\n p 2 2 2\nv h =\n p 0 2 2\n"
                  "v l1 =\n p 0.8 0.8 1.99\nv l2 =\n p 1.2 0.8 1.99\nv l3 =\n p 1.2 1.2 1.99\n"
                  "v l4 =\n p 0.8 1.2 1.99\n"
                  "m wall\nf a b c d\nf e h g f\nf a e f b\nf b f g c\nf c g h d\nf d h e a\n"
                  "m lamp\nf l1 l4 l3 l2\n");
    const std::string out = dir / "box.png";
    const auto run = mbr::test::run_program(
        MBR_TOOL, {"render", box, "-o", out, "--shots", "3", "--max-depth", "3"});
    INFO(run);
    REQUIRE(run.status == 0);
    CHECK(std::filesystem::file_size(out) > 1000);
    CHECK_THAT(run.out, Contains("box.mgf: 7 surfaces"));
}
#endif
