// radiosity/transfer/gauss_points.h - the m x m Gauss-Legendre points of a cell, where the stages
// of one transfer sample dB (paper section 5: "the sample values ... at the m x m Gauss-Legendre
// points of each subdomain").
#pragma once

#include "math/gauss_legendre.h"
#include "math/vec3.h"

namespace mbr {

/// The m x m Gauss-Legendre points of a rectangle, as (s_a, t_b) coordinates.
inline void gauss_points(const Rect& r, const GaussLegendre& rule, double* s, double* t) {
    for (int a = 0; a < rule.n(); ++a) {
        s[a] = r.x0 + 0.5 * (rule.x[a] + 1) * r.width();
        t[a] = r.y0 + 0.5 * (rule.x[a] + 1) * r.height();
    }
}

}  // namespace mbr
