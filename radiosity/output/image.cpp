// radiosity/output/image.cpp - PNG output with stb_image_write (Debian libstb-dev), encoded in
// memory: stb's file writer does not check fwrite or fclose, so it is never given a file.
#include "radiosity/output/image.h"

#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "math/check.h"
#include "radiosity/output/output_file.h"

namespace mbr {

std::string encode_png(const Image& image) {
    MBR_CHECK(image.width > 0 && image.height > 0 &&
              image.pixels.size() == size_t(image.width) * image.height);
    std::vector<unsigned char> bytes(size_t(image.width) * image.height * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            double v = image.pixels[i][c];
            v = std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 0.0;
            bytes[3 * i + c] = static_cast<unsigned char>(std::lround(255 * v));
        }
    std::string png;
    auto append = [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
    };
    // stb reports failure only when its own allocation of the compressed data fails.
    if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, bytes.data(),
                                image.width * 3))
        throw std::runtime_error("stb_image_write could not encode a " +
                                 std::to_string(image.width) + " x " +
                                 std::to_string(image.height) + " PNG");
    return png;
}

void write_png(const std::string& path, const Image& image) {
    write_file(path, encode_png(image));
}

}  // namespace mbr
