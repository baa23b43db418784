// test/report.h - measured numbers worth knowing (accuracies, evaluation counts, radii), printed
// only when MBR_TEST_REPORT is set, so a normal run stays quiet:
//   MBR_TEST_REPORT=1 build/test/mbr_tests "[gauss]"
#pragma once

#include <cstdlib>
#include <iostream>
#include <ostream>

namespace mbr::test {

/// std::cout when MBR_TEST_REPORT is set, else a stream that discards everything.
inline std::ostream& report() {
    static const bool enabled = std::getenv("MBR_TEST_REPORT") != nullptr;
    static std::ostream discard(nullptr);
    return enabled ? std::cout : discard;
}

}  // namespace mbr::test
