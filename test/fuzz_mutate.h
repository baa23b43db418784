// test/fuzz_mutate.h - the seeded mutations shared by the scene-reader tests
// (test/test_scene_fuzz.cpp) and the long-running fuzz driver (test/fuzz_readers.cpp):
// byte flips, insertions of bytes and reader tokens, deletions, duplicated and swapped lines,
// numbers replaced by huge, tiny, NaN or negative values, truncation.
#pragma once

#include <algorithm>
#include <cctype>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace mbr::fuzz_input {

/// Tokens that matter to the scene, OBJ and MTL readers, inserted at random places.
inline const char* const dictionary[] = {
    "nan",
    "inf",
    "-inf",
    "1e400",
    "1e308",
    "-1e308",
    "1e-320",
    "0",
    "-0",
    "-1",
    "1",
    "0.999",
    "99999999999999999999",
    "2147483648",
    "#",
    "\n",
    " ",
    "/",
    "//",
    "-",
    ".",
    "e",
    "include",
    "obj",
    "quad",
    "material",
    "set",
    "camera",
    "inward",
    "image",
    "checker",
    "f",
    "v",
    "usemtl",
    "mtllib",
    "newmtl",
    "Kd",
    "Ke",
    "map_Kd",
    "picture.png",
    "nothere.png",
    "\t",
    "\r",
    "",  // was a dangling c_str() of a temporary; NUL bytes come from random insertions
    "\xff\xfe",
    "\x89PNG",
    "reflectance",
    "emission",
    "1e8",
    "360",
    "180",
    "-360"};

/// Returns a mutated copy of `text`: one to four random edits.
inline std::string mutate(std::string text, std::mt19937_64& rng) {
    auto pick = [&](size_t n) { return n == 0 ? size_t(0) : size_t(rng() % n); };
    auto lines_of = [](const std::string& t) {
        std::vector<std::string> lines;
        std::string line;
        std::istringstream in(t);
        while (std::getline(in, line)) lines.push_back(line);
        return lines;
    };
    auto join = [](const std::vector<std::string>& lines) {
        std::string t;
        for (const std::string& l : lines) t += l + "\n";
        return t;
    };
    int n_edits = 1 + int(rng() % 4);
    for (int e = 0; e < n_edits; ++e) {
        switch (rng() % 9) {
            case 0:  // flip bits of a byte
                if (!text.empty()) text[pick(text.size())] ^= char(1 + rng() % 255);
                break;
            case 1: {  // insert random bytes
                std::string bytes;
                for (size_t n = 1 + pick(8); n > 0; --n) bytes += char(rng() % 256);
                text.insert(pick(text.size() + 1), bytes);
                break;
            }
            case 2:  // insert a token that matters to the readers
                text.insert(pick(text.size() + 1),
                            std::string(dictionary[pick(std::size(dictionary))]) + " ");
                break;
            case 3:  // delete a range
                if (!text.empty()) text.erase(pick(text.size()), 1 + pick(16));
                break;
            case 4: {  // duplicate a line
                auto lines = lines_of(text);
                if (!lines.empty()) {
                    size_t i = pick(lines.size());
                    lines.insert(lines.begin() + long(pick(lines.size() + 1)), lines[i]);
                }
                text = join(lines);
                break;
            }
            case 5: {  // swap two lines
                auto lines = lines_of(text);
                if (lines.size() >= 2)
                    std::swap(lines[pick(lines.size())], lines[pick(lines.size())]);
                text = join(lines);
                break;
            }
            case 6:
            case 7: {  // replace a number by a nasty one
                std::vector<size_t> starts;
                for (size_t i = 0; i < text.size(); ++i)
                    if ((std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '-') &&
                        (i == 0 || text[i - 1] == ' ' || text[i - 1] == '/'))
                        starts.push_back(i);
                if (starts.empty()) break;
                size_t s = starts[pick(starts.size())], end = s;
                while (end < text.size() && text[end] != ' ' && text[end] != '\n' &&
                       text[end] != '/')
                    ++end;
                static const char* const nasty[] = {
                    "nan",    "inf", "1e400", "1e300", "-1e300",      "-1",        "0",
                    "1e-300", "1",   "7",     "-7",    "99999999999", "1.0000001", "0.99999999"};
                text.replace(s, end - s, nasty[pick(std::size(nasty))]);
                break;
            }
            case 8:  // truncate
                text.resize(pick(text.size() + 1));
                break;
        }
    }
    return text;
}

/// An OBJ with every face form, negative indices, groups and polygons to split.
inline const std::string obj_sample =
    "mtllib cornell_box.mtl\n"
    "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 1 2 0.3\nv -1 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n"
    "o thing\ng part\nusemtl white\ns 1\n"
    "f 1 2 3 4\nf 1/1 2/2 3/1\nf 1//1 2//1 3//1 5//1 6//1\nf -6/-2/-1 -5/-1/-1 -4/-2/-1\n"
    "usemtl light\nf 1 2 5 4\nf 6 5 3 2 1\ng\nf 4 3 2 1\n";

}  // namespace mbr::fuzz_input
