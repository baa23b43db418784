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

/// One shooter of a shot and the occluders between it and the receiver. A shot of one surface
/// (the paper's) has one part; a planar cluster (coplanar surfaces that shoot together,
/// radiosity/solver/solver.h) has one per member, and I(p) in (21) is the sum of the parts'
/// integrals.
struct ShooterPart {
    const Shooter* shooter = nullptr;
    const OcclusionContext* occlusion = nullptr;  // the pair's occluders (null: none)
};

/// Evaluates sample values dB_i(s,t) = rho_i(s,t) I(x_i(s,t)) of eq. (21), with one quadrature
/// cache per thread (and per part).
class IncrementSampler {
public:
    /// One shooter; `occlusion` (may be null) puts VIS into (21): exact visibility
    /// (ShadowMethod::Exact).
    IncrementSampler(const Shooter& shooter, const ReceiverSurface& receiver,
                     const QuadratureOptions& options, const OcclusionContext* occlusion = nullptr);
    /// Several shooters whose integrals add up; `exact` puts each part's occluders into (21),
    /// else they are only named (the paper's fractions read them: part_occlusion).
    IncrementSampler(const std::vector<ShooterPart>& parts, const ReceiverSurface& receiver,
                     const QuadratureOptions& options, bool exact);
    /// dB at (s, t); `thread` selects the integrator (0 <= thread < n_threads()).
    Rgb sample(double s, double t, int thread, long* n_kernel_evals, bool* converged = nullptr);
    /// dB at (s, t) and at (s, t) + delta, the second on the first's shooter partition, for the
    /// divided differences of (22).
    void sample_pair(double s, double t, double ds, double dt, int thread, Rgb& at_p, Rgb& at_q,
                     long* n_kernel_evals);
    int n_threads() const { return n_threads_; }
    const ReceiverSurface& receiver() const { return receiver_; }
    /// The shooters whose integrals add up (1: the paper's single shooter).
    int n_parts() const { return static_cast<int>(parts_.size()); }
    const Shooter& shooter(int part = 0) const { return *parts_[size_t(part)].shooter; }
    /// A part's occluders (null: none). The one-shooter constructor names only exact
    /// visibility's; for the paper's fractions its caller keeps them (ReceiverState::occlusion).
    const OcclusionContext* part_occlusion(int part) const {
        return parts_[size_t(part)].occlusion;
    }
    /// The integrator of one thread and part (the shadow stage asks it for shooter partitions).
    IncrementIntegrator& integrator(int thread, int part = 0) {
        return *integrators_[size_t(thread) * parts_.size() + size_t(part)];
    }
    /// Rays cast by the integrators' exact visibility so far (all threads).
    long n_rays() const;
    /// Closed-form form factors the integrators computed so far (all threads;
    /// IncrementIntegrator::n_analytic).
    long n_analytic() const;

private:
    void make_integrators(const QuadratureOptions& options, bool exact);

    std::vector<ShooterPart> parts_;
    const ReceiverSurface& receiver_;
    int n_threads_ = 0;
    std::vector<std::unique_ptr<IncrementIntegrator>> integrators_;  // [thread * parts + part]
    std::vector<long> rays_;  // per thread
};

}  // namespace mbr
