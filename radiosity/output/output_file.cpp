// radiosity/output/output_file.cpp - all-or-nothing file output (rules in output_file.h). Written
// on the POSIX calls rather than iostreams or stdio so that every failure keeps its errno: stdio
// forgets a failed write once its buffer is dropped, and stb's own writer checks nothing.
#include "radiosity/output/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <utility>

#include "math/check.h"

namespace mbr {

OutputError::OutputError(std::string path, const std::string& message)
    : std::runtime_error(path.empty() ? message : path + ": " + message), path_(std::move(path)) {}

namespace {

std::string reason(int err) {
    return std::strerror(err);
}

// The folder holding `path` ("." for a bare file name).
std::string folder_of(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return ".";
    return slash == 0 ? "/" : path.substr(0, slash);
}

std::string name_of(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

// How one path is written.
enum class Method {
    Replace,  // a temporary in the target's folder, renamed over it
    Direct,   // an existing device, FIFO, socket: opened and written in place
    Stream    // the file behind our own stdout or stderr: written to that descriptor
};

struct Destination {
    std::string path;  // as given, for messages
    Method method = Method::Replace;
    std::string target;  // the file written: symbolic links resolved for Replace
    mode_t mode = 0644;  // Replace: permissions of the new file
    int fd = -1;         // Stream: STDOUT_FILENO or STDERR_FILENO
};

// Permissions of a new file: 0666 less the process's umask, as open(2) would give it. Read from
// /proc/self/status, because umask() can only read it by changing it for a moment in every
// thread.
mode_t new_file_mode() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("Umask:", 0) == 0)
            return 0666 & ~static_cast<mode_t>(std::strtoul(line.c_str() + 6, nullptr, 8));
    // DESIGN: a kernel older than 4.7 does not report the umask; take the usual 022 then.
    return 0644;
}

// The end of a dangling chain of symbolic links starting at `path`: the file to create.
std::string dangling_target(const std::string& path) {
    std::string current = path;
    for (int hops = 0; hops < 40; ++hops) {  // 40: the kernel's own limit (ELOOP)
        std::vector<char> buffer(PATH_MAX);
        const ssize_t n = ::readlink(current.c_str(), buffer.data(), buffer.size());
        if (n < 0) throw OutputError(path, "cannot write: " + reason(errno));
        if (size_t(n) == buffer.size())
            throw OutputError(path, "cannot write: " + reason(ENAMETOOLONG));
        std::string next(buffer.data(), size_t(n));
        if (next.empty()) throw OutputError(path, "cannot write: the symbolic link is empty");
        if (next[0] != '/') next = folder_of(current) + "/" + next;
        struct stat st;
        if (::lstat(next.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return next;
        current = next;
    }
    throw OutputError(path, "cannot write: " + reason(ELOOP));
}

Destination resolve(const std::string& path) {
    if (path.empty()) throw OutputError("", "the output path is empty");
    Destination d;
    d.path = path;
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) {  // follows symbolic links
        if (S_ISDIR(st.st_mode)) throw OutputError(path, "cannot write: is a directory");
        // Our own stdout or stderr (/dev/stdout, or the file it is redirected to): replacing
        // that file would leave the descriptor on the old one, so write the descriptor.
        for (int fd : {STDOUT_FILENO, STDERR_FILENO}) {
            struct stat s;
            if (::fstat(fd, &s) == 0 && s.st_dev == st.st_dev && s.st_ino == st.st_ino) {
                d.method = Method::Stream;
                d.fd = fd;
                return d;
            }
        }
        if (!S_ISREG(st.st_mode)) {
            d.method = Method::Direct;
            d.target = path;
            return d;
        }
        char* real = ::realpath(path.c_str(), nullptr);
        if (!real) throw OutputError(path, "cannot write: " + reason(errno));
        d.target = real;
        std::free(real);
        d.mode = st.st_mode & 07777;
        return d;
    }
    const int err = errno;
    if (err != ENOENT) throw OutputError(path, "cannot write: " + reason(err));
    if (path.back() == '/')
        throw OutputError(path, "cannot write: a file name cannot end with '/'");
    struct stat link;
    const bool dangling = ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode);
    d.target = dangling ? dangling_target(path) : path;
    const std::string folder = folder_of(d.target);
    const std::string via = dangling ? " (the symbolic link points to '" + d.target + "')" : "";
    struct stat fs;
    if (::stat(folder.c_str(), &fs) != 0) {
        const int e = errno;
        if (e == ENOENT)
            throw OutputError(path,
                              "cannot write: the folder '" + folder + "' does not exist" + via);
        throw OutputError(path, "cannot write: folder '" + folder + "': " + reason(e) + via);
    }
    if (!S_ISDIR(fs.st_mode))
        throw OutputError(path, "cannot write: '" + folder + "' is not a folder" + via);
    d.mode = new_file_mode();
    return d;
}

// Writes all of `bytes` to `fd`; false with errno set on failure.
bool write_all(int fd, std::string_view bytes) {
    const char* p = bytes.data();
    size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        p += n;
        left -= size_t(n);
    }
    return true;
}

// Writes the bytes to a new temporary file beside d.target and returns its name; on failure the
// temporary is removed and OutputError thrown.
std::string write_temporary(const Destination& d, std::string_view bytes) {
    const std::string folder = folder_of(d.target);
    // A hidden name, so that a glob over the folder does not pick up a file being written; the
    // stem is cut so that the name stays below NAME_MAX (255).
    std::string name = folder + "/." + name_of(d.target).substr(0, 200) + ".tmp-XXXXXX";
    const int fd = ::mkstemp(name.data());
    if (fd < 0)
        throw OutputError(d.path, "cannot write in folder '" + folder + "': " + reason(errno));
    auto fail = [&](bool close_fd) {
        const int e = errno;
        if (close_fd) ::close(fd);
        ::unlink(name.c_str());
        throw OutputError(d.path, "cannot write: " + reason(e));
    };
    if (::fchmod(fd, d.mode) != 0) fail(true);  // mkstemp makes 0600
    if (!write_all(fd, bytes)) fail(true);
    // DESIGN: fsync before the rename, so that a crash soon after cannot leave the new name on
    // an empty file (ext4 and XFS may commit the rename before the data). It also surfaces
    // write errors that network file systems report only here. Costs milliseconds per file.
    if (::fsync(fd) != 0) fail(true);
    if (::close(fd) != 0) fail(false);  // Linux releases the descriptor even when close fails
    return name;
}

void write_direct(const Destination& d, std::string_view bytes) {
    const int fd = ::open(d.target.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) throw OutputError(d.path, "cannot write: " + reason(errno));
    if (!write_all(fd, bytes)) {
        const int e = errno;
        ::close(fd);
        throw OutputError(d.path, "cannot write: " + reason(e));
    }
    if (::close(fd) != 0) throw OutputError(d.path, "cannot write: " + reason(errno));
}

void write_stream(const Destination& d, std::string_view bytes) {
    // What the program printed before must come first in the stream.
    if (d.fd == STDOUT_FILENO) {
        std::cout.flush();
        std::fflush(stdout);
    } else {
        std::cerr.flush();
        std::fflush(stderr);
    }
    if (!write_all(d.fd, bytes)) throw OutputError(d.path, "cannot write: " + reason(errno));
}

void write_all_files(const std::vector<std::pair<std::string, std::string_view>>& files) {
    std::vector<Destination> destinations;
    for (const auto& [path, bytes] : files) destinations.push_back(resolve(path));
    std::vector<std::string> temporaries(files.size());  // empty unless Replace
    auto remove_temporaries = [&] {
        for (std::string& name : temporaries)
            if (!name.empty()) ::unlink(name.c_str());
    };
    try {
        for (size_t i = 0; i < files.size(); ++i)
            if (destinations[i].method == Method::Replace)
                temporaries[i] = write_temporary(destinations[i], files[i].second);
        // Only now is any target touched.
        for (size_t i = 0; i < files.size(); ++i) {
            const Destination& d = destinations[i];
            if (d.method == Method::Replace) {
                if (::rename(temporaries[i].c_str(), d.target.c_str()) != 0)
                    throw OutputError(d.path, "cannot replace the file: " + reason(errno));
                temporaries[i].clear();
            }
        }
        // Devices and FIFOs last: they cannot be taken back.
        for (size_t i = 0; i < files.size(); ++i) {
            const Destination& d = destinations[i];
            if (d.method == Method::Direct) write_direct(d, files[i].second);
            if (d.method == Method::Stream) write_stream(d, files[i].second);
        }
    } catch (...) {
        remove_temporaries();
        throw;
    }
}

}  // namespace

void write_file(const std::string& path, std::string_view bytes) {
    write_all_files({{path, bytes}});
}

void write_file(const std::string& path, const std::function<void(std::ostream&)>& write) {
    std::ostringstream os;
    write(os);
    MBR_CHECK_MSG(!os.fail(), "the writer of " << path << " left its stream failed");
    const std::string bytes = os.str();
    write_all_files({{path, bytes}});
}

void write_files(const std::vector<OutputFile>& files) {
    std::vector<std::pair<std::string, std::string_view>> views;
    for (const OutputFile& f : files) views.push_back({f.path, f.bytes});
    write_all_files(views);
}

void check_output_path(const std::string& path) {
    const Destination d = resolve(path);
    if (d.method != Method::Replace) return;
    const std::string folder = folder_of(d.target);
    // The effective user's permission, and EROFS on a read-only file system, even for root.
    if (::faccessat(AT_FDCWD, folder.c_str(), W_OK, AT_EACCESS) != 0)
        throw OutputError(path, "cannot write in folder '" + folder + "': " + reason(errno));
}

bool is_standard_output(const std::string& path) {
    struct stat st, out;
    return ::stat(path.c_str(), &st) == 0 && ::fstat(STDOUT_FILENO, &out) == 0 &&
           st.st_dev == out.st_dev && st.st_ino == out.st_ino;
}

}  // namespace mbr
