// examples/common/reference_command.h - `mbr reference`: an independent Monte Carlo estimate of
// the radiosity B of eq. (1) at user-chosen world points of any scene (radiosity/reference/probe.h,
// radiosity/reference/path_tracer.h), to check mbr's solution or compare it with other renderers.
#pragma once

#include "examples/common/cli.h"

namespace mbr {

/// Usage text of `mbr reference`.
extern const char* reference_usage;

/// `mbr reference SCENE --points FILE.csv --paths N [--seed S] [--threads n]`: loads the scene
/// (.scene, or .obj with its MTL), locates the points of the CSV (probe.h: columns name, x, y, z
/// and optionally nx, ny, nz) within 1e-3 of the scene's diagonal, path-traces N paths per point
/// and prints `name,B_r,B_g,B_b,se_r,se_g,se_b` to stdout. Returns the exit status (0); bad
/// input throws UsageError or InputError for run_main.
int reference_command(Args& args);

}  // namespace mbr
