// test/test_render.cpp - the renderer (radiosity/output/render.h): radiance B / pi of the solved
// fields (eq. (20)) seen by the camera, one-sided surfaces, jitter that depends on the seed and not
// on the threads, sRGB tone mapping, Radiance RGBE files and the quadtree overlay.
//
// Independent references: a quad facing the camera squarely, whose (u, v) at a pixel is an affine
// function of the pixel coordinates worked out by hand; the sRGB decoder of texture.h; stb_image's
// PNG and HDR decoders and stb_image_write's run-length HDR encoder; hand-made RGBE bytes.
#include <stb_image.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "math/check.h"
#include "radiosity/geometry/texture.h"
#include "radiosity/output/render.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "test/report.h"

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mbr;

namespace {

constexpr int image_size = 32;
constexpr double quad_half = 1.25;  // the quad spans [-1.25, 1.25]^2 in the plane z = 0

// One planar quad in z = 0 with its front towards +z, and a camera at distance 1 with a 90 degree
// field of view: the view spans [-1, 1]^2 of the quad's plane, inside the quad, and pixel
// coordinates (x, y) meet the plane at (x / 16 - 1, 1 - y / 16). u grows to the right, v upwards.
Scene quad_scene(Vec3 eye = {0, 0, 1}, Vec3 look_at = {0, 0, 0}) {
    Scene scene;
    scene.materials.push_back({"grey", Texture::constant({0.5, 0.5, 0.5}), Texture()});
    const double a = quad_half;
    scene.surfaces.push_back(
        {"quad", Surface::planar_quad({-a, -a, 0}, {a, -a, 0}, {a, a, 0}, {-a, a, 0}), 0});
    scene.camera.eye = eye;
    scene.camera.look_at = look_at;
    scene.camera.up = {0, 1, 0};
    scene.camera.fov_degrees = 90;
    scene.camera.width = scene.camera.height = image_size;
    scene.has_camera = true;
    return scene;
}

// (u, v) of quad_scene's quad at image point (x, y), by hand.
Vec2 quad_uv(double x, double y) {
    const double p_x = 2 * x / image_size - 1, p_y = 1 - 2 * y / image_size;
    return {(p_x + quad_half) / (2 * quad_half), (p_y + quad_half) / (2 * quad_half)};
}

// B(u, v) = (u, v, 1): linear functions are reproduced exactly for m >= 2 by the Greville
// abscissae, sum_k 2^-j (k + m/2) N_m(2^j s - k) = s.
SplineField linear_field(int m, int level) {
    SplineField f(m, level);
    const int first = first_touching_index(m), n = touching_count(m, level);
    for (int k = first; k < first + n; ++k)
        for (int l = first; l < first + n; ++l)
            f.set_coefficient(
                k, l, {std::ldexp(k + 0.5 * m, -level), std::ldexp(l + 0.5 * m, -level), 1.0});
    return f;
}

Scene cornell_box(int size) {
    Scene scene = load_scene(std::string(MBR_SOURCE_DIR) + "/examples/scenes/cornell_box.scene");
    scene.camera.width = scene.camera.height = size;
    return scene;
}

// Each surface's reflectance as its radiosity: a stand-in for a solution.
std::vector<SplineField> reflectance_fields(const Scene& scene) {
    std::vector<SplineField> fields;
    for (size_t i = 0; i < scene.surfaces.size(); ++i)
        fields.push_back(SplineField::constant(2, 0, scene.material_of(int(i)).reflectance.mean()));
    return fields;
}

bool same_pixels(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height) return false;
    for (size_t p = 0; p < a.pixels.size(); ++p)
        if (!(a.pixels[p] == b.pixels[p])) return false;
    return true;
}

int n_not_black(const Image& image) {
    int n = 0;
    for (const Rgb& p : image.pixels) n += !(p == Rgb{0, 0, 0});
    return n;
}

std::string temp_path(const std::string& stem) {
    return (std::filesystem::temp_directory_path() /
            (stem + "_" + std::to_string(getpid()) + ".png"))
        .string();
}

Image read_hdr_string(const std::string& bytes) {
    std::istringstream in(bytes);
    return read_hdr(in, "test.hdr");
}

std::string hdr_string(const Image& image) {
    std::ostringstream out;
    write_hdr(out, image);
    return out.str();
}

void append_stb(void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

}  // namespace

TEST_CASE("render: a constant field filling the view renders to B / pi, in PNG and HDR",
          "[render]") {
    const Scene scene = quad_scene();
    const Octree octree = build_octree(scene);
    const Rgb B{0.3, 1.2, 2.5};
    const Rgb L = InvPi * B;
    RenderStats stats;
    const Image radiance = render_radiance(
        scene, octree, std::vector<SplineField>{SplineField::constant(4, 2, B)}, {}, &stats);
    REQUIRE(radiance.width == image_size);
    REQUIRE(radiance.height == image_size);
    CHECK(stats.n_camera_rays == 4L * image_size * image_size);
    CHECK(stats.n_front_hits == stats.n_camera_rays);
    int n_wrong = 0;
    for (const Rgb& p : radiance.pixels)
        for (int c = 0; c < 3; ++c)
            // The B-splines sum to one up to rounding of their 16 products and of the mean of four
            // equal samples: a few ulps.
            n_wrong += std::fabs(p[c] - L[c]) > 1e-14 * L[c];
    CHECK(n_wrong == 0);

    // Tone mapping is the sRGB curve (the inverse of texture.h's independent decoder), and the
    // PNG holds its 8-bit rounding.
    CHECK(linear_to_srgb(0.5) == Approx(0.7353569830524495).epsilon(1e-12));
    for (double x : {0.0, 0.001, 0.0031308, 0.02, 0.2, 0.7, 1.0})
        CHECK(srgb_to_linear(linear_to_srgb(x)) == Approx(x).margin(1e-12));
    const Image display = tone_map(radiance, 1);
    const std::string path = temp_path("mbr_test_render");
    write_png(path, display);
    int w = 0, h = 0, n = 0;
    unsigned char* png = stbi_load(path.c_str(), &w, &h, &n, 3);
    std::filesystem::remove(path);
    REQUIRE(png != nullptr);
    CHECK(w == image_size);
    CHECK(h == image_size);
    const long expected[3] = {std::lround(255 * linear_to_srgb(L.r)),
                              std::lround(255 * linear_to_srgb(L.g)),
                              std::lround(255 * linear_to_srgb(L.b))};
    // The same numbers by Python's floating point: 87.08, 166.13, 230.57 before rounding.
    CHECK(expected[0] == 87);
    CHECK(expected[1] == 166);
    CHECK(expected[2] == 231);
    n_wrong = 0;
    for (int p = 0; p < w * h; ++p)
        for (int c = 0; c < 3; ++c) n_wrong += png[3 * p + c] != expected[c];
    CHECK(n_wrong == 0);
    stbi_image_free(png);
    // Exposure scales before the clip: blue, 2 x 0.80, saturates.
    const Rgb bright = tone_map(radiance, 2).at(5, 7);
    CHECK(bright.r == Approx(linear_to_srgb(2 * L.r)).epsilon(1e-14));
    CHECK(bright.b == Approx(1.0).epsilon(1e-15));
    CHECK(bright.b == tone_map(radiance, 100).at(5, 7).b);

    // RGBE keeps 8 mantissa bits of the largest channel and decodes to the middle of the
    // interval: |error| <= max(r, g, b) / 256 (here 0.0031).
    const std::string hdr = hdr_string(radiance);
    const Image back = read_hdr_string(hdr);
    REQUIRE(back.width == image_size);
    REQUIRE(back.height == image_size);
    const double max_error = std::max({L.r, L.g, L.b}) / 256;
    n_wrong = 0;
    for (const Rgb& p : back.pixels)
        for (int c = 0; c < 3; ++c) n_wrong += std::fabs(p[c] - L[c]) > max_error;
    CHECK(n_wrong == 0);
    // stb_image decodes the same bytes to the bottom of the interval: within twice that.
    int n_channels = 0;
    float* stb = stbi_loadf_from_memory(reinterpret_cast<const stbi_uc*>(hdr.data()),
                                        static_cast<int>(hdr.size()), &w, &h, &n_channels, 3);
    REQUIRE(stb != nullptr);
    CHECK(w == image_size);
    CHECK(h == image_size);
    n_wrong = 0;
    for (int p = 0; p < w * h; ++p)
        for (int c = 0; c < 3; ++c) n_wrong += std::fabs(stb[3 * p + c] - L[c]) > 2 * max_error;
    CHECK(n_wrong == 0);
    stbi_image_free(stb);
}

TEST_CASE("render: the back of a one-sided surface and a miss are black", "[render]") {
    const std::vector<SplineField> B = {SplineField::constant(3, 1, {1, 2, 3})};
    SECTION("from behind the quad") {
        const Scene scene = quad_scene({0, 0, -1});
        RenderStats stats;
        const Image image = render_radiance(scene, build_octree(scene), B, {}, &stats);
        CHECK(stats.n_back_hits == stats.n_camera_rays);
        CHECK(n_not_black(image) == 0);
    }
    SECTION("looking away from the quad") {
        const Scene scene = quad_scene({0, 0, 1}, {0, 0, 2});
        RenderStats stats;
        const Image image = render_radiance(scene, build_octree(scene), B, {}, &stats);
        CHECK(stats.n_camera_rays == 4L * image_size * image_size);
        CHECK(stats.n_front_hits + stats.n_back_hits == 0);
        CHECK(n_not_black(image) == 0);
    }
    SECTION("an empty field") {
        const Scene scene = quad_scene();
        const Image image =
            render_radiance(scene, build_octree(scene), std::vector<SplineField>{SplineField()});
        CHECK(n_not_black(image) == 0);
    }
}

TEST_CASE("render: a surface's back is culled by default, black on request", "[render]") {
    // quad_scene's quad (z = 0, facing the camera at z = 1) behind a second quad at z = 0.5
    // that faces away from the camera and covers the whole view.
    Scene scene = quad_scene();
    const double a = 2 * quad_half;
    scene.surfaces.push_back(
        {"back", Surface::planar_quad({-a, -a, 0.5}, {-a, a, 0.5}, {a, a, 0.5}, {a, -a, 0.5}), 0});
    const std::vector<SplineField> B = {SplineField::constant(3, 1, {1, 1, 1}),
                                        SplineField::constant(3, 1, {5, 5, 5})};
    const Octree octree = build_octree(scene);
    RenderOptions black;
    black.back_faces = BackFaces::Black;
    RenderStats s_black, s_cull;
    const Image dark = render_radiance(scene, octree, B, black, &s_black);
    const Image seen = render_radiance(scene, octree, B, {}, &s_cull);
    CHECK(n_not_black(dark) == 0);
    CHECK(s_black.n_back_hits == s_black.n_camera_rays);
    // Culled: every ray goes on through the back and meets the far quad's front, B / pi = 1/pi.
    CHECK(s_cull.n_back_hits == s_cull.n_camera_rays);
    CHECK(s_cull.n_front_hits == s_cull.n_camera_rays);
    for (const Rgb& px : seen.pixels) CHECK(px.r == Approx(1 / Pi));
}

TEST_CASE("render: auto exposure shows the log-average luminance at 0.18", "[render]") {
    Image half(4, 2);  // four pixels of luminance 0.1, four of 1.0
    for (int x = 0; x < 4; ++x) {
        half.at(x, 0) = {0.1, 0.1, 0.1};
        half.at(x, 1) = {1, 1, 1};
    }
    CHECK(auto_exposure(half) == Approx(0.18 / std::sqrt(0.1)));
    Image with_black = half;  // unlit pixels (the background) do not count
    with_black.pixels.push_back({0, 0, 0});
    with_black.width = 9;
    with_black.height = 1;
    CHECK(auto_exposure(with_black) == Approx(auto_exposure(half)));
    CHECK(auto_exposure(Image(3, 3)) == 1);  // nothing lit: exposure 1
}

TEST_CASE("render: the framing camera stands up the way the lights hang", "[render]") {
    // The same open box turned so that z is up (the classic radiosity scenes' way): its light
    // on the ceiling faces down (-z), so the camera's up is +z and it looks horizontally.
    std::istringstream z_up(
        "material white reflectance 0.5 0.5 0.5\n"
        "material lamp reflectance 0 0 0 emission 5 5 5\n"
        "rectangle floor   white 0 0 0  2 0 0  0 3 0\n"
        "rectangle ceiling white 0 0 1  0 3 0  2 0 0\n"
        "rectangle light   lamp  0.5 1 0.99  0 1 0  1 0 0\n"
        "rectangle back    white 0 3 0  2 0 0  0 0 1\n");
    const Scene scene = parse_scene(z_up, "z_up.scene");
    CHECK(scene_up(scene) == Vec3{0, 0, 1});
    const Camera c = framing_camera(scene);
    CHECK(c.up == Vec3{0, 0, 1});
    const Vec3 f = normalize(c.look_at - c.eye);
    CHECK(f.z < 0);                        // a little from above
    CHECK(std::abs(f.z) < 0.2);            // but nearly horizontal
    CHECK(std::abs(f.y) > std::abs(f.x));  // through the open side y = 0, facing the back
    CHECK(c.eye.y < 0);
    // A light facing -x stands the camera on its side (up +x); a light that faces no axis
    // (along 1 1 1) leaves up at y.
    std::istringstream sideways(
        "material lamp reflectance 0 0 0 emission 5 5 5\n"
        "rectangle light lamp 0 0 0  0 0 1  0 1 0\n");
    CHECK(scene_up(parse_scene(sideways, "s.scene")) == Vec3{1, 0, 0});
    std::istringstream tilted(
        "material lamp reflectance 0 0 0 emission 5 5 5\n"
        "rectangle light lamp 0 0 0  1 -1 0  0 1 -1\n");
    CHECK(scene_up(parse_scene(tilted, "t.scene")) == Vec3{0, 1, 0});
}

TEST_CASE("render: the framing camera sees a whole box from its open side", "[render]") {
    // A box [0, 2] x [0, 1] x [0, 3] of five inward faces, open at z = 0 (the Cornell box's
    // shape): the camera stands on the open side and every corner of the bounds is in view.
    std::istringstream in(
        "material white reflectance 0.5 0.5 0.5\n"
        "rectangle floor   white 0 0 0  0 0 3  2 0 0\n"
        "rectangle ceiling white 0 1 0  2 0 0  0 0 3\n"
        "rectangle back    white 0 0 3  0 1 0  2 0 0\n"
        "rectangle left    white 0 0 0  0 1 0  0 0 3\n"
        "rectangle right   white 2 0 0  0 0 3  0 1 0\n");
    const Scene scene = parse_scene(in, "open.scene");
    REQUIRE_FALSE(scene.has_camera);
    const Camera c = framing_camera(scene);
    CHECK(c.eye.z < 0);  // the open side
    CHECK(c.width == 640);
    CHECK(c.height == 480);
    const Vec3 f = normalize(c.look_at - c.eye);
    const Vec3 right = normalize(cross(f, c.up)), up = cross(right, f);
    const double half_h = std::tan(0.5 * c.fov_degrees * Pi / 180),
                 half_w = half_h * c.width / c.height;
    const Box3 box = scene.bounds();
    for (int k = 0; k < 8; ++k) {
        const Vec3 corner{k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y,
                          k & 4 ? box.hi.z : box.lo.z};
        const Vec3 d = corner - c.eye;
        CAPTURE(k);
        REQUIRE(dot(d, f) > 0);
        CHECK(std::abs(dot(d, right) / dot(d, f)) < half_w);
        CHECK(std::abs(dot(d, up) / dot(d, f)) < half_h);
    }
    // Rendered from there with the default culling, the box's inside fills the middle.
    Scene shown = scene;
    shown.camera = c;
    shown.has_camera = true;
    std::vector<SplineField> B(scene.surfaces.size(), SplineField::constant(3, 0, {1, 1, 1}));
    RenderOptions o;
    o.samples_per_pixel = 1;
    const Image image = render_radiance(shown, build_octree(shown), B, o);
    const Rgb& middle = image.pixels[size_t(image.height / 2) * image.width + image.width / 2];
    CHECK(middle.r == Approx(1 / Pi));
}

TEST_CASE("render: a varying field is seen at the hit's (u, v)", "[render]") {
    const Scene scene = quad_scene();
    const Octree octree = build_octree(scene);
    for (int m = 2; m <= 4; ++m) {
        CAPTURE(m);
        const std::vector<SplineField> B = {linear_field(m, 2)};
        // Through pixel centres: the radiance is (u, v, 1) / pi at the (u, v) worked out by hand
        // (tolerance: rounding of the ray-plane intersection and the inverse bilinear map).
        for (int y = 0; y < image_size; y += 5)
            for (int x = 0; x < image_size; x += 3) {
                CAPTURE(x, y);
                const Rgb L =
                    radiance_along(scene, octree, B, camera_ray(scene.camera, x + 0.5, y + 0.5));
                const Vec2 uv = quad_uv(x + 0.5, y + 0.5);
                CHECK(Pi * L.r == Approx(uv.x).margin(1e-12));
                CHECK(Pi * L.g == Approx(uv.y).margin(1e-12));
                CHECK(Pi * L.b == Approx(1.0).margin(1e-12));
            }
        // A pixel averages jittered samples from inside its own footprint: u within the pixel's
        // column range, v within its row range (plus rounding), and the samples do spread.
        const Image image = render_radiance(scene, octree, B);
        int n_outside = 0, n_off_centre = 0;
        for (int y = 0; y < image_size; ++y)
            for (int x = 0; x < image_size; ++x) {
                const Vec2 lo = quad_uv(x, y + 1), hi = quad_uv(x + 1, y);
                const Rgb p = Pi * image.at(x, y);
                n_outside += p.r < lo.x - 1e-12 || p.r > hi.x + 1e-12 || p.g < lo.y - 1e-12 ||
                             p.g > hi.y + 1e-12;
                n_off_centre += std::fabs(p.r - quad_uv(x + 0.5, y + 0.5).x) > 1e-9;
            }
        CHECK(n_outside == 0);
        CHECK(n_off_centre > image_size * image_size / 2);
    }
}

TEST_CASE("render: the Cornell box camera puts the red wall on the left", "[render]") {
    // cornell_box.md: right-handed, image right = (look_at - eye) x up = -x, so the red wall
    // (x about 550) is on the left and the green wall (x = 0) on the right.
    const Scene scene = cornell_box(32);
    const Image image = render_radiance(scene, build_octree(scene), reflectance_fields(scene));
    const Rgb left = image.at(1, 16), right = image.at(30, 16);
    CAPTURE(left, right);
    CHECK(left.r > 5 * left.g);
    CHECK(right.g > 2 * right.r);
    // The light (reflectance 0.78 here) is at the top: row 0 is the top of the image.
    const Rgb top = image.at(16, 1), bottom = image.at(16, 30);
    CAPTURE(top, bottom);
    CHECK(top.r == Approx(0.725 * InvPi).epsilon(1e-12));     // the white ceiling
    CHECK(bottom.r == Approx(0.725 * InvPi).epsilon(1e-12));  // the white floor
}

TEST_CASE("render: the image depends on the seed, not on the threads", "[render]") {
    const Scene scene = cornell_box(40);
    const Octree octree = build_octree(scene);
    const std::vector<SplineField> B = reflectance_fields(scene);
    for (int spp : {4, 3}) {
        CAPTURE(spp);
        RenderOptions options;
        options.samples_per_pixel = spp;
        options.seed = 7;
#ifdef _OPENMP
        const int saved = omp_get_max_threads();
        omp_set_num_threads(1);
        const Image one = render_radiance(scene, octree, B, options);
        omp_set_num_threads(2);
        const Image two = render_radiance(scene, octree, B, options);
        omp_set_num_threads(saved);
        CHECK(same_pixels(one, two));
#endif
        const Image first = render_radiance(scene, octree, B, options);
        const Image again = render_radiance(scene, octree, B, options);
        CHECK(same_pixels(first, again));
        // Pixels across an edge of the box mix the two sides in proportions the jitter sets.
        options.seed = 8;
        const Image other = render_radiance(scene, octree, B, options);
        // (Inside a surface the constant field's value varies with (u, v) in the last bits
        // only: the B-splines sum to one up to rounding.)
        int n_differ = 0;
        for (size_t p = 0; p < first.pixels.size(); ++p)
            n_differ += max_abs(first.pixels[p] - other.pixels[p]) > 1e-12;
        test::report() << "render: spp " << spp << ", seeds 7 and 8 differ in " << n_differ
                       << " of " << first.pixels.size() << " pixels\n";
        CHECK(n_differ > 0);
        CHECK(n_differ < static_cast<int>(first.pixels.size()) / 2);  // edges only
    }
}

TEST_CASE("render: the overlay draws lines where cells meet and nowhere inside a cell",
          "[render]") {
    const Scene scene = quad_scene();
    const Octree octree = build_octree(scene);
    // Three level-1 cells and the fourth (u, v > 1/2: right, top) split in four. The quad's u is
    // 1/2 at pixel x = 16, 3/4 at x = 26; v is 1/2 at y = 16, 3/4 at y = 6 (quad_uv). Cells
    // outside the domain are ignored.
    const std::vector<std::vector<DyadicCell>> leaves = {
        {{1, 0, 0}, {1, 1, 0}, {1, 0, 1}, {2, 2, 2}, {2, 3, 2}, {2, 2, 3}, {2, 3, 3}, {1, -1, 0}}};
    const Rgb grey{0.5, 0.5, 0.5}, ink{0, 0, 0.1};
    Image display(image_size, image_size, grey);
    RenderStats stats;
    draw_quadtree_overlay(display, scene, octree, &leaves, ink, &stats);
    CHECK(stats.n_camera_rays == image_size * image_size);
    int n_wrong = 0, n_lines = 0;
    for (int y = 0; y < image_size; ++y)
        for (int x = 0; x < image_size; ++x) {
            // The pixel left of (above) each boundary carries the line.
            const bool line = x == 15 || y == 15 || (x == 25 && y < 16) || (y == 5 && x > 15);
            n_wrong += !(display.at(x, y) == (line ? ink : grey));
            n_lines += line;
        }
    CHECK(n_lines == 32 + 31 + 15 + 15);
    CHECK(n_wrong == 0);

    // Without a quadtree the surface is one cell: no line inside it.
    Image plain(image_size, image_size, grey);
    draw_quadtree_overlay(plain, scene, octree, nullptr, ink);
    const std::vector<std::vector<DyadicCell>> none(1);
    draw_quadtree_overlay(plain, scene, octree, &none, ink);
    CHECK(same_pixels(plain, Image(image_size, image_size, grey)));

    // render_display applies it over the tone-mapped image when asked.
    RenderOptions options;
    options.quadtree_overlay = true;
    options.overlay_colour = ink;
    const std::vector<SplineField> B = {SplineField::constant(2, 0, {1, 1, 1})};
    Image expected = tone_map(render_radiance(scene, octree, B, options), options.exposure);
    draw_quadtree_overlay(expected, scene, octree, &leaves, ink);
    CHECK(same_pixels(render_display(scene, octree, B, options, &leaves), expected));
}

TEST_CASE("render: write_hdr writes the header and the top row first", "[render]") {
    Image image(3, 2);
    image.at(0, 0) = {1, 0, 0};     // 1 = 0.5 x 2^1: mantissa 128, exponent 1 + 128
    image.at(2, 1) = {0, 0, 0.25};  // 0.5 x 2^-1
    image.at(1, 0) = {-1, NAN, 0};  // written as black
    const std::string hdr = hdr_string(image);
    const std::string head = "#?RADIANCE\n";
    REQUIRE(hdr.compare(0, head.size(), head) == 0);
    const std::string tail = "FORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 3\n";
    const size_t at = hdr.find(tail);
    REQUIRE(at != std::string::npos);
    const std::string pixels = hdr.substr(at + tail.size());
    REQUIRE(pixels.size() == 4 * 6);
    const auto byte = [&](int i) { return static_cast<unsigned char>(pixels[i]); };
    CHECK(byte(0) == 128);
    CHECK(byte(1) == 0);
    CHECK(byte(2) == 0);
    CHECK(byte(3) == 129);
    for (int i = 4; i < 8; ++i) CHECK(byte(i) == 0);
    CHECK(byte(22) == 128);
    CHECK(byte(23) == 127);
    const Image back = read_hdr_string(hdr);
    CHECK(back.at(0, 0).r == 128.5 / 128);  // the middle of the 8-bit interval
    CHECK(back.at(1, 0) == Rgb{0, 0, 0});
    CHECK(back.at(2, 1).b == 128.5 / 512);
}

TEST_CASE("render: read_hdr reads run-length scanlines", "[render]") {
    SECTION("hand-made bytes") {
        // Width 8: red a run of 8 x 128, green 8 literals 128..135, blue a run of 4 zeros then
        // 4 literal zeros, exponent a run of 129 (scale 2^(129 - 136) = 1/128).
        std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 8\n";
        const unsigned char data[] = {2,   2,   0,   8,   136, 128, 8, 128, 129, 130, 131, 132,
                                      133, 134, 135, 132, 0,   4,   0, 0,   0,   0,   136, 129};
        hdr.append(reinterpret_cast<const char*>(data), sizeof data);
        const Image image = read_hdr_string(hdr);
        REQUIRE(image.width == 8);
        REQUIRE(image.height == 1);
        for (int x = 0; x < 8; ++x) {
            CAPTURE(x);
            CHECK(image.at(x, 0).r == 128.5 / 128);
            CHECK(image.at(x, 0).g == (128 + x + 0.5) / 128);
            CHECK(image.at(x, 0).b == 0.5 / 128);
        }
    }
    SECTION("stb_image_write's encoder") {
        // Runs and literals both (stb writes a run where 4 or more bytes repeat), plus its
        // EXPOSURE= header line. Precision as for write_hdr: max(r, g, b) / 256.
        const int w = 40, h = 5;
        std::vector<float> rgb(size_t(3) * w * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                float* p = &rgb[3 * (size_t(y) * w + x)];
                p[0] = x < 20 ? 0.5f : 0.01f * float(x + y);
                p[1] = 3.0f;
                p[2] = float(y) * 1e-3f;
            }
        std::string hdr;
        REQUIRE(stbi_write_hdr_to_func(append_stb, &hdr, w, h, 3, rgb.data()) != 0);
        const Image image = read_hdr_string(hdr);
        REQUIRE(image.width == w);
        REQUIRE(image.height == h);
        int n_wrong = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float* p = &rgb[3 * (size_t(y) * w + x)];
                const double tol = std::max({p[0], p[1], p[2]}) / 256.0;
                for (int c = 0; c < 3; ++c) n_wrong += std::fabs(image.at(x, y)[c] - p[c]) > tol;
            }
        CHECK(n_wrong == 0);
    }
}

TEST_CASE("render: read_hdr refuses truncated and foreign files", "[render]") {
    Image image(9, 3, {0.2, 0.4, 0.8});
    const std::string good = hdr_string(image);
    REQUIRE(read_hdr_string(good).width == 9);

    const auto refused = [](const std::string& bytes, const std::string& what) {
        CAPTURE(what);
        try {
            read_hdr_string(bytes);
            FAIL("accepted");
        } catch (const InputError& e) {
            CHECK(e.file() == "test.hdr");
            CHECK(e.line() == 0);
            return e.message();
        }
        return std::string();
    };
    // Cut anywhere: inside the header, after the resolution line, inside the pixels.
    const size_t pixels_start = good.size() - 4 * 9 * 3;
    for (size_t cut : {size_t(0), size_t(5), size_t(12), pixels_start - 3, pixels_start,
                       pixels_start + 7, good.size() - 1})
        CHECK_THAT(refused(good.substr(0, cut), "cut at " + std::to_string(cut)),
                   Catch::Contains("truncated"));
    CHECK_THAT(refused("\x89PNG\r\n\x1a\n0000IHDR", "PNG"), Catch::Contains("not a Radiance"));
    CHECK_THAT(refused(std::string(100000, 'x'), "no newline"), Catch::Contains("not a Radiance"));
    CHECK_THAT(refused("#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\nabcd", "XYZE"),
               Catch::Contains("unsupported pixel format"));
    CHECK_THAT(refused("#?RADIANCE\n\n+Y 1 +X 1\nabcd", "orientation"),
               Catch::Contains("unsupported pixel order"));
    CHECK_THAT(refused("#?RADIANCE\n\n-Y one +X 1\nabcd", "resolution"),
               Catch::Contains("bad resolution line"));
    CHECK_THAT(refused("#?RADIANCE\n\n-Y 0 +X 1\n", "empty"), Catch::Contains("bad image size"));
    CHECK_THAT(refused("#?RADIANCE\n\n-Y 100000 +X 100000\n", "huge"),
               Catch::Contains("bad image size"));
    CHECK_THAT(refused("#?RADIANCE\nEXPOSURE=-1\n\n-Y 1 +X 1\nabcd", "exposure"),
               Catch::Contains("EXPOSURE"));
    // An old-style run: the pixel 1, 1, 1, 2 repeats the one before it twice.
    const char old_style[] = "#?RADIANCE\n\n-Y 1 +X 3\n\x80\0\0\x81\1\1\1\2\0\0\0\0";
    CHECK_THAT(refused(std::string(old_style, sizeof old_style - 1), "old-style"),
               Catch::Contains("old-style"));
    // Run-length data: a run past the scanline's end, a zero count, a wrong scanline length.
    std::string rle = "#?RADIANCE\n\n-Y 1 +X 8\n";
    rle += std::string("\x02\x02\x00\x08", 4);
    CHECK_THAT(refused(rle + "\x89\x80", "long run"), Catch::Contains("bad run-length"));
    CHECK_THAT(refused(rle + std::string(1, '\0'), "zero count"),
               Catch::Contains("bad run-length"));
    CHECK_THAT(refused(rle + "\x88\x80", "cut in a plane"), Catch::Contains("truncated"));
    std::string wrong = "#?RADIANCE\n\n-Y 1 +X 8\n";
    wrong += std::string("\x02\x02\x00\x09", 4);
    CHECK_THAT(refused(wrong, "length"), Catch::Contains("not the image's width"));
}
