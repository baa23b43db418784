// test/test_output_file.cpp - radiosity/output/output_file.h: a file is replaced only by a complete
// write; symbolic links, devices, FIFOs and stdout are written as what they are; directories,
// missing and read-only folders and full disks are refused with the system's reason, leaving no
// temporary file and the old content intact. The read-only folder and the full disk need a small
// tmpfs mounted in a private temporary folder; where the test may not mount one (not root, or a
// container without CAP_SYS_ADMIN) those cases are skipped with a warning.
#include <fcntl.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "radiosity/output/image.h"
#include "radiosity/output/output_file.h"
#include "test/file_bytes.h"

using namespace mbr;
namespace fs = std::filesystem;

namespace {

// A fresh folder under the system's temporary folder, removed (and unmounted) at the end.
class TempDir {
public:
    TempDir() {
        std::string pattern = (fs::temp_directory_path() / "mbr_test_output_XXXXXX").string();
        REQUIRE(::mkdtemp(pattern.data()) != nullptr);
        path_ = pattern;
    }
    ~TempDir() {
        for (auto it = mounts_.rbegin(); it != mounts_.rend(); ++it)
            ::umount2(it->c_str(), MNT_DETACH);
        std::error_code ec;
        fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ec);
        fs::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string operator/(const std::string& name) const { return (path_ / name).string(); }
    const fs::path& path() const { return path_; }

    // Mounts a tmpfs of `kib` KiB on the new folder `name`; false (errno kept) when not allowed.
    bool mount_tmpfs(const std::string& name, int kib) {
        const std::string where = *this / name;
        fs::create_directory(where);
        const std::string options = "size=" + std::to_string(kib) + "k,mode=0755";
        if (::mount("mbr_test", where.c_str(), "tmpfs", MS_NOSUID | MS_NODEV | MS_NOEXEC,
                    options.c_str()) != 0)
            return false;
        mounts_.push_back(where);
        return true;
    }

private:
    fs::path path_;
    std::vector<std::string> mounts_;
};

using test::read_bytes;

// The names in a folder: after a failed write, no temporary may be among them.
std::set<std::string> names_in(const std::string& folder) {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
        names.insert(entry.path().filename().string());
    return names;
}

// n bytes of a fixed pattern that includes NUL and 0xff, so that text-mode mangling would show.
std::string pattern_bytes(size_t n) {
    std::string s(n, '\0');
    for (size_t i = 0; i < n; ++i) s[i] = static_cast<char>((i * 131 + i / 7) & 0xff);
    return s;
}

// The message of the OutputError thrown by f, or "" when it throws none.
template <class F>
std::string output_error(F f) {
    try {
        f();
    } catch (const OutputError& e) {
        return e.what();
    }
    return "";
}

mode_t mode_of(const std::string& path) {
    struct stat st;
    REQUIRE(::lstat(path.c_str(), &st) == 0);
    return st.st_mode;
}

}  // namespace

TEST_CASE("output_file: a new file holds exactly the bytes; a regular file is replaced whole",
          "[output_file]") {
    TempDir dir;
    const std::string path = dir / "a.bin";
    const std::string first = pattern_bytes(100000), second = pattern_bytes(777);
    write_file(path, first);
    CHECK(read_bytes(path) == first);
    // The replaced file keeps its permissions (mkstemp alone would make it 0600).
    REQUIRE(::chmod(path.c_str(), 0640) == 0);
    write_file(path, second);
    CHECK(read_bytes(path) == second);  // shorter: nothing of the old content is left behind
    CHECK((mode_of(path) & 07777) == 0640);
    // The stream form gives the same bytes.
    write_file(path, [&](std::ostream& os) { os << first; });
    CHECK(read_bytes(path) == first);
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"a.bin"});
}

TEST_CASE("output_file: a writer that throws touches no file", "[output_file]") {
    TempDir dir;
    const std::string path = dir / "table.csv";
    write_file(path, std::string("old\n"));
    CHECK_THROWS_AS(write_file(path,
                               [](std::ostream& os) {
                                   os << "half a table";
                                   throw std::runtime_error("the producer failed");
                               }),
                    std::runtime_error);
    CHECK(read_bytes(path) == "old\n");
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"table.csv"});
}

TEST_CASE("output_file: a symbolic link stays a link and its target is replaced", "[output_file]") {
    TempDir dir;
    fs::create_directory(dir / "sub");
    const std::string target = dir / "sub/target.png", link = dir / "link.png";
    write_file(target, std::string("old"));
    fs::create_symlink("sub/target.png", link);  // relative, resolved from the link's folder
    write_file(link, std::string("new content"));
    CHECK(S_ISLNK(mode_of(link)));
    CHECK(fs::read_symlink(link) == "sub/target.png");
    CHECK(read_bytes(target) == "new content");

    // A chain of two links ends at the same file.
    const std::string link2 = dir / "link2.png";
    fs::create_symlink("link.png", link2);
    write_file(link2, std::string("third"));
    CHECK(S_ISLNK(mode_of(link2)));
    CHECK(S_ISLNK(mode_of(link)));
    CHECK(read_bytes(target) == "third");

    // A dangling link: its target is created, the link is kept.
    const std::string dangling = dir / "dangling.png";
    fs::create_symlink("sub/created.png", dangling);
    write_file(dangling, std::string("created"));
    CHECK(S_ISLNK(mode_of(dangling)));
    CHECK(read_bytes(dir / "sub/created.png") == "created");

    // A dangling link into a missing folder is refused, naming the folder.
    const std::string nowhere = dir / "nowhere.png";
    fs::create_symlink("missing/x.png", nowhere);
    const std::string message = output_error([&] { write_file(nowhere, std::string("x")); });
    CHECK_THAT(message, Catch::Contains("does not exist"));
    CHECK_THAT(message, Catch::Contains("missing"));
    CHECK(names_in(dir / "sub") == std::set<std::string>{"target.png", "created.png"});
}

TEST_CASE("output_file: a FIFO is written in place, not replaced", "[output_file]") {
    TempDir dir;
    const std::string fifo = dir / "pipe";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    // A descriptor open for writing holds the FIFO open, so that the reader's open returns at
    // once and its reads end only when this one is closed: the test cannot hang, whatever
    // write_file does with the path.
    const int holder = ::open(fifo.c_str(), O_RDWR);
    REQUIRE(holder >= 0);
    const int reading = ::open(fifo.c_str(), O_RDONLY);
    REQUIRE(reading >= 0);
    std::string received;
    std::thread reader([&] {
        char buffer[4096];
        for (ssize_t n; (n = ::read(reading, buffer, sizeof buffer)) > 0;)
            received.append(buffer, n);
    });
    const std::string bytes = pattern_bytes(300000);  // more than a pipe holds (64 KiB)
    const std::string message = output_error([&] { write_file(fifo, bytes); });
    ::close(holder);
    reader.join();
    ::close(reading);
    CHECK(message == "");
    CHECK(received == bytes);
    CHECK(S_ISFIFO(mode_of(fifo)));
}

TEST_CASE("output_file: stdout is written through its descriptor, whatever it is",
          "[output_file]") {
    TempDir dir;
    const std::string bytes = pattern_bytes(20000);  // fits in a pipe: no reader thread needed
    std::cout.flush();
    std::fflush(stdout);
    const int saved = ::dup(STDOUT_FILENO);
    REQUIRE(saved >= 0);
    auto restore = [&] {
        std::fflush(stdout);
        ::dup2(saved, STDOUT_FILENO);
    };

    // Stdout on a regular file: the file is written, not replaced (same inode after).
    const std::string file = dir / "captured.png";
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    REQUIRE(fd >= 0);
    struct stat before;
    REQUIRE(::fstat(fd, &before) == 0);
    ::dup2(fd, STDOUT_FILENO);
    ::close(fd);
    bool named = false;
    std::string message;
    try {
        named = is_standard_output("/dev/stdout") && is_standard_output(file);
        write_file("/dev/stdout", bytes);
    } catch (const OutputError& e) {
        message = e.what();
    }
    restore();
    CHECK(message == "");
    CHECK(named);
    CHECK_FALSE(is_standard_output(file));  // stdout is back on the test's own
    struct stat after;
    REQUIRE(::stat(file.c_str(), &after) == 0);
    CHECK(after.st_ino == before.st_ino);
    CHECK(read_bytes(file) == bytes);
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"captured.png"});

    // Stdout on a pipe.
    int pipe_fds[2];
    REQUIRE(::pipe(pipe_fds) == 0);
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::close(pipe_fds[1]);
    message.clear();
    try {
        write_file("/dev/stdout", bytes);
    } catch (const OutputError& e) {
        message = e.what();
    }
    restore();  // the last write end closes: the reader below sees the end
    ::close(saved);
    std::string received;
    char buffer[4096];
    for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof buffer)) > 0;)
        received.append(buffer, n);
    ::close(pipe_fds[0]);
    CHECK(message == "");
    CHECK(received == bytes);
    struct stat link;
    REQUIRE(::lstat("/dev/stdout", &link) == 0);
    CHECK(S_ISLNK(link.st_mode));  // /dev/stdout itself is untouched
}

TEST_CASE("output_file: a character device is written in place and its errors reported",
          "[output_file]") {
    TempDir dir;
    // Our own nodes for /dev/full (1, 7) and /dev/null (1, 3), so that a broken write_file could
    // only ever replace these copies.
    const std::string full = dir / "full", null = dir / "null";
    if (::mknod(full.c_str(), S_IFCHR | 0666, makedev(1, 7)) != 0 ||
        ::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0) {
        WARN("skipped: cannot create device nodes here (" << std::strerror(errno) << ")");
        return;
    }
    const int probe = ::open(null.c_str(), O_WRONLY);
    if (probe < 0) {
        WARN("skipped: the temporary folder does not allow devices (" << std::strerror(errno)
                                                                      << ")");
        return;
    }
    ::close(probe);
    write_file(null, pattern_bytes(1000));
    CHECK(S_ISCHR(mode_of(null)));
    const std::string message = output_error([&] { write_file(full, pattern_bytes(1000)); });
    CHECK(message == full + ": cannot write: " + std::strerror(ENOSPC));
    CHECK(S_ISCHR(mode_of(full)));
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"full", "null"});
}

TEST_CASE("output_file: a directory, a missing folder and a file used as a folder are refused",
          "[output_file]") {
    TempDir dir;
    fs::create_directory(dir / "images");
    std::string message = output_error([&] { write_file(dir / "images", std::string("x")); });
    CHECK(message == dir / "images" + ": cannot write: is a directory");
    CHECK(fs::is_directory(dir / "images"));
    CHECK(output_error([&] { check_output_path(dir / "images"); }) == message);

    const std::string missing = dir / "missing/x.png";
    message = output_error([&] { write_file(missing, std::string("x")); });
    CHECK(message ==
          missing + ": cannot write: the folder '" + dir / "missing" + "' does not exist");
    CHECK(output_error([&] { check_output_path(missing); }) == message);
    CHECK_FALSE(fs::exists(dir / "missing"));

    write_file(dir / "plain", std::string("x"));
    message = output_error([&] { write_file(dir / "plain/x.png", std::string("x")); });
    CHECK(message == dir / "plain/x.png" + ": cannot write: " + std::strerror(ENOTDIR));
    CHECK(output_error([&] { write_file("", std::string("x")); }) == "the output path is empty");
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"images", "plain"});
    CHECK(names_in(dir / "images").empty());
}

TEST_CASE("output_file: a read-only folder refuses the write and keeps the old file",
          "[output_file]") {
    TempDir dir;
    std::string folder;
    int expected = 0;
    if (::geteuid() != 0) {
        // Permissions stop an ordinary user.
        folder = dir / "locked";
        fs::create_directory(folder);
        write_file(folder + "/old.png", std::string("old"));
        REQUIRE(::chmod(folder.c_str(), 0555) == 0);
        expected = EACCES;
    } else {
        // Root passes permission checks: a tmpfs remounted read-only stops it.
        if (!dir.mount_tmpfs("ro", 64)) {
            WARN("skipped: cannot mount a tmpfs here (" << std::strerror(errno) << ")");
            return;
        }
        folder = dir / "ro";
        write_file(folder + "/old.png", std::string("old"));
        REQUIRE(::mount("mbr_test", folder.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, nullptr) == 0);
        expected = EROFS;
    }
    const std::string target = folder + "/old.png";
    const std::string reason = std::strerror(expected);
    const std::string message = output_error([&] { write_file(target, std::string("new")); });
    CHECK(message == target + ": cannot write in folder '" + folder + "': " + reason);
    CHECK(output_error([&] { check_output_path(folder + "/new.png"); }) ==
          folder + "/new.png: cannot write in folder '" + folder + "': " + reason);
    CHECK(read_bytes(target) == "old");
    CHECK(names_in(folder) == std::set<std::string>{"old.png"});
}

TEST_CASE("output_file: a full disk gives an error, no temporary file and the old content",
          "[output_file]") {
    TempDir dir;
    if (!dir.mount_tmpfs("small", 64)) {
        WARN("skipped: cannot mount a 64 KiB tmpfs here (" << std::strerror(errno) << ")");
        return;
    }
    const std::string folder = dir / "small", target = folder + "/ex.png";
    const std::string old = pattern_bytes(5000);
    write_file(target, old);
    const std::string full_reason = std::strerror(ENOSPC);

    // Twice the size of the disk: the temporary fills it up.
    std::string message = output_error([&] { write_file(target, pattern_bytes(128 * 1024)); });
    CHECK(message == target + ": cannot write: " + full_reason);
    CHECK(read_bytes(target) == old);
    CHECK(names_in(folder) == std::set<std::string>{"ex.png"});

    // A PNG that does not fit, through write_png: an OutputError, not a cut-off image.
    Image noise(256, 256);
    std::mt19937 rng(7);  // seeded: the same image every run
    std::uniform_real_distribution<double> uniform(0, 1);
    for (Rgb& p : noise.pixels) p = {uniform(rng), uniform(rng), uniform(rng)};
    REQUIRE(encode_png(noise).size() > 64 * 1024);  // noise does not compress below the disk
    message = output_error([&] { write_png(folder + "/noise.png", noise); });
    CHECK(message == folder + "/noise.png: cannot write: " + full_reason);
    CHECK(names_in(folder) == std::set<std::string>{"ex.png"});

    // Two files of 40 KiB each: the second temporary does not fit, so neither file is created
    // nor replaced, although the first alone would have fitted.
    message = output_error([&] {
        write_files(
            {{target, pattern_bytes(40 * 1024)}, {folder + "/b.png", pattern_bytes(40 * 1024)}});
    });
    CHECK(message == folder + "/b.png: cannot write: " + full_reason);
    CHECK(read_bytes(target) == old);
    CHECK(names_in(folder) == std::set<std::string>{"ex.png"});
}

TEST_CASE("output_file: a read-only file and a sticky folder's foreign file are refused first",
          "[output_file]") {
    TempDir dir;
    // As root, permissions stop nobody: the checks run as the user "nobody" (uid 65534) for a
    // moment then, with files that root owns. An ordinary user tests the read-only file only:
    // it cannot make a file that another user owns.
    const bool root = ::geteuid() == 0;
    REQUIRE(::chmod(dir.path().c_str(), 0777) == 0);
    const std::string read_only = dir / "read-only.png";
    write_file(read_only, std::string("old"));
    REQUIRE(::chmod(read_only.c_str(), 0444) == 0);
    const std::string sticky = dir / "sticky";
    fs::create_directory(sticky);
    REQUIRE(::chmod(sticky.c_str(), 01777) == 0);
    const std::string foreign = sticky + "/foreign.png";
    write_file(foreign, std::string("old"));
    REQUIRE(::chmod(foreign.c_str(), 0666) == 0);  // writable, but not replaceable by others

    if (root && ::seteuid(65534) != 0) {
        WARN("skipped: cannot act as another user (" << std::strerror(errno) << ")");
        return;
    }
    std::string read_only_message, write_message, foreign_message, own_message;
    read_only_message = output_error([&] { check_output_path(read_only); });
    write_message = output_error([&] { write_file(read_only, std::string("new")); });
    if (root) {
        foreign_message = output_error([&] { check_output_path(foreign); });
        // A new file in the sticky folder is fine.
        own_message = output_error([&] { check_output_path(sticky + "/new.png"); });
        REQUIRE(::seteuid(0) == 0);
    }
    const std::string denied = std::strerror(EACCES);
    CHECK(read_only_message == read_only + ": cannot write: " + denied);
    CHECK(write_message == read_only_message);
    CHECK(read_bytes(read_only) == "old");
    if (root) {
        CHECK_THAT(
            foreign_message,
            Catch::StartsWith(foreign + ": cannot replace the file: " + std::strerror(EPERM)));
        CHECK(own_message == "");
    }
    CHECK(read_bytes(foreign) == "old");
    CHECK(names_in(dir.path().string()) == std::set<std::string>{"read-only.png", "sticky"});
    CHECK(names_in(sticky) == std::set<std::string>{"foreign.png"});
}
