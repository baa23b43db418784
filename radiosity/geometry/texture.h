// radiosity/geometry/texture.h - a reflectance rho_i(s,t) or emission E_i(s,t) field over a
// surface's parameter domain [0,1]^2 (paper eqs. (1)-(2): "our algorithm does not require albedo to
// be constant over a surface", section 8). Three kinds: a constant RGB, a procedural checker, and
// an image (PNG, JPEG, ... through stb_image) looked up bilinearly.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "math/vec3.h"

namespace mbr {

/// A field of RGB values over (u,v) in [0,1]^2. Copies are cheap: image texels are shared, and
/// so are they between an image and its scaled() copies, so one image file costs its memory
/// once however many materials use it.
class Texture {
public:
    /// The three kinds of field.
    enum class Kind { Constant, Checker, Image };

    /// Constant black (no reflection, no emission).
    Texture() = default;
    /// The same value everywhere.
    static Texture constant(Rgb value);
    /// n x n squares alternating between a and b; the square holding (0,0) is a.
    static Texture checker(Rgb a, Rgb b, int n);
    /// An image read with stb_image. Each 8-bit channel c is decoded from sRGB to linear
    /// (IEC 61966-2-1) and multiplied by the channel of `scale`: value = scale * linear(c), so a
    /// white texel gives `scale`. Alpha is ignored. u runs left to right, v bottom to top
    /// (row 0 of the file is v = 1). Throws InputError(path, 0, ...) when the file is missing, is
    /// a folder, device or FIFO (refused before it is read), cannot be decoded, or has more than
    /// max_image_pixels pixels (a PNG's size is read from its header even where stb_image
    /// refuses the header as too large).
    static Texture image(const std::string& path, Rgb scale = {1, 1, 1});
    /// An image from linear texel values, row 0 at the top (v = 1), width * height of them.
    static Texture from_pixels(int width, int height, std::vector<Rgb> linear, Rgb scale,
                               const std::string& name = "");
    /// This field multiplied channel by channel by `scale`. An image's copy shares its texels
    /// (only the scale differs), so scaling costs no memory.
    Texture scaled(Rgb scale) const;

    /// Texture coordinates (OBJ's `vt`) at a surface's four parameter corners, in the order of
    /// Surface::planar_quad's corners: (u,v) = (0,0), (1,0), (1,1), (0,1).
    using CornerCoordinates = std::array<std::array<double, 2>, 4>;
    /// This field seen through texture coordinates: value(u, v) reads the field at the bilinear
    /// blend of `corners` at (u, v), wrapped into [0,1] where it falls outside (a texture
    /// repeats, as OBJ viewers show it). The copy shares the texels; its mean() is taken over
    /// the part of the field it shows (a 16 x 16 midpoint rule), its minimum() and maximum()
    /// stay the whole field's (bounds of what it shows).
    Texture mapped(const CornerCoordinates& corners) const;
    /// True when the field is seen through texture coordinates (mapped()).
    bool is_mapped() const { return mapped_; }

    /// Largest image accepted (pixels), a guard against absurd headers and memory exhaustion.
    static constexpr long max_image_pixels = 1L << 25;

    /// Which of the three kinds this is.
    Kind kind() const { return kind_; }
    /// The value at (u,v); arguments outside [0,1] are clamped to it (NaN reads as 0).
    Rgb value(double u, double v) const;
    /// True when value() does not depend on (u,v) (a constant, or a checker of equal colours).
    bool is_constant() const;
    /// The mean over [0,1]^2 (exact for all three kinds: a bilinear image with clamped edges
    /// integrates to the average of its texels).
    Rgb mean() const;
    /// Per-channel minimum over [0,1]^2 (exact: bilinear lookups stay within the range of the
    /// texels they blend).
    Rgb minimum() const;
    /// Per-channel maximum over [0,1]^2 (exact, as minimum()).
    Rgb maximum() const;
    /// Where an image came from (empty for the procedural kinds).
    const std::string& source() const { return source_; }
    /// Checker squares per side (0 for the other kinds).
    int checker_squares() const { return n_; }
    /// True when both are images reading one and the same texel storage (one decoded file).
    bool shares_texels(const Texture& other) const {
        return pixels_ != nullptr && pixels_ == other.pixels_;
    }

    /// Bytes of the texel storage (shared by every texture that shares_texels() with this one);
    /// 0 for the procedural kinds.
    long texel_bytes() const;

private:
    // Unscaled texels, row 0 at the top (v = 1), in one of two forms: linear values (from_pixels)
    // or the file's 8-bit sRGB codes with their 256 decoded values (image: 3 bytes a texel
    // instead of 24, and the same doubles as decoding each texel up front). The codes stay in
    // the buffer stb_image decoded them into, so loading never holds two copies.
    struct Pixels {
        int width = 0, height = 0;
        std::vector<Rgb> linear;                    // from_pixels
        std::shared_ptr<const unsigned char> srgb;  // image: r, g, b codes of each texel
        std::vector<double> decoded;  // image: srgb_to_linear(code / 255) for the 256 codes
        Rgb mean, lo, hi;             // of the unscaled texels
        Rgb texel(int x, int y) const;
    };
    static Texture from_shared(std::shared_ptr<const Pixels> pixels, Rgb scale,
                               const std::string& name);
    Kind kind_ = Kind::Constant;
    Rgb a_, b_;            // constant value; checker colours
    int n_ = 0;            // checker squares per side
    Rgb scale_{1, 1, 1};   // an image's scale, applied to its texels on lookup
    bool mapped_ = false;  // value() reads through corners_ (mapped())
    CornerCoordinates corners_{};
    Rgb mapped_mean_;  // mean() of a mapped field
    /// value() without the texture coordinates: the field at (u, v) of its own square.
    Rgb unmapped_value(double u, double v) const;
    std::shared_ptr<const Pixels> pixels_;
    std::string source_;
};

/// The sRGB decoding function (IEC 61966-2-1): an encoded value in [0,1] to linear [0,1].
double srgb_to_linear(double encoded);

}  // namespace mbr
