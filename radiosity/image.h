// radiosity/image.h - an RGB image and PNG output through stb_image_write. Files are written
// to a temporary name in the same folder and renamed, so a failed run never leaves a partial
// image behind.
#pragma once

#include <string>
#include <vector>

#include "math/vec3.h"

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

/// Writes an 8-bit PNG (values clamped to [0, 1], rounded). Throws InputError naming the path
/// when the file cannot be written; the target is replaced only on success.
void write_png(const std::string& path, const Image& image);

}  // namespace mbr
