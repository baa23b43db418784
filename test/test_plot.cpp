// test/test_plot.cpp - the examples' plotting library (examples/common/plot.h): font coverage,
// nice ticks, colour maps, rasterisation of lines and text, composition, and a PNG round trip.
#include <stb_image.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "examples/common/plot.h"

using namespace mbr;

namespace {

bool is_white(Rgb c) {
    return c.r == 1 && c.g == 1 && c.b == 1;
}
bool is_black(Rgb c) {
    return c.r == 0 && c.g == 0 && c.b == 0;
}

// Is step 1, 2 or 5 times a power of ten (to rounding)?
bool is_nice(double step) {
    const double f = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    return std::fabs(f - 1) < 1e-9 || std::fabs(f - 2) < 1e-9 || std::fabs(f - 5) < 1e-9;
}

}  // namespace

// === Font

TEST_CASE("plot: every printable ASCII character has its own glyph", "[plot]") {
    std::set<std::pair<std::array<std::uint8_t, 7>, int>> seen;
    for (char c = ' '; c <= '~'; ++c) {
        CAPTURE(c);
        REQUIRE(has_glyph(c));
        const Glyph g = glyph(c);
        int ink = 0;
        for (std::uint8_t row : g.rows) {
            CHECK(row < (1u << glyph_width));  // five columns only
            for (int b = 0; b < glyph_width; ++b) ink += (row >> b) & 1;
        }
        CHECK((c == ' ') == (ink == 0));  // only the space is blank
        CHECK(g.drop >= 0);
        CHECK(g.drop <= 2);                           // descenders stay inside the line height
        CHECK(seen.insert({g.rows, g.drop}).second);  // no two glyphs alike
    }
    CHECK(seen.size() == 95);
    CHECK_FALSE(has_glyph('\n'));
    CHECK_FALSE(has_glyph('\x7f'));
    CHECK(glyph('\t').rows[0] == 0x1f);  // the hollow box
    CHECK(text_width("", 2) == 0);
    CHECK(text_width("DN_3", 1) == 4 * glyph_advance - 1);
    CHECK(text_width("DN_3", 3) == 3 * (4 * glyph_advance - 1));
}

TEST_CASE("plot: text sets exactly the glyph's pixels, scaled and rotated", "[plot]") {
    const Glyph g = glyph('F');
    for (int scale : {1, 2}) {
        CAPTURE(scale);
        Image img(20, 20, {1, 1, 1});
        Canvas(img).text(1, 2, "F", {0, 0, 0}, scale);
        for (int y = 0; y < 20; ++y)
            for (int x = 0; x < 20; ++x) {
                const int col = (x - 1) / scale, row = (y - 2) / scale;
                const bool ink = x >= 1 && y >= 2 && col < glyph_width && row < glyph_height &&
                                 (g.rows[row] >> (glyph_width - 1 - col)) & 1;
                CAPTURE(x, y);
                CHECK(is_black(img.at(x, y)) == ink);
            }
    }
    // Vertical: a quarter turn anticlockwise, read bottom to top from the anchor.
    Image img(20, 20, {1, 1, 1});
    Canvas(img).text(3, 15, "F", {0, 0, 0}, 1, Align::start, Align::start, true);
    for (int row = 0; row < glyph_height; ++row)
        for (int col = 0; col < glyph_width; ++col) {
            const bool ink = (g.rows[row] >> (glyph_width - 1 - col)) & 1;
            CAPTURE(row, col);
            CHECK(is_black(img.at(3 + row, 15 - col - 1)) == ink);
        }
}

// === Ticks

TEST_CASE("plot: nice ticks are 1, 2, 5 x 10^k inside the range", "[plot]") {
    CHECK(nice_step(1, 5) == Approx(0.2));
    CHECK(nice_step(100, 5) == Approx(20));
    CHECK(nice_step(3.5, 7) == Approx(0.5));  // 0.5 exactly
    CHECK(nice_step(12, 7) == Approx(2));     // 1.71 rounds to 2
    CHECK(nice_step(3.7, 7) == Approx(0.5));  // 0.53 rounds to 0.5
    CHECK(nice_step(8, 1) == Approx(10));     // 8 rounds up to 10
    // Heckbert's thresholds on the mantissa: 1.5, 3 and 7.
    CHECK(nice_step(1.4, 1) == Approx(1));
    CHECK(nice_step(1.6, 1) == Approx(2));
    CHECK(nice_step(2.9, 1) == Approx(2));
    CHECK(nice_step(3.1, 1) == Approx(5));
    CHECK(nice_step(6.9, 1) == Approx(5));
    CHECK(nice_step(7.1, 1) == Approx(10));
    CHECK(next_nice_step(1) == Approx(2));
    CHECK(next_nice_step(0.2) == Approx(0.5));
    CHECK(next_nice_step(5e-3) == Approx(1e-2));

    const std::vector<double> unit = nice_ticks(0, 1, 5);
    REQUIRE(unit.size() == 6);
    for (int i = 0; i <= 5; ++i) CHECK(unit[i] == Approx(0.2 * i).margin(1e-15));

    const std::vector<double> mixed = nice_ticks(-1.2, 2.3, 6);  // step 0.5: -1 .. 2
    REQUIRE(mixed.size() == 7);
    CHECK(mixed.front() == Approx(-1));
    CHECK(mixed.back() == Approx(2));
    CHECK(mixed[2] == 0.0);  // snapped to exactly zero

    struct Range {
        double lo, hi;
        int target;
    };
    for (Range r : {Range{0, 1, 5}, Range{-1.2, 2.3, 6}, Range{3.7e-5, 9.1e-5, 4},
                    Range{-4.5, 7.5, 7}, Range{1234, 98765, 8}, Range{-0.013, -0.002, 5}}) {
        CAPTURE(r.lo, r.hi, r.target);
        const double step = nice_step(r.hi - r.lo, r.target);
        CHECK(is_nice(step));
        const std::vector<double> t = nice_ticks(r.lo, r.hi, r.target);
        REQUIRE(t.size() >= 2);
        CHECK(t.front() >= r.lo - 1e-12 * step);
        CHECK(t.back() <= r.hi + 1e-12 * step);
        CHECK(t.front() - step < r.lo);  // no tick of the range is missing
        CHECK(t.back() + step > r.hi);
        for (size_t i = 1; i < t.size(); ++i) CHECK(t[i] - t[i - 1] == Approx(step));
    }

    CHECK(tick_label(0.5, 0.5) == "0.5");
    CHECK(tick_label(-1, 0.5) == "-1.0");
    CHECK(tick_label(2, 1) == "2");
    CHECK(tick_label(40, 20) == "40");
    CHECK(tick_label(0.75, 0.25) == "0.75");
    CHECK(tick_label(-1e-17, 0.2) == "0.0");  // never "-0"
    CHECK(tick_label(3e-5, 1e-5) == "3e-05");
}

// === Colour maps

TEST_CASE("plot: colour_map is viridis-like, monotone in luminance, with documented ends",
          "[plot]") {
    const Rgb lo = colour_map(0), hi = colour_map(1);
    CHECK(lo.r == Approx(68 / 255.0));
    CHECK(lo.g == Approx(1 / 255.0));
    CHECK(lo.b == Approx(84 / 255.0));
    CHECK(hi.r == Approx(253 / 255.0));
    CHECK(hi.g == Approx(231 / 255.0));
    CHECK(hi.b == Approx(37 / 255.0));
    double previous = -1;
    for (int i = 0; i <= 1000; ++i) {
        const Rgb c = colour_map(i / 1000.0);
        CAPTURE(i, c);
        for (int k = 0; k < 3; ++k) {
            CHECK(c[k] >= 0);
            CHECK(c[k] <= 1);
        }
        CHECK(luminance(c) > previous);
        previous = luminance(c);
    }
    CHECK(colour_map(-3) == lo);  // clamped
    CHECK(colour_map(7) == hi);
    CHECK(colour_map(NAN) == Rgb{0.5, 0.5, 0.5});

    // The diverging map: blue, white in the middle, red; luminance peaks at the middle.
    CHECK(diverging_map(0.5) == Rgb{1, 1, 1});
    CHECK(diverging_map(0).b > diverging_map(0).r);
    CHECK(diverging_map(1).r > diverging_map(1).b);
    for (int i = 1; i <= 500; ++i) {
        CAPTURE(i);
        CHECK(luminance(diverging_map(i / 1000.0)) > luminance(diverging_map((i - 1) / 1000.0)));
        CHECK(luminance(diverging_map(1 - i / 1000.0)) >
              luminance(diverging_map(1 - (i - 1) / 1000.0)));
    }
}

// === Canvas

TEST_CASE("plot: a 2 px line covers exactly the expected pixels", "[plot]") {
    SECTION("horizontal, on a pixel boundary") {
        Image img(20, 10, {1, 1, 1});
        Canvas(img).line({2, 5}, {17, 5}, {{0, 0, 0}, 2});
        for (int x = 0; x < 20; ++x) {
            CAPTURE(x);
            // Rows 4 and 5 have centres 0.5 from the line: fully inside a width of 2.
            if (x >= 2 && x < 17) {
                CHECK(is_black(img.at(x, 4)));
                CHECK(is_black(img.at(x, 5)));
            }
            for (int y : {0, 1, 2, 3, 6, 7, 8, 9}) CHECK(is_white(img.at(x, y)));
        }
        CHECK(is_white(img.at(0, 4)));  // beyond the round cap
        CHECK(is_white(img.at(19, 5)));
    }
    SECTION("vertical") {
        Image img(10, 20, {1, 1, 1});
        Canvas(img).line({4, 1}, {4, 18}, {{0, 0, 0}, 2});
        for (int y = 1; y < 18; ++y) {
            CAPTURE(y);
            CHECK(is_black(img.at(3, y)));
            CHECK(is_black(img.at(4, y)));
            CHECK(is_white(img.at(2, y)));
            CHECK(is_white(img.at(5, y)));
        }
    }
    SECTION("diagonal: anti-aliased, symmetric, nothing far away") {
        Image img(20, 20, {1, 1, 1});
        Canvas(img).line({2, 2}, {18, 18}, {{0, 0, 0}, 2});
        bool partial = false;
        for (int y = 0; y < 20; ++y)
            for (int x = 0; x < 20; ++x) {
                CAPTURE(x, y);
                const double v = img.at(x, y).r;
                CHECK(v == Approx(img.at(y, x).r));  // mirror symmetric about the diagonal
                if (x == y && x >= 3 && x < 17) CHECK(v == 0.0);  // centres on the line
                if (std::abs(x - y) >= 3) CHECK(v == 1.0);        // 2.1 px or more away
                partial = partial || (v > 0 && v < 1);
            }
        CHECK(partial);  // edges are blended, not stair-stepped
    }
    SECTION("polyline joints are drawn once; dashes leave gaps; the clip holds") {
        Image img(40, 12, {1, 1, 1});
        Canvas canvas(img);
        // Back and forth over the same pixels: a blended colour must not darken there.
        canvas.polyline({{2, 4}, {30, 4}, {10, 4}, {36, 4}}, {{0.5, 0.5, 0.5}, 2});
        for (int x = 0; x < 40; ++x) CHECK(img.at(x, 3).r >= 0.5);
        CHECK(img.at(20, 3).r == 0.5);
        canvas.line({2, 9}, {38, 9}, {{0, 0, 0}, 2, 4, 4});
        int n_ink = 0, n_paper = 0;
        for (int x = 4; x < 36; ++x) (img.at(x, 8).r < 0.5 ? n_ink : n_paper)++;
        CHECK(n_ink > 10);
        CHECK(n_paper > 10);
        canvas.set_clip({0, 0, 10, 12});
        canvas.fill_rect({5, 0, 20, 2}, {0, 0, 0});
        CHECK(is_black(img.at(9, 0)));
        CHECK(is_white(img.at(10, 0)));
    }
}

TEST_CASE("plot: scalar fields, colour bars and blit", "[plot]") {
    Image img(8, 8, {1, 1, 1});
    // A 2 x 2 field stretched over 4 x 4 pixels: each value fills one quadrant.
    draw_scalar_field(img, {2, 2, 4, 4}, {0.0, 1.0, 0.5, NAN}, 2, 2, 0.0, 1.0);
    CHECK(img.at(2, 2) == colour_map(0));
    CHECK(img.at(3, 3) == colour_map(0));
    CHECK(img.at(4, 2) == colour_map(1));
    CHECK(img.at(2, 5) == colour_map(0.5));
    CHECK(img.at(5, 5) == Rgb{0.5, 0.5, 0.5});
    CHECK(is_white(img.at(1, 1)));
    CHECK(is_white(img.at(6, 6)));

    Image bar(60, 200, {1, 1, 1});
    draw_colour_bar(bar, {0, 0, 60, 200}, -1, 1, "", colour_map, 1);
    // Vertical: high values at the top. Sample inside the 1 px border.
    const Rgb top = bar.at(5, 6), bottom = bar.at(5, 193);
    CHECK(luminance(top) > luminance(bottom));
    CHECK(luminance(top) > luminance(colour_map(0.9)));
    CHECK(luminance(bottom) < luminance(colour_map(0.1)));

    Image src(3, 2, {0, 0, 0});
    src.at(0, 0) = {1, 0, 0};
    Image dst(4, 4, {1, 1, 1});
    blit(dst, src, 2, 3);  // only the top row of src lands inside
    CHECK(dst.at(2, 3) == Rgb{1, 0, 0});
    CHECK(is_black(dst.at(3, 3)));
    CHECK(is_white(dst.at(1, 3)));
    CHECK(is_white(dst.at(2, 2)));
    blit(dst, src, -10, -10);  // wholly outside: no effect, no crash
    CHECK(dst.at(2, 3) == Rgb{1, 0, 0});
}

TEST_CASE("plot: wrap_text keeps every word, in order, within the width", "[plot]") {
    const std::string text = "the quick brown fox jumps over the lazy dog\nnext one";
    const int max_width = text_width("the quick brown", 2);
    const std::vector<std::string> lines = wrap_text(text, max_width, 2);
    std::string joined;
    for (const std::string& line : lines) {
        CAPTURE(line);
        CHECK(text_width(line, 2) <= max_width);
        joined += (joined.empty() ? "" : " ") + line;
    }
    CHECK(joined == "the quick brown fox jumps over the lazy dog next one");
    CHECK(lines.front() == "the quick brown");
    CHECK(lines.back() == "next one");  // the newline starts a line
    // A word longer than the width gets a line of its own, unbroken.
    const std::vector<std::string> long_word = wrap_text("a abcdefghij b", text_width("abc", 1), 1);
    REQUIRE(long_word.size() == 3);
    CHECK(long_word[1] == "abcdefghij");
}

TEST_CASE("plot: circles are outlines; concentric ones stay apart", "[plot]") {
    Image img(40, 40, {1, 1, 1});
    Canvas canvas(img);
    const Vec2 c{20, 20};
    canvas.circle(c, 6, {{0, 0, 0}, 2});
    canvas.circle(c, 13, {{0, 0, 0}, 2});
    // Coverage ramps over one pixel: a pixel whose centre is 0.52 px from the circle is 98 %
    // covered by a 2 px stroke.
    auto dark = [](Rgb c) { return max_abs(c) < 0.05; };
    CHECK(is_white(img.at(20, 20)));  // the centre stays empty
    CHECK(dark(img.at(26, 19)));      // on the inner circle (pixel centre 6.52 px out)
    CHECK(dark(img.at(19, 33)));      // on the outer circle (13.51 px out, below the centre)
    CHECK(is_white(img.at(29, 19)));  // between the two, 9.5 px out
    CHECK(is_white(img.at(0, 0)));    // outside both
}

TEST_CASE("plot: map_layout and draw_axes frame a hand-drawn area without touching it", "[plot]") {
    Image img(300, 260, {1, 1, 1});
    const PixelRect area{80, 20, 200, 160};
    const PlotLayout L = map_layout(area, -1, 3, 0, 1, 1);
    const Vec2 lower_left = L.to_pixel(-1, 0), upper_right = L.to_pixel(3, 1);
    CHECK(lower_left.x == Approx(area.x));
    CHECK(lower_left.y == Approx(area.bottom()));
    CHECK(upper_right.x == Approx(area.right()));
    CHECK(upper_right.y == Approx(area.y));
    REQUIRE(L.x_ticks.size() >= 2);
    for (double t : L.x_ticks) CHECK((t >= -1 && t <= 3));
    CHECK(is_nice(L.x_step));
    draw_axes(img, L, "s", "a long y label", {0, 0, 0}, 1);
    bool untouched = true;
    for (int y = area.y; y < area.bottom(); ++y)
        for (int x = area.x; x < area.right(); ++x) untouched = untouched && is_white(img.at(x, y));
    CHECK(untouched);
    CHECK(is_black(img.at(area.x - 1, area.y + 50)));  // the frame, just outside
    CHECK(is_black(img.at(area.x + 50, area.bottom() + 1)));
    CHECK(axes_margin(1) > 0);
}

TEST_CASE("plot: a colour scale runs from map(0) to map(1), log scales by decades", "[plot]") {
    for (bool log : {false, true}) {
        CAPTURE(log);
        Image img(300, 120, {1, 1, 1});
        const PixelRect bar{20, 30, 256, 20};
        draw_colour_scale(img, bar, log ? 1e-8 : 0.0, 1, "caption", colour_map, 1, log);
        auto close = [](Rgb a, Rgb b) { return max_abs(a - b) < 0.01; };
        CHECK(close(img.at(bar.x, bar.y + 10), colour_map(0.5 / bar.w)));
        CHECK(close(img.at(bar.right() - 1, bar.y + 10), colour_map(1 - 0.5 / bar.w)));
        // The middle of the bar: 0.5 on the linear scale, 1e-4 on the log one.
        CHECK(close(img.at(bar.x + 128, bar.y + 10), colour_map(128.5 / 256)));
    }
    Image img(100, 100, {1, 1, 1});
    CHECK_THROWS(draw_colour_scale(img, {10, 10, 50, 10}, 0, 1, "", colour_map, 1, true));
}

// === Plot

TEST_CASE("plot: layout maps the data ranges onto the plot area", "[plot]") {
    Plot plot;
    plot.title = "t";
    plot.x_label = "x";
    plot.y_label = "y";
    plot.x_min = -2;
    plot.x_max = 6;
    plot.add_line({-2, 0, 6}, {-1, 3, 0}, {});
    const PixelRect panel{10, 20, 400, 300};
    const PlotLayout L = plot.layout(panel);
    CHECK(L.area.x > panel.x);
    CHECK(L.area.y > panel.y);
    CHECK(L.area.right() <= panel.right());
    CHECK(L.area.bottom() <= panel.bottom());
    CHECK(L.x_min == -2);
    CHECK(L.x_max == 6);
    CHECK(L.y_min == Approx(-1 - 0.05 * 4));  // 5% padding of the auto range
    CHECK(L.y_max == Approx(3 + 0.05 * 4));
    const Vec2 bottom_left = L.to_pixel(L.x_min, L.y_min), top_right = L.to_pixel(L.x_max, L.y_max);
    CHECK(bottom_left.x == Approx(L.area.x));
    CHECK(bottom_left.y == Approx(L.area.bottom()));
    CHECK(top_right.x == Approx(L.area.right()));
    CHECK(top_right.y == Approx(L.area.y));
    CHECK(L.x_ticks.size() >= 3);
    CHECK(L.y_ticks.size() >= 3);
    for (double t : L.x_ticks) CHECK((t >= L.x_min && t <= L.x_max));
    for (double t : L.y_ticks) CHECK((t >= L.y_min && t <= L.y_max));
    CHECK(is_nice(L.x_step));
    CHECK(is_nice(L.y_step));

    Plot log_plot;  // log axis: ticks at whole decades
    log_plot.log_y = true;
    log_plot.add_line({1, 2, 3, 4}, {1e-1, 1e-3, 1e-5, 1e-6}, {});
    const PlotLayout G = log_plot.layout(panel);
    REQUIRE(G.y_ticks.size() >= 2);
    for (double t : G.y_ticks) CHECK(std::log10(t) == Approx(std::round(std::log10(t))));

    Plot empty;
    CHECK_THROWS(empty.layout(panel));  // nothing to show and no ranges
}

TEST_CASE("plot: a plot written to a temporary file is a readable PNG", "[plot]") {
    Plot plot;
    plot.title = "(a) sin(x)";
    plot.x_label = "x";
    plot.y_label = "sin(x)";
    std::vector<double> x, y;
    for (int i = 0; i <= 200; ++i) {
        x.push_back(0.05 * i);
        y.push_back(std::sin(0.05 * i));
    }
    plot.add_line(x, y, {{0.8, 0.2, 0.1}, 2}, "sin");
    plot.add_vline(Pi, {{0.4, 0.4, 0.4}, 1, 4, 3}, "pi");
    Image image(320, 200, {1, 1, 1});
    const PlotLayout L = plot.draw(image, {0, 0, 320, 200});

    // The curve passes through the peak (pi/2, 1): that pixel carries the line colour.
    const Vec2 peak = L.to_pixel(Pi / 2, 1);
    const Rgb at_peak = image.at(int(peak.x), int(peak.y));
    CHECK(at_peak.r > at_peak.b + 0.3);

    const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                       ("mbr_test_plot_" + std::to_string(getpid()) + ".png");
    write_png(path.string(), image);
    std::ifstream in(path, std::ios::binary);
    unsigned char head[24] = {};
    in.read(reinterpret_cast<char*>(head), sizeof head);
    REQUIRE(in.gcount() == 24);
    const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    for (int i = 0; i < 8; ++i) CHECK(head[i] == signature[i]);
    CHECK(std::string(reinterpret_cast<char*>(head) + 12, 4) == "IHDR");
    CHECK(((head[16] << 24) | (head[17] << 16) | (head[18] << 8) | head[19]) == 320);
    CHECK(((head[20] << 24) | (head[21] << 16) | (head[22] << 8) | head[23]) == 200);
    in.close();

    // Decoded, it holds the image we drew (8-bit rounding only).
    int w = 0, h = 0, n = 0;
    unsigned char* pixels = stbi_load(path.string().c_str(), &w, &h, &n, 3);
    REQUIRE(pixels != nullptr);
    CHECK(w == 320);
    CHECK(h == 200);
    int n_wrong = 0;
    for (int i = 0; i < w * h; ++i)
        for (int c = 0; c < 3; ++c)
            n_wrong += std::abs(pixels[3 * i + c] - std::lround(255 * image.pixels[i][c])) > 0;
    CHECK(n_wrong == 0);
    stbi_image_free(pixels);
    std::filesystem::remove(path);
}
