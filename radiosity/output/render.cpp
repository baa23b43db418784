// radiosity/output/render.cpp - the camera's view of the solved radiosity (eq. (20), radiance B /
// pi of Lambertian surfaces), tone mapping, Radiance RGBE files and the quadtree overlay.
#include "radiosity/output/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <istream>
#include <optional>
#include <ostream>
#include <sstream>
#include <unordered_map>

#include "math/check.h"
#include "math/parallel.h"
#include "radiosity/geometry/texture.h"

namespace mbr {

namespace {

// The camera's frame, computed once per image rather than once per ray.
struct CameraFrame {
    Vec3 eye, forward, right, up;
    double half_w = 0, half_h = 0;  // half extents of the image plane at distance 1
    double width = 0, height = 0;

    explicit CameraFrame(const Camera& camera) {
        MBR_CHECK(camera.width > 0 && camera.height > 0);
        MBR_CHECK(camera.fov_degrees > 0 && camera.fov_degrees < 180);
        eye = camera.eye;
        forward = normalize(camera.look_at - camera.eye);
        right = normalize(cross(forward, camera.up));
        MBR_CHECK(length(forward) > 0 && length(right) > 0);  // up not along the view
        up = cross(right, forward);
        half_h = std::tan(0.5 * camera.fov_degrees * Pi / 180);
        half_w = half_h * camera.width / camera.height;
        width = camera.width;
        height = camera.height;
    }

    Ray ray(double x, double y) const {
        const double s_x = (2 * x / width - 1) * half_w;   // image right
        const double s_y = (1 - 2 * y / height) * half_h;  // image up: row 0 is the top
        return Ray{eye, forward + s_x * right + s_y * up};
    }
};

// DESIGN: a counter-based generator, so that a pixel's jitter depends only on (seed, x, y),
// never on which thread renders it or in what order: SplitMix64 [Steele, Lea and Flood 2014],
// whose state is a counter advanced by the golden-ratio increment and whose output is the
// counter passed through a bijective mixing function; the pixel's key selects the start.
constexpr std::uint64_t golden_gamma = 0x9e3779b97f4a7c15ULL;

std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

class PixelRng {
public:
    PixelRng(std::uint64_t seed, int x, int y) {
        const std::uint64_t key = (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x);
        state_ = mix64(mix64(seed + golden_gamma) ^ key);
    }
    /// Uniform in [0, 1): the top 53 bits of the next output.
    double uniform() {
        state_ += golden_gamma;
        return double(mix64(state_) >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t state_;
};

void check_fields(const Scene& scene, const RadiosityView& radiosity) {
    MBR_CHECK(radiosity.size() == static_cast<int>(scene.surfaces.size()));
}

// The one-sidedness test and the (surface, u, v) of a camera ray, shared by the radiance and
// the overlay.
struct FrontHit {
    int surface = -1;
    double u = 0, v = 0;
};

/// A culled ray goes on through at most this many backs (a closed object seen from inside
/// another: two backs per wall of a room of boxes seen from outside).
constexpr int max_culled_backs = 64;

std::optional<FrontHit> front_hit(const Octree& octree, const Ray& ray, RenderStats* stats,
                                  BackFaces back_faces) {
    RayStats* ray_stats = stats ? &stats->rays : nullptr;
    if (stats) ++stats->n_camera_rays;
    Ray r = ray;
    for (int backs = 0; backs <= max_culled_backs; ++backs) {
        const std::optional<Hit> hit = octree.closest_hit(r, ray_stats);
        if (!hit) return std::nullopt;
        // DESIGN: the side is decided by the normal of the polygon the ray met rather than by
        // Surface::normal at the hit's (u, v). Both agree on the front (facets are
        // counter-clockwise seen from it), but only the facet's normal matches the geometry the
        // ray actually hit: near the silhouette of a tessellated sphere or cylinder the true
        // normal at (u, v) can already face away while the facet still faces the camera, which
        // would leave a ring of black pixels.
        if (dot(r.dir, octree.polygons()[hit->polygon].normal()) < 0) {
            if (stats) ++stats->n_front_hits;
            // Polygon::uv_at extrapolates slightly beyond a facet's edge (the octree's slack).
            return FrontHit{hit->surface, std::clamp(hit->uv.x, 0.0, 1.0),
                            std::clamp(hit->uv.y, 0.0, 1.0)};
        }
        if (stats) ++stats->n_back_hits;
        if (back_faces == BackFaces::Black) return std::nullopt;
        // DESIGN: culled, the ray goes on from just beyond the back (1e-9 of its distance).
        r.t_min = hit->t + 1e-9 * std::max(hit->t, 1e-300);
    }
    return std::nullopt;
}

Rgb radiance_at(const RadiosityView& radiosity, const std::optional<FrontHit>& hit) {
    if (!hit) return {};
    MBR_CHECK(hit->surface >= 0 && hit->surface < radiosity.size());
    // Lambertian: L = B / pi, with B = E + rho H where the field holds H (radiosity_view.h).
    return InvPi * radiosity.at(hit->surface, hit->u, hit->v);
}

// The leaves of one surface's quadtree, found by (level, i, j) from the coarsest level down.
class LeafLookup {
public:
    LeafLookup() = default;
    explicit LeafLookup(const std::vector<DyadicCell>& leaves) {
        for (int index = 0; index < static_cast<int>(leaves.size()); ++index) {
            const DyadicCell& c = leaves[index];
            if (!c.in_domain()) continue;
            MBR_CHECK(c.level >= 0 && c.level <= max_supported_level);
            cells_.emplace(key(c.level, c.i, c.j), index);
            max_level_ = std::max(max_level_, c.level);
        }
    }
    /// Index of the leaf holding (u, v) (half-open cells, u = 1 in the last), or -1.
    int find(double u, double v) const {
        for (int level = 0; level <= max_level_; ++level) {
            const int n = 1 << level;
            const int i = std::min(static_cast<int>(u * n), n - 1);
            const int j = std::min(static_cast<int>(v * n), n - 1);
            auto it = cells_.find(key(level, i, j));
            if (it != cells_.end()) return it->second;
        }
        return -1;
    }

private:
    static constexpr int max_supported_level = 28;  // i, j fit 29 bits of the key
    static std::uint64_t key(int level, int i, int j) {
        return (std::uint64_t(level) << 58) | (std::uint64_t(i) << 29) | std::uint64_t(j);
    }
    std::unordered_map<std::uint64_t, int> cells_;
    int max_level_ = -1;
};

// ---- Radiance RGBE (Ward, "Real Pixels", Graphics Gems II, 1991) ----

std::array<unsigned char, 4> to_rgbe(Rgb c) {
    for (int k = 0; k < 3; ++k)
        if (!(std::isfinite(c[k]) && c[k] > 0)) c[k] = 0;
    const double v = std::max({c.r, c.g, c.b});
    int e = 0;
    std::frexp(v, &e);  // v = m 2^e, m in [0.5, 1)
    if (v == 0 || e + 128 < 1) return {0, 0, 0, 0};
    e = std::min(e, 127);                         // saturate beyond 2^127
    const double scale = std::ldexp(1.0, 8 - e);  // the largest channel to [128, 256)
    std::array<unsigned char, 4> rgbe;
    for (int k = 0; k < 3; ++k)
        rgbe[k] = static_cast<unsigned char>(std::min(255.0, std::floor(c[k] * scale)));
    rgbe[3] = static_cast<unsigned char>(e + 128);
    return rgbe;
}

// The centre of each 8-bit interval, as Radiance's own colr_color decodes.
Rgb from_rgbe(const unsigned char* rgbe) {
    if (rgbe[3] == 0) return {};
    const double f = std::ldexp(1.0, int(rgbe[3]) - (128 + 8));
    return {(rgbe[0] + 0.5) * f, (rgbe[1] + 0.5) * f, (rgbe[2] + 0.5) * f};
}

class HdrReader {
public:
    HdrReader(std::istream& in, const std::string& name) : in_(in), name_(name) {}

    Image read() {
        const std::string magic = line("the header");
        if (magic != "#?RADIANCE" && magic != "#?RGBE")
            fail("not a Radiance HDR image (the first line is not #?RADIANCE)");
        double exposure = 1;
        for (;;) {
            const std::string l = line("the header");
            if (l.empty()) break;
            if (l.rfind("FORMAT=", 0) == 0) {
                const std::string format = l.substr(7);
                if (format != "32-bit_rle_rgbe")
                    fail("unsupported pixel format '" + format +
                         "' (only 32-bit_rle_rgbe is read)");
            } else if (l.rfind("EXPOSURE=", 0) == 0) {
                std::istringstream is(l.substr(9));
                double e = 0;
                if (!(is >> e) || !std::isfinite(e) || e <= 0)
                    fail("bad header line '" + l + "' (EXPOSURE must be a positive number)");
                exposure *= e;
            }
        }
        const std::string resolution = line("the resolution line");
        std::istringstream is(resolution);
        std::string y_axis, x_axis, extra;
        long h = 0, w = 0;
        if (!(is >> y_axis >> h >> x_axis >> w) || (is >> extra))
            fail("bad resolution line '" + resolution + "'");
        if (y_axis != "-Y" || x_axis != "+X")
            fail("unsupported pixel order '" + resolution + "' (only -Y height +X width is read)");
        if (w < 1 || h < 1 || w > Texture::max_image_pixels || h > Texture::max_image_pixels ||
            w * h > Texture::max_image_pixels)
            fail("bad image size " + std::to_string(w) + " x " + std::to_string(h) + " (at most " +
                 std::to_string(Texture::max_image_pixels) + " pixels)");

        Image image(static_cast<int>(w), static_cast<int>(h));
        std::vector<unsigned char> row(4 * size_t(w));
        for (int y = 0; y < image.height; ++y) {
            scanline(row, image.width, y);
            for (int x = 0; x < image.width; ++x)
                image.at(x, y) = (1 / exposure) * from_rgbe(&row[4 * size_t(x)]);
        }
        return image;
    }

private:
    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(name_, 0, message);
    }

    // One header line without its '\n' (a trailing '\r' is dropped too).
    std::string line(const char* what) {
        std::string l;
        for (;;) {
            const int c = in_.get();
            if (c == std::char_traits<char>::eof()) fail(std::string("truncated in ") + what);
            if (c == '\n') break;
            if (++header_bytes_ > max_header_bytes)
                fail("not a Radiance HDR image (header longer than 64 KiB)");
            l.push_back(static_cast<char>(c));
        }
        if (!l.empty() && l.back() == '\r') l.pop_back();
        return l;
    }

    unsigned char byte(int y) {
        const int c = in_.get();
        if (c == std::char_traits<char>::eof()) truncated(y);
        return static_cast<unsigned char>(c);
    }

    void bytes(unsigned char* out, size_t n, int y) {
        in_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
        if (static_cast<size_t>(in_.gcount()) != n) truncated(y);
    }

    [[noreturn]] void truncated(int y) const {
        fail("truncated in scanline " + std::to_string(y) + " (counting from the top, from 0)");
    }

    // A scanline is flat (4 bytes a pixel) or new-style run-length encoded: the marker 2, 2,
    // width (16 bits), then each of the four byte planes in runs, a count above 128 repeating
    // the next byte count - 128 times, a count of 1..128 followed by that many literal bytes.
    void scanline(std::vector<unsigned char>& row, int w, int y) {
        unsigned char head[4];
        bytes(head, 4, y);
        const bool rle = w >= 8 && w < 32768 && head[0] == 2 && head[1] == 2 && head[2] < 128;
        if (!rle) {
            std::copy(head, head + 4, row.begin());
            bytes(row.data() + 4, 4 * (size_t(w) - 1), y);
            // Old-style runs mark a repeat by a pixel 1, 1, 1, count, which no encoder that
            // normalises the largest mantissa to >= 128 writes as a colour.
            for (int x = 0; x < w; ++x)
                if (row[4 * size_t(x)] == 1 && row[4 * size_t(x) + 1] == 1 &&
                    row[4 * size_t(x) + 2] == 1)
                    fail("old-style run-length data in scanline " + std::to_string(y) +
                         " (not supported)");
            return;
        }
        if (((head[2] << 8) | head[3]) != w)
            fail("scanline " + std::to_string(y) + " has length " +
                 std::to_string((head[2] << 8) | head[3]) + ", not the image's width " +
                 std::to_string(w));
        std::vector<unsigned char> plane(static_cast<size_t>(w));
        for (int k = 0; k < 4; ++k) {
            for (int x = 0; x < w;) {
                int count = byte(y);
                const bool run = count > 128;
                if (run) count -= 128;
                if (count == 0 || x + count > w)
                    fail("bad run-length data in scanline " + std::to_string(y));
                if (run)
                    std::fill_n(plane.begin() + x, count, byte(y));
                else
                    bytes(plane.data() + x, size_t(count), y);
                x += count;
            }
            for (int x = 0; x < w; ++x) row[4 * size_t(x) + k] = plane[x];
        }
    }

    static constexpr long max_header_bytes = 1 << 16;
    std::istream& in_;
    const std::string& name_;
    long header_bytes_ = 0;
};

}  // namespace

RenderStats& RenderStats::operator+=(const RenderStats& other) {
    n_camera_rays += other.n_camera_rays;
    n_front_hits += other.n_front_hits;
    n_back_hits += other.n_back_hits;
    rays += other.rays;
    return *this;
}

Vec3 scene_up(const Scene& scene) {
    // The lights' mean normal, weighted by their power (area x the emission's mean channel).
    Vec3 down;
    for (const SceneSurface& s : scene.surfaces) {
        const Material& m = scene.materials[size_t(s.material)];
        if (!m.emits()) continue;
        const Rgb e = m.emission.mean();
        const double power = (e.r + e.g + e.b) / 3;
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                const SurfacePoint p = s.surface.evaluate((a + 0.5) / 4, (b + 0.5) / 4);
                down += (power * p.area_factor / 16) * p.normal;
            }
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (std::fabs(down[k]) > std::fabs(down[axis])) axis = k;
    if (!(length(down) > 0) || std::fabs(down[axis]) < 0.7 * length(down)) return {0, 1, 0};
    Vec3 up;
    up[axis] = down[axis] > 0 ? -1 : 1;
    return up;
}

Camera framing_camera(const Scene& scene) {
    Camera c;
    c.fov_degrees = 45;
    c.width = 640;
    c.height = 480;
    c.up = scene_up(scene);
    const Box3 bounds = scene.bounds();
    const Vec3 centre = bounds.empty() ? Vec3{0, 0, 0} : bounds.centre();
    const double r = bounds.empty() ? 0 : 0.5 * length(bounds.extent());
    const double radius = r > 0 ? r : 1;  // a point or nothing: a unit sphere around it
    const double distance = 1.05 * radius / std::sin(0.5 * c.fov_degrees * Pi / 180);
    // The four sides, each a horizontal axis raised by 0.15 (from straight ahead both side
    // walls of a box face the eye; a little above, its floor shows). With up the y axis they
    // are +z, -z, +x, -x; with up axis k, the axes k + 2 and k + 1 (mod 3) likewise.
    int k = 0;
    while (c.up[k] == 0) ++k;
    Vec3 h1, h2;
    h1[(k + 2) % 3] = 1;
    h2[(k + 1) % 3] = 1;
    const Vec3 raise = 0.15 * c.up;
    const Vec3 sides[4] = {h1 + raise, -1.0 * h1 + raise, h2 + raise, -1.0 * h2 + raise};
    Vec3 best = normalize(sides[0]);
    double best_facing = -HUGE_VAL;
    for (const Vec3& side : sides) {
        const Vec3 d = normalize(side);
        double facing = 0;
        for (const SceneSurface& s : scene.surfaces)
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) {
                    const SurfacePoint p = s.surface.evaluate((a + 0.5) / 4, (b + 0.5) / 4);
                    facing += p.area_factor / 16 * dot(p.normal, d);
                }
        if (facing > best_facing) {
            best_facing = facing;
            best = d;
        }
    }
    c.look_at = centre;
    c.eye = centre + distance * best;
    return c;
}

Ray camera_ray(const Camera& camera, double x, double y) {
    return CameraFrame(camera).ray(x, y);
}

Rgb radiance_along(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                   const Ray& ray, RenderStats* stats, BackFaces back_faces) {
    check_fields(scene, radiosity);
    return radiance_at(radiosity, front_hit(octree, ray, stats, back_faces));
}

double render_bytes(int width, int height, const RenderOptions& options) {
    // Calibration (Release, the Cornell box rendered from a saved solution with --spp 1, peak
    // resident size from /usr/bin/time -f %M): 62,892 KB at 1024 x 1024, 894,524 KB at
    // 4096 x 4096, i.e. 54.3 bytes a pixel above the program: two Images of Rgb (48), the
    // 8-bit pixels (3) and the PNG encoder's filtered rows and output (about 3). DESIGN: 56 a
    // pixel, and 8 more for the overlay's (surface, leaf) per pixel.
    const double pixels = double(width) * double(height);
    return pixels * (56.0 + (options.quadtree_overlay ? 8.0 : 0.0));
}

Image render_radiance(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                      const RenderOptions& options, RenderStats* stats) {
    check_fields(scene, radiosity);
    MBR_CHECK(options.samples_per_pixel >= 1);
    const CameraFrame camera(scene.camera);
    const int width = scene.camera.width, height = scene.camera.height;
    const int spp = options.samples_per_pixel;
    // DESIGN: jitter is stratified on a k x k grid when spp = k^2 (one sample in each sub-square),
    // plain uniform inside the pixel otherwise; the filter is a box, the plain mean of the samples.
    const int k = static_cast<int>(std::lround(std::sqrt(double(spp))));
    const bool stratified = k * k == spp;

    Image image(width, height);
    std::vector<RenderStats> row_stats(height);  // summed in row order after the loop
    parallel_for(height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            PixelRng rng(options.seed, x, y);
            Rgb sum;
            for (int s = 0; s < spp; ++s) {
                double j_x = rng.uniform(), j_y = rng.uniform();
                if (stratified) {
                    j_x = (s % k + j_x) / k;
                    j_y = (s / k + j_y) / k;
                }
                const Ray ray = camera.ray(x + j_x, y + j_y);
                sum += radiance_at(radiosity,
                                   front_hit(octree, ray, &row_stats[y], options.back_faces));
            }
            image.at(x, y) = (1.0 / spp) * sum;
        }
    });
    if (stats) {
        *stats = RenderStats{};
        for (const RenderStats& s : row_stats) *stats += s;
    }
    return image;
}

double linear_to_srgb(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
}

double clip_to_display(double linear) {
    return std::isfinite(linear) ? std::clamp(linear, 0.0, 1.0) : 0.0;
}

Image tone_map(const Image& radiance, double exposure) {
    Image display(radiance.width, radiance.height);
    for (size_t p = 0; p < radiance.pixels.size(); ++p)
        for (int c = 0; c < 3; ++c)
            display.pixels[p][c] =
                linear_to_srgb(clip_to_display(exposure * radiance.pixels[p][c]));
    return display;
}

double auto_exposure(const Image& radiance) {
    // Reinhard et al. (2002): the log-average luminance of the scene shown at the key 0.18.
    double log_sum = 0;
    long lit = 0;
    for (const Rgb& p : radiance.pixels) {
        const double y = 0.2126 * p.r + 0.7152 * p.g + 0.0722 * p.b;
        if (!(std::isfinite(y) && y > 0)) continue;
        log_sum += std::log(y);
        ++lit;
    }
    return lit == 0 ? 1.0 : 0.18 / std::exp(log_sum / double(lit));
}

void draw_quadtree_overlay(Image& display, const Scene& scene, const Octree& octree,
                           const std::vector<std::vector<DyadicCell>>* leaves, Rgb colour,
                           RenderStats* stats, BackFaces back_faces) {
    const CameraFrame camera(scene.camera);
    const int width = scene.camera.width, height = scene.camera.height;
    MBR_CHECK(display.width == width && display.height == height);
    MBR_CHECK(!leaves || leaves->size() == scene.surfaces.size());
    std::vector<LeafLookup> lookup(scene.surfaces.size());
    if (leaves)
        for (size_t i = 0; i < leaves->size(); ++i) lookup[i] = LeafLookup((*leaves)[i]);

    // DESIGN: one ray through each pixel centre names the (surface, leaf) seen there (a miss or
    // the back of a surface names nothing); a pixel whose right or lower neighbour names something
    // else is a line pixel. Lines are one pixel wide, lie on the upper-left side of each
    // boundary, and follow cell edges under perspective, occlusion and curved surfaces alike.
    struct Seen {
        int surface = -1, leaf = -1;
        bool operator!=(const Seen& o) const { return surface != o.surface || leaf != o.leaf; }
    };
    std::vector<Seen> seen(size_t(width) * height);
    std::vector<RenderStats> row_stats(height);
    parallel_for(height, [&](int y) {
        for (int x = 0; x < width; ++x) {
            const std::optional<FrontHit> hit =
                front_hit(octree, camera.ray(x + 0.5, y + 0.5), &row_stats[y], back_faces);
            if (hit)
                seen[size_t(y) * width + x] = {hit->surface,
                                               lookup[hit->surface].find(hit->u, hit->v)};
        }
    });
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const Seen& here = seen[size_t(y) * width + x];
            if ((x + 1 < width && seen[size_t(y) * width + x + 1] != here) ||
                (y + 1 < height && seen[size_t(y + 1) * width + x] != here))
                display.at(x, y) = colour;
        }
    if (stats)
        for (const RenderStats& s : row_stats) *stats += s;
}

Image render_display(const Scene& scene, const Octree& octree, const RadiosityView& radiosity,
                     const RenderOptions& options,
                     const std::vector<std::vector<DyadicCell>>* leaves, RenderStats* stats) {
    Image display =
        tone_map(render_radiance(scene, octree, radiosity, options, stats), options.exposure);
    if (options.quadtree_overlay)
        draw_quadtree_overlay(display, scene, octree, leaves, options.overlay_colour, stats);
    return display;
}

void write_hdr(std::ostream& out, const Image& radiance) {
    MBR_CHECK(radiance.width > 0 && radiance.height > 0 &&
              radiance.pixels.size() == size_t(radiance.width) * radiance.height);
    out << "#?RADIANCE\n# linear radiance written by mbr\nFORMAT=32-bit_rle_rgbe\n\n"
        << "-Y " << radiance.height << " +X " << radiance.width << '\n';
    std::vector<unsigned char> row(4 * size_t(radiance.width));
    for (int y = 0; y < radiance.height; ++y) {
        for (int x = 0; x < radiance.width; ++x) {
            const std::array<unsigned char, 4> rgbe = to_rgbe(radiance.at(x, y));
            std::copy(rgbe.begin(), rgbe.end(), row.begin() + 4 * size_t(x));
        }
        // DESIGN: flat scanlines. A flat scanline can look like the run-length marker only if
        // its first pixel is 2, 2, w >> 8, w & 255, which a normalised pixel (largest mantissa
        // >= 128) never is.
        out.write(reinterpret_cast<const char*>(row.data()),
                  static_cast<std::streamsize>(row.size()));
    }
}

Image read_hdr(std::istream& in, const std::string& name) {
    return HdrReader(in, name).read();
}

}  // namespace mbr
