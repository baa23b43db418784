// examples/common/transfer_cli.cpp - shared options and measurement of one transfer.
#include "examples/common/transfer_cli.h"

#include <sstream>

#include "radiosity/solver/cost.h"

namespace mbr {

const char* receiver_options_usage =
    "  --order m                 B-spline order, 2..8 (default 4)\n"
    "  --extrapolation K         linear (23)-(25) (default), higher = quadratic (26), cubic (27)\n"
    "  --rhombus-radius R        truncation radius in cells of each fulcrum's scale\n"
    "  --eps E                   relative truncation |DN x DN| > E (default 1e-7, about 26\n"
    "                            cells for m = 4); not together with --rhombus-radius\n"
    "  --quadrature-tolerance T  relative tolerance of the adaptive rule of (21) (default 1e-4)\n"
    "  --unify paper|projection  stage 8: refine coarse coefficients by (17) (the paper's rule,\n"
    "                            default) or project every finest-scale coefficient\n"
    "  --edgefill-tolerance T    edgefill's relative tolerance (default 1e-4)\n"
    "  --edgefill chord|paper    edgefill's test: the midpoint against the chord (default),\n"
    "                            or the paper's |dB(s3) - dB(s1)| small\n"
    "  --clamp C                 derivative clamp of the linear extrapolation (default 1)\n"
    "  --coarsen-shooter L       levels the shooter's unshot field is coarsened, 0..14\n"
    "                            (default 1)\n";

ReceiverOptions read_receiver_options(Args& args) {
    ReceiverOptions o;
    o.m = args.integer("--order", o.m, 2, 8);
    const std::string kind = args.text("--extrapolation", "linear");
    if (kind == "linear") o.extrapolation = Extrapolation::Linear;
    else if (kind == "higher" || kind == "quadratic") o.extrapolation = Extrapolation::Quadratic;
    else if (kind == "cubic") o.extrapolation = Extrapolation::Cubic;
    else throw UsageError("--extrapolation must be linear, higher, quadratic or cubic");
    if (args.has("--eps") && args.has("--rhombus-radius"))
        throw UsageError("--eps and --rhombus-radius exclude each other: both set the truncation");
    o.truncation_eps = args.number("--eps", o.truncation_eps);
    if (!(o.truncation_eps > 0 && o.truncation_eps < 1)) throw UsageError("--eps must be in (0, 1)");
    o.rhombus_radius = args.number("--rhombus-radius", 0);
    if (o.rhombus_radius < 0 || o.rhombus_radius > 200)
        throw UsageError("--rhombus-radius must be between 0 and 200 cells");
    o.quadrature.rel_tolerance = args.number("--quadrature-tolerance", o.quadrature.rel_tolerance);
    if (!(o.quadrature.rel_tolerance > 0 && o.quadrature.rel_tolerance < 1))
        throw UsageError("--quadrature-tolerance must be in (0, 1)");
    const std::string unify = args.text("--unify", "paper");
    if (unify != "paper" && unify != "projection")
        throw UsageError("--unify must be paper or projection");
    o.unify_by_projection = unify == "projection";
    o.edgefill_tolerance = args.number("--edgefill-tolerance", o.edgefill_tolerance);
    if (!(o.edgefill_tolerance > 0)) throw UsageError("--edgefill-tolerance must be positive");
    const std::string edgefill = args.text("--edgefill", "chord");
    if (edgefill != "chord" && edgefill != "paper") throw UsageError("--edgefill must be chord or paper");
    o.edgefill_test = edgefill == "paper" ? EdgefillTest::Variation : EdgefillTest::Linearity;
    o.clamp_factor = args.number("--clamp", o.clamp_factor);
    if (!(o.clamp_factor > 0)) throw UsageError("--clamp must be positive");
    // 14: the deepest receiver tree transfer() accepts, so the finest field there is.
    o.shooter_coarsening = args.integer("--coarsen-shooter", o.shooter_coarsening, 0, 14);
    return o;
}

ReceiverOptions read_tree_options(Args& args, ReceiverOptions o) {
    const bool adaptive = args.flag("--adaptive");
    const int depth = args.integer("--depth", 3, 0, 12);
    o.oracle_tolerance = args.number("--oracle-tolerance", o.oracle_tolerance);
    o.min_depth = args.integer("--min-depth", o.min_depth, 0, 12);
    o.max_depth = args.integer("--max-depth", o.max_depth, 0, 12);
    // Each mode refuses the options of the other rather than ignoring them.
    if (adaptive && args.has("--depth"))
        throw UsageError("--depth has no effect with --adaptive: the adaptive tree is bounded by "
                         "--min-depth and --max-depth");
    if (!adaptive) {
        if (args.has("--min-depth") || args.has("--max-depth") || args.has("--oracle-tolerance"))
            throw UsageError("--min-depth, --max-depth and --oracle-tolerance need --adaptive");
        o.min_depth = o.max_depth = depth;
    }
    if (o.min_depth > o.max_depth) throw UsageError("--min-depth must not exceed --max-depth");
    if (!(o.oracle_tolerance > 0)) throw UsageError("--oracle-tolerance must be positive");
    // The cost is said before it is spent: a full tree at the deepest depth allowed.
    const double budget = read_memory_budget(args);
    check_cost(transfer_cost(o), budget,
               adaptive ? "an adaptive transfer up to depth " + std::to_string(o.max_depth)
                        : "a transfer at depth " + std::to_string(o.max_depth),
               o.max_depth >= slow_receiver_depth);
    return o;
}

bool fronts_face_each_other(const Surface& shooter, const Surface& receiver) {
    // Relative to each plane's own centre, so that the test does not depend on where the pair
    // sits; the normals are unit vectors, so a positive distance is a positive dot product.
    auto some_corner_in_front = [](const Surface& quad, const Surface& plane) {
        const SurfacePoint c = plane.evaluate(0.5, 0.5);
        for (int k = 0; k < 4; ++k)
            if (dot(quad.corners()[k] - c.position, c.normal) > 0) return true;
        return false;
    };
    return some_corner_in_front(receiver, shooter) && some_corner_in_front(shooter, receiver);
}

std::string describe(const ReceiverOptions& o) {
    std::ostringstream os;
    const char* extrapolation = o.extrapolation == Extrapolation::Linear      ? "linear (23)-(25)"
                                : o.extrapolation == Extrapolation::Quadratic ? "quadratic (26)"
                                                                              : "cubic (27)";
    os << "m = " << o.m << ", " << extrapolation << " extrapolation, ";
    if (o.rhombus_radius > 0)
        os << "rhombus radius " << o.rhombus_radius << " cells";
    else
        os << "eps = " << o.truncation_eps;
    os << ", quadrature tolerance " << o.quadrature.rel_tolerance << ", "
       << (o.unify_by_projection ? "unification by projection" : "unification by (17)");
    return os.str();
}

TransferRun run_transfer(const TransferSetup& setup, const ReceiverOptions& options, int grid,
                         ReceiverState* keep_state) {
    TransferRun run;
    const SplineField unshot = SplineField::constant(options.m, 0, {1, 1, 1});
    const Shooter shooter = make_shooter(setup.shooter, unshot, options.shooter_coarsening);
    const ReceiverSurface receiver{&setup.receiver, [](double, double) { return Rgb{1, 1, 1}; }};
    run.field = transfer(shooter, receiver, options, &run.stats, keep_state);
    run.errors = compare_with_exact(run.field, setup, 1, 1, grid);
    run.n_coefficients = touching_count(options.m, run.field.level()) * touching_count(options.m, run.field.level());
    return run;
}

}  // namespace mbr
