// radiosity/texture.h - a reflectance rho_i(s,t) or emission E_i(s,t) field over a surface's
// parameter domain [0,1]^2 (paper eqs. (1)-(2): "our algorithm does not require albedo to be
// constant over a surface", section 8). Three kinds: a constant RGB, a procedural checker, and
// an image (PNG, JPEG, ... through stb_image) looked up bilinearly.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "math/vec3.h"

namespace mbr {

/// A field of RGB values over (u,v) in [0,1]^2. Copies are cheap (image texels are shared).
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
    /// (row 0 of the file is v = 1). Throws InputError(path, 0, ...) when the file is missing or
    /// cannot be decoded, or has more than max_image_pixels pixels.
    static Texture image(const std::string& path, Rgb scale = {1, 1, 1});
    /// An image from linear texel values, row 0 at the top (v = 1), width * height of them.
    static Texture from_pixels(int width, int height, std::vector<Rgb> linear, Rgb scale,
                               const std::string& name = "");

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

private:
    struct Pixels {
        int width = 0, height = 0;
        std::vector<Rgb> texels;  // linear, already scaled; row 0 is the top (v = 1)
        Rgb mean, lo, hi;
    };
    Kind kind_ = Kind::Constant;
    Rgb a_, b_;  // constant value; checker colours
    int n_ = 0;  // checker squares per side
    std::shared_ptr<const Pixels> pixels_;
    std::string source_;
};

/// The sRGB decoding function (IEC 61966-2-1): an encoded value in [0,1] to linear [0,1].
double srgb_to_linear(double encoded);

}  // namespace mbr
