// radiosity/output/output_file.cpp - all-or-nothing file output (rules in output_file.h). Written
// on the POSIX calls rather than iostreams or stdio so that every failure keeps its errno: stdio
// forgets a failed write once its buffer is dropped, and stb's own writer checks nothing.
#include "radiosity/output/output_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <mutex>
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
    bool exists = false;  // the path names an existing file (st below is its stat)
    struct stat st {};
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
    struct stat& st = d.st;
    if (::stat(path.c_str(), &st) == 0) {  // follows symbolic links
        if (S_ISDIR(st.st_mode)) throw OutputError(path, "cannot write: is a directory");
        d.exists = true;
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

// The temporaries that exist now, for the signal handler below: a fixed table, because a
// handler may not allocate or lock. A slot is Registered from just before mkstemp fills in its
// name until the temporary is renamed or removed; the handler unlinks every Registered name (one
// not created yet, or already renamed, is simply not found).
enum SlotState : int { Free, Claimed, Registered };
struct TemporarySlot {
    std::atomic<int> state{Free};
    char name[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "the handler reads the slots' states");
// DESIGN: 32 temporaries at once (write_files of one program writes at most a few); beyond
// that, or for a name longer than PATH_MAX, a temporary is made without the table and a signal
// may leave it behind.
constexpr int temporary_slots = 32;
TemporarySlot slots[temporary_slots];

// The signals that end a program by default while it writes: on one of them the temporaries
// are removed, then the signal is raised again with its default action, so that the program
// ends as it would have (the shell's status 128 + N: 130 for SIGINT, 143 for SIGTERM).
constexpr int cleanup_signals[] = {SIGHUP, SIGINT, SIGTERM, SIGPIPE, SIGXFSZ};

extern "C" void remove_temporaries_on_signal(int sig) {
    for (TemporarySlot& slot : slots)
        if (slot.state.load(std::memory_order_acquire) == Registered) ::unlink(slot.name);
    // SA_RESETHAND restored the default action and SA_NODEFER leaves the signal unblocked:
    // raise() ends the process here.
    ::raise(sig);
}

// Installs the handler for each of cleanup_signals whose action is still the default (a signal
// the caller ignores or handles itself is left alone). Once per process.
void install_signal_handlers() {
    static std::once_flag once;
    std::call_once(once, [] {
        for (int sig : cleanup_signals) {
            struct sigaction old {};
            if (::sigaction(sig, nullptr, &old) != 0) continue;
            if ((old.sa_flags & SA_SIGINFO) || old.sa_handler != SIG_DFL) continue;
            struct sigaction action {};
            action.sa_handler = remove_temporaries_on_signal;
            sigemptyset(&action.sa_mask);
            action.sa_flags = SA_RESETHAND | SA_NODEFER;
            ::sigaction(sig, &action, nullptr);
        }
    });
}

// A temporary file: created from a mkstemp template, registered for the signal handler while it
// exists. remove() or renamed() ends the registration.
class Temporary {
public:
    // Creates the file; returns its descriptor, or -1 with errno set.
    int create(const std::string& pattern) {
        install_signal_handlers();
        if (pattern.size() < PATH_MAX)
            for (TemporarySlot& s : slots) {
                int expected = Free;
                if (s.state.compare_exchange_strong(expected, Claimed)) {
                    slot_ = &s;
                    break;
                }
            }
        if (!slot_) {
            name_ = pattern;
            return ::mkstemp(name_.data());
        }
        std::memcpy(slot_->name, pattern.c_str(), pattern.size() + 1);
        slot_->state.store(Registered, std::memory_order_release);
        const int fd = ::mkstemp(slot_->name);
        const int e = errno;
        name_ = slot_->name;
        if (fd < 0) release();
        errno = e;
        return fd;
    }
    const std::string& name() const { return name_; }
    // Unlinks the file (when there is one) and ends the registration.
    void remove() {
        if (!name_.empty()) ::unlink(name_.c_str());
        release();
        name_.clear();
    }
    // The file has been renamed: only the registration ends.
    void renamed() {
        release();
        name_.clear();
    }

private:
    void release() {
        if (slot_) slot_->state.store(Free, std::memory_order_release);
        slot_ = nullptr;
    }
    TemporarySlot* slot_ = nullptr;
    std::string name_;
};

// Writes the bytes to a new temporary file beside d.target (registered in `temporary`); on
// failure the temporary is removed and OutputError thrown.
void write_temporary(const Destination& d, std::string_view bytes, Temporary& temporary) {
    const std::string folder = folder_of(d.target);
    // A hidden name, so that a glob over the folder does not pick up a file being written; the
    // stem is cut so that the name stays below NAME_MAX (255).
    const std::string pattern = folder + "/." + name_of(d.target).substr(0, 200) + ".tmp-XXXXXX";
    const int fd = temporary.create(pattern);
    if (fd < 0)
        throw OutputError(d.path, "cannot write in folder '" + folder + "': " + reason(errno));
    auto fail = [&](bool close_fd) {
        const int e = errno;
        if (close_fd) ::close(fd);
        temporary.remove();
        throw OutputError(d.path, "cannot write: " + reason(e));
    };
    if (::fchmod(fd, d.mode) != 0) fail(true);  // mkstemp makes 0600
    if (!write_all(fd, bytes)) fail(true);
    // DESIGN: fsync before the rename, so that a crash soon after cannot leave the new name on
    // an empty file (ext4 and XFS may commit the rename before the data). It also surfaces
    // write errors that network file systems report only here. Costs milliseconds per file.
    if (::fsync(fd) != 0) fail(true);
    if (::close(fd) != 0) fail(false);  // Linux releases the descriptor even when close fails
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

// Refuses what the write would fail on, before any file is touched: a folder the temporary
// cannot be made in, an existing file the user may not write (as the shell's `>` refuses it:
// root may), a file in a sticky folder that only its owner may replace.
void check_destination(const Destination& d) {
    if (d.method == Method::Stream) return;
    if (d.method == Method::Direct) {
        if (::faccessat(AT_FDCWD, d.target.c_str(), W_OK, AT_EACCESS) != 0)
            throw OutputError(d.path, "cannot write: " + reason(errno));
        return;
    }
    const std::string folder = folder_of(d.target);
    // The effective user's permission, and EROFS on a read-only file system, even for root.
    if (::faccessat(AT_FDCWD, folder.c_str(), W_OK, AT_EACCESS) != 0)
        throw OutputError(d.path, "cannot write in folder '" + folder + "': " + reason(errno));
    if (!d.exists) return;
    if (::faccessat(AT_FDCWD, d.target.c_str(), W_OK, AT_EACCESS) != 0)
        throw OutputError(d.path, "cannot write: " + reason(errno));
    // In a sticky folder (such as /tmp) only the file's owner, the folder's owner or root may
    // replace the file (rename(2), EPERM).
    struct stat fs;
    const uid_t user = ::geteuid();
    if (::stat(folder.c_str(), &fs) == 0 && (fs.st_mode & S_ISVTX) && user != 0 &&
        d.st.st_uid != user && fs.st_uid != user)
        throw OutputError(d.path, "cannot replace the file: " + reason(EPERM) +
                                      " (the folder is sticky and the file another user's)");
}

// What a destination is, to tell whether two paths name one file: the device and inode of an
// existing file, else the path made absolute through its folder's real path.
struct Identity {
    bool exists = false;
    dev_t dev = 0;
    ino_t ino = 0;
    std::string normal;
    bool operator==(const Identity& o) const {
        return exists == o.exists && (exists ? dev == o.dev && ino == o.ino : normal == o.normal);
    }
};

Identity identity_of(const Destination& d) {
    Identity id;
    if (d.exists) {
        id.exists = true;
        id.dev = d.st.st_dev;
        id.ino = d.st.st_ino;
        return id;
    }
    char* real = ::realpath(folder_of(d.target).c_str(), nullptr);
    if (!real) throw OutputError(d.path, "cannot write: " + reason(errno));
    id.normal = std::string(real) + "/" + name_of(d.target);
    std::free(real);
    return id;
}

// The destinations of `paths`, each checked, and no two naming one file.
std::vector<Destination> checked_destinations(const std::vector<std::string>& paths) {
    std::vector<Destination> destinations;
    std::vector<Identity> ids;
    for (const std::string& path : paths) {
        destinations.push_back(resolve(path));
        check_destination(destinations.back());
        ids.push_back(identity_of(destinations.back()));
        for (size_t i = 0; i + 1 < ids.size(); ++i)
            if (ids[i] == ids.back())
                throw OutputError(
                    path, "cannot write: it names the same file as the output '" + paths[i] + "'");
    }
    return destinations;
}

// DESIGN: the order of an all-or-nothing write of several files: every destination checked,
// every temporary written, then the devices, FIFOs and standard streams written (they cannot
// be taken back, and they fail more often than a rename: a full device, a closed pipe), and
// only then every target renamed in a row. What remains possible: a device written before a
// later one (or a rename) fails, a rename failing after earlier ones (the folder changed since
// the check), and a crash or SIGKILL between two renames.
void write_all_files(const std::vector<std::pair<std::string, std::string_view>>& files) {
    std::vector<std::string> paths;
    for (const auto& file : files) paths.push_back(file.first);
    const std::vector<Destination> destinations = checked_destinations(paths);
    std::vector<Temporary> temporaries(files.size());  // used only for Replace
    try {
        for (size_t i = 0; i < files.size(); ++i)
            if (destinations[i].method == Method::Replace)
                write_temporary(destinations[i], files[i].second, temporaries[i]);
        for (size_t i = 0; i < files.size(); ++i) {
            const Destination& d = destinations[i];
            if (d.method == Method::Direct) write_direct(d, files[i].second);
            if (d.method == Method::Stream) write_stream(d, files[i].second);
        }
        // Only now is any file replaced.
        for (size_t i = 0; i < files.size(); ++i) {
            const Destination& d = destinations[i];
            if (d.method == Method::Replace) {
                if (::rename(temporaries[i].name().c_str(), d.target.c_str()) != 0)
                    throw OutputError(d.path, "cannot replace the file: " + reason(errno));
                temporaries[i].renamed();
            }
        }
    } catch (...) {
        for (Temporary& t : temporaries) t.remove();
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
    check_destination(resolve(path));
}

void check_outputs(const std::vector<std::string>& outputs,
                   const std::vector<std::string>& inputs) {
    std::vector<std::string> paths;
    for (const std::string& p : outputs)
        if (!p.empty()) paths.push_back(p);
    const std::vector<Destination> destinations = checked_destinations(paths);
    for (const std::string& input : inputs) {
        struct stat in;
        if (input.empty() || ::stat(input.c_str(), &in) != 0) continue;
        for (const Destination& d : destinations)
            if (d.exists && d.st.st_dev == in.st_dev && d.st.st_ino == in.st_ino)
                throw OutputError(d.path, "cannot write: it is an input of this run ('" + input +
                                              "'), which the output would replace");
    }
}

bool is_standard_output(const std::string& path) {
    struct stat st, out;
    return ::stat(path.c_str(), &st) == 0 && ::fstat(STDOUT_FILENO, &out) == 0 &&
           st.st_dev == out.st_dev && st.st_ino == out.st_ino;
}

}  // namespace mbr
