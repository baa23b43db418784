// radiosity/solver/limiter.h - keeping fields within their physical bounds (beyond the paper).
//
// The dual projection of section 5 is exact for what the quadtree resolves, but a step it does
// not resolve (a contact shadow, a light a hair above a floor) overshoots beside the step and
// rings below zero beyond it. Radiosity is never negative, and one shot's increment never
// exceeds rho_max max B_h (H(x) = int F B_h dA <= max B_h since int F dA <= 1). The B-splines
// are non-negative and sum to one, so a field is a convex combination of its coefficients:
// where every coefficient of the B-splines covering a cell lies within bounds, so does the field
// on that cell. The limiter moves those coefficients towards the bounds where the field leaves
// them, by no more than that takes, and leaves the field unchanged elsewhere.
//
// Two clips, measured on the Cornell box (docs/method.md, "Limiter"): an increment's overshoot
// above its bound, at every shot; the dips below zero of what is viewed (radiosity_view), so
// that the solution itself stays linear in the emission. Clipping each increment below zero
// instead moves the Cornell box's reference points (the clipped lobes sat beside overshoots
// that later shots and the projection balanced), and so does giving a clip's mass back to the
// coefficients nearby.
#pragma once

#include "math/vec3.h"
#include "radiosity/geometry/spline_field.h"

namespace mbr {

/// Per channel: where the field exceeds upper + slack (checked at the corners, edge midpoints
/// and centres of its cells), the coefficients above upper of the B-splines covering those
/// points are lowered towards it, each by the least fraction that brings every such point to
/// at most upper (limit_positive's rule applied to upper - f). A smaller excess is within the
/// transfer's tolerance.
void limit_increment(SplineField& field, Rgb upper, double slack);

/// Per channel: where the field is below zero (on a grid of at least 4 intervals a cell and 256
/// over the domain, its edges included), the negative coefficients of the B-splines covering
/// those points are raised towards zero, each by the least fraction that makes every such point
/// >= 0 (f = P + (1 - theta) N, P and N the parts of the positive and negative coefficients):
/// the field is then >= 0 at every point of the grid, and it only grows, by no more than the
/// negative lobes asked for.
void limit_positive(SplineField& field);

}  // namespace mbr
