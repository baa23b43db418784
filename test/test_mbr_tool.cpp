// test/test_mbr_tool.cpp - the mbr command-line tool (examples/mbr/mbr.cpp) end to end, run as a
// child process: `mbr render` writes a PNG of the camera's size and nothing else, a
// missing output folder is status 2 with no file left, outputs that name an input or each other
// are refused, a signal leaves no temporary file, outputs are all written or none, bad arguments
// and bad input are status 2 with one stderr line naming the problem, a saved solution loads back
// to the same image, `mbr probe` prints B at points in their order (the emission on a light, zero
// on a black surface and the analytic rho E F on a floor under a rectangle light), help and version
// go to stdout, and no progress bar appears with --quiet or without a terminal.
//
// The tool's path comes from the compile definition MBR_TOOL (test/CMakeLists.txt). It is run
// by test/run_program.h, no shell, so that the temporary folders' names can hold spaces (they do).
// The scene is tiny (three rectangles, max_depth 3, at most 3 shots, a 32 x 24 camera, one sample
// per pixel), so that every run of the tool takes a fraction of a second, also under ASan.
#include <fcntl.h>
#include <signal.h>
#include <stb_image.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "math/vec3.h"
#include "radiosity/output/render.h"
#include "test/file_bytes.h"
#include "test/report.h"
#include "test/run_program.h"

#ifndef MBR_TOOL
#error "MBR_TOOL must name the mbr program (test/CMakeLists.txt defines it)"
#endif

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

// A light (reflectance 0, so it only emits) 0.5 above a grey floor, and a black panel beside
// them facing away. The floor's radiosity is then exactly rho E F(x): the light cannot reflect
// what the floor sends back, and the planar floor cannot see itself. The light is narrower than
// the floor, off its centre and longer along z than along x, so that a mirrored or transposed
// (u, v) on the floor changes the values at the probe points below by 0.1 or more.
// The constants below restate the numbers of the scene for the analytic check.
const char* lit_floor_scene =
    "# test/test_mbr_tool.cpp: a rectangle light over a grey floor, a black panel beside\n"
    "material light reflectance 0 0 0 emission 10 20 30\n"
    "material grey  reflectance 0.5 0.4 0.3\n"
    "material black reflectance 0 0 0\n"
    "rectangle floor grey   0 0 0       0 0 1     1 0 0      # y = 0, x and z in [0, 1], up\n"
    "rectangle light light  0.1 0.5 0.3   0.3 0 0   0 0 0.6  # y = 0.5, facing down\n"
    "rectangle panel black  2 0 0       0 1 0     0 0 1      # x = 2, facing +x\n"
    "set max_depth 3\n"
    "set max_shots 3\n"
    "camera eye 0.5 0.35 -1  look_at 0.5 0.15 0.6  fov 60  size 32 24\n";
constexpr int camera_width = 32, camera_height = 24;
constexpr double emission[3] = {10, 20, 30};        // the light's E, r g b
constexpr double reflectance[3] = {0.5, 0.4, 0.3};  // the floor's rho, r g b
constexpr double light_x0 = 0.1, light_x1 = 0.4;    // the light's extent over the floor
constexpr double light_z0 = 0.3, light_z1 = 0.9;
constexpr double light_height = 0.5;
constexpr double light_area = 0.3 * 0.6, total_area = 1 + light_area + 1;
// The bounding box [0, 2] x [0, 1] x [0, 1] and its diagonal.
const double scene_diagonal = std::sqrt(4.0 + 1 + 1);

using mbr::test::TempFolder;
using ToolRun = mbr::test::ProgramRun;

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    REQUIRE(out.good());
}

using mbr::test::read_bytes;

// Every file and folder below `folder`, as paths relative to it: a run may leave nothing else.
std::set<std::string> entries_under(const fs::path& folder) {
    std::set<std::string> names;
    for (const auto& entry : fs::recursive_directory_iterator(folder))
        names.insert(fs::relative(entry.path(), folder).string());
    return names;
}

// Runs `mbr ARGS...` (test/run_program.h), stderr on `stderr_fd` when that is given.
ToolRun run_mbr(const std::vector<std::string>& args, int stderr_fd = -1) {
    return mbr::test::run_program(MBR_TOOL, args, stderr_fd);
}

size_t count_lines(const std::string& s) {
    return size_t(std::count(s.begin(), s.end(), '\n'));
}

// One complete line: the tool's promise for every error (examples/mbr/mbr.cpp, STYLE.md B7).
bool is_one_line(const std::string& s) {
    return count_lines(s) == 1 && s.back() == '\n';
}

std::vector<std::string> split(const std::string& s, char separator) {
    std::vector<std::string> parts;
    std::string part;
    std::istringstream in(s);
    while (std::getline(in, part, separator)) parts.push_back(part);
    return parts;
}

unsigned big_endian_u32(const std::string& bytes, size_t at) {
    unsigned v = 0;
    for (size_t i = 0; i < 4; ++i) v = v << 8 | static_cast<unsigned char>(bytes[at + i]);
    return v;
}

// Form factor from a point to a parallel rectangle at distance c whose corner lies straight
// above the point, sides a and b (Howell's catalogue, configuration B-3; Siegel and Howell):
//   F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))],
// X = a/c, Y = b/c. Signed in a and b, so that sums over corners give any parallel rectangle.
double corner_form_factor(double a, double b, double c) {
    const double sign = (a < 0) != (b < 0) ? -1 : 1;
    const double X = std::abs(a) / c, Y = std::abs(b) / c;
    const double sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
    return sign * (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2 * mbr::Pi);
}

// Form factor from the floor point (x, 0, z), facing up, to the light: the four corner-aligned
// rectangles from the point's foot to the light's corners, added and subtracted.
double floor_to_light_form_factor(double x, double z) {
    const double c = light_height;
    return corner_form_factor(light_x1 - x, light_z1 - z, c) -
           corner_form_factor(light_x0 - x, light_z1 - z, c) -
           corner_form_factor(light_x1 - x, light_z0 - z, c) +
           corner_form_factor(light_x0 - x, light_z0 - z, c);
}

}  // namespace

TEST_CASE("mbr_tool: render writes a PNG of the camera's size and nothing else", "[mbr_tool]") {
    TempFolder dir;
    write_text(dir / "lit floor.scene", lit_floor_scene);
    const ToolRun run = run_mbr(
        {"render", dir / "lit floor.scene", "-o", dir / "out.png", "--spp", "1", "--quiet"});
    CAPTURE(run);
    REQUIRE(run.status == 0);
    CHECK(run.err.empty());
    // No temporary file left beside the image.
    CHECK(entries_under(dir.path()) == std::set<std::string>{"lit floor.scene", "out.png"});

    const std::string png = read_bytes(dir / "out.png");
    REQUIRE(png.size() >= 24);
    CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
    CHECK(big_endian_u32(png, 8) == 13);  // the IHDR chunk's length, then its name
    CHECK(png.compare(12, 4, "IHDR") == 0);
    CHECK(big_endian_u32(png, 16) == unsigned(camera_width));
    CHECK(big_endian_u32(png, 20) == unsigned(camera_height));
    // And the whole file decodes, to that size.
    int w = 0, h = 0, n = 0;
    stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(png.data()),
                                            int(png.size()), &w, &h, &n, 3);
    REQUIRE(pixels != nullptr);
    stbi_image_free(pixels);
    CHECK(w == camera_width);
    CHECK(h == camera_height);
}

TEST_CASE("mbr_tool: --exposure auto shows the lit pixels' log-average at middle grey",
          "[mbr_tool]") {
    TempFolder dir;
    write_text(dir / "lit floor.scene", lit_floor_scene);
    const std::string scene = dir / "lit floor.scene";
    const ToolRun run = run_mbr({"render", scene, "-o", dir / "auto.png", "--spp", "1", "--hdr",
                                 dir / "auto.hdr", "--exposure", "auto"});
    CAPTURE(run);
    REQUIRE(run.status == 0);
    // The exposure said is the one auto_exposure finds in the picture's radiance.
    std::ifstream hdr_in(dir / "auto.hdr", std::ios::binary);
    const mbr::Image radiance = mbr::read_hdr(hdr_in, "auto.hdr");
    const double said = mbr::test::number_after(run.out, "exposure");
    std::ostringstream exact;
    exact.precision(17);
    exact << mbr::auto_exposure(radiance);
    CHECK(said == Approx(mbr::auto_exposure(radiance)).epsilon(1e-3));
    // The same picture as that exposure given by hand (to the HDR file's 8-bit mantissas:
    // within one level of 255).
    const ToolRun by_hand = run_mbr({"render", scene, "-o", dir / "hand.png", "--spp", "1",
                                     "--exposure", exact.str(), "--quiet"});
    REQUIRE(by_hand.status == 0);
    int w1 = 0, h1 = 0, n1 = 0, w2 = 0, h2 = 0, n2 = 0;
    stbi_uc* a = stbi_load((dir / "auto.png").c_str(), &w1, &h1, &n1, 3);
    stbi_uc* b = stbi_load((dir / "hand.png").c_str(), &w2, &h2, &n2, 3);
    REQUIRE(a != nullptr);
    REQUIRE(b != nullptr);
    REQUIRE(w1 * h1 == w2 * h2);
    int largest = 0, bright = 0;
    for (int k = 0; k < 3 * w1 * h1; ++k) {
        largest = std::max(largest, std::abs(int(a[k]) - int(b[k])));
        bright = std::max(bright, int(a[k]));
    }
    stbi_image_free(a);
    stbi_image_free(b);
    CHECK(largest <= 1);
    CHECK(bright > 64);  // and the picture is not black
    // Anything else that is not a number is refused.
    const ToolRun bad = run_mbr({"render", scene, "-o", dir / "x.png", "--exposure", "bright"});
    CHECK(bad.status == 2);
    CHECK_THAT(bad.err, Contains("--exposure expects a number"));
}

TEST_CASE("mbr_tool: a missing output folder is status 2, one line, and no file anywhere",
          "[mbr_tool]") {
    TempFolder dir;
    write_text(dir / "lit floor.scene", lit_floor_scene);
    const std::string out = dir / "missing/x.png";
    const ToolRun run = run_mbr({"render", dir / "lit floor.scene", "-o", out, "--spp", "1"});
    CAPTURE(run);
    // An output path that cannot be written is a bad command line, found before any work.
    CHECK(run.status == 2);
    CHECK(is_one_line(run.err));
    CHECK_THAT(run.err, Contains(out));
    CHECK(run.out.empty());
    CHECK(entries_under(dir.path()) == std::set<std::string>{"lit floor.scene"});
    CHECK_FALSE(fs::exists(dir / "missing"));
}

TEST_CASE("mbr_tool: bad arguments and bad input are status 2 with one stderr line", "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    const std::string out = dir / "out.png";
    write_text(scene, lit_floor_scene);
    // Line 3 is a quad with 9 of its 12 numbers.
    const std::string bad = dir / "bad scene.scene";
    write_text(bad,
               "material grey reflectance 0.5 0.5 0.5\n"
               "\n"
               "quad q grey  0 0 0   1 0 0   1 1 0\n");
    struct Case {
        const char* what;
        std::vector<std::string> args;
        std::string named;  // what the line must name
    };
    const Case cases[] = {
        {"unknown option", {"render", scene, "-o", out, "--bogus"}, "--bogus"},
        {"missing -o", {"render", scene, "--spp", "1"}, "-o"},
        {"order out of range", {"render", scene, "-o", out, "--order", "99"}, "--order"},
        {"unknown command", {"frobnicate", scene}, "frobnicate"},
        {"malformed scene", {"render", bad, "-o", out}, bad + ":3:"},
        {"missing scene", {"render", dir / "no such.scene", "-o", out}, dir / "no such.scene"},
    };
    for (const Case& c : cases) {
        const ToolRun run = run_mbr(c.args);
        CAPTURE(c.what, run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, StartsWith("mbr"));
        CHECK_THAT(run.err, Contains(c.named));
        CHECK(run.out.empty());
        CHECK(entries_under(dir.path()) ==
              std::set<std::string>{"lit floor.scene", "bad scene.scene"});
    }
}

TEST_CASE("mbr_tool: no command is status 2 with one stderr line", "[mbr_tool]") {
    const ToolRun run = run_mbr({});
    CAPTURE(run);
    CHECK(run.status == 2);
    CHECK(is_one_line(run.err));
    CHECK(run.out.empty());
}

TEST_CASE("mbr_tool: a saved solution loads back to the same image; a cut one is refused",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    const std::string solution = dir / "lit floor.solution";
    write_text(scene, lit_floor_scene);
    const std::vector<std::string> image = {"--spp", "1", "--seed", "7", "--quiet"};
    auto render = [&](const std::string& out, const std::vector<std::string>& more) {
        std::vector<std::string> args = {"render", scene, "-o", out};
        args.insert(args.end(), image.begin(), image.end());
        args.insert(args.end(), more.begin(), more.end());
        return run_mbr(args);
    };
    const ToolRun saved = render(dir / "solved.png", {"--save-solution", solution});
    CAPTURE(saved);
    REQUIRE(saved.status == 0);
    const ToolRun loaded = render(dir / "loaded.png", {"--load-solution", solution});
    CAPTURE(loaded);
    REQUIRE(loaded.status == 0);
    const std::string solved_png = read_bytes(dir / "solved.png");
    const std::string loaded_png = read_bytes(dir / "loaded.png");
    REQUIRE(!solved_png.empty());
    CHECK(solved_png == loaded_png);
    // The image is not uniform, so a lost field would change its bytes: the light, the lit floor
    // and the black background give several distinct pixels.
    int w = 0, h = 0, n = 0;
    stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(solved_png.data()),
                                            int(solved_png.size()), &w, &h, &n, 3);
    REQUIRE(pixels != nullptr);
    std::set<std::vector<int>> colours;
    for (int i = 0; i < w * h; ++i)
        colours.insert({pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]});
    stbi_image_free(pixels);
    CHECK(colours.size() >= 10);

    // The probe sees the loaded fields to all nine printed digits, not only through 8-bit pixels.
    const std::string points = dir / "points.csv";
    write_text(points, "name,x,y,z\nunder,0.25,0,0.6\noutside,0.7,0,0.3\n");
    const ToolRun probe_solved = run_mbr({"probe", scene, "--points", points, "--quiet"});
    const ToolRun probe_loaded =
        run_mbr({"probe", scene, "--points", points, "--load-solution", solution});
    CAPTURE(probe_solved, probe_loaded);
    REQUIRE(probe_solved.status == 0);
    REQUIRE(probe_loaded.status == 0);
    CHECK(probe_solved.out == probe_loaded.out);

    // Cut copies: in the middle of a number, just before the second surface, and all but the
    // closing `end` line. Each is refused with status 2 and one line naming the file, before
    // any image is written. (The tool reports a cut file as bad input, status 2.)
    const std::string whole = read_bytes(solution);
    const size_t second_surface = whole.find("\nsurface 1 ");
    const size_t end_line = whole.rfind("\nend");
    REQUIRE(second_surface != std::string::npos);
    REQUIRE(end_line != std::string::npos);
    for (size_t keep : {whole.size() / 2, second_surface + 1, end_line + 1}) {
        CAPTURE(keep, whole.size());
        const std::string cut = dir / "cut solution";
        write_text(cut, whole.substr(0, keep));
        const ToolRun run = render(dir / "cut.png", {"--load-solution", cut});
        CAPTURE(run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains(cut));
        CHECK_FALSE(fs::exists(dir / "cut.png"));
    }
}

TEST_CASE("mbr_tool: render without a camera frames the scene; camera options replace it",
          "[mbr_tool]") {
    TempFolder dir;
    std::string no_camera = lit_floor_scene;
    no_camera.erase(no_camera.find("camera eye"));
    write_text(dir / "bare.scene", no_camera);
    auto render = [&](const std::string& out, const std::vector<std::string>& more) {
        std::vector<std::string> args = {"render", dir / "bare.scene", "-o", out, "--spp", "1"};
        args.insert(args.end(), more.begin(), more.end());
        return run_mbr(args);
    };
    auto png_size = [](const std::string& path) {
        int w = 0, h = 0, n = 0;
        REQUIRE(stbi_info(path.c_str(), &w, &h, &n));
        return std::pair<int, int>(w, h);
    };
    const ToolRun framed = render(dir / "framed.png", {"--quiet"});
    CAPTURE(framed);
    REQUIRE(framed.status == 0);
    CHECK(png_size(dir / "framed.png") == std::pair<int, int>(640, 480));
    const ToolRun given =
        render(dir / "given.png", {"--camera", "0.5", "0.35", "-1", "0.5", "0.15", "0.6", "0", "1",
                                   "0", "--fov", "60", "--size", "32", "24", "--quiet"});
    CAPTURE(given);
    REQUIRE(given.status == 0);
    CHECK(png_size(dir / "given.png") == std::pair<int, int>(32, 24));
    for (const std::vector<std::string>& bad :
         {std::vector<std::string>{"--back-faces", "grey"},
          {"--fov", "180"},
          {"--size", "0", "10"},
          {"--camera", "1", "1", "1", "1", "1", "1", "0", "1", "0"}}) {
        const ToolRun run = render(dir / "bad.png", bad);
        CAPTURE(run);
        CHECK(run.status == 2);
        CHECK_FALSE(fs::exists(dir / "bad.png"));
    }
}

TEST_CASE("mbr_tool: probe saves its solution and says its summary on stderr", "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    const std::string points = dir / "points.csv";
    write_text(scene, lit_floor_scene);
    write_text(points, "name,x,y,z\nunder,0.25,0,0.6\noutside,0.7,0,0.3\n");
    // Solved and saved: the summary goes to stderr (stdout holds the CSV alone).
    const ToolRun saved =
        run_mbr({"probe", scene, "--points", points, "--save-solution", dir / "p.solution"});
    CAPTURE(saved);
    REQUIRE(saved.status == 0);
    CHECK_THAT(saved.err, Contains("shots "));
    CHECK_THAT(saved.err, Contains("kernel evaluations"));
    CHECK_THAT(saved.err, Contains("wrote " + (dir / "p.solution")));
    CHECK(saved.out.rfind("name,B_r,B_g,B_b\n", 0) == 0);
    // The same fields as render saves, and loaded back the same values.
    const ToolRun rendered = run_mbr({"render", scene, "-o", dir / "r.png", "--spp", "1", "--quiet",
                                      "--save-solution", dir / "r.solution"});
    REQUIRE(rendered.status == 0);
    CHECK(read_bytes(dir / "p.solution") == read_bytes(dir / "r.solution"));
    const ToolRun loaded = run_mbr(
        {"probe", scene, "--points", points, "--load-solution", dir / "p.solution", "--quiet"});
    CAPTURE(loaded);
    REQUIRE(loaded.status == 0);
    CHECK(loaded.out == saved.out);
    CHECK(loaded.err.empty());  // --quiet: nothing on stderr
    // An output that is an input (the points) or two solution options: refused, nothing written.
    const ToolRun clash = run_mbr({"probe", scene, "--points", points, "--save-solution", points});
    CHECK(clash.status == 2);
    CHECK(read_bytes(points) == "name,x,y,z\nunder,0.25,0,0.6\noutside,0.7,0,0.3\n");
    const ToolRun both = run_mbr({"probe", scene, "--points", points, "--save-solution",
                                  dir / "x.solution", "--load-solution", dir / "p.solution"});
    CHECK(both.status == 2);
    CHECK_FALSE(fs::exists(dir / "x.solution"));
}

TEST_CASE("mbr_tool: probe prints B at the points in order: E, zero and rho E F", "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    // Neither alphabetical nor in the scene's surface order.
    enum class On { Floor, Light, Panel };
    struct Point {
        const char* name;
        double x, y, z;
        On on;
    };
    const Point points[] = {{"under", 0.25, 0, 0.6, On::Floor},
                            {"panel", 2, 0.5, 0.7, On::Panel},
                            {"light", 0.2, 0.5, 0.4, On::Light},
                            {"outside", 0.7, 0, 0.3, On::Floor},
                            {"edge", 0.4, 0, 0.5, On::Floor}};
    std::ostringstream csv;
    csv.precision(17);
    csv << "name,x,y,z\n";
    for (const Point& p : points) csv << p.name << "," << p.x << "," << p.y << "," << p.z << "\n";
    write_text(dir / "points.csv", csv.str());

    const ToolRun run = run_mbr({"probe", scene, "--points", dir / "points.csv", "--quiet"});
    CAPTURE(run);
    REQUIRE(run.status == 0);
    CHECK(run.err.empty());
    const std::vector<std::string> lines = split(run.out, '\n');
    REQUIRE(lines.size() == 1 + std::size(points));
    CHECK(lines[0] == "name,B_r,B_g,B_b");
    CHECK(count_lines(run.out) == lines.size());  // every row ends with its newline

    // The solver's accuracy target: tolerance 1e-3 (the default) times the scene's radiosity
    // scale, its largest emitted power over the total area (radiosity/solver/solver.h), as an
    // absolute error of each transfer; exactly one transfer (light to floor) reaches the floor.
    // That is 2.5e-3 here, about 1% of the values; the errors are at most 5.2e-4 (MBR_TEST_REPORT=1
    // prints them), and a wrong rho, E, channel order or a mirrored or transposed floor would
    // be off by 0.1 or more.
    const double floor_margin = 1e-3 * emission[2] * light_area / total_area;
    for (size_t i = 0; i < std::size(points); ++i) {
        const Point& p = points[i];
        const std::vector<std::string> fields = split(lines[i + 1], ',');
        CAPTURE(lines[i + 1]);
        REQUIRE(fields.size() == 4);
        CHECK(fields[0] == p.name);
        for (int c = 0; c < 3; ++c) {
            const double B = std::stod(fields[1 + c]);
            CAPTURE(c, B);
            if (p.on == On::Light) {
                // On the light: B = E + rho H with rho = 0, E itself. A constant is reproduced
                // exactly by the B-splines (partition of unity); the CSV keeps 9 significant
                // digits, so the margin is that rounding.
                CHECK(B == Approx(emission[c]).epsilon(1e-8));
            } else if (p.on == On::Panel) {
                // On the black panel, which also faces away: nothing at all.
                CHECK(B == 0.0);
            } else {
                const double expected =
                    reflectance[c] * emission[c] * floor_to_light_form_factor(p.x, p.z);
                mbr::test::report() << "mbr_tool probe " << p.name << " channel " << c << ": B "
                                    << B << ", rho E F " << expected << ", error " << B - expected
                                    << " (margin " << floor_margin << ")\n";
                CHECK(B == Approx(expected).margin(floor_margin));
            }
        }
    }

    // A point ten scene diagonals away from everything, between two good points: status 2, one
    // line naming it, and no half-written CSV.
    std::ostringstream far;
    far.precision(17);
    far << "name,x,y,z\nunder,0.25,0,0.6\nfar," << 2 + 10 * scene_diagonal
        << ",0.5,0.5\nlight,0.2,0.5,0.4\n";
    write_text(dir / "far.csv", far.str());
    const ToolRun far_run = run_mbr({"probe", scene, "--points", dir / "far.csv"});
    CAPTURE(far_run);
    CHECK(far_run.status == 2);
    CHECK(is_one_line(far_run.err));
    CHECK_THAT(far_run.err, Contains("'far'"));
    CHECK_THAT(far_run.err, Contains("far.csv:3:"));
    CHECK(far_run.out.empty());
}

TEST_CASE("mbr_tool: --help and --version print on stdout and exit 0", "[mbr_tool]") {
    const ToolRun help = run_mbr({"--help"});
    CAPTURE(help);
    CHECK(help.status == 0);
    CHECK_THAT(help.out, StartsWith("usage: mbr "));
    CHECK_THAT(help.out, Contains("render"));
    CHECK_THAT(help.out, Contains("probe"));
    CHECK(help.err.empty());

    const ToolRun render_help = run_mbr({"render", "--help"});
    CAPTURE(render_help);
    CHECK(render_help.status == 0);
    CHECK_THAT(render_help.out, StartsWith("usage: mbr render "));
    CHECK_THAT(render_help.out, Contains("--spp"));
    CHECK(render_help.err.empty());

    const ToolRun version = run_mbr({"--version"});
    CAPTURE(version);
    CHECK(version.status == 0);
    CHECK(is_one_line(version.out));
    CHECK_THAT(version.out, StartsWith("mbr "));
    CHECK(version.err.empty());
}

TEST_CASE("mbr_tool: no progress bar with --quiet or without a terminal", "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    const std::vector<std::string> render = {"render", scene, "-o", dir / "out.png", "--spp", "1"};

    // stderr a file, no --quiet: nothing on stderr, in particular no carriage return.
    const ToolRun plain = run_mbr(render);
    CAPTURE(plain);
    REQUIRE(plain.status == 0);
    CHECK(plain.err.find('\r') == std::string::npos);
    CHECK(plain.err.empty());

    // stderr a terminal (a pseudo-terminal in raw mode, so that the terminal adds no '\r' of
    // its own): the bar is drawn without --quiet, which shows this check can see it, and not
    // with --quiet.
    auto on_terminal = [&](const std::vector<std::string>& args) {
        const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
        REQUIRE(master >= 0);
        REQUIRE(::grantpt(master) == 0);
        REQUIRE(::unlockpt(master) == 0);
        const int terminal = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
        REQUIRE(terminal >= 0);
        termios mode;
        REQUIRE(::tcgetattr(terminal, &mode) == 0);
        ::cfmakeraw(&mode);
        REQUIRE(::tcsetattr(terminal, TCSANOW, &mode) == 0);
        const ToolRun run = run_mbr(args, terminal);
        ::close(terminal);
        // The child has ended and the last descriptor of the terminal side is closed: the
        // master returns what was written, then EIO.
        std::string err;
        char buffer[4096];
        for (ssize_t n; (n = ::read(master, buffer, sizeof buffer)) > 0;)
            err.append(buffer, size_t(n));
        ::close(master);
        CAPTURE(run, err);
        CHECK(run.status == 0);
        return err;
    };
    const std::string drawn = on_terminal(render);
    CHECK(drawn.find('\r') != std::string::npos);
    CHECK_THAT(drawn, Contains("shot"));
    std::vector<std::string> quiet = render;
    quiet.push_back("--quiet");
    CHECK(on_terminal(quiet).empty());
}

TEST_CASE("mbr_tool: an output that is one of the inputs is refused, by the file's identity",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    const ToolRun saved = run_mbr({"render", scene, "-o", dir / "a.png", "--spp", "1", "--quiet",
                                   "--save-solution", dir / "s.solution"});
    CAPTURE(saved);
    REQUIRE(saved.status == 0);
    const std::string solution_bytes = read_bytes(dir / "s.solution");
    // The scene under other spellings: through "./", a symbolic link and a hard link.
    fs::create_symlink(scene, dir / "link.png");
    fs::create_hard_link(scene, dir / "hard.png");
    // A scene that includes another: the included file is an input too.
    write_text(dir / "inner.scene", lit_floor_scene);
    write_text(dir / "outer.scene", "include inner.scene\n");
    const std::string dotted = (dir.path() / "." / "lit floor.scene").string();
    struct Case {
        const char* what;
        std::vector<std::string> args;
    };
    const std::vector<std::string> base = {"render", scene, "--spp", "1", "--quiet"};
    const Case cases[] = {
        {"-o the scene", {"-o", scene}},
        {"--hdr the scene", {"-o", dir / "b.png", "--hdr", scene}},
        {"--save-solution the scene", {"-o", dir / "b.png", "--save-solution", scene}},
        {"-o the scene, spelt with ./", {"-o", dotted}},
        {"-o a symbolic link to the scene", {"-o", dir / "link.png"}},
        {"-o a hard link of the scene", {"-o", dir / "hard.png"}},
        {"-o the loaded solution",
         {"-o", dir / "s.solution", "--load-solution", dir / "s.solution"}},
        {"-o the included scene", {"-o", dir / "inner.scene"}},
    };
    for (const Case& c : cases) {
        std::vector<std::string> args = base;
        if (c.args.size() == 2 && std::string(c.what) == "-o the included scene")
            args[1] = dir / "outer.scene";
        args.insert(args.end(), c.args.begin(), c.args.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(c.what, run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains("input"));
        CHECK(run.out.empty());
        CHECK(read_bytes(scene) == lit_floor_scene);
        CHECK(read_bytes(dir / "inner.scene") == lit_floor_scene);
        CHECK(read_bytes(dir / "s.solution") == solution_bytes);
        CHECK_FALSE(fs::exists(dir / "b.png"));
        // (entries_under names the symbolic link by its target, through fs::relative.)
        CHECK(fs::is_symlink(dir / "link.png"));
        CHECK(entries_under(dir.path()) == std::set<std::string>{"lit floor.scene", "a.png",
                                                                 "s.solution", "hard.png",
                                                                 "inner.scene", "outer.scene"});
    }
}

TEST_CASE("mbr_tool: two outputs naming one file are refused, status 2, nothing written",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    write_text(dir / "old.png", "old");
    fs::create_hard_link(dir / "old.png", dir / "old hard.png");
    const std::string same = dir / "same.png";
    const std::string dotted = (dir.path() / "." / "same.png").string();
    const std::string up = (dir.path() / "sub" / ".." / "same.png").string();
    fs::create_directory(dir / "sub");
    struct Case {
        const char* what;
        std::vector<std::string> args;
    };
    const Case cases[] = {
        {"-o and --hdr alike", {"-o", same, "--hdr", same}},
        {"-o and --save-solution alike", {"-o", same, "--save-solution", same}},
        {"--hdr and --save-solution alike",
         {"-o", dir / "x.png", "--hdr", same, "--save-solution", same}},
        {"a new file by two spellings", {"-o", same, "--hdr", dotted}},
        {"a new file through sub/..", {"-o", up, "--save-solution", same}},
        {"an existing file and its hard link",
         {"-o", dir / "old.png", "--hdr", dir / "old hard.png"}},
    };
    for (const Case& c : cases) {
        std::vector<std::string> args = {"render", scene, "--spp", "1", "--quiet"};
        args.insert(args.end(), c.args.begin(), c.args.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(c.what, run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains("same file"));
        CHECK(run.out.empty());
        CHECK(read_bytes(dir / "old.png") == "old");
        CHECK(entries_under(dir.path()) ==
              std::set<std::string>{"lit floor.scene", "old.png", "old hard.png", "sub"});
    }
}

TEST_CASE("mbr_tool: a failing image write leaves no solution written: all outputs or none",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    if (::access("/dev/full", W_OK) != 0) {
        WARN("skipped: no writable /dev/full here");
        return;
    }
    for (const std::vector<std::string>& outputs :
         {std::vector<std::string>{"-o", "/dev/full"},
          std::vector<std::string>{"-o", dir / "x.png", "--hdr", "/dev/full"}}) {
        std::vector<std::string> args = {
            "render", scene, "--spp", "1", "--quiet", "--save-solution", dir / "s.solution"};
        args.insert(args.end(), outputs.begin(), outputs.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(run);
        CHECK(run.status == 1);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains("/dev/full"));
        CHECK(entries_under(dir.path()) == std::set<std::string>{"lit floor.scene"});
    }
}

TEST_CASE("mbr_tool: SIGINT or SIGTERM while outputs are written leaves no temporary file",
          "[mbr_tool]") {
    for (int sig : {SIGTERM, SIGINT}) {
        CAPTURE(sig);
        TempFolder dir;
        const std::string scene = dir / "lit floor.scene";
        write_text(scene, lit_floor_scene);
        // The image goes to a FIFO that nobody reads: the tool blocks there with the other
        // outputs written to their temporaries, which is when the signal comes.
        const std::string fifo = dir / "fifo";
        REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
        mbr::test::StartedProgram started = mbr::test::start_program(
            MBR_TOOL, {"render", scene, "-o", fifo, "--spp", "1", "--quiet", "--hdr", dir / "x.hdr",
                       "--save-solution", dir / "s.solution"});
        auto temporaries = [&] {
            int n = 0;
            for (const std::string& name : entries_under(dir.path()))
                n += name.find(".tmp-") != std::string::npos;
            return n;
        };
        const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        while (temporaries() < 2 && !fs::exists(dir / "x.hdr") &&
               std::chrono::steady_clock::now() < give_up)
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        const int seen = temporaries();
        ::kill(started.pid, sig);
        const ToolRun run = mbr::test::finish_program(started);
        CAPTURE(run, seen);
        CHECK(seen == 2);           // the signal came while the temporaries existed
        CHECK(run.status == -sig);  // ended by the signal, as the shell's 130 or 143 shows
        CHECK(entries_under(dir.path()) == std::set<std::string>{"lit floor.scene", "fifo"});
    }
}

TEST_CASE("mbr_tool: a destination that cannot be written is refused before any work",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    fs::create_directory(dir / "images");
    write_text(dir / "read-only.png", "old");
    REQUIRE(::chmod((dir / "read-only.png").c_str(), 0444) == 0);
    struct Case {
        const char* what;
        std::vector<std::string> args;
        std::string named;
    };
    std::vector<Case> cases = {
        {"a folder as -o", {"-o", dir / "images"}, dir / "images"},
        {"a folder as --save-solution",
         {"-o", dir / "x.png", "--save-solution", dir / "images"},
         dir / "images"},
        {"a missing folder for --hdr",
         {"-o", dir / "x.png", "--hdr", dir / "missing/x.hdr"},
         dir / "missing"},
    };
    // Root may write a read-only file, as the shell's `>` lets it: that case is tested only for
    // an ordinary user (test_output_file.cpp tests it as root too, by changing the user).
    if (::geteuid() != 0)
        cases.push_back({"a read-only file", {"-o", dir / "read-only.png"}, "read-only.png"});
    for (const Case& c : cases) {
        std::vector<std::string> args = {"render", scene, "--spp", "1", "--quiet"};
        args.insert(args.end(), c.args.begin(), c.args.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(c.what, run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains(c.named));
        CHECK(read_bytes(dir / "read-only.png") == "old");
        CHECK(entries_under(dir.path()) ==
              std::set<std::string>{"lit floor.scene", "images", "read-only.png"});
    }
}

TEST_CASE("mbr_tool: messages name an unknown option, a 0/0 unshot share and ranges",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    const std::string out = dir / "out.png";
    struct Case {
        const char* what;
        std::vector<std::string> args;
        std::string named;
    };
    const Case cases[] = {
        {"a single-dash unknown option", {"render", scene, "-o", out, "-x"}, "unknown option -x"},
        {"an unknown option with values",
         {"render", scene, "-o", out, "--lens", "0", "1", "3"},
         "unknown option --lens"},
        {"--camera with too few numbers",
         {"render", scene, "-o", out, "--camera", "0", "1", "3"},
         "--camera needs 9 numbers, got 3"},
        {"--shots beyond its range",
         {"render", scene, "-o", out, "--shots", "10000001"},
         "--shots"},
        {"--max-depth beyond any integer",
         {"render", scene, "-o", out, "--max-depth", "99999999999999999999"},
         "--max-depth"},
    };
    for (const Case& c : cases) {
        const ToolRun run = run_mbr(c.args);
        CAPTURE(c.what, run);
        CHECK(run.status == 2);
        CHECK(is_one_line(run.err));
        CHECK_THAT(run.err, Contains(c.named));
        CHECK_FALSE(fs::exists(out));
    }
    // A light that emits nothing: no power was emitted and none is left, 0 %, not an empty cell.
    std::string dark = lit_floor_scene;
    const std::string emitting = "emission 10 20 30";
    dark.replace(dark.find(emitting), emitting.size(), "emission 0 0 0");
    write_text(dir / "dark.scene", dark);
    const ToolRun run = run_mbr({"render", dir / "dark.scene", "-o", out, "--spp", "1"});
    CAPTURE(run);
    CHECK(run.status == 0);
    CHECK_THAT(run.out, Contains(" 0 % of the power unshot in total"));
}

TEST_CASE("mbr_tool: the summary says why the solve stopped, and the total left unshot",
          "[mbr_tool]") {
    TempFolder dir;
    const std::string scene = dir / "lit floor.scene";
    write_text(scene, lit_floor_scene);
    auto summary = [&](const std::vector<std::string>& more) {
        std::vector<std::string> args = {"render", scene, "-o", dir / "x.png", "--spp", "1"};
        args.insert(args.end(), more.begin(), more.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(run);
        REQUIRE(run.status == 0);
        return run.out;
    };
    // One shot of the light: the floor's reflected power is still unshot, above the threshold.
    const std::string limited = summary({"--max-shots", "1"});
    CHECK_THAT(limited, Contains("shots 1, stopped at the shot limit, "));
    CHECK_THAT(limited, Contains(" % of the power unshot in total (ambient correction applied)"));
    const std::string converged = summary({"--convergence", "0.5"});
    CHECK_THAT(converged,
               Contains(", stopped: largest unshot share below the convergence threshold, "));
    const std::string no_ambient = summary({"--max-shots", "1", "--ambient", "off"});
    CHECK_THAT(no_ambient, Contains("(no ambient correction)"));
    CHECK_THAT(limited, !Contains("converged"));
    // More than 5 % unshot under the gathered ambient correction, more than 1 % under the
    // constant one: a warning says how far its placement goes (without the correction the
    // missing light is plain to see in the figure).
    CHECK_THAT(limited, Contains("% of the power is still unshot; the ambient gather places it "
                                 "with coarse fields (finer on large bright surfaces)"));
    const std::string constant = summary({"--max-shots", "1", "--ambient-rays", "0"});
    CHECK_THAT(constant, Contains("% of the power is still unshot; the ambient correction "
                                  "restores its total, not where it falls"));
    CHECK_THAT(no_ambient, !Contains("is still unshot"));
    CHECK_THAT(summary({"--convergence", "1e-9", "--max-shots", "40"}),
               !Contains("is still unshot"));
    // The light reflects nothing here, so the correction adds nothing and says nothing; with a
    // reflecting light the floor's unshot power comes back to it, and the summary says how.
    CHECK_THAT(limited, !Contains("ambient correction: "));
    std::string reflecting = lit_floor_scene;
    reflecting.replace(reflecting.find("light reflectance 0 0 0"), 23,
                       "light reflectance 0.5 0.5 0.5");
    write_text(scene, reflecting);
    CHECK_THAT(summary({"--max-shots", "1"}),
               Contains(" % of the emitted power added, gathered by "));
    CHECK_THAT(summary({"--max-shots", "1", "--ambient-rays", "0"}),
               Contains(" % of the emitted power added, a constant per surface"));
}

TEST_CASE("mbr_tool: the picture's memory is in the estimate, said before the solve",
          "[mbr_tool]") {
    // An 8192 x 8192 picture holds about 3.5 GiB (radiosity/output/render.h, render_bytes): a
    // budget of 100 MiB (the solve is estimated at about 55 MiB) must refuse it before anything
    // is solved or written, where it used to be accepted and run out of memory at the render.
    TempFolder dir;
    std::string scene = lit_floor_scene;
    const std::string size =
        "size " + std::to_string(camera_width) + " " + std::to_string(camera_height);
    const size_t at = scene.find(size);
    REQUIRE(at != std::string::npos);
    scene.replace(at, size.size(), "size 8192 8192");
    write_text(dir / "big.scene", scene);
    const ToolRun run = run_mbr({"render", dir / "big.scene", "-o", dir / "out.png", "--spp", "1",
                                 "--memory-budget", "100M", "--quiet"});
    CAPTURE(run);
    CHECK(run.status == 2);
    CHECK(is_one_line(run.err));
    CHECK_THAT(run.err, Contains("8192 x 8192"));
    CHECK_THAT(run.err, Contains("image 3.5 GiB"));
    CHECK(entries_under(dir.path()) == std::set<std::string>{"big.scene"});
    // The same scene at its own size fits.
    write_text(dir / "small.scene", lit_floor_scene);
    const ToolRun small = run_mbr({"render", dir / "small.scene", "-o", dir / "out.png", "--spp",
                                   "1", "--memory-budget", "100M", "--quiet"});
    CAPTURE(small);
    CHECK(small.status == 0);
}

TEST_CASE("mbr_tool: an OBJ with defects and no camera renders as it is meant; --strict refuses",
          "[mbr_tool][obj]") {
    TempFolder dir;
    // A closed box room (walls facing in), a lamp 1 cm below the ceiling wound facing up, a
    // material with Kd 1 and a stray statement in the MTL, a zero-area face; the extension in
    // capitals.
    write_text(dir / "room.mtl",
               "newmtl wall\nKd 0.6 0.6 0.6\nv 1 2 3\nnewmtl lamp\nKe 3 3 3\n"
               "newmtl white\nKd 1 1 1\n");
    const std::string obj = dir / "ROOM.OBJ";
    write_text(obj,
               "mtllib room.mtl\nusemtl wall\n"
               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
               "f 1 5 6 2\nf 4 3 7 8\nf 1 2 3 4\nf 5 8 7 6\nf 1 4 8 5\nf 2 6 7 3\n"
               "usemtl white\nf 1 2 2\n"
               "usemtl lamp\nv 0.4 0.99 0.4\nv 0.6 0.99 0.4\nv 0.6 0.99 0.6\nv 0.4 0.99 0.6\n"
               "f 9 12 11 10\n");
    const std::string png = dir / "room.png";
    ToolRun run =
        run_mbr({"render", obj, "-o", png, "--spp", "1", "--size", "48", "36", "--max-shots", "8"});
    CAPTURE(run);
    REQUIRE(run.status == 0);
    CHECK_THAT(run.err, Contains("ROOM.OBJ:24: light 'ROOM.6' faced a surface 0.01 away"));
    CHECK_THAT(run.err, Contains("unknown MTL statement 'v'; the statement is skipped"));
    CHECK_THAT(run.err, Contains("Kd 1 is outside [0, 1)"));
    CHECK_THAT(run.err, Contains("degenerate face"));
    // The floor is lit: a probe below the lamp sees the lamp's light.
    write_text(dir / "p.csv", "name,x,y,z\nfloor,0.5,0,0.5\n");
    ToolRun probe =
        run_mbr({"probe", obj, "--points", dir / "p.csv", "--max-shots", "8", "--quiet"});
    CAPTURE(probe);
    REQUIRE(probe.status == 0);
    const std::vector<std::string> rows = split(probe.out, '\n');
    REQUIRE(rows.size() == 2);
    CHECK(std::stod(split(rows[1], ',')[1]) > 0.1);
    // Strict: the first fault, at its file and line, and no picture.
    fs::remove(png);
    run = run_mbr({"render", obj, "-o", png, "--strict"});
    CHECK(run.status == 2);
    CHECK_THAT(run.err, Contains("room.mtl:3: unknown MTL statement 'v'"));
    CHECK(!fs::exists(png));
}

TEST_CASE("mbr_tool: --light lights a file without Ke; --two-sided-lights makes back faces",
          "[mbr_tool][obj]") {
    TempFolder dir;
    write_text(dir / "m.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl panel\nKd 0.5 0.5 0.5\n");
    const std::string obj = dir / "dark.obj";
    write_text(obj,
               "mtllib m.mtl\no floor\nusemtl floor\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\n"
               "f 1 2 3 4\no panel\nusemtl panel\n"
               "v 0.3 0.5 0.3\nv 0.7 0.5 0.3\nv 0.7 0.5 0.7\nv 0.3 0.5 0.7\nf 5 6 7 8\n");
    write_text(dir / "p.csv", "name,x,y,z\nfloor,0.5,0,0.5\n");
    auto floor_value = [&](const std::vector<std::string>& more, std::string* err = nullptr) {
        std::vector<std::string> args = {"probe", obj, "--points", dir / "p.csv", "--quiet"};
        args.insert(args.end(), more.begin(), more.end());
        const ToolRun run = run_mbr(args);
        CAPTURE(run);
        REQUIRE(run.status == 0);
        if (err) *err = run.err;
        return std::stod(split(split(run.out, '\n')[1], ',')[1]);
    };
    std::string err;
    CHECK(floor_value({}, &err) == 0);
    CHECK_THAT(err, Contains("nothing in the scene emits light"));
    CHECK_THAT(err, Contains("--light NAME"));
    // The panel as a light with E = 10 (by material), facing down onto the floor.
    const double lit = floor_value({"--light", "panel=10"}, &err);
    CHECK_THAT(err, Contains("--light panel: 1 surface (material) emit E = 10"));
    CHECK(lit > 0.5);
    // Without E: the default emission, said.
    CHECK(floor_value({"--light", "panel"}, &err) > 0);
    CHECK_THAT(err, Contains("--light panel: 1 surface (material) emit E = "));
    // Facing up (wound the other way), the panel lights the floor only when two-sided.
    write_text(obj,
               "mtllib m.mtl\no floor\nusemtl floor\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\n"
               "f 1 2 3 4\no panel\nusemtl panel\n"
               "v 0.3 0.5 0.3\nv 0.7 0.5 0.3\nv 0.7 0.5 0.7\nv 0.3 0.5 0.7\nf 8 7 6 5\n");
    CHECK(floor_value({"--light", "panel=10"}) == 0);
    CHECK(floor_value({"--light", "panel=10", "--two-sided-lights"}) == Approx(lit).epsilon(0.01));
    const ToolRun bad = run_mbr({"probe", obj, "--points", dir / "p.csv", "--light", "nothing"});
    CHECK(bad.status == 2);
    CHECK_THAT(bad.err, Contains("has no material and no surface of that name"));
}
