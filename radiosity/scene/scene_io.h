// radiosity/scene/scene_io.h - reading scenes: mbr's plain-text scene format and Wavefront OBJ + MTL
// import, with validation (docs/scene-format.md is the reference for both). Every bad input
// becomes one InputError naming the file, the line and what is wrong; no input, however
// mangled, crashes or hangs the reader.
#pragma once

#include <array>
#include <iosfwd>
#include <string>

#include "math/vec3.h"
#include "radiosity/scene/scene.h"

namespace mbr {

/// Reads a scene file (docs/scene-format.md). Relative paths inside it (textures, `obj`,
/// `include`) are relative to the file's folder. Throws InputError.
Scene load_scene(const std::string& path);

/// Parses scene text from a stream; `name` is used in messages and, through its folder, to
/// resolve relative paths. The same checks as load_scene. Throws InputError.
Scene parse_scene(std::istream& in, const std::string& name);

/// Imports a Wavefront OBJ file and the MTL libraries it names (docs/scene-format.md, "OBJ
/// import"): Kd -> reflectance, Ke (emitted radiance) -> emission E = pi Ke, every face ->
/// one or more planar quads. The scene has no camera and default settings. Throws InputError.
Scene load_obj(const std::string& path);

/// Parses OBJ text from a stream; `name` is used in messages and to resolve `mtllib` paths.
Scene parse_obj(std::istream& in, const std::string& name);

/// Largest relative deviation from planarity accepted for a planar quad: every corner lies
/// within this fraction of the quad's size (its largest corner-to-corner distance) of the
/// corners' mean plane. The Cornell box's red wall (1.02e-3) passes.
constexpr double planarity_tolerance = 2.5e-3;

/// Largest absolute coordinate or length accepted in scene and OBJ files.
constexpr double max_coordinate = 1e8;

/// Why four corners do not make a valid planar quad, or an empty string when they do: corners
/// that coincide, zero area, self-intersection, non-planarity beyond planarity_tolerance, or a
/// corner that is not strictly convex (a non-convex quad folds its bilinear map). The tests are
/// invariant under translation and scaling: they work relative to corner 0, in units of the
/// largest coordinate difference, so that quads near max_coordinate cannot overflow and small
/// quads far from the origin do not lose their shape to cancellation.
std::string planar_quad_problem(const std::array<Vec3, 4>& corners);

}  // namespace mbr
