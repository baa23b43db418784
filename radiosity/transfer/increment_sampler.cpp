// radiosity/transfer/increment_sampler.cpp - the sample values of eq. (21) and the pairs of them
// that the divided differences (22) take.
#include "radiosity/transfer/increment_sampler.h"

#include "math/check.h"
#include "math/parallel.h"

namespace mbr {

IncrementSampler::IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                                   const QuadratureOptions& options,
                                   const OcclusionContext* occlusion)
    : shooter_(shooter), receiver_(receiver) {
    MBR_CHECK(receiver.surface != nullptr && receiver.reflectance);
    const std::optional<Plane> plane = surface_plane(*receiver.surface);
    for (int i = 0; i < thread_count(); ++i) {
        integrators_.push_back(std::make_unique<IncrementIntegrator>(shooter, options, occlusion));
        if (plane) integrators_.back()->set_receiver_plane(*plane);
    }
    rays_.assign(integrators_.size(), 0);
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
    const IncrementIntegrator::Result r = integrators_[thread]->integrate(p);
    if (n_kernel_evals) *n_kernel_evals += r.n_evaluations;
    rays_[thread] += r.n_rays;
    if (converged) *converged = r.converged;
    return receiver_.reflectance(s, t) * r.value;
}

void IncrementSampler::sample_pair(double s, double t, double ds, double dt, int thread, Rgb& at_p,
                                   Rgb& at_q, long* n_kernel_evals) {
    IncrementIntegrator& integrator = *integrators_[thread];
    if (receiver_.hidden && receiver_.hidden->hidden(s, t)) {  // constant extension: no slope
        at_p = at_q = sample(s, t, thread, n_kernel_evals);
        return;
    }
    const SurfacePoint p = receiver_.surface->evaluate(s, t);
    if (integrator.analytic()) {  // closed form at both points: no partition to share
        const SurfacePoint q = receiver_.surface->evaluate(s + ds, t + dt);
        at_p = receiver_.reflectance(s, t) * integrator.integrate(p).value;
        at_q = receiver_.reflectance(s + ds, t + dt) * integrator.integrate(q).value;
        return;
    }
    const IncrementIntegrator::Result r = integrator.integrate(p, true);
    const SurfacePoint q = receiver_.surface->evaluate(s + ds, t + dt);
    long evals = r.n_evaluations;
    rays_[thread] += r.n_rays;
    const Rgb value_q = integrator.integrate_on(q, r.partition, &evals, &rays_[thread], &r);
    if (n_kernel_evals) *n_kernel_evals += evals;
    at_p = receiver_.reflectance(s, t) * r.value;
    at_q = receiver_.reflectance(s + ds, t + dt) * value_q;
}

}  // namespace mbr
