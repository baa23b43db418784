// radiosity/transfer/receiver_state.cpp - the fulcrums' positions (paper section 5, Figure 2),
// the boundary profiles' interpolation (edgefill) and the state of one transfer.
#include "radiosity/transfer/receiver_state.h"

#include <algorithm>
#include <cmath>

#include "math/check.h"

namespace mbr {

ReceiverState::ReceiverState(const ReceiverOptions& options_, double rhombus_radius_,
                             const OcclusionContext* occlusion_)
    : options(options_), rhombus_radius(rhombus_radius_), occlusion(occlusion_) {}

Vec2 Fulcrum::position(int m) const {
    const double h = std::ldexp(1.0, -level);
    return {(k + 0.5 * m) * h, (l + 0.5 * m) * h};
}

void EdgeProfile::at(double s, Rgb& v, Rgb& d) const {
    MBR_CHECK(!sigma.empty());
    if (s <= sigma.front()) {
        v = value.front();
        d = derivative.front();
        return;
    }
    if (s >= sigma.back()) {
        v = value.back();
        d = derivative.back();
        return;
    }
    const size_t i = std::upper_bound(sigma.begin(), sigma.end(), s) - sigma.begin();  // >= 1
    const double w = (s - sigma[i - 1]) / (sigma[i] - sigma[i - 1]);
    v = (1 - w) * value[i - 1] + w * value[i];
    d = (1 - w) * derivative[i - 1] + w * derivative[i];
}

}  // namespace mbr
