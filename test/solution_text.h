// test/solution_text.h - comparing solutions in tests: fields bit for bit, and a solution's file
// text (radiosity/solver/solution_file.h).
#pragma once

#include <sstream>
#include <string>

#include "radiosity/solver/solution_file.h"
#include "radiosity/solver/solver.h"

namespace mbr::test {

/// True when the two fields have the same order, level and coefficients, bit for bit.
inline bool same_fields(const SplineField& a, const SplineField& b) {
    if (a.order() != b.order() || a.level() != b.level()) return false;
    for (int c = 0; c < 3; ++c)
        if (a.channel(c).a != b.channel(c).a) return false;
    return true;
}

/// The text save_solution writes for the solution.
inline std::string saved(const Scene& scene, const Solution& solution) {
    std::ostringstream os;
    save_solution(os, scene, solution);
    return os.str();
}

}  // namespace mbr::test
