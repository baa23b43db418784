// examples/common/plot.cpp - canvas, bitmap font, plots and colour maps (see plot.h).
#include "examples/common/plot.h"

#include <algorithm>
#include <cstdio>
#include <limits>

#include "math/check.h"

namespace mbr {

// === Font
//
// Our own 5x7 bitmap font for printable ASCII, drawn here as pictures: '#' is ink, '.' is
// paper. Capitals and digits fill the 7 rows; lower case has a 5-row x-height (rows 2-6);
// `drop` shifts a glyph down so that descenders hang below the baseline (row 6).

namespace {

struct GlyphArt {
    char ch;
    int drop;
    const char* rows[7];
};

// clang-format off
constexpr GlyphArt font_art[] = {
    {' ', 0, {".....", ".....", ".....", ".....", ".....", ".....", "....."}},
    {'!', 0, {"..#..", "..#..", "..#..", "..#..", "..#..", ".....", "..#.."}},
    {'"', 0, {".#.#.", ".#.#.", ".#.#.", ".....", ".....", ".....", "....."}},
    {'#', 0, {".#.#.", ".#.#.", "#####", ".#.#.", "#####", ".#.#.", ".#.#."}},
    {'$', 0, {"..#..", ".####", "#.#..", ".###.", "..#.#", "####.", "..#.."}},
    {'%', 0, {"##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##"}},
    {'&', 0, {".##..", "#..#.", "#.#..", ".#...", "#.#.#", "#..#.", ".##.#"}},
    {'\'', 0, {"..#..", "..#..", ".#...", ".....", ".....", ".....", "....."}},
    {'(', 0, {"...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#."}},
    {')', 0, {".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#..."}},
    {'*', 0, {".....", "..#..", "#.#.#", ".###.", "#.#.#", "..#..", "....."}},
    {'+', 0, {".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."}},
    {',', 1, {".....", ".....", ".....", ".....", ".##..", "..#..", ".#..."}},
    {'-', 0, {".....", ".....", ".....", "#####", ".....", ".....", "....."}},
    {'.', 0, {".....", ".....", ".....", ".....", ".....", ".##..", ".##.."}},
    {'/', 0, {".....", "....#", "...#.", "..#..", ".#...", "#....", "....."}},
    {'0', 0, {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
    {'1', 0, {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'2', 0, {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}},
    {'3', 0, {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}},
    {'4', 0, {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}},
    {'5', 0, {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
    {'6', 0, {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}},
    {'7', 0, {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}},
    {'8', 0, {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}},
    {'9', 0, {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}},
    {':', 0, {".....", ".##..", ".##..", ".....", ".##..", ".##..", "....."}},
    {';', 1, {".....", ".##..", ".##..", ".....", ".##..", "..#..", ".#..."}},
    {'<', 0, {"...#.", "..#..", ".#...", "#....", ".#...", "..#..", "...#."}},
    {'=', 0, {".....", ".....", "#####", ".....", "#####", ".....", "....."}},
    {'>', 0, {".#...", "..#..", "...#.", "....#", "...#.", "..#..", ".#..."}},
    {'?', 0, {".###.", "#...#", "....#", "...#.", "..#..", ".....", "..#.."}},
    {'@', 0, {".###.", "#...#", "....#", ".##.#", "#.#.#", "#.#.#", ".###."}},
    {'A', 0, {".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'B', 0, {"####.", "#...#", "#...#", "####.", "#...#", "#...#", "####."}},
    {'C', 0, {".###.", "#...#", "#....", "#....", "#....", "#...#", ".###."}},
    {'D', 0, {"###..", "#..#.", "#...#", "#...#", "#...#", "#..#.", "###.."}},
    {'E', 0, {"#####", "#....", "#....", "####.", "#....", "#....", "#####"}},
    {'F', 0, {"#####", "#....", "#....", "####.", "#....", "#....", "#...."}},
    {'G', 0, {".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####"}},
    {'H', 0, {"#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#"}},
    {'I', 0, {".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'J', 0, {"..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##.."}},
    {'K', 0, {"#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#"}},
    {'L', 0, {"#....", "#....", "#....", "#....", "#....", "#....", "#####"}},
    {'M', 0, {"#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"}},
    {'N', 0, {"#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#"}},
    {'O', 0, {".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'P', 0, {"####.", "#...#", "#...#", "####.", "#....", "#....", "#...."}},
    {'Q', 0, {".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#"}},
    {'R', 0, {"####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#"}},
    {'S', 0, {".####", "#....", "#....", ".###.", "....#", "....#", "####."}},
    {'T', 0, {"#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
    {'U', 0, {"#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###."}},
    {'V', 0, {"#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
    {'W', 0, {"#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#."}},
    {'X', 0, {"#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#"}},
    {'Y', 0, {"#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#.."}},
    {'Z', 0, {"#####", "....#", "...#.", "..#..", ".#...", "#....", "#####"}},
    {'[', 0, {".###.", ".#...", ".#...", ".#...", ".#...", ".#...", ".###."}},
    {'\\', 0, {".....", "#....", ".#...", "..#..", "...#.", "....#", "....."}},
    {']', 0, {".###.", "...#.", "...#.", "...#.", "...#.", "...#.", ".###."}},
    {'^', 0, {"..#..", ".#.#.", "#...#", ".....", ".....", ".....", "....."}},
    {'_', 1, {".....", ".....", ".....", ".....", ".....", ".....", "#####"}},
    {'`', 0, {".#...", "..#..", "...#.", ".....", ".....", ".....", "....."}},
    {'a', 0, {".....", ".....", ".###.", "....#", ".####", "#...#", ".####"}},
    {'b', 0, {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "####."}},
    {'c', 0, {".....", ".....", ".###.", "#....", "#....", "#...#", ".###."}},
    {'d', 0, {"....#", "....#", ".##.#", "#..##", "#...#", "#...#", ".####"}},
    {'e', 0, {".....", ".....", ".###.", "#...#", "#####", "#....", ".###."}},
    {'f', 0, {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#..."}},
    {'g', 2, {".####", "#...#", "#...#", "#...#", ".####", "....#", ".###."}},
    {'h', 0, {"#....", "#....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
    {'i', 0, {".....", "..#..", ".....", ".##..", "..#..", "..#..", ".###."}},
    {'j', 1, {"...#.", ".....", "..##.", "...#.", "...#.", "#..#.", ".##.."}},
    {'k', 0, {"#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."}},
    {'l', 0, {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'m', 0, {".....", ".....", "##.#.", "#.#.#", "#.#.#", "#.#.#", "#.#.#"}},
    {'n', 0, {".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
    {'o', 0, {".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."}},
    {'p', 2, {"####.", "#...#", "#...#", "#...#", "####.", "#....", "#...."}},
    {'q', 2, {".####", "#...#", "#...#", "#...#", ".####", "....#", "....#"}},
    {'r', 0, {".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."}},
    {'s', 0, {".....", ".....", ".####", "#....", ".###.", "....#", "####."}},
    {'t', 0, {".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##."}},
    {'u', 0, {".....", ".....", "#...#", "#...#", "#...#", "#..##", ".##.#"}},
    {'v', 0, {".....", ".....", "#...#", "#...#", "#...#", ".#.#.", "..#.."}},
    {'w', 0, {".....", ".....", "#...#", "#...#", "#.#.#", "#.#.#", ".#.#."}},
    {'x', 0, {".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"}},
    {'y', 2, {"#...#", "#...#", "#...#", "#...#", ".####", "....#", ".###."}},
    {'z', 0, {".....", ".....", "#####", "...#.", "..#..", ".#...", "#####"}},
    {'{', 0, {"...#.", "..#..", "..#..", ".#...", "..#..", "..#..", "...#."}},
    {'|', 0, {"..#..", "..#..", "..#..", "..#..", "..#..", "..#..", "..#.."}},
    {'}', 0, {".#...", "..#..", "..#..", "...#.", "..#..", "..#..", ".#..."}},
    {'~', 0, {".....", ".....", ".#...", "#.#.#", "...#.", ".....", "....."}},
};
// clang-format on

constexpr int n_font_glyphs = sizeof(font_art) / sizeof(font_art[0]);
static_assert(n_font_glyphs == '~' - ' ' + 1, "one glyph per printable ASCII character");

Glyph pack(const GlyphArt& art) {
    Glyph g;
    g.drop = art.drop;
    for (int row = 0; row < glyph_height; ++row) {
        std::uint8_t bits = 0;
        for (int col = 0; col < glyph_width; ++col)
            if (art.rows[row][col] == '#') bits |= std::uint8_t(1u << (glyph_width - 1 - col));
        g.rows[row] = bits;
    }
    return g;
}

}  // namespace

bool has_glyph(char c) {
    return c >= ' ' && c <= '~';
}

Glyph glyph(char c) {
    if (has_glyph(c)) {
        const GlyphArt& art = font_art[c - ' '];
        MBR_CHECK(art.ch == c);  // the table is in code order
        return pack(art);
    }
    Glyph box;  // hollow box for anything else
    box.rows = {0x1f, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1f};
    return box;
}

int text_width(const std::string& s, int scale) {
    if (s.empty()) return 0;
    return scale * (glyph_advance * static_cast<int>(s.size()) - (glyph_advance - glyph_width));
}

std::vector<std::string> wrap_text(const std::string& s, int max_width, int scale) {
    std::vector<std::string> lines;
    size_t start = 0;
    while (start <= s.size()) {
        const size_t newline = std::min(s.find('\n', start), s.size());
        const std::string paragraph = s.substr(start, newline - start);
        std::string line;
        size_t i = 0;
        while (i < paragraph.size()) {
            const size_t space = std::min(paragraph.find(' ', i), paragraph.size());
            const std::string word = paragraph.substr(i, space - i);
            const std::string joined = line.empty() ? word : line + " " + word;
            if (!line.empty() && text_width(joined, scale) > max_width) {
                lines.push_back(line);
                line = word;
            } else {
                line = joined;
            }
            i = space + 1;
        }
        lines.push_back(line);
        start = newline + 1;
    }
    return lines;
}

// === Canvas

namespace {

PixelRect intersect(const PixelRect& a, const PixelRect& b) {
    int x0 = std::max(a.x, b.x), y0 = std::max(a.y, b.y);
    int x1 = std::min(a.right(), b.right()), y1 = std::min(a.bottom(), b.bottom());
    return {x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0)};
}

// The pixels whose centres may lie within `reach` of the box [x0, x1] x [y0, y1], clipped.
PixelRect reach_box(double x0, double x1, double y0, double y1, double reach,
                    const PixelRect& clip) {
    auto lo = [](double v) { return static_cast<int>(std::max(-1e9, std::floor(v))); };
    auto hi = [](double v) { return static_cast<int>(std::min(1e9, std::ceil(v))); };
    int ix0 = lo(x0 - reach), iy0 = lo(y0 - reach);
    int ix1 = hi(x1 + reach), iy1 = hi(y1 + reach);
    return intersect({ix0, iy0, ix1 - ix0 + 1, iy1 - iy0 + 1}, clip);
}

}  // namespace

Canvas::Canvas(Image& image) : image_(image), clip_{0, 0, image.width, image.height} {}

void Canvas::set_clip(const PixelRect& r) {
    clip_ = intersect(r, {0, 0, image_.width, image_.height});
}

void Canvas::reset_clip() {
    clip_ = {0, 0, image_.width, image_.height};
}

void Canvas::blend(int x, int y, Rgb c, double alpha) {
    if (x < clip_.x || y < clip_.y || x >= clip_.right() || y >= clip_.bottom()) return;
    alpha = std::clamp(alpha, 0.0, 1.0);
    Rgb& p = image_.at(x, y);
    p = (1 - alpha) * p + alpha * c;
}

void Canvas::fill_rect(const PixelRect& r, Rgb c) {
    PixelRect q = intersect(r, clip_);
    for (int y = q.y; y < q.bottom(); ++y)
        for (int x = q.x; x < q.right(); ++x) image_.at(x, y) = c;
}

void Canvas::stroke_rect(const PixelRect& r, Rgb c, int thickness) {
    int t = std::min({thickness, r.w, r.h});
    if (t <= 0) return;
    fill_rect({r.x, r.y, r.w, t}, c);
    fill_rect({r.x, r.bottom() - t, r.w, t}, c);
    fill_rect({r.x, r.y, t, r.h}, c);
    fill_rect({r.right() - t, r.y, t, r.h}, c);
}

void Canvas::line(Vec2 a, Vec2 b, const Stroke& stroke) {
    polyline({a, b}, stroke);
}

void Canvas::polyline(const std::vector<Vec2>& points, const Stroke& stroke) {
    if (points.empty() || !(stroke.width > 0)) return;
    // Coverage of a pixel = how far its centre lies inside the stroke's edge, clamped to [0, 1]
    // (a one-pixel ramp). Taking the maximum over the segments before blending draws each
    // pixel once, so joints do not darken where consecutive segments overlap.
    const double radius = 0.5 * stroke.width;
    double bx0 = HUGE_VAL, bx1 = -HUGE_VAL, by0 = HUGE_VAL, by1 = -HUGE_VAL;
    for (Vec2 p : points) {
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) return;
        bx0 = std::min(bx0, p.x), bx1 = std::max(bx1, p.x);
        by0 = std::min(by0, p.y), by1 = std::max(by1, p.y);
    }
    const PixelRect box = reach_box(bx0, bx1, by0, by1, radius + 1, clip_);
    if (box.w <= 0 || box.h <= 0) return;
    std::vector<float> cover(size_t(box.w) * box.h, 0.0f);

    const bool dashed = stroke.dash > 0 && stroke.gap > 0;
    const double period = stroke.dash + stroke.gap;
    double arc_start = 0;  // arc length at the start of the current segment (dash phase)
    const size_t n_segments = points.size() == 1 ? 1 : points.size() - 1;
    for (size_t i = 0; i < n_segments; ++i) {
        const Vec2 a = points[i], b = points[std::min(i + 1, points.size() - 1)];
        const Vec2 d = b - a;
        const double len2 = dot(d, d), len = std::sqrt(len2);
        const PixelRect q = reach_box(std::min(a.x, b.x), std::max(a.x, b.x), std::min(a.y, b.y),
                                      std::max(a.y, b.y), radius + 1, box);
        for (int y = q.y; y < q.bottom(); ++y)
            for (int x = q.x; x < q.right(); ++x) {
                const Vec2 c{x + 0.5, y + 0.5};
                const double t = len2 > 0 ? std::clamp(dot(c - a, d) / len2, 0.0, 1.0) : 0.0;
                const Vec2 off = c - (a + t * d);
                double cov = std::clamp(radius + 0.5 - std::sqrt(dot(off, off)), 0.0, 1.0);
                if (cov <= 0) continue;
                if (dashed) {
                    // Signed distance along the line into the nearest dash, ramped like the edge.
                    const double phase = std::fmod(arc_start + t * len, period);
                    const double inside = phase <= stroke.dash
                                              ? std::min(phase, stroke.dash - phase)
                                              : -std::min(phase - stroke.dash, period - phase);
                    cov *= std::clamp(inside + 0.5, 0.0, 1.0);
                }
                float& slot = cover[size_t(y - box.y) * box.w + (x - box.x)];
                slot = std::max(slot, static_cast<float>(cov));
            }
        arc_start += len;
    }
    for (int y = box.y; y < box.bottom(); ++y)
        for (int x = box.x; x < box.right(); ++x) {
            const float cov = cover[size_t(y - box.y) * box.w + (x - box.x)];
            if (cov > 0) blend(x, y, stroke.colour, cov);
        }
}

void Canvas::disc(Vec2 centre, double radius, Rgb c) {
    const PixelRect q = reach_box(centre.x, centre.x, centre.y, centre.y, radius + 1, clip_);
    for (int y = q.y; y < q.bottom(); ++y)
        for (int x = q.x; x < q.right(); ++x) {
            const Vec2 off = Vec2{x + 0.5, y + 0.5} - centre;
            const double cov = std::clamp(radius + 0.5 - std::sqrt(dot(off, off)), 0.0, 1.0);
            if (cov > 0) blend(x, y, c, cov);
        }
}

void Canvas::circle(Vec2 centre, double radius, const Stroke& stroke) {
    if (!(stroke.width > 0) || !(radius >= 0)) return;
    // Coverage from the distance to the circle, ramped over one pixel like line().
    const double half = 0.5 * stroke.width;
    const PixelRect q = reach_box(centre.x, centre.x, centre.y, centre.y, radius + half + 1, clip_);
    for (int y = q.y; y < q.bottom(); ++y)
        for (int x = q.x; x < q.right(); ++x) {
            const Vec2 off = Vec2{x + 0.5, y + 0.5} - centre;
            const double d = std::fabs(std::sqrt(dot(off, off)) - radius);
            const double cov = std::clamp(half + 0.5 - d, 0.0, 1.0);
            if (cov > 0) blend(x, y, stroke.colour, cov);
        }
}

void Canvas::text(int x, int y, const std::string& s, Rgb c, int scale, Align h_align,
                  Align v_align, bool vertical) {
    MBR_CHECK(scale >= 1);
    // Work in the text's own frame: u along the text, v downwards from the top of the caps.
    const int width = text_width(s, scale), cap = glyph_height * scale;
    const int u0 = h_align == Align::start ? 0 : (h_align == Align::centre ? -width / 2 : -width);
    const int v0 = v_align == Align::start ? 0 : (v_align == Align::centre ? -cap / 2 : -cap);
    auto put = [&](int u, int v) {  // one font pixel, scale x scale image pixels
        for (int j = 0; j < scale; ++j)
            for (int i = 0; i < scale; ++i) {
                const int uu = u0 + u + i, vv = v0 + v + j;
                if (vertical)
                    blend(x + vv, y - uu - 1, c);  // a quarter turn anticlockwise
                else
                    blend(x + uu, y + vv, c);
            }
    };
    for (size_t k = 0; k < s.size(); ++k) {
        const Glyph g = glyph(s[k]);
        const int u_char = static_cast<int>(k) * glyph_advance * scale;
        for (int row = 0; row < glyph_height; ++row)
            for (int col = 0; col < glyph_width; ++col)
                if (g.rows[row] & (1u << (glyph_width - 1 - col)))
                    put(u_char + col * scale, (row + g.drop) * scale);
    }
}

// === Ticks

double nice_step(double span, int target_intervals) {
    MBR_CHECK_MSG(std::isfinite(span) && span > 0 && target_intervals >= 1,
                  "span = " << span << ", target_intervals = " << target_intervals);
    // Heckbert's rounding ("Nice numbers for graph labels", Graphics Gems 1990): the mantissa
    // f of span / target goes to 1 below 1.5, to 2 below 3, to 5 below 7, else to 10.
    const double raw = span / target_intervals;
    const double decade = std::pow(10.0, std::floor(std::log10(raw)));
    const double f = raw / decade;
    if (f < 1.5) return decade;
    if (f < 3) return 2 * decade;
    if (f < 7) return 5 * decade;
    return 10 * decade;
}

double next_nice_step(double step) {
    MBR_CHECK(std::isfinite(step) && step > 0);
    const double decade = std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    const double f = step / decade;
    if (f < 1.5) return 2 * decade;
    if (f < 3.5) return 5 * decade;
    return 10 * decade;
}

std::vector<double> ticks_with_step(double lo, double hi, double step) {
    MBR_CHECK_MSG(std::isfinite(lo) && std::isfinite(hi) && lo <= hi && step > 0,
                  "lo = " << lo << ", hi = " << hi << ", step = " << step);
    const double slack = 1e-9;  // in steps: ticks at the ends survive rounding of lo and hi
    const double first = std::ceil(lo / step - slack), last = std::floor(hi / step + slack);
    std::vector<double> ticks;
    for (double k = first; k <= last && ticks.size() < 10000; ++k) {
        const double v = k * step;
        ticks.push_back(std::fabs(v) < slack * step ? 0.0 : v);
    }
    return ticks;
}

std::vector<double> nice_ticks(double lo, double hi, int target_intervals) {
    return ticks_with_step(lo, hi, nice_step(hi - lo, target_intervals));
}

std::string tick_label(double value, double step) {
    if (std::fabs(value) < 1e-9 * step) value = 0;  // never "-0"
    char buf[64];
    const double magnitude = std::max(std::fabs(value), step);
    if (magnitude >= 1e6 || step < 1e-4) {
        std::snprintf(buf, sizeof buf, "%g", value);
    } else {
        // The fewest decimals that write the step exactly (0.5 -> 1, 0.25 -> 2, 20 -> 0).
        int decimals = 0;
        for (double scaled = step; decimals < 12; ++decimals, scaled *= 10)
            if (std::fabs(scaled - std::round(scaled)) < 1e-9 * scaled) break;
        std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    }
    return buf;
}

// === Plot

namespace {

double axis_value(double v, bool log) {
    return log ? std::log10(v) : v;
}
bool usable(double v, bool log) {
    return std::isfinite(v) && (!log || v > 0);
}

// Where one axis goes: its transformed range and its ticks for a given pixel length.
struct AxisTicks {
    std::vector<double> ticks;  // in data units
    double step = 1;            // in transformed units
};

// Ticks for an axis of `length` pixels: nice steps, coarsened until neighbouring labels
// (measured by `label_extent`, pixels along the axis) leave at least `min_gap` pixels free.
template <class Extent>
AxisTicks axis_ticks(double t0, double t1, bool log, int length, int target, Extent label_extent,
                     int min_gap) {
    AxisTicks out;
    const double span = t1 - t0;
    double step = nice_step(span, std::max(1, target));
    if (log) step = std::max(1.0, std::round(step));  // whole decades
    for (int attempt = 0; attempt < 20; ++attempt) {
        std::vector<double> t = ticks_with_step(t0, t1, step);
        int widest = 0;
        for (double v : t)
            widest = std::max(widest, label_extent(log ? std::pow(10.0, v) : v, step));
        const double step_px = step / span * length;
        if (t.size() <= 2 || step_px >= widest + min_gap) {
            out.step = step;
            for (double v : t) out.ticks.push_back(log ? std::pow(10.0, v) : v);
            return out;
        }
        step = next_nice_step(step);
    }
    out.step = step;
    return out;
}

std::string axis_label(double value, double step, bool log) {
    if (!log) return tick_label(value, step);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", value);
    return buf;
}

}  // namespace

Vec2 PlotLayout::to_pixel(double x, double y) const {
    const double tx = axis_value(x, log_x), ty = axis_value(y, log_y);
    const double tx0 = axis_value(x_min, log_x), tx1 = axis_value(x_max, log_x);
    const double ty0 = axis_value(y_min, log_y), ty1 = axis_value(y_max, log_y);
    return {area.x + (tx - tx0) / (tx1 - tx0) * area.w,
            area.y + area.h - (ty - ty0) / (ty1 - ty0) * area.h};
}

void Plot::add(Series series) {
    MBR_CHECK_MSG(series.x.size() == series.y.size(),
                  "x has " << series.x.size() << " values, y has " << series.y.size());
    series_.push_back(std::move(series));
}

void Plot::add_line(std::vector<double> x, std::vector<double> y, const Stroke& stroke,
                    const std::string& label) {
    Series s;
    s.x = std::move(x);
    s.y = std::move(y);
    s.stroke = stroke;
    s.label = label;
    add(std::move(s));
}

void Plot::add_vline(double x, const Stroke& stroke, const std::string& label) {
    vlines_.push_back({x, stroke, label});
}

PlotLayout Plot::layout(const PixelRect& panel) const {
    PlotLayout L;
    L.log_x = log_x;
    L.log_y = log_y;

    // Ranges, in transformed (log10 on a log axis) units.
    double dx0 = HUGE_VAL, dx1 = -HUGE_VAL, dy0 = HUGE_VAL, dy1 = -HUGE_VAL;
    for (const Series& s : series_)
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!usable(s.x[i], log_x) || !usable(s.y[i], log_y)) continue;
            dx0 = std::min(dx0, axis_value(s.x[i], log_x));
            dx1 = std::max(dx1, axis_value(s.x[i], log_x));
            dy0 = std::min(dy0, axis_value(s.y[i], log_y));
            dy1 = std::max(dy1, axis_value(s.y[i], log_y));
        }
    for (const VLine& v : vlines_)
        if (usable(v.x, log_x)) {
            dx0 = std::min(dx0, axis_value(v.x, log_x));
            dx1 = std::max(dx1, axis_value(v.x, log_x));
        }
    double tx0 = usable(x_min, log_x) ? axis_value(x_min, log_x) : dx0;
    double tx1 = usable(x_max, log_x) ? axis_value(x_max, log_x) : dx1;
    double ty0 = usable(y_min, log_y) ? axis_value(y_min, log_y) : dy0;
    double ty1 = usable(y_max, log_y) ? axis_value(y_max, log_y) : dy1;
    MBR_CHECK_MSG(
        std::isfinite(tx0) && std::isfinite(tx1) && std::isfinite(ty0) && std::isfinite(ty1),
        "a plot needs data or explicit ranges (x " << tx0 << ".." << tx1 << ", y " << ty0 << ".."
                                                   << ty1 << ")");
    if (tx1 <= tx0) tx0 -= 0.5, tx1 += 0.5;
    if (ty1 <= ty0) ty0 -= 0.5, ty1 += 0.5;
    const double pad = y_padding * (ty1 - ty0);
    if (!usable(y_min, log_y)) ty0 -= pad;
    if (!usable(y_max, log_y)) ty1 += pad;
    auto data = [](double t, bool log) { return log ? std::pow(10.0, t) : t; };
    L.x_min = data(tx0, log_x), L.x_max = data(tx1, log_x);
    L.y_min = data(ty0, log_y), L.y_max = data(ty1, log_y);

    // Margins: title above; tick labels and the axis label below and to the left.
    const int s = text_scale, line = glyph_line_height * s, gap = 4 * s, tick_len = 3 * s;
    const int top = (title.empty() ? gap : (glyph_line_height * (s + 1) + 2 * gap));
    const int bottom = tick_len + gap + line + (x_label.empty() ? 0 : line + gap) + gap;
    L.area.y = panel.y + top;
    L.area.h = std::max(1, panel.h - top - bottom);
    const AxisTicks yt = axis_ticks(
        ty0, ty1, log_y, L.area.h, std::max(2, L.area.h / (28 * s)),
        [&](double, double) { return glyph_height * s; }, 3 * glyph_height * s / 2);
    L.y_ticks = yt.ticks;
    L.y_step = yt.step;
    int widest_y = 0;
    for (double v : L.y_ticks)
        widest_y = std::max(widest_y, text_width(axis_label(v, yt.step, log_y), s));
    const int left = (y_label.empty() ? gap : line + gap) + widest_y + gap + tick_len + gap;
    // Room on the right for half of a label centred on the last x tick.
    const int right = std::max(3 * gap, text_width(axis_label(L.x_max, 1, log_x), s) / 2 + gap);
    L.area.x = panel.x + left;
    L.area.w = std::max(1, panel.w - left - right);
    const AxisTicks xt = axis_ticks(
        tx0, tx1, log_x, L.area.w, std::max(2, L.area.w / (35 * s)),
        [&](double v, double step) { return text_width(axis_label(v, step, log_x), s); },
        4 * glyph_advance * s);
    L.x_ticks = xt.ticks;
    L.x_step = xt.step;
    return L;
}

PlotLayout Plot::draw(Image& image, const PixelRect& panel) const {
    const PlotLayout L = layout(panel);
    Canvas canvas(image);
    canvas.set_clip(panel);
    canvas.fill_rect(panel, background);
    const PixelRect& a = L.area;
    const int s = text_scale, line = glyph_line_height * s, gap = 4 * s, tick_len = 3 * s;
    const Rgb grid_colour{0.88, 0.88, 0.88}, zero_colour{0.45, 0.45, 0.45};

    // Grid and zero line, under the data.
    auto x_px = [&](double x) { return static_cast<int>(std::lround(L.to_pixel(x, L.y_min).x)); };
    auto y_px = [&](double y) { return static_cast<int>(std::lround(L.to_pixel(L.x_min, y).y)); };
    if (grid) {
        for (double x : L.x_ticks) canvas.fill_rect({x_px(x), a.y, 1, a.h}, grid_colour);
        for (double y : L.y_ticks) canvas.fill_rect({a.x, y_px(y), a.w, 1}, grid_colour);
    }
    if (zero_line && !log_y && L.y_min < 0 && L.y_max > 0)
        canvas.fill_rect({a.x, y_px(0.0) - 1, a.w, 2}, zero_colour);

    // Data, clipped to the plot area.
    canvas.set_clip(intersect(a, panel));
    for (const VLine& v : vlines_)
        if (usable(v.x, log_x))
            canvas.line({L.to_pixel(v.x, L.y_min).x, double(a.y)},
                        {L.to_pixel(v.x, L.y_min).x, double(a.bottom())}, v.stroke);
    for (const Series& ser : series_) {
        if (ser.draw_line) {
            std::vector<Vec2> run;  // a line breaks at unusable points
            for (size_t i = 0; i <= ser.x.size(); ++i) {
                if (i < ser.x.size() && usable(ser.x[i], log_x) && usable(ser.y[i], log_y)) {
                    run.push_back(L.to_pixel(ser.x[i], ser.y[i]));
                } else {
                    if (run.size() >= 2) canvas.polyline(run, ser.stroke);
                    run.clear();
                }
            }
        }
        if (ser.marker != Marker::none)
            for (size_t i = 0; i < ser.x.size(); ++i) {
                if (!usable(ser.x[i], log_x) || !usable(ser.y[i], log_y)) continue;
                const Vec2 p = L.to_pixel(ser.x[i], ser.y[i]);
                const double r = ser.marker_radius;
                if (ser.marker == Marker::disc)
                    canvas.disc(p, r, ser.stroke.colour);
                else
                    canvas.fill_rect({int(std::lround(p.x - r)), int(std::lround(p.y - r)),
                                      int(std::lround(2 * r)), int(std::lround(2 * r))},
                                     ser.stroke.colour);
            }
    }
    canvas.set_clip(panel);

    // Frame, ticks and their labels.
    canvas.stroke_rect({a.x - 1, a.y - 1, a.w + 2, a.h + 2}, foreground, 2);
    for (double x : L.x_ticks) {
        const int px = x_px(x);
        canvas.fill_rect({px - 1, a.bottom() + 1, 2, tick_len}, foreground);
        canvas.text(px, a.bottom() + 1 + tick_len + gap, axis_label(x, L.x_step, log_x), foreground,
                    s, Align::centre, Align::start);
    }
    int widest_y = 0;
    for (double y : L.y_ticks) {
        const int py = y_px(y);
        const std::string label = axis_label(y, L.y_step, log_y);
        widest_y = std::max(widest_y, text_width(label, s));
        canvas.fill_rect({a.x - 1 - tick_len, py - 1, tick_len, 2}, foreground);
        canvas.text(a.x - 1 - tick_len - gap, py, label, foreground, s, Align::end, Align::centre);
    }

    // Axis labels and title.
    if (!x_label.empty())
        canvas.text(a.x + a.w / 2, a.bottom() + 1 + tick_len + gap + line + gap, x_label,
                    foreground, s, Align::centre, Align::start);
    if (!y_label.empty())
        canvas.text(a.x - 1 - tick_len - gap - widest_y - gap - line, a.y + a.h / 2, y_label,
                    foreground, s, Align::centre, Align::start, true);
    if (!title.empty())
        canvas.text(a.x + a.w / 2, panel.y + gap, title, foreground, s + 1, Align::centre,
                    Align::start);

    // Legend: a box in a corner of the plot area, one sample line and label per entry.
    struct Entry {
        const Stroke* stroke;
        Marker marker;
        double marker_radius;
        bool draw_line;
        const std::string* label;
    };
    std::vector<Entry> entries;
    for (const Series& ser : series_)
        if (!ser.label.empty())
            entries.push_back(
                {&ser.stroke, ser.marker, ser.marker_radius, ser.draw_line, &ser.label});
    for (const VLine& v : vlines_)
        if (!v.label.empty()) entries.push_back({&v.stroke, Marker::none, 0, true, &v.label});
    const int sample = 5 * glyph_advance * s;  // length of the legend's sample lines
    int widest = 0;
    for (const Entry& e : entries) widest = std::max(widest, text_width(*e.label, s));
    const int w = gap + sample + gap + widest + gap;
    const int h = gap + int(entries.size()) * line + gap / 2;
    // A legend that would hide much of a small plot is left out.
    if (legend != LegendPlace::none && !entries.empty() && 4 * w <= 3 * a.w && 2 * h <= a.h) {
        auto corner_box = [&](LegendPlace place) {
            const bool left = place == LegendPlace::top_left || place == LegendPlace::bottom_left;
            const bool upper = place == LegendPlace::top_left || place == LegendPlace::top_right;
            return PixelRect{left ? a.x + 2 * gap : a.right() - 2 * gap - w,
                             upper ? a.y + 2 * gap : a.bottom() - 2 * gap - h, w, h};
        };
        LegendPlace place = legend;
        if (place == LegendPlace::best) {
            // Count the drawn data (lines sampled every 2 pixels, markers, reference lines)
            // that each corner's box would hide; keep the first corner hiding the least.
            std::vector<Vec2> drawn;
            for (const Series& ser : series_)
                for (size_t i = 0; i < ser.x.size(); ++i) {
                    if (!usable(ser.x[i], log_x) || !usable(ser.y[i], log_y)) continue;
                    const Vec2 p = L.to_pixel(ser.x[i], ser.y[i]);
                    drawn.push_back(p);
                    if (!ser.draw_line || i + 1 >= ser.x.size() || !usable(ser.x[i + 1], log_x) ||
                        !usable(ser.y[i + 1], log_y))
                        continue;
                    const Vec2 q = L.to_pixel(ser.x[i + 1], ser.y[i + 1]);
                    const double len = std::sqrt(dot(q - p, q - p));
                    const int n = std::min(10000, static_cast<int>(len / 2));
                    for (int k = 1; k < n; ++k) drawn.push_back(p + (double(k) / n) * (q - p));
                }
            for (const VLine& v : vlines_)
                if (usable(v.x, log_x))
                    for (int y = a.y; y < a.bottom(); y += 2)
                        drawn.push_back({L.to_pixel(v.x, L.y_min).x, double(y)});
            size_t fewest = std::numeric_limits<size_t>::max();
            for (LegendPlace c : {LegendPlace::top_right, LegendPlace::top_left,
                                  LegendPlace::bottom_right, LegendPlace::bottom_left}) {
                const PixelRect r = corner_box(c);
                size_t n_hidden = 0;
                for (Vec2 p : drawn)
                    n_hidden += p.x >= r.x - gap && p.x <= r.right() + gap && p.y >= r.y - gap &&
                                p.y <= r.bottom() + gap;
                if (n_hidden < fewest) fewest = n_hidden, place = c;
            }
        }
        const PixelRect box = corner_box(place);
        const int bx = box.x, by = box.y;
        canvas.fill_rect({bx, by, w, h}, background);
        canvas.stroke_rect({bx, by, w, h}, {0.6, 0.6, 0.6}, 1);
        for (size_t i = 0; i < entries.size(); ++i) {
            const Entry& e = entries[i];
            const double cy = by + gap + int(i) * line + glyph_height * s / 2.0;
            if (e.draw_line)
                canvas.line({bx + gap + 0.0, cy}, {bx + gap + double(sample), cy}, *e.stroke);
            if (e.marker == Marker::disc)
                canvas.disc({bx + gap + sample / 2.0, cy}, e.marker_radius, e.stroke->colour);
            else if (e.marker == Marker::square)
                canvas.fill_rect(
                    {int(bx + gap + sample / 2 - e.marker_radius), int(cy - e.marker_radius),
                     int(2 * e.marker_radius), int(2 * e.marker_radius)},
                    e.stroke->colour);
            canvas.text(bx + gap + sample + gap, int(std::lround(cy)), *e.label, foreground, s,
                        Align::start, Align::centre);
        }
    }
    return L;
}

PlotLayout map_layout(const PixelRect& area, double x_min, double x_max, double y_min, double y_max,
                      int text_scale) {
    MBR_CHECK_MSG(area.w > 0 && area.h > 0 && x_max > x_min && y_max > y_min,
                  "area " << area.w << " x " << area.h << ", x " << x_min << ".." << x_max << ", y "
                          << y_min << ".." << y_max);
    const int s = text_scale;
    PlotLayout L;
    L.area = area;
    L.x_min = x_min, L.x_max = x_max, L.y_min = y_min, L.y_max = y_max;
    const AxisTicks xt = axis_ticks(
        x_min, x_max, false, area.w, std::max(2, area.w / (35 * s)),
        [&](double v, double step) { return text_width(tick_label(v, step), s); },
        4 * glyph_advance * s);
    const AxisTicks yt = axis_ticks(
        y_min, y_max, false, area.h, std::max(2, area.h / (35 * s)),
        [&](double, double) { return glyph_height * s; }, 3 * glyph_height * s / 2);
    L.x_ticks = xt.ticks, L.x_step = xt.step;
    L.y_ticks = yt.ticks, L.y_step = yt.step;
    return L;
}

void draw_axes(Image& image, const PlotLayout& L, const std::string& x_label,
               const std::string& y_label, Rgb foreground, int text_scale) {
    Canvas canvas(image);
    const PixelRect& a = L.area;
    const int s = text_scale, line = glyph_line_height * s, gap = 4 * s, tick_len = 3 * s;
    canvas.stroke_rect({a.x - 2, a.y - 2, a.w + 4, a.h + 4}, foreground, 2);
    for (double x : L.x_ticks) {
        const int px = static_cast<int>(std::lround(L.to_pixel(x, L.y_min).x));
        canvas.fill_rect({px - 1, a.bottom() + 2, 2, tick_len}, foreground);
        canvas.text(px, a.bottom() + 2 + tick_len + gap, axis_label(x, L.x_step, L.log_x),
                    foreground, s, Align::centre, Align::start);
    }
    int widest_y = 0;
    for (double y : L.y_ticks) {
        const int py = static_cast<int>(std::lround(L.to_pixel(L.x_min, y).y));
        const std::string label = axis_label(y, L.y_step, L.log_y);
        widest_y = std::max(widest_y, text_width(label, s));
        canvas.fill_rect({a.x - 2 - tick_len, py - 1, tick_len, 2}, foreground);
        canvas.text(a.x - 2 - tick_len - gap, py, label, foreground, s, Align::end, Align::centre);
    }
    if (!x_label.empty())
        canvas.text(a.x + a.w / 2, a.bottom() + 2 + tick_len + gap + line + gap / 2, x_label,
                    foreground, s, Align::centre, Align::start);
    if (y_label.size() > 3)
        canvas.text(a.x - 2 - tick_len - gap - widest_y - gap - glyph_height * s, a.y + a.h / 2,
                    y_label, foreground, s, Align::centre, Align::start, true);
    else if (!y_label.empty())
        canvas.text(a.x - 2 - tick_len - gap - widest_y - 2 * gap, a.y + a.h / 2, y_label,
                    foreground, s, Align::end, Align::centre);
}

int axes_margin(int text_scale, int label_chars) {
    const int s = text_scale, line = glyph_line_height * s, gap = 4 * s, tick_len = 3 * s;
    const int left = 2 + tick_len + gap + label_chars * glyph_advance * s + gap + line;
    const int bottom = 2 + tick_len + gap + line + gap / 2 + line;
    return std::max(left, bottom);
}

// === Colour maps and images of scalars

namespace {

// Piecewise-linear interpolation through equally spaced stops (display values 0..255).
Rgb interpolate_stops(const double (*stops)[3], int n_stops, double t) {
    if (std::isnan(t)) return {0.5, 0.5, 0.5};
    t = std::clamp(t, 0.0, 1.0);
    const double f = t * (n_stops - 1);
    const int i = std::min(n_stops - 2, static_cast<int>(f));
    const double w = f - i;
    Rgb c;
    for (int k = 0; k < 3; ++k) c[k] = ((1 - w) * stops[i][k] + w * stops[i + 1][k]) / 255.0;
    return c;
}

// viridis (matplotlib; van der Walt and Smith 2015) at t = 0, 1/8, ..., 1, rounded to 8 bits.
constexpr double viridis_stops[9][3] = {
    {68, 1, 84},    {71, 45, 123}, {59, 82, 139},  {44, 114, 142}, {33, 145, 140},
    {40, 174, 128}, {94, 201, 98}, {173, 220, 48}, {253, 231, 37},
};

// Blue - white - red, with the end colours of Moreland's "cool to warm" map (2009).
constexpr double diverging_stops[3][3] = {{59, 76, 192}, {255, 255, 255}, {180, 4, 38}};

std::string bar_label(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

}  // namespace

Rgb colour_map(double t) {
    return interpolate_stops(viridis_stops, 9, t);
}

Rgb diverging_map(double t) {
    return interpolate_stops(diverging_stops, 3, t);
}

void draw_scalar_field(Image& image, const PixelRect& r, const std::vector<double>& values, int w,
                       int h, double v_min, double v_max, ColourMapFn map) {
    MBR_CHECK_MSG(w > 0 && h > 0 && values.size() == size_t(w) * h,
                  w << " x " << h << " field with " << values.size() << " values");
    const PixelRect q = intersect(r, {0, 0, image.width, image.height});
    const double span = v_max - v_min;
    for (int y = q.y; y < q.bottom(); ++y) {
        const int sy = std::min(h - 1, static_cast<int>((y - r.y + 0.5) * h / r.h));
        for (int x = q.x; x < q.right(); ++x) {
            const int sx = std::min(w - 1, static_cast<int>((x - r.x + 0.5) * w / r.w));
            const double v = values[size_t(sy) * w + sx];
            const double t = span > 0 ? (v - v_min) / span : 0.5;
            image.at(x, y) = std::isfinite(v) ? map(t) : Rgb{0.5, 0.5, 0.5};
        }
    }
}

void draw_colour_bar(Image& image, const PixelRect& r, double v_min, double v_max,
                     const std::string& caption, ColourMapFn map, int text_scale) {
    Canvas canvas(image);
    canvas.set_clip(r);
    const int s = text_scale, line = glyph_line_height * s, gap = 3 * s;
    const int half_cap = glyph_height * s / 2;
    const Rgb ink{0, 0, 0};
    if (r.h > r.w) {
        // Vertical: caption on top, bar on the left, max label at its top, min at its bottom.
        const int top = r.y + (caption.empty() ? 0 : line + gap) + half_cap;
        const int bottom = r.bottom() - half_cap;
        const int bar_w = std::max(4, std::min(r.w / 3, 10 * s));
        if (!caption.empty()) canvas.text(r.x, r.y, caption, ink, s);
        for (int y = top; y < bottom; ++y) {
            const double t = bottom - top > 1 ? double(bottom - 1 - y) / (bottom - 1 - top) : 0.5;
            canvas.fill_rect({r.x, y, bar_w, 1}, map(t));
        }
        canvas.stroke_rect({r.x, top, bar_w, bottom - top}, ink, 1);
        canvas.text(r.x + bar_w + gap, top, bar_label(v_max), ink, s, Align::start, Align::centre);
        canvas.text(r.x + bar_w + gap, bottom - 1, bar_label(v_min), ink, s, Align::start,
                    Align::centre);
    } else {
        // Horizontal: bar on top; min label at the left end, max at the right, caption between.
        const int bar_h = std::max(4, std::min(r.h - line - gap, 10 * s));
        for (int x = r.x; x < r.right(); ++x) {
            const double t = r.w > 1 ? double(x - r.x) / (r.w - 1) : 0.5;
            canvas.fill_rect({x, r.y, 1, bar_h}, map(t));
        }
        canvas.stroke_rect({r.x, r.y, r.w, bar_h}, ink, 1);
        const int ty = r.y + bar_h + gap;
        canvas.text(r.x, ty, bar_label(v_min), ink, s);
        canvas.text(r.right(), ty, bar_label(v_max), ink, s, Align::end);
        if (!caption.empty()) canvas.text(r.x + r.w / 2, ty, caption, ink, s, Align::centre);
    }
}

void draw_colour_scale(Image& image, const PixelRect& bar, double v_min, double v_max,
                       const std::string& caption, ColourMapFn map, int text_scale, bool log) {
    MBR_CHECK_MSG(v_max > v_min && (!log || v_min > 0),
                  "colour scale " << v_min << ".." << v_max << (log ? " (log)" : ""));
    Canvas canvas(image);
    const int s = text_scale, gap = 3 * s, tick_len = 3 * s;
    const Rgb ink{0, 0, 0};
    const bool horizontal = bar.w >= bar.h;
    const double t0 = log ? std::log10(v_min) : v_min, t1 = log ? std::log10(v_max) : v_max;
    // The bar: colour by position, v_min at the left (horizontal) or bottom (vertical).
    const int length = horizontal ? bar.w : bar.h;
    for (int p = 0; p < length; ++p) {
        const Rgb c = map(length > 1 ? (p + 0.5) / length : 0.5);
        if (horizontal)
            canvas.fill_rect({bar.x + p, bar.y, 1, bar.h}, c);
        else
            canvas.fill_rect({bar.x, bar.bottom() - 1 - p, bar.w, 1}, c);
    }
    canvas.stroke_rect({bar.x - 1, bar.y - 1, bar.w + 2, bar.h + 2}, ink, 1);
    // Ticks spaced so that their labels do not touch.
    const AxisTicks ticks =
        horizontal
            ? axis_ticks(
                  t0, t1, log, bar.w, std::max(2, bar.w / (40 * s)),
                  [&](double v, double step) { return text_width(axis_label(v, step, log), s); },
                  3 * glyph_advance * s)
            : axis_ticks(
                  t0, t1, log, bar.h, std::max(2, bar.h / (30 * s)),
                  [&](double, double) { return glyph_height * s; }, glyph_height * s);
    for (double v : ticks.ticks) {
        const double t = ((log ? std::log10(v) : v) - t0) / (t1 - t0);
        const std::string label = axis_label(v, ticks.step, log);
        if (horizontal) {
            const int px = bar.x + static_cast<int>(std::lround(t * (bar.w - 1)));
            canvas.fill_rect({px - s / 2, bar.bottom() + 1, std::max(1, s), tick_len}, ink);
            canvas.text(px, bar.bottom() + 1 + tick_len + gap, label, ink, s, Align::centre);
        } else {
            const int py = bar.bottom() - 1 - static_cast<int>(std::lround(t * (bar.h - 1)));
            canvas.fill_rect({bar.right() + 1, py - s / 2, tick_len, std::max(1, s)}, ink);
            canvas.text(bar.right() + 1 + tick_len + gap, py, label, ink, s, Align::start,
                        Align::centre);
        }
    }
    if (!caption.empty())
        canvas.text(bar.x, bar.y - 1 - gap, caption, ink, s, Align::start, Align::end);
}

void blit(Image& dst, const Image& src, int x, int y) {
    const PixelRect q = intersect({x, y, src.width, src.height}, {0, 0, dst.width, dst.height});
    for (int j = q.y; j < q.bottom(); ++j)
        for (int i = q.x; i < q.right(); ++i) dst.at(i, j) = src.at(i - x, j - y);
}

}  // namespace mbr
