// examples/paper/figure8_coplanar_strips.cpp - Figures 8 and 9 of the paper (section 7): three
// narrow coplanar rectangles lit from above, each solved on its own. "We can not see any
// discontinuity of radiosity at boundaries between adjacent rectangles. It indicates that the
// technique of function extrapolation in this paper can keep a certain degree of continuity between
// coplanar surfaces." Here the continuity is measured.
//
// Run:  figure8_coplanar_strips [SCENE] [--csv] [--points n] [-o FILE.png]
//                               [--image linear|higher] [solver options]
//
// Solves examples/scenes/three_strips.scene (or SCENE, which must hold surfaces strip0, strip1,
// strip2 with strip k's top edge v = 1 on strip k+1's bottom edge v = 0) twice: with the linear
// extrapolation of eqs. (23)-(25) (the paper's choice for its pictures) and with the
// higher-order one, eq. (26) (Extrapolation::Quadratic). Along each shared edge it evaluates B
// of both strips at n points (cell centres of the edge, n = 1024; the world points are checked
// to coincide) and reports
//   - the largest relative jump |B_k(u, 1) - B_k+1(u', 0)| / (mean of the two), over the three
//     channels and both edges, and where it sits (edge, x along it); target <= 1 %;
//   - the largest jump over the largest B of the strips (the jump as one sees it in a picture);
//   - the largest relative error of both sides against the exact value rho E F(x -> light) at
//     the same points (the analytic point-to-polygon form factor; the scene has no occluders
//     between the light and the strips), so that continuity is not mistaken for accuracy;
// with the solve statistics of each run (shots, unshot power, seconds, peak memory,
// coefficients). --csv prints one row per extrapolation under the header
//   extrapolation,max_rel_jump_percent,edge,x,max_jump_over_max_b_percent,
//   max_rel_err_percent,shots,seconds,coefficients
// -o FILE.png renders the solution (linear by default, --image higher for the other) with the
// scene's camera.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "examples/common/scene_cli.h"
#include "radiosity/output/output_file.h"
#include "radiosity/transfer/form_factor.h"

namespace mbr {
namespace {

std::string usage() {
    return std::string(
               "usage: figure8_coplanar_strips [SCENE] [--csv] [--points n] [-o FILE.png]\n"
               "                               [--image linear|higher] [options]\n"
               "  Figures 8 and 9: three coplanar strips solved separately (default\n"
               "  examples/scenes/three_strips.scene), with linear and with higher-order\n"
               "  extrapolation; reports the largest relative jump of B across the shared edges.\n"
               "  --csv                     header extrapolation,max_rel_jump_percent,edge,x,\n"
               "                            max_jump_over_max_b_percent,max_rel_err_percent,\n"
               "                            shots,seconds,coefficients\n"
               "  --points n                points along each shared edge, 2..100000 (1024)\n"
               "  -o FILE.png               a picture of one of the two solutions\n"
               "  --image linear|higher     which one (default linear)\n") +
           solver_options_usage();
}

/// The three strips and the light, by name in the scene.
struct Strips {
    int strip[3] = {-1, -1, -1};
    std::vector<Vec3> light;  // the emitter's corners (the exact reference)
    Rgb light_e;              // its emission
};

Strips find_strips(const SceneRun& run) {
    const Scene& scene = run.scene;
    Strips s;
    for (int k = 0; k < 3; ++k) {
        const std::string name = "strip" + std::to_string(k);
        s.strip[k] = scene.find_surface(name);
        if (s.strip[k] < 0)
            throw InputError(run.path, 0, "the scene has no surface '" + name + "'");
    }
    // Strip k's top edge must be strip k+1's bottom edge, point for point.
    for (int k = 0; k < 2; ++k) {
        const Surface& a = scene.surfaces[s.strip[k]].surface;
        const Surface& b = scene.surfaces[s.strip[k + 1]].surface;
        const double size = length(a.bounds().extent());
        for (double u : {0.0, 0.5, 1.0})
            if (length(a.point(u, 1) - b.point(u, 0)) > 1e-9 * size)
                throw InputError(run.path, 0,
                                 "strip" + std::to_string(k) + "'s top edge (v = 1) is not strip" +
                                     std::to_string(k + 1) + "'s bottom edge (v = 0)");
    }
    const std::vector<int> emitters = scene.emitters();
    if (emitters.size() != 1 ||
        scene.surfaces[emitters[0]].surface.kind() != Surface::Kind::PlanarQuad)
        throw InputError(run.path, 0, "the scene must have exactly one emitter, a planar quad");
    const Surface& light = scene.surfaces[emitters[0]].surface;
    s.light = {light.point(0, 0), light.point(1, 0), light.point(1, 1), light.point(0, 1)};
    s.light_e = scene.material_of(emitters[0]).emission.value(0.5, 0.5);
    return s;
}

/// Each edge is also reported in eighths of its length (where the jump sits).
constexpr int n_segments = 8;

/// What one solution shows along the two shared edges.
struct EdgeReport {
    double max_rel_jump = 0;     // |B_below - B_above| / mean of the two
    int edge = 0;                // 1: between strip0 and strip1, 2: strip1 and strip2
    double x = 0;                // world x of the largest jump (the edge runs along x)
    double max_jump_over_b = 0;  // largest |B_below - B_above| / largest B on the strips
    double max_rel_err = 0;      // largest |B - exact| / exact on either side
    double segment_jump[2][n_segments] = {};  // the largest relative jump per edge and eighth
};

EdgeReport measure_edges(const SceneRun& run, const Strips& strips, const Solution& solution,
                         int n) {
    const Scene& scene = run.scene;
    EdgeReport r;
    // The largest B on the strips, on a grid of each (the scale of a visible jump).
    double largest = 0;
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a <= 64; ++a)
            for (int b = 0; b <= 64; ++b)
                largest = std::max(largest, max_abs(solution.radiosity[strips.strip[k]].evaluate(
                                                a / 64.0, b / 64.0)));
    for (int k = 0; k < 2; ++k) {
        const int below = strips.strip[k], above = strips.strip[k + 1];
        const Surface& surface = scene.surfaces[below].surface;
        const Rgb rho = scene.material_of(below).reflectance.value(0.5, 1.0);
        const Rgb rho_above = scene.material_of(above).reflectance.value(0.5, 0.0);
        for (int i = 0; i < n; ++i) {
            const double u = (i + 0.5) / n;
            // Strip k at its top edge, strip k+1 at its bottom edge: the same world point.
            const Rgb b_below = solution.radiosity[below].evaluate(u, 1);
            const Rgb b_above = solution.radiosity[above].evaluate(u, 0);
            const Vec3 x = surface.point(u, 1);
            const double F = point_polygon_form_factor(x, surface.normal(u, 1), strips.light);
            for (int c = 0; c < 3; ++c) {
                const double mean = 0.5 * (b_below[c] + b_above[c]);
                const double jump = std::abs(b_below[c] - b_above[c]);
                double& segment = r.segment_jump[k][std::min(int(u * n_segments), n_segments - 1)];
                if (mean > 0) segment = std::max(segment, jump / mean);
                if (mean > 0 && jump / mean > r.max_rel_jump) {
                    r.max_rel_jump = jump / mean;
                    r.edge = k + 1;
                    r.x = x.x;
                }
                if (largest > 0) r.max_jump_over_b = std::max(r.max_jump_over_b, jump / largest);
                // Exact: one shot from a constant emitter, dB = rho E F (no occluders).
                const double exact_below = rho[c] * strips.light_e[c] * F;
                const double exact_above = rho_above[c] * strips.light_e[c] * F;
                if (exact_below > 0)
                    r.max_rel_err =
                        std::max(r.max_rel_err, std::abs(b_below[c] - exact_below) / exact_below);
                if (exact_above > 0)
                    r.max_rel_err =
                        std::max(r.max_rel_err, std::abs(b_above[c] - exact_above) / exact_above);
            }
        }
    }
    return r;
}

int run(Args& args) {
    const bool csv = args.flag("--csv");
    const int n = args.integer("--points", 1024, 2, 100000);
    const std::string out = args.text("-o", "");
    const std::string image = args.text("--image", "linear");
    if (image != "linear" && image != "higher")
        throw UsageError("--image must be linear or higher");
    if (!out.empty()) check_output_path(out);  // refuse an unwritable path before solving
    SceneRun run =
        read_scene_run(args, std::string(MBR_SOURCE_DIR) + "/examples/scenes/three_strips.scene");
    args.finish();
    const Strips strips = find_strips(run);

    struct Case {
        const char* name;
        Extrapolation extrapolation;
    };
    const Case cases[] = {{"linear", Extrapolation::Linear}, {"higher", Extrapolation::Quadratic}};
    Table t({"extrapolation", "max_rel_jump_percent", "edge", "x", "max_jump_over_max_b_percent",
             "max_rel_err_percent", "shots", "seconds", "coefficients"});
    Solution pictured;
    std::vector<EdgeReport> reports;
    for (const Case& c : cases) {
        run.options.receiver.extrapolation = c.extrapolation;
        Solution solution = solve_scene(run, !csv);
        const EdgeReport r = measure_edges(run, strips, solution, n);
        reports.push_back(r);
        const SolveStats& st = solution.stats;
        t.add_row({c.name, cell(100 * r.max_rel_jump, 4), std::to_string(r.edge), cell(r.x, 4),
                   cell(100 * r.max_jump_over_b, 4), cell(100 * r.max_rel_err, 4),
                   std::to_string(st.shots), cell(st.seconds, 3), std::to_string(st.coefficients)});
        if (!csv) {
            std::cout << "== " << c.name << " extrapolation ==\n";
            print_summary(std::cout, run, st);
        }
        if (image == c.name) pictured = std::move(solution);
    }
    if (csv) {
        t.write_csv(std::cout);
    } else {
        std::cout << "\nB along the shared edges (" << n
                  << " points each; relative jump = |B below - B above| / their mean; target "
                     "<= 1 %):\n";
        t.write_text(std::cout);
        // Where the jumps sit: the largest relative jump in each eighth of each edge (the edge
        // runs along the strips' u, from x(u = 0) to x(u = 1)).
        std::cout << "\nlargest relative jump (percent) per eighth of each shared edge:\n";
        Table p({"edge", "u_from", "u_to", "linear", "higher"});
        for (int k = 0; k < 2; ++k)
            for (int g = 0; g < n_segments; ++g)
                p.add_row({std::to_string(k + 1), cell(double(g) / n_segments, 3),
                           cell(double(g + 1) / n_segments, 3),
                           cell(100 * reports[0].segment_jump[k][g], 4),
                           cell(100 * reports[1].segment_jump[k][g], 4)});
        p.write_text(std::cout);
    }
    if (!out.empty()) {
        const double seconds = write_render(run, pictured, out);
        (csv ? std::cerr : std::cout)
            << "wrote " << out << " (" << image << " extrapolation, rendered in "
            << cell(seconds, 2) << " s)\n";
    }
    return 0;
}

}  // namespace
}  // namespace mbr

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, mbr::usage(), mbr::run);
}
