// radiosity/transfer/increment_sampler.h - the sample values of one transfer, eq. (21)
// dB_i(s,t) = rho_i(s,t) I(x_i(s,t)) (paper section 4; section 5, "... and Computation of Sample
// Values"), with one adaptive quadrature (radiosity/transfer/sample_values.h) per thread.
#pragma once

#include <memory>
#include <vector>

#include "radiosity/transfer/receiver_state.h"
#include "radiosity/transfer/sample_values.h"
#include "radiosity/visibility/occlusion.h"

namespace mbr {

/// Evaluates sample values dB_i(s,t) = rho_i(s,t) I(x_i(s,t)) of eq. (21), with one quadrature
/// cache per thread.
class IncrementSampler {
public:
    /// `occlusion` (may be null) puts VIS into (21): exact visibility (ShadowMethod::Exact).
    IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                     const QuadratureOptions& options, const OcclusionContext* occlusion = nullptr);
    /// dB at (s, t); `thread` selects the integrator (0 <= thread < n_threads()).
    Rgb sample(double s, double t, int thread, long* n_kernel_evals, bool* converged = nullptr);
    /// dB at (s, t) and at (s, t) + delta, the second on the first's shooter partition, for the
    /// divided differences of (22).
    void sample_pair(double s, double t, double ds, double dt, int thread, Rgb& at_p, Rgb& at_q,
                     long* n_kernel_evals);
    int n_threads() const { return static_cast<int>(integrators_.size()); }
    const ReceiverSurface& receiver() const { return receiver_; }
    const Shooter& shooter() const { return shooter_; }
    /// The integrator of one thread (the shadow stage asks it for shooter partitions).
    IncrementIntegrator& integrator(int thread) { return *integrators_[thread]; }
    /// Rays cast by the integrators' exact visibility so far (all threads).
    long n_rays() const;
    /// Closed-form form factors the integrators computed so far (all threads;
    /// IncrementIntegrator::n_analytic).
    long n_analytic() const;

private:
    const Shooter& shooter_;
    const ReceiverSurface& receiver_;
    std::vector<std::unique_ptr<IncrementIntegrator>> integrators_;
    std::vector<long> rays_;  // per thread
};

}  // namespace mbr
