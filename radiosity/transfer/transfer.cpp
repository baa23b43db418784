// radiosity/transfer/transfer.cpp - one energy transfer, the stages of paper section 5 in order.
#include "radiosity/transfer/transfer.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "math/check.h"

namespace mbr {

namespace {

/// Adds the seconds of its scope to a field of TransferStats (or any counter) when the scope
/// ends.
class StageTimer {
public:
    explicit StageTimer(double& seconds)
        : seconds_(seconds), start_(std::chrono::steady_clock::now()) {}
    ~StageTimer() {
        seconds_ +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    double& seconds_;
    std::chrono::steady_clock::time_point start_;
};

/// The rhombus radius once the samples are known. DESIGN: a weak shot needs no more truncation
/// accuracy than the scene's tolerance. The error a truncation eps causes is about 50 eps
/// relative to max|dB| (rea against eps on Tables 1-2, docs/method.md: 0.3-0.9 % at 1e-4,
/// 0.04-0.07 % more at 1e-5 than at 1e-6), so eps = (absolute tolerance / max|dB|) / 50, at
/// most 1e-4.
double rhombus_radius_for_samples(const ReceiverState& state, const DualTable& dn) {
    const ReceiverOptions& options = state.options;
    if (options.absolute_tolerance <= 0 || options.rhombus_radius > 0 || state.max_sample <= 0)
        return state.rhombus_radius;
    const double eps = std::clamp(0.02 * options.absolute_tolerance / state.max_sample,
                                  options.truncation_eps, std::max(options.truncation_eps, 1e-4));
    return dn.rhombus_radius(eps);
}

}  // namespace

Shooter make_shooter(const Surface& surface, const SplineField& unshot, int levels) {
    Shooter shooter;
    shooter.surface = &surface;
    shooter.unshot = unshot.coarsened_to(std::max(0, unshot.level() - std::max(0, levels)));
    // A shot runs one integrator per receiver, each reading B_h at scattered points: its
    // polynomial pieces are built here, once (building them per transfer took 8 % of cube.mgf's
    // CPU).
    if (surface.kind() == Surface::Kind::PlanarQuad && !shooter.unshot.is_constant())
        shooter.patches = std::make_shared<const PolynomialPatches>(shooter.unshot);
    return shooter;
}

SplineField transfer(const Shooter& shooter, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats_out,
                     ReceiverState* keep_state, const OcclusionContext* occlusion,
                     const DualTable* dual) {
    return transfer({ShooterPart{&shooter, occlusion}}, receiver, options, stats_out, keep_state,
                    dual);
}

SplineField transfer(const std::vector<ShooterPart>& given_parts, const ReceiverSurface& receiver,
                     const ReceiverOptions& options, TransferStats* stats_out,
                     ReceiverState* keep_state, const DualTable* dual) {
    MBR_CHECK(!given_parts.empty());
    MBR_CHECK_MSG(options.m >= 2 && options.m <= 8, "order m = " << options.m);
    MBR_CHECK(options.min_depth >= 0 && options.min_depth <= options.max_depth &&
              options.max_depth <= 14);
    ReceiverState local;
    ReceiverState& state = keep_state ? *keep_state : local;
    double seconds_total = 0;
    SplineField result;
    {
        const StageTimer total(seconds_total);
        std::unique_ptr<DualTable> own_dual;
        if (!dual || dual->order() != options.m) {
            own_dual = std::make_unique<DualTable>(options.m);
            dual = own_dual.get();
        }
        const DualTable& dn = *dual;
        // A pair that nothing can come between casts no rays and projects nothing.
        std::vector<ShooterPart> parts = given_parts;
        const OcclusionContext* occlusion = nullptr;  // the first part's occluders, if any
        for (ShooterPart& part : parts) {
            if (part.occlusion && part.occlusion->clear()) part.occlusion = nullptr;
            if (!occlusion) occlusion = part.occlusion;
        }
        state = ReceiverState(options, rhombus_radius_cells(options, dn), occlusion);
        const ShadowMethod shadows = state.occlusion ? options.shadows.method : ShadowMethod::None;
        IncrementSampler sampler(parts, receiver, options.quadrature,
                                 shadows == ShadowMethod::Exact);
        // With unify_by_projection the expanded domain is not built: project_fine_grid
        // evaluates the extrapolation (23)-(27) at the nodes it needs.
        const bool fine_grid = options.unify_by_projection;
        TransferStats& stats = state.stats;
        {
            const StageTimer timer(stats.seconds_sampling);
            subdivide_by_oracle(state, sampler);                            // stage 1
            adjust_neighbour_scales(state.forest, Forest::Region::Domain);  // stage 2
            sample_leaves(state, sampler);                                  //   eq. (21)
            stats.n_leaves = static_cast<int>(state.forest.leaves(Forest::Region::Domain).size());
            state.rhombus_radius = rhombus_radius_for_samples(state, dn);
            stats.rhombus_radius = state.rhombus_radius;
        }
        if (stats.weak) {
            // The weak transfer rule kept the root alone (weak_transfer.h): stages 3-8 at level 0.
            {
                const StageTimer timer(stats.seconds_projection);
                result = project_root_polynomial(state);
            }
            const StageTimer timer(stats.seconds_shadows);
            if (shadows == ShadowMethod::Fractions) mask_root_coefficients(result, state, sampler);
        } else {
            {
                const StageTimer timer(stats.seconds_boundary);
                fill_boundary(state, sampler);  // stage 3, eq. (22)
            }
            {
                const StageTimer timer(stats.seconds_expanded);
                if (!fine_grid) expand_domain(state, sampler);  // stage 4, (23)-(27)
            }
            {
                const StageTimer timer(stats.seconds_projection);
                state.fulcrums = select_fulcrums(state.forest, options.m);  // stage 5
                stats.n_fulcrums = static_cast<int>(state.fulcrums.size());
                if (!fine_grid) project_in_rhombi(state, dn);  // stage 6, eq. (19)
            }
            {
                const StageTimer timer(stats.seconds_shadows);
                if (shadows == ShadowMethod::Fractions)
                    apply_shadows(state, sampler, dn);  // 7, (28)
            }
            {
                const StageTimer timer(stats.seconds_projection);
                result = fine_grid ? project_fine_grid(state, dn)  // stages 6 and 8
                                   : unify_scales(state, dn);      // stage 8, eq. (17)
            }
        }
        state.mask = nullptr;  // it refers to the sampler, which ends here
        stats.n_rays += sampler.n_rays();
        stats.n_analytic_evals += sampler.n_analytic();
    }
    state.stats.seconds_total = seconds_total;
    if (stats_out) *stats_out = state.stats;
    return result;
}

}  // namespace mbr
