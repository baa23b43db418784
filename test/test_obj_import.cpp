// test/test_obj_import.cpp - the forgiving OBJ import (docs/scene-format.md, "A forgiving
// import"): files of our own that carry each defect users meet in public OBJ files import with
// one warning per kind and give what the file means; strict refuses the first fault. Also
// texture coordinates (vt), BMP and TGA textures, and the sides lights shine from
// (radiosity/scene/light_sides.h).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "radiosity/geometry/texture.h"
#include "radiosity/scene/light_sides.h"
#include "radiosity/scene/scene_io.h"
#include "test/run_program.h"

using namespace mbr;
using Catch::Matchers::Contains;
using mbr::test::TempFolder;

namespace {

/// The warning of `kind`, or null.
const SceneWarning* warning_of(const Scene& scene, const std::string& kind) {
    for (const SceneWarning& w : scene.warnings)
        if (w.kind == kind) return &w;
    return nullptr;
}

/// A little-endian 16- or 32-bit field appended to `s`.
void put(std::string& s, std::uint32_t x, int bytes) {
    for (int k = 0; k < bytes; ++k) s += char((x >> (8 * k)) & 0xff);
}

/// A 2 x 1 BMP of 16-bit RGB565 pixels (red, then blue) with a BITMAPV3INFOHEADER (56 bytes,
/// the header image editors write for 16-bit pixels, which stb_image refuses on its own).
std::string bmp565_v3() {
    std::string header, pixels;
    put(pixels, 0xF800, 2);  // red
    put(pixels, 0x001F, 2);  // blue
    put(header, 56, 4);      // header size: BITMAPV3INFOHEADER
    put(header, 2, 4);       // width
    put(header, 1, 4);       // height
    put(header, 1, 2);       // planes
    put(header, 16, 2);      // bits per pixel
    put(header, 3, 4);       // BI_BITFIELDS
    put(header, 4, 4);       // image size
    put(header, 2835, 4);
    put(header, 2835, 4);
    put(header, 0, 4);
    put(header, 0, 4);
    put(header, 0xF800, 4);  // masks: red, green, blue, alpha
    put(header, 0x07E0, 4);
    put(header, 0x001F, 4);
    put(header, 0, 4);
    std::string file = "BM";
    put(file, std::uint32_t(14 + header.size() + pixels.size()), 4);
    put(file, 0, 4);
    put(file, std::uint32_t(14 + header.size()), 4);
    return file + header + pixels;
}

/// A 2 x 1 uncompressed true-colour TGA (green, then white), rows from the top.
std::string tga_green_white() {
    std::string t;
    t += char(0);  // no image ID
    t += char(0);  // no colour map
    t += char(2);  // uncompressed true colour
    t += std::string(5, '\0');
    put(t, 0, 2);  // origin
    put(t, 0, 2);
    put(t, 2, 2);  // width
    put(t, 1, 2);  // height
    t += char(24);
    t += char(0x20);                      // top-left origin
    t += std::string("\x00\xff\x00", 3);  // B G R: green
    t += std::string("\xff\xff\xff", 3);  // white
    return t;
}

const std::string room_quad = "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\n";  // faces up

}  // namespace

TEST_CASE("obj_import: BMP with a V3 header, 16-bit pixels, and TGA textures decode",
          "[obj][texture][forgiving]") {
    TempFolder dir;
    const Texture bmp = Texture::image(dir.write("t16.bmp", bmp565_v3()));
    // Texel centres at u = 1/4 (red) and 3/4 (blue); full channels decode to linear 1.
    CHECK(bmp.value(0.25, 0.5).r == Approx(1));
    CHECK(bmp.value(0.25, 0.5).b == Approx(0));
    CHECK(bmp.value(0.75, 0.5).b == Approx(1));
    CHECK(bmp.value(0.75, 0.5).r == Approx(0));
    const Texture tga = Texture::image(dir.write("t.tga", tga_green_white()));
    CHECK(tga.value(0.25, 0.5).g == Approx(1));
    CHECK(tga.value(0.25, 0.5).r == Approx(0));
    CHECK(tga.value(0.75, 0.5).r == Approx(1));
}

TEST_CASE("obj_import: every defect is repaired with one warning per kind; strict refuses it",
          "[obj][forgiving]") {
    TempFolder dir;
    dir.write("t16.bmp", bmp565_v3());
    dir.write("m.mtl",
              "newmtl bright\nKd 1 1 1\n"
              "v 1 2 3\n"                                     // a stray statement
              "newmtl wood\nKd 0 0 0\nmap_Kd sub\\t16.bmp\n"  // Kd 0 with a texture, a Windows path
              "newmtl lost\nKd 0.3 0.4 0.5\nmap_Kd missing.png\n"
              "newmtl mirror\nKd 0 0 0\nKs 0.8 0.8 0.8\nillum 3\n"
              "newmtl glossy\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\n"
              "newmtl hot\nKe -1 2 3\n");
    const std::string obj =
        dir.write("x.obj", "mtllib elsewhere/m.mtl\n" + room_quad +
                               "usemtl bright\nf 1 2 3 4\n"
                               "usemtl wood\nf 1 2 3 4\n"   // the same face, another material
                               "f 1 1 2\n"                  // zero area
                               "f 1 2 9\n"                  // an index out of range
                               "v 0 nan 0\nf 1 5 2\n"       // an unusable vertex
                               "frobnicate 1\n"             // an unknown statement
                               "usemtl nowhere\nf 4 3 2\n"  // an unknown material
                               "usemtl lost\nf 1 4 3\n"
                               "usemtl mirror\nf 2 1 4\n"
                               "usemtl glossy\nf 3 2 1\n"
                               "usemtl hot\nf 4 1 2\n");
    const Scene s = load_obj(obj);
    CAPTURE(s.warnings.size());
    std::string all;
    for (const SceneWarning& w : s.warnings) all += w.text() + "\n";
    CAPTURE(all);
    const auto expect = [&](const std::string& kind, const std::string& part, long count) {
        const SceneWarning* w = warning_of(s, kind);
        CAPTURE(kind);
        REQUIRE(w != nullptr);
        CHECK_THAT(w->text(), Contains(part));
        CHECK(w->count == count);
    };
    expect("material library found elsewhere", "x.obj:1: material library", 1);
    expect("statement skipped", "m.mtl:3: unknown MTL statement 'v'", 2);  // and frobnicate
    expect("value clamped", "m.mtl:2: Kd 1 is outside [0, 1)", 2);         // and Ke -1
    expect("texture found elsewhere", "m.mtl:6:", 1);
    expect("texture replaced", "missing.png': file not found; the material's colour 0.3 0.4 0.5",
           1);
    expect("specular material", "treated as diffuse, albedo 0.8 0.8 0.8", 1);
    expect("specular part dropped", "keeps Kd", 1);
    expect("face dropped", "x.obj:10: degenerate face: zero area", 3);
    expect("unusable vertex", "x.obj:12:", 1);
    expect("unknown material", "x.obj:15: unknown material 'nowhere'", 1);
    expect("duplicate surface with another material", "the first is kept", 1);
    // What the repairs give.
    const auto material = [&](const std::string& name) {
        const int m = s.find_material(name);
        REQUIRE(m >= 0);
        return s.materials[size_t(m)];
    };
    CHECK(material("bright").reflectance.maximum().r == Approx(0.99));
    // Kd 0 beside map_Kd: the texture alone, scaled by 0.9 (red texel at u = 1/4).
    CHECK(material("wood").reflectance.value(0.25, 0.5).r == Approx(0.9));
    CHECK(material("lost").reflectance.is_constant());
    CHECK(material("lost").reflectance.mean().b == Approx(0.5));
    CHECK(material("mirror").reflectance.mean().g == Approx(0.8));
    CHECK(material("glossy").reflectance.mean().r == Approx(0.2));
    CHECK(material("hot").emission.mean().r == 0);
    CHECK(material("hot").emission.mean().g == Approx(2 * Pi));
    // The quad of `bright`, its repeat dropped; the triangles make three quads each.
    CHECK(s.surfaces.size() == 1 + 5 * 3);

    // Strictly, the first fault is refused at its line.
    try {
        load_obj(obj, ImportOptions{true});
        FAIL("no InputError");
    } catch (const InputError& e) {
        CHECK(e.line() == 1);
        CHECK_THAT(e.message(), Contains("material library"));
    }
}

TEST_CASE("obj_import: a textured quad written as two triangles stays six quads", "[obj]") {
    // Each quad shows the image over its own (u, v) square: joining the halves would change the
    // picture, so triangles of a textured material are not joined (docs/scene-format.md).
    TempFolder dir;
    dir.write("t.tga", tga_green_white());
    dir.write("m.mtl",
              "newmtl tiles\nKd 0.5 0.5 0.5\nmap_Kd t.tga\nnewmtl plain\nKd 0.5 0.5 0.5\n");
    const std::string halves = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
    CHECK(load_obj(dir.write("t.obj", "mtllib m.mtl\nusemtl tiles\n" + halves)).surfaces.size() ==
          6);
    CHECK(load_obj(dir.write("p.obj", "mtllib m.mtl\nusemtl plain\n" + halves)).surfaces.size() ==
          1);
}

TEST_CASE("obj_import: texture coordinates (vt) place the image on each face", "[obj][forgiving]") {
    TempFolder dir;
    dir.write("t.tga", tga_green_white());
    dir.write("m.mtl", "newmtl tiles\nKd 0.5 0.5 0.5\nmap_Kd t.tga\n");
    // A 2 x 1 rectangle whose coordinates are (x / 4, y / 2): affine, so every point of every
    // quad made from it (the rectangle itself; the triangle's three quads) has known coordinates.
    const std::string obj = dir.write(
        "vt.obj",
        "mtllib m.mtl\nusemtl tiles\n"
        "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\n"
        "vt 0 0\nvt 0.5 0\nvt 0.5 0.5\nvt 0 0.5\n"
        "f 1/1 2/2 3/3 4/4\n"
        "v 0 0 1\nv 2 0 1\nv 0 1 1\n"
        "vt 0 0\nvt 0.5 0\nvt 0 0.5\n"
        "f 5/5 6/6 7/7\n"
        "v 0 0 2\nv 2 0 2\nv 2 1 2\nv 0 1 2\n"
        "vt 0 0\nvt 4 0\nvt 4 1\nvt 0 1\n"  // tiling: u from 0 to 4, the image twice a unit
        "f 8/8 9/9 10/10 11/11\n");
    const Scene s = load_obj(obj);
    CHECK(s.warnings.empty());
    const Texture base = s.materials[size_t(s.find_material("tiles"))].reflectance;
    REQUIRE(s.surfaces.size() == 1 + 3 + 1);
    for (size_t i = 0; i < s.surfaces.size(); ++i) {
        const Texture& t = s.material_of(int(i)).reflectance;
        CHECK(t.is_mapped());
        // (Not u = 1/2, where the third face's tiles meet and rounding picks either.)
        for (double u : {0.1, 0.4, 0.85})
            for (double v : {0.2, 0.7}) {
                const Vec3 x = s.surfaces[i].surface.point(u, v);
                CAPTURE(i, u, v, x.x, x.y);
                // The third face's coordinates are (2 x, y) wrapped into [0, 1].
                const double tu = x.z < 1.5 ? x.x / 4 : 2 * x.x - std::floor(2 * x.x);
                const double tv = x.z < 1.5 ? x.y / 2 : x.y;
                CHECK(t.value(u, v).r == Approx(base.value(tu, tv).r).margin(1e-9));
                CHECK(t.value(u, v).g == Approx(base.value(tu, tv).g).margin(1e-9));
            }
    }
    // The rectangle shows the image's left half of its lower half: green to the blend.
    const Texture& rect = s.material_of(0).reflectance;
    CHECK(rect.mean().r < base.mean().r);
}

TEST_CASE("obj_import: a light wound the wrong way is turned to the room", "[obj][forgiving]") {
    TempFolder dir;
    dir.write("m.mtl", "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 10 10 10\n");
    // A floor facing up, a ceiling at y = 2 facing down, and a lamp 1 cm below the ceiling whose
    // front faces up, into the ceiling.
    const std::string text =
        "mtllib m.mtl\nusemtl white\n"
        "v 0 0 0\nv 0 0 2\nv 2 0 2\nv 2 0 0\nf 1 2 3 4\n"
        "v 0 2 0\nv 2 2 0\nv 2 2 2\nv 0 2 2\nf 5 6 7 8\n"
        "usemtl lamp\n"
        "v 0.5 1.99 0.5\nv 0.5 1.99 1.5\nv 1.5 1.99 1.5\nv 1.5 1.99 0.5\n"
        "f 9 10 11 12\n";
    const std::string obj = dir.write("lamp.obj", text);
    const Scene s = load_obj(obj);
    const int lamp = 2;  // the file's third face (the surfaces are lamp.0, lamp.1, lamp.2)
    REQUIRE(s.surfaces.size() == 3);
    CHECK(s.surfaces[size_t(lamp)].surface.normal(0.5, 0.5).y == Approx(-1));
    const SceneWarning* w = warning_of(s, "light turned around");
    REQUIRE(w != nullptr);
    CHECK_THAT(w->text(), Contains("lamp.obj:18: light 'lamp.2' faced a surface 0.01 away"));
    // Strict: left as it is, and said.
    const Scene strict = load_obj(obj, ImportOptions{true});
    CHECK(strict.surfaces[size_t(lamp)].surface.normal(0.5, 0.5).y == Approx(1));
    CHECK(warning_of(strict, "light faces away") != nullptr);
    // A lamp that faces the room is left alone, without a word.
    const std::string right =
        dir.write("right.obj", text.substr(0, text.size() - std::string("f 9 10 11 12\n").size()) +
                                   "f 12 11 10 9\n");
    const Scene r = load_obj(right);
    CHECK(r.warnings.empty());
    CHECK(r.surfaces[size_t(lamp)].surface.normal(0.5, 0.5).y == Approx(-1));
}

TEST_CASE("obj_import: a two_sided material gets back faces", "[obj][scene_io]") {
    std::istringstream in(
        "material lamp emission 5 5 5 two_sided\n"
        "quad l lamp 0 0 0  1 0 0  1 1 0  0 1 0\n"
        "material white reflectance 0.5 0.5 0.5\n"
        "quad w white 0 0 1  1 0 1  1 1 1  0 1 1\n");
    const Scene s = parse_scene(in, "two.scene");
    REQUIRE(s.surfaces.size() == 3);
    const SceneSurface& back = s.surfaces[2];
    CHECK(back.name == "l.back");
    CHECK(back.material == s.surfaces[0].material);
    CHECK(back.surface.normal(0.3, 0.6).z == Approx(-s.surfaces[0].surface.normal(0.3, 0.6).z));
    CHECK(back.surface.area() == Approx(s.surfaces[0].surface.area()));
    std::istringstream twice("material lamp emission 5 5 5 two_sided two_sided\n");
    CHECK_THROWS_WITH(parse_scene(twice, "t.scene"), Contains("'two_sided' is given twice"));
}

TEST_CASE("obj_import: Surface::reversed keeps the points and turns the normal", "[obj][surface]") {
    const Surface kinds[] = {
        Surface::planar_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}),
        Surface::bilinear_patch({0, 0, 0}, {1, 0, 0.2}, {1, 1, 0}, {0, 1, 0.1}),
        Surface::cylinder({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 1, 2, 0, 1.5),
        Surface::sphere({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 1, 0.2, 1.2, 0, 2),
        Surface::disk({0, 0, 0}, {0, 0, 1}, {1, 0, 0}, 0.2, 1, 0, 3),
    };
    for (const Surface& s : kinds) {
        const Surface r = s.reversed();
        CAPTURE(int(s.kind()));
        CHECK(r.area() == Approx(s.area()));
        // Each point of r is a point of s with the opposite normal.
        for (double u : {0.2, 0.8})
            for (double v : {0.3, 0.6}) {
                const Vec3 x = r.point(u, v);
                double best = HUGE_VAL, bu = 0, bv = 0;
                for (int i = 0; i <= 200; ++i)
                    for (int j = 0; j <= 200; ++j) {
                        const double d = length(s.point(i / 200.0, j / 200.0) - x);
                        if (d < best) best = d, bu = i / 200.0, bv = j / 200.0;
                    }
                CHECK(best < 0.02);
                CHECK(dot(r.normal(u, v), s.normal(bu, bv)) < -0.99);
            }
    }
}
