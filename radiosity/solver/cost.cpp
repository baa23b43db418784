// radiosity/solver/cost.cpp - memory and time of a run from its settings ("bounded cost,
// said before it is spent"). The figures are deliberately simple: a count the settings fix
// (leaves, coefficients, polygons, texels) times bytes per item, so that the estimate is
// monotone in every setting and errs on the high side.
#include "radiosity/solver/cost.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "math/check.h"

namespace mbr {

namespace {

// Calibration (Release build, m = 4, single_transfer --depth d with the default 256 x 256
// error grid, peak resident size from /usr/bin/time -f %M): 6,488 KB at d = 0 (the program
// itself), 8,692 KB at d = 6, 19,320 KB at d = 7, 60,988 KB at d = 8. Above the d = 0 base,
// d = 7 -> 8 adds 41.7 MB for 49,152 more leaves, 6 -> 7 adds 10.6 MB for 12,288: about 850
// bytes a leaf, of which the m x m samples (24 bytes each, 384) are the part that grows with m.
// The rest (~470 bytes a leaf) is the node, the fulcrums, the coefficient map, the expanded
// ring and the result.
constexpr double bytes_per_leaf_fixed = 470;
constexpr double bytes_per_sample = sizeof(Rgb);
// Calibration of the time: the same runs took 3.7 s at d = 7 and 12.8 s at d = 8 of wall time on
// two busy cores, ~2e-4 s a leaf. A rough figure for a warning, nothing more.
constexpr double seconds_per_leaf = 2e-4;
// The hidden regions before the first shot (find_hidden, up to 64^2 texels of 4 to 16 rays),
// CPU seconds a surface of the full 64^2: 0.68 s for the room's 27 surfaces (25 ms), 7.2 s for
// 505 tiles of scene_scaling (14 ms), user time of `mbr probe SCENE --max-shots 0`; a surface of
// fewer texels (hidden_texels) in proportion. Since the masks are found through the octree's
// contacts (find_contacts), only surfaces that something touches from in front cast rays, and
// only near the contact: this figure (and the masks' bytes below) is an upper bound, reached
// by a scene whose every surface is in contact all over (classroom.mgf: 8,831 of 9,804
// surfaces in contact, 10.5 s of CPU against the 58 s this bound gives).
constexpr double hidden_seconds_per_surface = 0.025;

// Calibration of the polygons (octree_stats examples/scenes/room.scene --tessellation T
// --rays 1000, peak resident size): 6,984 KB at T = 24 (2,558 polygons), 65,540 KB at T = 128
// (66,830), 249,152 KB at T = 256 (264,718): about 930-945 bytes a polygon, counting the
// facets, the polygons with their planes, and the octree's references and nodes (328,164 KB
// at T = 256 since the leaves' lists hold boxes, 32 bytes a reference, and a parallelogram
// keeps its corners' (u, v) inline: 1,269 bytes). A whole solve holds more a polygon: a unit
// sphere at T = 1024 (1,048,576 polygons) under a lamp, `mbr probe`, peaked at 1,184,952 KB,
// about 1,100 bytes a polygon beyond the rest of the estimate; on 2026-12-07 at 1,325,604 KB
// before those two changes and 1,503,088 KB after (about 1,390 bytes a polygon).
constexpr double bytes_per_polygon = 1450;

// The program before any scene: 6,488 KB resident (single_transfer --depth 0 above), 6.2-6.9 MB
// for mbr probe of a small scene.
constexpr double program_bytes = 8.0 * (1 << 20);

}  // namespace

double field_bytes(int m, int level) {
    MBR_CHECK(m >= 1 && level >= 0 && level <= 30);
    const double side = std::ldexp(1.0, level) + m - 1;
    return side * side * 3 * sizeof(double);
}

double transfer_bytes(int m, int depth) {
    MBR_CHECK(m >= 1 && depth >= 0 && depth <= 30);
    const double leaves = std::ldexp(1.0, 2 * depth);
    return leaves * (bytes_per_leaf_fixed + double(m) * m * bytes_per_sample);
}

double transfer_seconds(int m, int depth) {
    MBR_CHECK(m >= 1 && depth >= 0 && depth <= 30);
    // Samples (m^2 a leaf) dominate; the calibration is at m = 4.
    return std::ldexp(1.0, 2 * depth) * seconds_per_leaf * (double(m) * m / 16);
}

CostEstimate transfer_cost(const ReceiverOptions& o) {
    CostEstimate c;
    c.bytes = transfer_bytes(o.m, o.max_depth);
    c.seconds = transfer_seconds(o.m, o.max_depth);
    c.detail = std::to_string(1L << (2 * std::min(o.max_depth, 30))) + " receiver leaves of " +
               std::to_string(o.m * o.m) + " samples";
    return c;
}

CostEstimate scene_cost(const Scene& scene, const SolverOptions& options, int threads) {
    const int d = options.receiver.max_depth;
    const double n_surfaces = double(scene.surfaces.size());
    // Radiosity and unshot per surface, and every receiver's result of one shot held at once,
    // each in its surface's order; a transfer's scratch at the largest order in use.
    double fields = 0, seconds = 0;
    int m = 0;
    std::vector<int> orders;
    for (int i = 0; i < static_cast<int>(scene.surfaces.size()); ++i) {
        const int mi = surface_order(scene, i, options.receiver.m);
        orders.push_back(mi);
        fields += 3 * field_bytes(mi, d);
        seconds += transfer_seconds(mi, d);  // one shot's transfers, each a full tree
        m = std::max(m, mi);
    }
    if (m == 0) m = options.receiver.m;  // no surfaces
    // Transfers run one per thread over the receivers, except with the paper's fractions,
    // which run one transfer at a time, parallel inside.
    const bool one_at_a_time = options.receiver.shadows.method == ShadowMethod::Fractions;
    const double at_once =
        std::max(1.0, std::min(one_at_a_time ? 1.0 : double(std::max(1, threads)), n_surfaces));
    const double transfers = at_once * transfer_bytes(m, d);
    double polygons = 0;
    for (const SceneSurface& s : scene.surfaces) {
        polygons += double(s.surface.facet_count(scene.settings.tessellation)) * bytes_per_polygon;
    }
    // Each distinct texel storage once: materials sharing an image share its texels.
    std::vector<const Texture*> seen;
    double textures = 0;
    for (const Material& mat : scene.materials)
        for (const Texture* t : {&mat.reflectance, &mat.emission}) {
            if (t->texel_bytes() == 0) continue;
            const bool shared = std::any_of(seen.begin(), seen.end(),
                                            [&](const Texture* u) { return u->shares_texels(*t); });
            if (shared) continue;
            seen.push_back(t);
            textures += double(t->texel_bytes());
        }
    // Every thread's integrator holds its shooter-point caches at their bound (sample_values.h),
    // and the program itself (code, runtime, stack) comes first.
    const double caches = double(std::max(1, threads)) * cached_points_bytes();
    // Per surface: its hidden-region mask (a byte and a substitute point per texel), and a row
    // of the measured coupling for every shooter that has shot (at most max_shots rows).
    double texels = 0;  // of every surface's mask (hidden_texels a side)
    const double diagonal = length(scene.bounds().extent());
    for (const SceneSurface& s : scene.surfaces) {
        const double n = hidden_texels(length(s.surface.bounds().extent()), diagonal);
        texels += n * n;
    }
    const double hidden = options.hidden_regions ? texels * (1.0 + sizeof(Vec2)) : 0.0;
    const double coupling =
        std::min(double(std::max(0, options.max_shots)), n_surfaces) * n_surfaces * sizeof(Rgb);
    fields += coupling;
    // The occluder candidates kept per pair (ProgressiveSolver::occlusion_of): at most every
    // polygon for every pair that transfers, within max_cached_candidates ints (their boxes
    // included), and a map node each.
    const double pairs = std::min(double(std::max(0, options.max_shots)), n_surfaces) * n_surfaces;
    const double occluder_lists =
        options.receiver.shadows.method == ShadowMethod::None
            ? 0.0
            : std::min(double(max_cached_candidates), pairs * (polygons / bytes_per_polygon)) *
                      sizeof(int) +
                  pairs * 96.0;
    // The ambient gather's rays at the end (ambient_gather.h).
    const bool gathers = options.ambient && options.ambient_rays > 0;
    const double gather =
        gathers
            ? ambient_gather_bytes(orders, options.ambient_level, options.ambient_rays) +
                  (options.ambient_final ? final_gather_bytes(scene, orders, options.ambient_level,
                                                              options.ambient_rays)
                                         : 0.0)
            : 0.0;
    CostEstimate c;
    c.bytes = program_bytes + fields + hidden + transfers + caches + polygons + textures +
              occluder_lists + gather;
    c.setup_seconds = options.hidden_regions ? texels / (hidden_resolution * hidden_resolution) *
                                                   hidden_seconds_per_surface
                                             : 0.0;
    c.seconds = c.setup_seconds + seconds;
    c.detail = "program " + format_bytes(program_bytes) + ", fields " + format_bytes(fields) +
               ", hidden regions " + format_bytes(hidden) + ", transfers " +
               format_bytes(transfers) + ", quadrature caches " + format_bytes(caches) +
               ", occluder lists " + format_bytes(occluder_lists) + ", ambient gather " +
               format_bytes(gather) + ", polygons " + format_bytes(polygons) + ", textures " +
               format_bytes(textures);
    return c;
}

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? double(pages) * double(page) : 0;
}

double default_memory_budget() {
    const double physical = physical_memory_bytes();
    // DESIGN: half the machine: the run, the system and whatever else runs beside it.
    return physical > 0 ? physical / 2 : 4.0 * (1L << 30);
}

std::string format_bytes(double bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB"};
    int u = 0;
    while (bytes >= 1024 && u < 5) {
        bytes /= 1024;
        ++u;
    }
    char buf[64];
    std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
    return buf;
}

std::string format_seconds(double seconds) {
    char buf[64];
    if (seconds >= 7200)
        std::snprintf(buf, sizeof buf, "%.0f h", seconds / 3600);
    else if (seconds >= 120)
        std::snprintf(buf, sizeof buf, "%.0f min", seconds / 60);
    else
        std::snprintf(buf, sizeof buf, "%.0f s", seconds);
    return buf;
}

}  // namespace mbr
