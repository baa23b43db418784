// radiosity/transfer/increment_sampler.cpp - the sample values of eq. (21) and the pairs of them
// that the divided differences (22) take.
#include "radiosity/transfer/increment_sampler.h"

#include "math/check.h"
#include "math/parallel.h"

namespace mbr {

IncrementSampler::IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                                   const QuadratureOptions& options,
                                   const OcclusionContext* occlusion)
    : parts_{ShooterPart{&shooter, occlusion}}, receiver_(receiver) {
    make_integrators(options, occlusion != nullptr);
}

IncrementSampler::IncrementSampler(const std::vector<ShooterPart>& parts,
                                   const ReceiverSurface& receiver,
                                   const QuadratureOptions& options, bool exact)
    : parts_(parts), receiver_(receiver) {
    MBR_CHECK(!parts_.empty());
    make_integrators(options, exact);
}

void IncrementSampler::make_integrators(const QuadratureOptions& options, bool exact) {
    MBR_CHECK(receiver_.surface != nullptr && receiver_.reflectance);
    const std::optional<Plane> plane = surface_plane(*receiver_.surface);
    n_threads_ = thread_count();
    for (int i = 0; i < n_threads_; ++i)
        for (const ShooterPart& part : parts_) {
            MBR_CHECK(part.shooter != nullptr);
            integrators_.push_back(std::make_unique<IncrementIntegrator>(
                *part.shooter, options, exact ? part.occlusion : nullptr));
            if (plane) integrators_.back()->set_receiver_plane(*plane);
        }
    rays_.assign(size_t(n_threads_), 0);
}

long IncrementSampler::n_rays() const {
    long n = 0;
    for (long r : rays_) n += r;
    return n;
}

long IncrementSampler::n_analytic() const {
    long n = 0;
    for (const auto& integrator : integrators_) n += integrator->n_analytic();
    return n;
}

Rgb IncrementSampler::sample(double s, double t, int thread, long* n_kernel_evals,
                             bool* converged) {
    // Eq. (21): dB_i(s,t) = rho_i(s,t) * int int F VIS B_h A_h du dv (at the nearest visible
    // point when (s, t) is hidden: radiosity/visibility/hidden_regions.h).
    const Vec2 at = receiver_.hidden ? receiver_.hidden->substitute(s, t) : Vec2{s, t};
    const SurfacePoint p = receiver_.surface->evaluate(at.x, at.y);
    Rgb value;
    if (converged) *converged = true;
    for (int part = 0; part < n_parts(); ++part) {  // a cluster's parts add up
        const IncrementIntegrator::Result r = integrator(thread, part).integrate(p);
        if (n_kernel_evals) *n_kernel_evals += r.n_evaluations;
        rays_[thread] += r.n_rays;
        if (converged) *converged = *converged && r.converged;
        value += r.value;
    }
    return receiver_.reflectance(s, t) * value;
}

void IncrementSampler::sample_pair(double s, double t, double ds, double dt, int thread, Rgb& at_p,
                                   Rgb& at_q, long* n_kernel_evals) {
    if (receiver_.hidden && receiver_.hidden->hidden(s, t)) {  // constant extension: no slope
        at_p = at_q = sample(s, t, thread, n_kernel_evals);
        return;
    }
    const SurfacePoint p = receiver_.surface->evaluate(s, t);
    const SurfacePoint q = receiver_.surface->evaluate(s + ds, t + dt);
    Rgb value_p, value_q;
    for (int part = 0; part < n_parts(); ++part) {  // each part on its own partition
        IncrementIntegrator& in = integrator(thread, part);
        if (in.analytic()) {  // closed form at both points: no partition to share
            value_p += in.integrate(p).value;
            value_q += in.integrate(q).value;
            continue;
        }
        const IncrementIntegrator::Result r = in.integrate(p, true);
        long evals = r.n_evaluations;
        rays_[thread] += r.n_rays;
        value_q += in.integrate_on(q, r.partition, &evals, &rays_[thread], &r);
        if (n_kernel_evals) *n_kernel_evals += evals;
        value_p += r.value;
    }
    at_p = receiver_.reflectance(s, t) * value_p;
    at_q = receiver_.reflectance(s + ds, t + dt) * value_q;
}

}  // namespace mbr
