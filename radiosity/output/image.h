// radiosity/output/image.h - an RGB image and PNG output through stb_image_write. The PNG is
// encoded in memory and written by write_file (radiosity/output/output_file.h): all or nothing,
// every write checked, so a full disk or a missing folder never leaves a partial image behind.
#pragma once

#include <string>
#include <vector>

#include "math/vec3.h"
#include "radiosity/output/output_file.h"

namespace mbr {

/// Display values in [0, 1] per channel (tone mapping happens before); row 0 is the top.
struct Image {
    int width = 0, height = 0;
    std::vector<Rgb> pixels;

    Image() = default;
    Image(int width, int height, Rgb fill = {0, 0, 0})
        : width(width), height(height), pixels(size_t(width) * height, fill) {}
    Rgb& at(int x, int y) { return pixels[size_t(y) * width + x]; }
    const Rgb& at(int x, int y) const { return pixels[size_t(y) * width + x]; }
};

/// The bytes of an 8-bit RGB PNG of the image (values clamped to [0, 1], rounded; NaN as 0).
std::string encode_png(const Image& image);

/// Writes encode_png(image) to path with write_file: the target is replaced only on success.
/// Throws OutputError naming the path and the system's reason when it cannot be written.
void write_png(const std::string& path, const Image& image);

}  // namespace mbr
