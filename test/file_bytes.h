// test/file_bytes.h - a whole file's bytes, for the tests and the fuzz driver that compare or
// mutate files.
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace mbr::test {

/// The whole file, bytes as they are ("" when it cannot be opened).
inline std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream os;
    os << in.rdbuf();
    return os.str();
}

}  // namespace mbr::test
