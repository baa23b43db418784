// test/test_readers.cpp - what every reader of mbr's inputs (scene files and includes, OBJ, MTL,
// textures, solution files, probe CSVs) does with inputs that are not text files of reasonable
// lines: a folder, a device, a FIFO, an endless line; and the messages of the texture reader and
// of values beyond the formats' limits.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <streambuf>
#include <string>

#include "math/check.h"
#include "radiosity/geometry/texture.h"
#include "radiosity/reference/probe.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/solver/solution_file.h"
#include "radiosity/solver/solver.h"

using namespace mbr;
using Catch::Matchers::Contains;

namespace {

/// A folder of scratch files, removed at the end of the test.
struct Scratch {
    std::filesystem::path path;
    Scratch() {
        path = std::filesystem::temp_directory_path() /
               ("mbr_test_readers_" + std::to_string(long(getpid())));
        std::filesystem::create_directories(path);
    }
    ~Scratch() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string write(const std::string& name, const std::string& bytes) const {
        std::string p = (path / name).string();
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
    /// A FIFO in the folder, or an empty string where one cannot be made.
    std::string fifo(const std::string& name) const {
        std::string p = (path / name).string();
        return ::mkfifo(p.c_str(), 0600) == 0 ? p : std::string();
    }
};

/// The InputError that `read` throws (fails the test when there is none).
InputError error_of(const std::function<void()>& read) {
    try {
        read();
    } catch (const InputError& e) {
        return e;
    }
    FAIL("no InputError");
    return InputError("");
}

/// An endless stream of one byte without a line end, counting the bytes taken from it.
class EndlessBuf : public std::streambuf {
public:
    explicit EndlessBuf(char byte) : block_(4096, byte) {}
    size_t taken() const { return taken_; }

protected:
    int_type underflow() override {
        taken_ += block_.size();
        setg(block_.data(), block_.data(), block_.data() + block_.size());
        return traits_type::to_int_type(block_[0]);
    }

private:
    std::string block_;
    size_t taken_ = 0;
};

const std::string white = "material white reflectance 0.5 0.5 0.5\n";
const std::string square = "quad sq white 0 0 0  1 0 0  1 1 0  0 1 0\n";

Scene small_scene() {
    std::istringstream in(white + square);
    return parse_scene(in, "small.scene");
}

}  // namespace

TEST_CASE("readers: a folder, a device or a FIFO is refused by every reader, by name",
          "[readers][errors]") {
    Scratch dir;
    const std::string folder = dir.path.string();
    const std::string fifo = dir.fifo("fifo");
    const Scene scene = small_scene();
    std::vector<std::pair<std::string, std::string>> cases = {
        {folder, "is a folder, not a file"}, {"/dev/zero", "is not a regular file"}};
    if (!fifo.empty()) cases.push_back({fifo, "is not a regular file"});
    for (const auto& [path, problem] : cases) {
        CAPTURE(path);
        const std::vector<std::function<void()>> readers = {
            [&] { load_scene(path); },           [&] { load_obj(path); },
            [&] { load_solution(path, scene); }, [&] { read_probe_points(path); },
            [&] { Texture::image(path); },
        };
        for (const auto& read : readers) {
            InputError e = error_of(read);
            CHECK(e.file() == path);
            CHECK(e.line() == 0);
            CHECK(e.message() == problem);
        }
        // Named in a scene: an include, an OBJ, an MTL library and a texture.
        const std::string named[] = {"include " + path, "obj " + path,
                                     "material t reflectance image " + path};
        for (const std::string& statement : named) {
            std::istringstream in(white + square + statement + "\n");
            InputError e = error_of([&] { parse_scene(in, "s.scene"); });
            CHECK(e.line() == 3);
            CHECK_THAT(e.message(), Contains("'" + path + "': " + problem));
        }
        const std::string obj = dir.write("m.obj", "mtllib " + path + "\n");
        InputError e = error_of([&] { load_obj(obj, ImportOptions{true}); });
        CHECK(e.message() == "material library '" + path + "': " + problem);
    }
}

TEST_CASE("readers: a stream that is a folder gives an input error, not a stream exception",
          "[readers][errors]") {
    // Opening a folder as a std::ifstream succeeds on Linux; its first read fails (EISDIR),
    // which libstdc++ reports by throwing from the stream buffer.
    Scratch dir;
    const std::string folder = dir.path.string();
    const Scene scene = small_scene();
    const std::vector<std::function<void(std::istream&)>> readers = {
        [&](std::istream& in) { parse_scene(in, folder); },
        [&](std::istream& in) { parse_obj(in, folder); },
        [&](std::istream& in) { load_solution(in, folder, scene); },
        [&](std::istream& in) { parse_probe_points(in, folder); },
    };
    for (const auto& read : readers) {
        std::ifstream in(folder);
        if (!in) {
            WARN("this system does not open a folder as a stream; nothing to check");
            return;
        }
        InputError e = error_of([&] { read(in); });
        CHECK(e.file() == folder);
        CHECK(e.message() == "is a folder, not a file");
    }
}

TEST_CASE("readers: an endless line is refused at the format's limit, having read no more",
          "[readers][errors]") {
    const Scene scene = small_scene();
    {
        EndlessBuf buf('x');
        std::istream in(&buf);
        InputError e = error_of([&] { parse_probe_points(in, "points.csv"); });
        CHECK(e.line() == 1);
        CHECK(e.message() == "line is longer than 65536 bytes");
        CHECK(buf.taken() <= 65536 + 4096);
    }
    {
        EndlessBuf buf('x');
        std::istream in(&buf);
        InputError e = error_of([&] { parse_scene(in, "s.scene"); });
        CHECK(e.message() == "line is longer than 65536 bytes");
        CHECK(buf.taken() <= 65536 + 4096);
    }
    {
        EndlessBuf buf('0');
        std::istream in(&buf);
        InputError e = error_of([&] { load_solution(in, "s.solution", scene); });
        CHECK(e.line() == 1);
        CHECK(e.message() == "line is too long");
        CHECK(buf.taken() <= (size_t(1) << 26) + 4096);
    }
}

namespace {

void big_endian(std::string& s, unsigned v) {
    for (int i = 3; i >= 0; --i) s += char((v >> (8 * i)) & 255);
}

/// A PNG of the given size whose only pixel data chunk holds `data`, after a chunk of type
/// `extra` when that is not empty (CRCs are zero: stb_image does not check them).
std::string png(unsigned width, unsigned height, const std::string& data,
                const std::string& extra = "") {
    std::string s("\x89PNG\r\n\x1a\n", 8);
    big_endian(s, 13);
    s += "IHDR";
    big_endian(s, width);
    big_endian(s, height);
    s += std::string("\x08\x02\x00\x00\x00", 5);
    big_endian(s, 0);
    if (!extra.empty()) {
        big_endian(s, 0);
        s += extra;
        big_endian(s, 0);
    }
    big_endian(s, unsigned(data.size()));
    s += "IDAT" + data;
    big_endian(s, 0);
    big_endian(s, 0);
    s += "IEND";
    big_endian(s, 0);
    return s;
}

std::string texture_error(const Scratch& dir, const std::string& bytes) {
    const std::string path = dir.write("t.png", bytes);
    return error_of([&] { Texture::image(path); }).message();
}

}  // namespace

TEST_CASE("readers: texture messages say what the image's header or data says",
          "[readers][texture][errors]") {
    Scratch dir;
    // Both too big: stb_image refuses the first header itself (over 2^30 bytes of pixels).
    CHECK(texture_error(dir, png(20000, 20000, "x")) ==
          "texture image is 20000 x 20000 pixels; at most 33554432 pixels are accepted");
    CHECK(texture_error(dir, png(6000, 6000, "x")) ==
          "texture image is 6000 x 6000 pixels; at most 33554432 pixels are accepted");
    CHECK(texture_error(dir, png(4, 4, "x").substr(0, 20)) ==
          "cannot read the texture image (a damaged or truncated PNG header)");
    // An unknown critical chunk: its type in the message, never an empty or cut reason.
    CHECK(texture_error(dir, png(4, 4, "x", std::string("ID\0T", 4))) ==
          "cannot decode the texture image (unknown PNG chunk type (it holds a zero byte))");
    CHECK(texture_error(dir, png(4, 4, "x", std::string("\0DAT", 4))) ==
          "cannot decode the texture image (unknown PNG chunk type (it holds a zero byte))");
    CHECK(texture_error(dir, png(4, 4, "x",
                                 "I\xff"
                                 "AT")) ==
          "cannot decode the texture image (unknown PNG chunk type 'I\\xffAT')");
    CHECK(texture_error(dir, png(4, 4, "garbage")) ==
          "cannot decode the texture image (bad zlib header)");
}

TEST_CASE("readers: one emission limit for the scene format and MTL; probe coordinates bounded",
          "[readers][errors]") {
    auto scene_error = [](const std::string& text) {
        std::istringstream in(text);
        return error_of([&] { parse_scene(in, "s.scene"); }).message();
    };
    CHECK(scene_error("material m emission 1e308 0 0\n") ==
          "emission 1e+308 exceeds the limit 1e+30");
    CHECK(scene_error("material m emission checker 2 1 1 1 2e30 0 0\n") ==
          "emission checker colour 2e+30 exceeds the limit 1e+30");
    std::istringstream at_limit("material white emission 1e30 0 0\n" + square);
    CHECK(parse_scene(at_limit, "s.scene").materials[0].emission.maximum().r == 1e30);
    Scratch dir;
    dir.write("m.mtl", "newmtl hot\nKe 1e30 0 0\n");
    const std::string obj =
        dir.write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    InputError e = error_of([&] { load_obj(obj, ImportOptions{true}); });
    CHECK(e.line() == 2);
    CHECK(e.message() ==
          "Ke 1e+30 exceeds the limit 3.183098861837907e+29 (the emission E = pi Ke is at most "
          "1e+30)");

    auto probe_error = [](const std::string& text) {
        std::istringstream in(text);
        return error_of([&] { parse_probe_points(in, "p.csv"); });
    };
    e = probe_error("name,x,y,z\np,1e308,0,0\n");
    CHECK(e.line() == 2);
    CHECK(e.message() == "column 'x': 1e+308 exceeds the coordinate limit 100000000");
    CHECK(probe_error("name,x,y,Z\np,0,0,-100000000.1\n").message() ==
          "column 'Z': -100000000.1 exceeds the coordinate limit 100000000");
    // A normal's size does not matter, however large or small its components.
    std::istringstream huge("name,x,y,z,nx,ny,nz\np,0,0,1e8,1e308,1e308,0\nq,0,0,0,0,1e-320,0\n");
    const std::vector<ProbePoint> points = parse_probe_points(huge, "p.csv");
    CHECK(points[0].normal.x == Approx(std::sqrt(0.5)));
    CHECK(points[1].normal.y == 1);
}
