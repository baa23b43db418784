// radiosity/solver/solution_file.h - solution files (docs/solution-format.md): the solved fields B
// and dB_unshot of paper section 4 saved and loaded, so that rendering can be separate from
// solving.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

#include "radiosity/scene/scene.h"

namespace mbr {

struct Solution;  // radiosity/solver/solver.h

/// Solution files (docs/solution-format.md): a versioned text format holding each surface's
/// name and both fields, with a fingerprint of the scene's surfaces. save_solution writes through
/// `out`; load_solution refuses a damaged, truncated, foreign or mismatched file with an
/// InputError naming `name` (the file) and the line.
void save_solution(std::ostream& out, const Scene& scene, const Solution& solution);
/// Reads what save_solution wrote for `scene`; throws InputError(name, line, ...).
Solution load_solution(std::istream& in, const std::string& name, const Scene& scene);
/// Reads the solution file at `path` for `scene`. Refuses what is not a regular file (a folder,
/// a device, a FIFO) before reading a byte: InputError(path, 0, ...).
Solution load_solution(const std::string& path, const Scene& scene);

/// A fingerprint of the scene's surfaces and materials (names, kinds, corners, reflectance and
/// emission means), for matching solution files to scenes.
std::uint64_t scene_fingerprint(const Scene& scene);

}  // namespace mbr
