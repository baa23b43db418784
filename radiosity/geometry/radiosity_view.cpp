// radiosity/geometry/radiosity_view.cpp - B from a field of B or of H (eq. (2)).
#include "radiosity/geometry/radiosity_view.h"

#include "math/check.h"

namespace mbr {

RadiosityView::RadiosityView(const std::vector<SplineField>& radiosity) {
    surfaces_.reserve(radiosity.size());
    for (const SplineField& f : radiosity) surfaces_.push_back({&f});
}

bool RadiosityView::empty(int surface) const {
    MBR_CHECK(surface >= 0 && surface < size());
    const ShadedField& s = surfaces_[surface];
    return !s.field || s.field->empty();
}

Rgb RadiosityView::at(int surface, double u, double v) const {
    MBR_CHECK(surface >= 0 && surface < size());
    const ShadedField& s = surfaces_[surface];
    if (!s.field || s.field->empty()) return {};
    const Rgb f = s.field->evaluate(u, v);
    if (s.quantity == FieldQuantity::radiosity) return f;
    // Eq. (2): B = E + rho H.
    Rgb b = s.reflectance ? s.reflectance->value(u, v) * f : Rgb{};
    if (s.emission) b += s.emission->value(u, v);
    return b;
}

}  // namespace mbr
