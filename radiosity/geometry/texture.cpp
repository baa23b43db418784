// radiosity/geometry/texture.cpp - constant, checker and image fields over [0,1]^2 (texture.h).
#include "radiosity/geometry/texture.h"

#include <stb_image.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "math/check.h"

namespace mbr {

namespace {

Rgb channel_min(Rgb a, Rgb b) {
    return {std::min(a.r, b.r), std::min(a.g, b.g), std::min(a.b, b.b)};
}
Rgb channel_max(Rgb a, Rgb b) {
    return {std::max(a.r, b.r), std::max(a.g, b.g), std::max(a.b, b.b)};
}

/// Clamps to [0,1]; NaN becomes 0 so that a bad argument can never index outside the texels.
double clamp01(double x) {
    return x >= 0 ? (x <= 1 ? x : 1.0) : 0.0;
}

}  // namespace

double srgb_to_linear(double c) {
    // IEC 61966-2-1: a linear toe below 0.04045, a 2.4 power above.
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

Texture Texture::constant(Rgb value) {
    Texture t;
    t.kind_ = Kind::Constant;
    t.a_ = value;
    return t;
}

Texture Texture::checker(Rgb a, Rgb b, int n) {
    MBR_CHECK_MSG(n >= 1, "checker squares n = " << n);
    Texture t;
    t.kind_ = Kind::Checker;
    t.a_ = a;
    t.b_ = b;
    t.n_ = n;
    return t;
}

Rgb Texture::Pixels::texel(int x, int y) const {
    const size_t i = size_t(y) * size_t(width) + size_t(x);
    if (!srgb) return linear[i];
    const unsigned char* c = srgb.get() + 3 * i;
    return {decoded[c[0]], decoded[c[1]], decoded[c[2]]};
}

Texture Texture::from_shared(std::shared_ptr<const Pixels> pixels, Rgb scale,
                             const std::string& name) {
    Texture t;
    t.kind_ = Kind::Image;
    t.pixels_ = std::move(pixels);
    t.scale_ = scale;
    t.source_ = name;
    return t;
}

namespace {

/// Fills mean, lo and hi of the unscaled texels.
template <typename Pixels>
void summarize(Pixels& p) {
    Rgb sum, lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x) {
            const Rgb texel = p.texel(x, y);
            sum += texel;
            lo = channel_min(lo, texel);
            hi = channel_max(hi, texel);
        }
    p.mean = sum * (1.0 / (double(p.width) * double(p.height)));
    p.lo = lo;
    p.hi = hi;
}

}  // namespace

Texture Texture::from_pixels(int width, int height, std::vector<Rgb> linear, Rgb scale,
                             const std::string& name) {
    MBR_CHECK(width >= 1 && height >= 1 && linear.size() == size_t(width) * size_t(height));
    auto pixels = std::make_shared<Pixels>();
    pixels->width = width;
    pixels->height = height;
    pixels->linear = std::move(linear);
    summarize(*pixels);
    return from_shared(std::move(pixels), scale, name);
}

namespace {

/// True when the bytes begin with the PNG signature; width and height are then those of its
/// IHDR chunk, or -1 when the header is cut short or does not begin with IHDR.
bool is_png(const std::string& bytes, long& width, long& height) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    const auto h = [&](size_t i) { return static_cast<unsigned char>(bytes[i]); };
    if (bytes.size() < 8) return false;
    for (size_t i = 0; i < 8; ++i)
        if (h(i) != signature[i]) return false;
    width = height = -1;
    if (bytes.size() < 24 || bytes.compare(12, 4, "IHDR") != 0) return true;
    const auto big_endian = [&](size_t at) {
        return (long(h(at)) << 24) | (long(h(at + 1)) << 16) | (long(h(at + 2)) << 8) | h(at + 3);
    };
    width = big_endian(16);
    height = big_endian(20);
    return true;
}

/// The largest texture file read (bytes): beyond what the largest image accepted takes
/// uncompressed at four channels, with room for headers.
constexpr long max_image_file_bytes = 4 * Texture::max_image_pixels + (1L << 20);

/// The whole file at `path` (a regular file, checked by the caller), or InputError(path, 0, ...)
/// when it cannot be opened or read, or is larger than max_image_file_bytes.
std::string read_image_file(const std::string& path) {
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "cannot open the texture file" + system_reason());
    std::string bytes;
    char buffer[1 << 16];
    while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
        bytes.append(buffer, size_t(in.gcount()));
        if (long(bytes.size()) > max_image_file_bytes)
            throw InputError(path, 0,
                             "the texture file is larger than " +
                                 std::to_string(max_image_file_bytes >> 20) +
                                 " MiB; no image mbr accepts needs that much");
    }
    if (in.bad()) throw InputError(path, 0, "cannot read the texture file" + system_reason());
    return bytes;
}

/// A BMP with a BITMAPV3INFOHEADER (56 bytes: the 40 of BITMAPINFOHEADER, then the red, green,
/// blue and alpha masks), which image editors write for 16-bit pixels, is one stb_image refuses.
/// It is rewritten in memory as the BITMAPINFOHEADER that stb_image reads: the header's size set
/// to 40, followed by the three colour masks when the pixels are bit fields (compression 3) and
/// by nothing otherwise, the masks it does not read (alpha, which mbr ignores) cut out, and the
/// pixels' offset in the file header moved back by the bytes cut.
void accept_bmp_v3_header(std::string& bytes) {
    if (bytes.size() < 14 + 56 || bytes[0] != 'B' || bytes[1] != 'M') return;
    const auto u32 = [&](size_t i) {
        const auto b = [&](size_t k) {
            return static_cast<unsigned long>(static_cast<unsigned char>(bytes[k]));
        };
        return b(i) | (b(i + 1) << 8) | (b(i + 2) << 16) | (b(i + 3) << 24);
    };
    const auto set_u32 = [&](size_t i, unsigned long x) {
        for (size_t k = 0; k < 4; ++k) bytes[i + k] = static_cast<char>((x >> (8 * k)) & 0xff);
    };
    if (u32(14) != 56) return;
    const unsigned long offset = u32(10);
    const bool bit_fields = u32(14 + 16) == 3;
    const size_t keep = 14 + 40 + (bit_fields ? 12 : 0);  // what stb_image reads of the header
    const size_t cut = 14 + 56 - keep;
    if (offset < 14 + 56) return;  // pixels inside the header: leave it to stb_image to refuse
    bytes.erase(keep, cut);
    set_u32(14, 40);
    set_u32(10, offset - cut);
    set_u32(2, static_cast<unsigned long>(bytes.size()));
}

/// A byte string for a message: printable ASCII as is, other bytes as \xHH.
std::string printable(const std::string& s) {
    std::string out;
    for (unsigned char c : s) {
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

/// stb_image's reason for a failure, in words. Its reason for an unknown critical PNG chunk,
/// "XXXX PNG chunk not known", holds the chunk type's four raw bytes and is cut short at a
/// zero byte among them (every other reason of stb_image has at least 5 characters).
std::string failure_reason(const char* why, const char* otherwise) {
    if (!why) return otherwise;
    const std::string s = why;
    const std::string suffix = " PNG chunk not known";
    if (s.size() == 4 + suffix.size() && s.compare(4, std::string::npos, suffix) == 0)
        return "unknown PNG chunk type '" + printable(s.substr(0, 4)) + "'";
    if (s.size() < 5) return "unknown PNG chunk type (it holds a zero byte)";
    return printable(s);
}

std::string too_many_pixels(long width, long height) {
    return "texture image is " + std::to_string(width) + " x " + std::to_string(height) +
           " pixels; at most " + std::to_string(Texture::max_image_pixels) + " pixels are accepted";
}

}  // namespace

Texture Texture::image(const std::string& path, Rgb scale) {
    // A folder, a device or a FIFO is refused before it is read (stb_image would read /dev/zero
    // or wait on a FIFO).
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!ec && fs::is_directory(st)) throw InputError(path, 0, "is a folder, not a file");
    if (!ec && fs::exists(st) && !fs::is_regular_file(st))
        throw InputError(path, 0, "is not a regular file");
    std::string bytes = read_image_file(path);
    accept_bmp_v3_header(bytes);
    const auto* data_in = reinterpret_cast<const stbi_uc*>(bytes.data());
    const int n_bytes = int(bytes.size());
    // Ask for the size first, so that an absurd header cannot make stb_image allocate gigabytes.
    int width = 0, height = 0, channels = 0;
    if (!stbi_info_from_memory(data_in, n_bytes, &width, &height, &channels)) {
        const std::string why = failure_reason(stbi_failure_reason(), "unknown format");
        // stb_image refuses a PNG header of more than 2^30 bytes of pixels ("too large") and
        // then reports the last format it tried ("unknown image type"): say what the header says.
        long png_width = 0, png_height = 0;
        if (is_png(bytes, png_width, png_height)) {
            if (png_width > 0 && png_height > 0 && png_width * png_height > max_image_pixels)
                throw InputError(path, 0, too_many_pixels(png_width, png_height));
            throw InputError(path, 0,
                             "cannot read the texture image (a damaged or truncated PNG header)");
        }
        throw InputError(path, 0, "cannot read the texture image (" + why + ")");
    }
    if (width < 1 || height < 1 || long(width) * long(height) > max_image_pixels)
        throw InputError(path, 0, too_many_pixels(width, height));
    unsigned char* data = stbi_load_from_memory(data_in, n_bytes, &width, &height, &channels, 3);
    if (!data) {
        const std::string why = failure_reason(stbi_failure_reason(), "unknown error");
        throw InputError(path, 0, "cannot decode the texture image (" + why + ")");
    }
    bytes = std::string();  // the file's bytes are not needed beside the decoded texels
    auto pixels = std::make_shared<Pixels>();
    pixels->width = width;
    pixels->height = height;
    pixels->srgb = std::shared_ptr<const unsigned char>(
        data, [](const unsigned char* p) { stbi_image_free(const_cast<unsigned char*>(p)); });
    // sRGB decoding of the 256 possible 8-bit values, once.
    pixels->decoded.resize(256);
    for (int i = 0; i < 256; ++i) pixels->decoded[size_t(i)] = srgb_to_linear(i / 255.0);
    summarize(*pixels);
    return from_shared(std::move(pixels), scale, path);
}

long Texture::texel_bytes() const {
    if (!pixels_) return 0;
    const long n = long(pixels_->width) * pixels_->height;
    // The 8-bit codes stb_image decoded (3 a texel) or the linear values (24 a texel).
    return pixels_->srgb ? 3 * n : long(sizeof(Rgb)) * n;
}

Texture Texture::scaled(Rgb scale) const {
    Texture t = *this;
    t.a_ = a_ * scale;
    t.b_ = b_ * scale;
    t.scale_ = scale_ * scale;
    t.mapped_mean_ = mapped_mean_ * scale;
    return t;
}

namespace {

/// A texture coordinate inside [0,1] as it is; outside, its fractional part (the texture
/// repeats). NaN stays NaN, which clamp01 reads as 0.
double wrap01(double x) {
    return (x >= 0 && x <= 1) ? x : x - std::floor(x);
}

}  // namespace

Texture Texture::mapped(const CornerCoordinates& corners) const {
    if (kind_ == Kind::Constant) return *this;  // no coordinates change a constant
    Texture t = *this;
    t.corners_ = corners;
    // The mean of what the coordinates show: a midpoint rule of 16 x 16 points.
    constexpr int n = 16;
    Rgb sum;
    t.mapped_ = true;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) sum += t.value((i + 0.5) / n, (j + 0.5) / n);
    t.mapped_mean_ = sum * (1.0 / (n * n));
    return t;
}

Rgb Texture::value(double u, double v) const {
    if (!mapped_) return unmapped_value(u, v);
    // The bilinear blend of the corners' coordinates (corners at (0,0), (1,0), (1,1), (0,1)).
    const double a = (1 - u) * (1 - v), b = u * (1 - v), c = u * v, d = (1 - u) * v;
    const CornerCoordinates& k = corners_;
    return unmapped_value(wrap01(a * k[0][0] + b * k[1][0] + c * k[2][0] + d * k[3][0]),
                          wrap01(a * k[0][1] + b * k[1][1] + c * k[2][1] + d * k[3][1]));
}

Rgb Texture::unmapped_value(double u, double v) const {
    switch (kind_) {
        case Kind::Constant:
            return a_;
        case Kind::Checker: {
            // Square (i, j) holds [i/n, (i+1)/n) x [j/n, (j+1)/n); u = 1 belongs to the last one.
            int i = std::min(int(clamp01(u) * n_), n_ - 1);
            int j = std::min(int(clamp01(v) * n_), n_ - 1);
            return (i + j) % 2 == 0 ? a_ : b_;
        }
        case Kind::Image: {
            // Texel (x, y) sits at its centre ((x + 0.5)/w, 1 - (y + 0.5)/h); bilinear between
            // centres, constant in the half texel along the border (clamp to edge).
            const Pixels& p = *pixels_;
            double fx = clamp01(u) * p.width - 0.5;
            double fy = (1 - clamp01(v)) * p.height - 0.5;
            fx = std::clamp(fx, 0.0, double(p.width - 1));
            fy = std::clamp(fy, 0.0, double(p.height - 1));
            int x0 = std::min(int(fx), p.width - 1), y0 = std::min(int(fy), p.height - 1);
            int x1 = std::min(x0 + 1, p.width - 1), y1 = std::min(y0 + 1, p.height - 1);
            double tx = fx - x0, ty = fy - y0;
            Rgb blend = (1 - ty) * ((1 - tx) * p.texel(x0, y0) + tx * p.texel(x1, y0)) +
                        ty * ((1 - tx) * p.texel(x0, y1) + tx * p.texel(x1, y1));
            return scale_ * blend;
        }
    }
    return {};
}

bool Texture::is_constant() const {
    switch (kind_) {
        case Kind::Constant:
            return true;
        case Kind::Checker:
            return a_ == b_ || n_ == 1;
        case Kind::Image:
            return minimum() == maximum();
    }
    return true;
}

Rgb Texture::mean() const {
    if (mapped_) return mapped_mean_;
    switch (kind_) {
        case Kind::Constant:
            return a_;
        case Kind::Checker: {
            // Squares with i + j even hold a: ceil(n^2 / 2) of them.
            long n2 = long(n_) * n_;
            long n_a = (n2 + 1) / 2;
            return (double(n_a) * a_ + double(n2 - n_a) * b_) * (1.0 / double(n2));
        }
        case Kind::Image:
            return scale_ * pixels_->mean;
    }
    return {};
}

Rgb Texture::minimum() const {
    switch (kind_) {
        case Kind::Constant:
            return a_;
        case Kind::Checker:
            return n_ == 1 ? a_ : channel_min(a_, b_);
        case Kind::Image:  // a negative scale turns the range around
            return channel_min(scale_ * pixels_->lo, scale_ * pixels_->hi);
    }
    return {};
}

Rgb Texture::maximum() const {
    switch (kind_) {
        case Kind::Constant:
            return a_;
        case Kind::Checker:
            return n_ == 1 ? a_ : channel_max(a_, b_);
        case Kind::Image:
            return channel_max(scale_ * pixels_->lo, scale_ * pixels_->hi);
    }
    return {};
}

}  // namespace mbr
