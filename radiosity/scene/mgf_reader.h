// radiosity/scene/mgf_reader.h - MGF import (Ward's Materials and Geometry Format, the format of
// the classic radiosity test scenes; docs/scene-format.md, "MGF import"): vertices and faces to
// the planar quads of paper section 2, spheres, cylinders and rings to mbr's curved surfaces,
// cones, tori and prisms to quads, materials to the reflectance rho and emission E of eq. (1),
// transforms with arrays, objects and includes. Faults are repaired with warnings or, strictly,
// refused with one InputError naming the file and line (ImportOptions, scene.h).
#pragma once

#include <array>
#include <iosfwd>
#include <string>

#include "math/vec3.h"
#include "radiosity/scene/obj_reader.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// Imports an MGF file and the files it includes (docs/scene-format.md, "MGF import"). The
/// scene has no camera and default settings. Throws InputError.
Scene load_mgf(const std::string& path, const ImportOptions& options = {});

/// Parses MGF text from a stream; `name` is used in messages and to resolve `i` includes.
Scene parse_mgf(std::istream& in, const std::string& name, const ImportOptions& options = {});

/// True when `path` names an MGF file: its extension is .mgf in any case.
bool is_mgf_path(const std::string& path);

/// True for the files the forgiving import reads (OBJ and MGF; ImportOptions), whose lights may
/// be turned around and whose repeated faces of another material are dropped.
bool is_import_path(const std::string& path);

/// Any scene file by its extension: OBJ (is_obj_path), MGF (is_mgf_path), else mbr's format.
Scene load_scene_file(const std::string& path, const ImportOptions& options = {});

/// Linear sRGB (ITU-R BT.709 primaries) of the CIE colour of chromaticity (x, y) and luminance
/// Y, with equal-energy white (x = y = 1/3) as the white point, as MGF defines its colours:
/// neutral (1/3, 1/3) gives (Y, Y, Y). Channels outside the gamut come out negative.
Rgb mgf_colour_to_rgb(double x, double y, double Y);

namespace detail {

/// Reads MGF text named `name` as part of the load `state`, without the check for repeated
/// faces (the caller runs it on the whole scene).
Scene read_mgf(std::istream& in, const std::string& name, LoadState& state);

/// A rigid, scaled or mirrored map of MGF's `xf` arguments: x -> m x + t.
struct Affine {
    std::array<std::array<double, 3>, 3> m{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    Vec3 t;
    double scale = 1;  // the length factor (|det m|^(1/3): -s, with rotations and mirrors)
    /// The image of a point.
    Vec3 point(Vec3 p) const;
    /// The image of a direction (not normalised).
    Vec3 vector(Vec3 v) const;
    /// True when the map mirrors (det m < 0): faces turn their other side.
    bool mirrors() const;
    /// This map after `first`: x -> this(first(x)).
    Affine after(const Affine& first) const;
};

}  // namespace detail

}  // namespace mbr
