// radiosity/output/render.h - turning the solved radiosity into images: the camera's view of every
// surface's radiosity B_i(u,v) (eq. (20), a SplineField per surface) as radiance B / pi, since
// the surfaces are Lambertian (eq. (1)); then tone mapping to sRGB for PNG, Radiance RGBE (.hdr)
// output of the linear radiance, and an overlay of the receivers' quadtrees (paper section 5) for
// teaching. docs/method.md, "Rendering", lists the decisions.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "math/vec3.h"
#include "octree/octree.h"
#include "radiosity/geometry/quadtree.h"
#include "radiosity/geometry/radiosity_view.h"
#include "radiosity/geometry/spline_field.h"
#include "radiosity/output/image.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// Options of the renderer.
/// What a camera ray that meets the back of a surface sees (surfaces are one-sided): black, or
/// what lies beyond (the back face culled, as viewers of the classic radiosity scenes do: their
/// cameras stand outside the room, behind a wall).
enum class BackFaces { Black, Cull };

struct RenderOptions {
    int samples_per_pixel = 4;                // jittered camera rays per pixel (>= 1); stratified
                                              // on a k x k grid when a square k^2
    std::uint64_t seed = 1;                   // jitter seed; pixel (x, y) draws from (seed, x, y)
    double exposure = 1;                      // multiplier on radiance before tone mapping
    bool quadtree_overlay = false;            // draw the quadtree leaves' boundaries (teaching)
    Rgb overlay_colour = {0.08, 0.08, 0.08};  // their line colour, a display value in [0, 1]
    BackFaces back_faces = BackFaces::Cull;   // a camera ray meeting a surface's back
};

/// Work done by a render.
struct RenderStats {
    long n_camera_rays = 0;  // rays cast (samples, plus one per pixel for the overlay)
    long n_front_hits = 0;   // rays that met the front of a surface
    long n_back_hits = 0;    // backs of surfaces met (culled: passed; black: zero radiance)
    RayStats rays;           // octree work of those rays
    /// Adds another part's counts.
    RenderStats& operator+=(const RenderStats& other);
};

/// Peak memory of rendering a width x height picture to PNG (and HDR), from its size alone:
/// the linear radiance and the tone-mapped image (an Rgb a pixel each), the 8-bit pixels and
/// stb's PNG encoding, and with the quadtree overlay the surface and leaf seen at each pixel.
double render_bytes(int width, int height, const RenderOptions& options = {});

/// The up direction of a scene without a camera: lights hang from ceilings, so up is the
/// coordinate axis opposite the lights' mean normal (weighted by area and mean emission) when
/// that normal lies within about 45 degrees of an axis (its largest component at least 0.7 of
/// its length); otherwise, and without lights, (0, 1, 0), the OBJ convention.
Vec3 scene_up(const Scene& scene);

/// The camera a scene without a camera statement is rendered from (docs/scene-format.md,
/// "camera"): up is scene_up; it looks at the centre c of the scene's bounds from one of four
/// horizontal sides (with up y: +z, -z, +x, -x; with up axis k: the axes k + 2, k + 1 mod 3,
/// each way; each direction d raised by 0.15 along up), the side the scene's
/// surfaces face most on balance (the sum of area x n . d over a 4 x 4 grid of each surface: a
/// box open on one side is seen through its opening; a closed room ties, and ties go to the
/// first), a vertical field of view of 45 degrees and 640 x 480 pixels,
/// from the distance at which the bounds' sphere (radius r, half the diagonal) fits the field
/// of view with 5 % to spare: 1.05 r / sin(22.5 degrees). With back faces culled (the default)
/// the walls between it and the inside of a room are not drawn.
Camera framing_camera(const Scene& scene);

/// The pinhole ray of scene-format.md through image point (x, y) in pixels, (0, 0) the top left
/// corner of the image and (width, height) the bottom right; the image's right is
/// (look_at - eye) x up. The direction is not normalised (t counts distances to the image plane).
Ray camera_ray(const Camera& camera, double x, double y);

/// Radiance arriving along `ray`: at the first surface i hit, B_i(u, v) / pi by eq. (20) from
/// radiosity.at(i, u, v) (radiosity_view() of a solution, or a list of B fields) with (u, v)
/// clamped to [0,1]^2; zero for a miss, for the back of a surface and
/// for an empty field. Adds its counts to *stats if given.
Rgb radiance_along(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                   const Ray& ray, RenderStats* stats = nullptr,
                   BackFaces back_faces = BackFaces::Black);

/// The linear radiance image of scene.camera: per pixel the plain average (box filter) of
/// options.samples_per_pixel radiance_along() samples jittered inside the pixel. radiosity gives
/// the total radiosity of each of scene.surfaces (emission included), one per surface. Parallel
/// over rows; the image does not depend on the number of threads. Values are not clamped. *stats,
/// if given, receives this render's counts.
Image render_radiance(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                      const RenderOptions& options = {}, RenderStats* stats = nullptr);

/// The sRGB encoding function (IEC 61966-2-1): linear [0,1] to an encoded value in [0,1].
double linear_to_srgb(double linear);

/// A linear display value clipped to [0, 1], NaN and infinities to 0: what tone_map encodes,
/// given exposure x radiance (the export's colours take it too, radiosity/output/export.h).
double clip_to_display(double linear);

/// Display values for write_png: exposure x radiance, clipped to [0,1] (NaN to 0), sRGB-encoded.
Image tone_map(const Image& radiance, double exposure);

/// The exposure of `mbr render --exposure auto`: the log-average luminance (0.2126 R + 0.7152 G
/// + 0.0722 B) of the pixels that see anything lit (luminance > 0) shown at 0.18, the middle grey
/// of photography (Reinhard, Stark, Shirley and Ferwerda 2002's key value), so that a scene whose
/// lights are given in any unit (MGF's lm/m^2, an OBJ's Ke) shows its walls in the middle of the
/// range; 1 when no pixel is lit. The Cornell box gets about 3.2 (its exposure 1 is darker than
/// a photograph's), the room 4.7, the classroom of the MGF scenes after one shot 46.
double auto_exposure(const Image& radiance);

/// Draws the boundaries of every surface's quadtree leaves, one pixel wide, in `colour` over a
/// display image of scene.camera's size. A pixel is a line pixel when the (surface, leaf) seen
/// through its centre differs from that of its right or lower neighbour. leaves[i] holds the
/// leaves of surface i's quadtree over [0,1]^2 (cells outside the domain are ignored; an empty
/// list makes the whole surface one cell); a null `leaves` treats every surface as one cell, so
/// only the surfaces' outlines are drawn. Adds its camera rays to *stats if given.
void draw_quadtree_overlay(Image& display, const Scene& scene, const Octree& octree,
                           const std::vector<std::vector<DyadicCell>>* leaves, Rgb colour,
                           RenderStats* stats = nullptr, BackFaces back_faces = BackFaces::Cull);

/// The whole display pipeline: render_radiance, tone_map with options.exposure, and, when
/// options.quadtree_overlay is on, draw_quadtree_overlay with `leaves`.
Image render_display(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                     const RenderOptions& options = {},
                     const std::vector<std::vector<DyadicCell>>* leaves = nullptr,
                     RenderStats* stats = nullptr);

/// Writes linear radiance in Radiance's RGBE format: the "#?RADIANCE" header with
/// FORMAT=32-bit_rle_rgbe, the resolution line "-Y height +X width", then flat (uncompressed)
/// scanlines, top row first. Negative and non-finite values are written as 0. RGBE keeps 8 bits
/// of mantissa for the largest channel of a pixel: read back, every channel is within
/// max(r, g, b) / 256 of its value.
void write_hdr(std::ostream& out, const Image& radiance);

/// Reads a Radiance RGBE image (flat or new-style run-length scanlines, "-Y h +X w" order,
/// EXPOSURE lines divided out) into linear radiance. Throws InputError(name, 0, ...) when the
/// stream is not such a file, is truncated or malformed, uses old-style run-length scanlines, or
/// is larger than Texture::max_image_pixels.
Image read_hdr(std::istream& in, const std::string& name);

}  // namespace mbr
