// radiosity/scene/scene_io.h - reading scenes: mbr's plain-text scene format and Wavefront OBJ +
// MTL import, with validation (docs/scene-format.md is the reference for both). Every bad input
// becomes one InputError naming the file, the line and what is wrong; no input, however
// mangled, crashes or hangs the reader.
//
// This header only gathers the readers' headers, one per concept, so that its includers keep
// what it always declared: scene_reader.h (load_scene, parse_scene), obj_reader.h (load_obj,
// parse_obj), mgf_reader.h (load_mgf, parse_mgf, load_scene_file) and faces_to_quads.h
// (planarity_tolerance, max_coordinate, planar_quad_problem). The line reader they share is
// line_reader.h.
#pragma once

#include "radiosity/scene/faces_to_quads.h"
#include "radiosity/scene/mgf_reader.h"
#include "radiosity/scene/obj_reader.h"
#include "radiosity/scene/scene_reader.h"
