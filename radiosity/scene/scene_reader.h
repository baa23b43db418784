// radiosity/scene/scene_reader.h - mbr's plain-text scene format (docs/scene-format.md): the
// surfaces of paper section 2 (planar quads, bilinear patches, cylinders, spheres, disks) with
// the reflectance rho and emission E of eq. (1), a camera, solver settings, OBJ imports and
// includes. Every bad input becomes one InputError naming the file, the line and what is wrong.
#pragma once

#include <iosfwd>
#include <string>

#include "radiosity/scene/scene.h"

namespace mbr {

/// Reads a scene file (docs/scene-format.md). Relative paths inside it (textures, `obj`,
/// `include`) are relative to the file's folder. A surface that repeats another (its file,
/// includes and OBJ imports together) is dropped with a warning in Scene::warnings, or refused
/// when its material differs (duplicate_faces.h). The OBJ files it imports are read as `options`
/// say (ImportOptions: forgiving or strict); the scene's own statements always strictly.
/// Throws InputError.
Scene load_scene(const std::string& path, const ImportOptions& options = {});

/// Parses scene text from a stream; `name` is used in messages and, through its folder, to
/// resolve relative paths. The same checks as load_scene. Throws InputError.
Scene parse_scene(std::istream& in, const std::string& name, const ImportOptions& options = {});

}  // namespace mbr
