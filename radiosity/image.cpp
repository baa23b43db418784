// radiosity/image.cpp - PNG output with stb_image_write (Debian libstb-dev).
#include "radiosity/image.h"

#include <stb_image_write.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "math/check.h"

namespace mbr {

void write_png(const std::string& path, const Image& image) {
    MBR_CHECK(image.width > 0 && image.height > 0 &&
              image.pixels.size() == size_t(image.width) * image.height);
    std::vector<unsigned char> bytes(size_t(image.width) * image.height * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            double v = image.pixels[i][c];
            v = std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 0.0;
            bytes[3 * i + c] = static_cast<unsigned char>(std::lround(255 * v));
        }
    // Same folder as the target, so the rename cannot cross file systems.
    const std::string tmp = path + ".tmp-" + std::to_string(static_cast<long>(getpid()));
    if (!stbi_write_png(tmp.c_str(), image.width, image.height, 3, bytes.data(), image.width * 3)) {
        std::remove(tmp.c_str());
        throw InputError(path, 0, "cannot write the PNG file (does its folder exist?)");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        int err = errno;
        std::remove(tmp.c_str());
        throw InputError(path, 0, std::string("cannot write the PNG file: ") + std::strerror(err));
    }
}

}  // namespace mbr
