// radiosity/geometry/radiosity_view.h - the radiosity B_i(u, v) of every surface from what its
// spline field holds (paper eq. (2): B = E + rho H, with H(x) = int F(x, y) B(y) dA_y the
// irradiance over pi, eq. (21) without the reflectance).
//
// The paper stores B itself. For a surface whose reflectance is a texture (a checker, an image),
// B carries the texture's steps, which a spline field of the quadtree's level can neither follow
// nor keep positive (it rings between the squares). H is as smooth as the light arriving, so
// such a surface stores H, and B = E + rho H is formed wherever B is needed: at every pixel and
// probe point, with rho and E read from their textures at their own resolution (docs/method.md,
// "Textured reflectance").
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "radiosity/geometry/spline_field.h"
#include "radiosity/geometry/texture.h"

namespace mbr {

/// What a surface's spline field holds.
enum class FieldQuantity {
    radiosity,   // B itself, emission included (the paper's representation)
    irradiance,  // H, with B = E + rho H (emission not included in the field)
};

/// One surface's field and, for an irradiance field, the textures that turn it into B.
struct ShadedField {
    const SplineField* field = nullptr;
    FieldQuantity quantity = FieldQuantity::radiosity;
    const Texture* reflectance = nullptr;  // rho (irradiance fields only)
    const Texture* emission = nullptr;     // E (irradiance fields only)
};

/// B_i(u, v) for every surface i of a solution. Holds pointers: the fields and textures must
/// outlive the view (except the fields it owns). A plain list of fields converts implicitly (every field then holds B).
class RadiosityView {
public:
    RadiosityView() = default;
    /// Every field holds B.
    RadiosityView(const std::vector<SplineField>& radiosity);  // NOLINT: implicit on purpose
    /// `owned` keeps fields alive that `surfaces` point into (copies the view made), shared by
    /// the view's copies.
    explicit RadiosityView(std::vector<ShadedField> surfaces,
                           std::shared_ptr<const std::vector<SplineField>> owned = nullptr)
        : surfaces_(std::move(surfaces)), owned_(std::move(owned)) {}

    int size() const { return static_cast<int>(surfaces_.size()); }
    /// True when surface i has no field (it is then black).
    bool empty(int surface) const;
    /// B_i(u, v), eq. (2): the field's value, or E(u, v) + rho(u, v) H(u, v).
    Rgb at(int surface, double u, double v) const;
    const ShadedField& surface(int i) const { return surfaces_[i]; }

private:
    std::vector<ShadedField> surfaces_;
    std::shared_ptr<const std::vector<SplineField>> owned_;
};

}  // namespace mbr
