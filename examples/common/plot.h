// examples/common/plot.h - a small raster plotting library of our own, for the figures the
// examples reproduce (paper Figure 1 graphs, later error images and composed panels).
//
// Three layers, each usable alone:
//   - Canvas: anti-aliased lines and polylines (solid or dashed), discs, filled and stroked
//     rectangles, and text in a built-in 5x7 bitmap font at integer scales, on an Image.
//   - Plot: a 2D line plot that maps data to a plot area, with frame, "nice" ticks (1, 2, 5 x
//     10^k), numeric labels, axis labels, title, legend, grid and a horizontal zero line.
//   - Images of scalars: colour_map (a viridis approximation), diverging_map, a labelled colour
//     bar, a scalar field drawn through a map, and blit for composing panels.
// Pixel coordinates: x right, y down, pixel (x, y) covers [x, x + 1) x [y, y + 1), so its centre
// is (x + 0.5, y + 0.5). Colours are display values in [0, 1], as in Image.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/output/image.h"

namespace mbr {

// === Font

/// One glyph of the built-in font: 5 columns x 7 rows, rows top to bottom, bit 4 = left column.
/// `drop` moves the glyph down by that many rows (descenders of g, j, p, q, y and of , ; _).
struct Glyph {
    std::array<std::uint8_t, 7> rows{};
    int drop = 0;
};

/// Font metrics in unscaled pixels: a glyph is 5 x 7, the cap height is 7, descenders reach
/// 2 rows below the baseline, characters advance by 6 and lines by 10.
constexpr int glyph_width = 5;
constexpr int glyph_height = 7;
constexpr int glyph_advance = 6;
constexpr int glyph_line_height = 10;

/// True for the printable ASCII characters ' ' .. '~', every one of which has a glyph.
bool has_glyph(char c);
/// The glyph of c; characters without one get a hollow box.
Glyph glyph(char c);
/// Width in pixels of s drawn at the given scale (no trailing gap).
int text_width(const std::string& s, int scale);
/// s broken at spaces into lines no wider than max_width pixels at the given scale (a word
/// longer than a line gets a line of its own); existing newlines are kept.
std::vector<std::string> wrap_text(const std::string& s, int max_width, int scale);

// === Canvas

/// An integer pixel rectangle [x, x + w) x [y, y + h).
struct PixelRect {
    int x = 0, y = 0, w = 0, h = 0;
    int right() const { return x + w; }
    int bottom() const { return y + h; }
};

/// How a line is drawn: colour, width in pixels, and an optional dash pattern along its length.
struct Stroke {
    Rgb colour{0, 0, 0};
    double width = 2;  // pixels
    double dash = 0;   // length of the drawn dashes in pixels; 0 draws a solid line
    double gap = 0;    // length of the gaps between dashes in pixels
};

/// Where text sits relative to its anchor point, along one axis.
enum class Align { start, centre, end };

/// Drawing on an Image, restricted to a clip rectangle (initially the whole image). Shapes are
/// anti-aliased by pixel coverage and alpha-blended over what is there.
class Canvas {
public:
    /// Draws on `image`, which must outlive the canvas.
    explicit Canvas(Image& image);
    /// The image drawn on.
    Image& image() { return image_; }
    /// Restricts later drawing to r (intersected with the image).
    void set_clip(const PixelRect& r);
    /// Lets later drawing reach the whole image again.
    void reset_clip();
    /// Blends c over pixel (x, y) with opacity alpha in [0, 1]; pixels outside the clip are kept.
    void blend(int x, int y, Rgb c, double alpha = 1.0);
    /// Fills r with c (opaque).
    void fill_rect(const PixelRect& r, Rgb c);
    /// Draws the border of r, `thickness` pixels wide, inside r.
    void stroke_rect(const PixelRect& r, Rgb c, int thickness = 1);
    /// A straight segment from a to b (pixel coordinates, round ends).
    void line(Vec2 a, Vec2 b, const Stroke& stroke);
    /// Connected segments through the points; joints are drawn once, without darker dots.
    void polyline(const std::vector<Vec2>& points, const Stroke& stroke);
    /// A filled, anti-aliased disc (plot markers).
    void disc(Vec2 centre, double radius, Rgb c);
    /// An anti-aliased circle outline of the given radius (to the middle of the stroke); the
    /// stroke's dash pattern is ignored. Concentric circles of different radii stay apart.
    void circle(Vec2 centre, double radius, const Stroke& stroke);
    /// Text at an integer scale, anchored at (x, y): h_align picks left/centre/right of the
    /// text, v_align top/middle/bottom of the cap height (bottom = baseline). vertical = true
    /// rotates it a quarter turn anticlockwise, to read bottom to top (y-axis labels); the
    /// alignments then refer to the rotated text's own directions.
    void text(int x, int y, const std::string& s, Rgb c, int scale = 1,
              Align h_align = Align::start, Align v_align = Align::start, bool vertical = false);

private:
    Image& image_;
    PixelRect clip_;
};

// === Ticks

/// A "nice" tick spacing for a span: span / target_intervals rounded to 1, 2, 5 or 10 x 10^k
/// (mantissa below 1.5 -> 1, below 3 -> 2, below 7 -> 5, else 10; Heckbert 1990).
double nice_step(double span, int target_intervals);
/// The next nice spacing above a nice step: 1 -> 2 -> 5 -> 10 (x 10^k).
double next_nice_step(double step);
/// The multiples of step inside [lo, hi] (end points included within rounding), with values
/// within 1e-9 step of zero snapped to exactly zero.
std::vector<double> ticks_with_step(double lo, double hi, double step);
/// ticks_with_step(lo, hi, nice_step(hi - lo, target_intervals)).
std::vector<double> nice_ticks(double lo, double hi, int target_intervals = 5);
/// A tick label: fixed notation with as many decimals as the step needs ("0.5", "-1", "2.25"),
/// or %g notation for very small or large values; never "-0".
std::string tick_label(double value, double step);

// === Plot

/// Marker drawn at each data point of a series.
enum class Marker { none, disc, square };

/// One data series: points joined by a line (breaks at non-finite values) and/or markers.
struct Series {
    std::vector<double> x, y;
    Stroke stroke;                 // line style; its colour also colours the markers
    bool draw_line = true;         // false: markers only
    Marker marker = Marker::none;
    double marker_radius = 4;      // pixels
    std::string label;             // legend entry; empty keeps the series out of the legend
};

/// Where the legend box goes inside the plot area; `best` takes the corner whose box covers
/// the least of the drawn data (ties in the order top right, top left, bottom right, bottom left).
/// A legend wider than 3/4 or taller than 1/2 of the plot area is not drawn.
enum class LegendPlace { none, best, top_left, top_right, bottom_left, bottom_right };

/// Where a plot's data went on the image: the plot area, the data ranges, the ticks.
struct PlotLayout {
    PixelRect area;                           // the framed plot area
    double x_min = 0, x_max = 1, y_min = 0, y_max = 1;
    bool log_x = false, log_y = false;
    std::vector<double> x_ticks, y_ticks;
    double x_step = 1, y_step = 1;            // tick spacing (in decades on a log axis)
    /// The pixel position of data point (x, y); on a log axis its log10 is mapped.
    Vec2 to_pixel(double x, double y) const;
};

/// A 2D line plot. Settings are public fields with defaults (set them, add series, draw).
class Plot {
public:
    std::string title;                 // centred above the plot area
    std::string x_label, y_label;      // below the x axis; rotated, left of the y axis
    double x_min = NAN, x_max = NAN;   // data range shown; NaN takes it from the data
    double y_min = NAN, y_max = NAN;
    double y_padding = 0.05;           // fraction of the y span added above and below auto ranges
    bool log_x = false, log_y = false; // base-10 logarithmic axes (positive data only)
    bool grid = true;                  // light lines at the major ticks
    bool zero_line = true;             // a horizontal line at y = 0 when it is inside the range
    LegendPlace legend = LegendPlace::best;  // corner of the legend box, or none
    int text_scale = 2;                // font scale of ticks, labels and legend; title one larger
    Rgb background{1, 1, 1};           // fills the whole panel first
    Rgb foreground{0, 0, 0};           // frame, ticks and text

    /// Adds a series.
    void add(Series series);
    /// Adds a line through (x[i], y[i]).
    void add_line(std::vector<double> x, std::vector<double> y, const Stroke& stroke,
                  const std::string& label = "");
    /// Adds a vertical reference line at data coordinate x, spanning the plot area.
    void add_vline(double x, const Stroke& stroke, const std::string& label = "");
    /// Computes the ranges, ticks and plot area that draw() would use inside `panel`.
    PlotLayout layout(const PixelRect& panel) const;
    /// Draws the whole plot (background, grid, zero line, data, frame, ticks, labels, title,
    /// legend) into `panel` of the image. Throws CheckFailure when there is nothing to show.
    PlotLayout draw(Image& image, const PixelRect& panel) const;

private:
    struct VLine {
        double x;
        Stroke stroke;
        std::string label;
    };
    std::vector<Series> series_;
    std::vector<VLine> vlines_;
};

/// A data rectangle [x_min, x_max] x [y_min, y_max] mapped onto the pixel rectangle `area`
/// (y up), with nice ticks sized for labels at `text_scale`: the frame of a picture drawn by
/// hand (maps of the (s,t) plane, images of fields), to be finished by draw_axes.
PlotLayout map_layout(const PixelRect& area, double x_min, double x_max, double y_min,
                      double y_max, int text_scale = 2);
/// The frame around a layout's area (just outside it), with outward ticks, their labels and the
/// axis labels below and to the left, as Plot::draw draws them (a y label of up to three
/// characters stays upright, a longer one is turned to read upwards). Leave about
/// axes_margin(text_scale) pixels free on the left and below the area.
void draw_axes(Image& image, const PlotLayout& layout, const std::string& x_label,
               const std::string& y_label, Rgb foreground = {0, 0, 0}, int text_scale = 2);
/// The margin, in pixels, that draw_axes needs left of and below the area for tick labels of
/// up to `label_chars` characters and one axis label.
int axes_margin(int text_scale = 2, int label_chars = 4);

// === Colour maps and images of scalars

/// A perceptually ordered sequential map for t in [0, 1] (clamped; NaN gives mid grey):
/// piecewise-linear through nine samples of matplotlib's viridis (van der Walt and Smith 2015)
/// at t = 0, 1/8, ..., 1, in display values. Dark blue-violet rgb(68, 1, 84)/255 at t = 0,
/// yellow rgb(253, 231, 37)/255 at t = 1; its luminance rises strictly with t.
Rgb colour_map(double t);
/// A diverging map for signed data, t in [0, 1] (clamped; NaN gives mid grey): blue
/// rgb(59, 76, 192)/255 at 0, white at 0.5, red rgb(180, 4, 38)/255 at 1, piecewise linear.
/// Its luminance peaks at 0.5, so equal |t - 0.5| read as equal strength.
Rgb diverging_map(double t);
/// A colour map as a plain function pointer (colour_map, diverging_map).
using ColourMapFn = Rgb (*)(double);

/// Draws values[y * w + x] (row 0 at the top) scaled to fill `r`, nearest sample per pixel,
/// coloured by map((v - v_min) / (v_max - v_min)); non-finite values are drawn mid grey.
void draw_scalar_field(Image& image, const PixelRect& r, const std::vector<double>& values,
                       int w, int h, double v_min, double v_max,
                       ColourMapFn map = colour_map);
/// A colour bar filling `r`, with its min and max labels (and an optional caption) inside r:
/// vertical (max at the top, labels to the right) when r is taller than wide, else horizontal
/// (min at the left, labels below).
void draw_colour_bar(Image& image, const PixelRect& r, double v_min, double v_max,
                     const std::string& caption = "", ColourMapFn map = colour_map,
                     int text_scale = 2);
/// A colour scale: the bar fills `bar` exactly; ticks at nice values (whole decades when `log`,
/// which needs 0 < v_min < v_max) are labelled below a horizontal bar or right of a vertical
/// one, and the caption goes above the bar. The caller leaves room for the labels (about
/// 3 glyph lines below, or six characters to the right) and one line for the caption above.
void draw_colour_scale(Image& image, const PixelRect& bar, double v_min, double v_max,
                       const std::string& caption, ColourMapFn map = colour_map,
                       int text_scale = 2, bool log = false);
/// Copies src into dst with its top-left corner at (x, y); parts outside dst are dropped.
void blit(Image& dst, const Image& src, int x, int y);

}  // namespace mbr
