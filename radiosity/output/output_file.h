// radiosity/output/output_file.h - how every mbr program writes a file (images, tables, solutions,
// grids): completely or not at all, and never by replacing what the path is.
//
// The rules (docs/method.md, "Writing files"):
//   - a new path or an existing regular file: the bytes go to a temporary file in the same
//     folder (mkstemp), every write, the fsync and the close are checked, then the temporary is
//     renamed over the target. A failure removes the temporary and leaves the target as it was.
//   - a symbolic link: the file it points to is replaced (a dangling link's target is created)
//     and the link stays a link.
//   - an existing file that is not a regular file (a character device such as /dev/full, a
//     FIFO, a pipe or terminal behind /dev/stdout): opened and written directly, no rename. A
//     FIFO without a reader blocks until one comes, as a shell redirection does.
//   - a directory, a missing folder, a folder without write permission, an existing file the
//     user may not write (as the shell's `>` refuses it), a file in a sticky folder that only its
//     owner may replace: refused with the system's reason before anything is written.
//   - a signal that ends the program by default (SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ)
//     while temporaries exist: they are removed, then the program ends by that signal as it
//     would have (the shell's status 130, 143, ...). A signal the program ignores or handles
//     itself is left alone.
// The content is complete in memory before the file is touched, so a failure while producing
// it leaves nothing behind.
#pragma once

#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace mbr {

/// A file could not be written. what() reads "PATH: MESSAGE", e.g.
/// "out/x.png: cannot write: No space left on device"; the reason is the system's (strerror).
/// Programs exit with status 1 on it (run_main in examples/common/cli.h).
class OutputError : public std::runtime_error {
public:
    OutputError(std::string path, const std::string& message);
    /// The path as the program was given it.
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

/// Writes `bytes` to `path` by the rules above; OutputError on any failure.
void write_file(const std::string& path, std::string_view bytes);

/// The same, with the content produced by write(os) into memory first: an exception from
/// `write`, or a stream it leaves failed, touches no file.
void write_file(const std::string& path, const std::function<void(std::ostream&)>& write);

/// One file of write_files().
struct OutputFile {
    std::string path;
    std::string bytes;
};

/// Several files, all or none as far as the file system allows: every path is checked (two paths
/// naming one file are refused), every temporary written, then the devices, FIFOs and standard
/// streams written, and only then every target renamed, in a row. What can still leave a part
/// written: a device or FIFO written before a later one fails, a rename failing after earlier
/// ones (the folder changed since the check), a crash or SIGKILL between two renames.
void write_files(const std::vector<OutputFile>& files);

/// Throws the OutputError that write_file would throw before writing anything (a directory, a
/// missing folder, a folder that is read-only or without write permission, a read-only file, a
/// sticky folder's file of another user), so that a program can refuse its output path before a
/// long computation. Writes nothing.
void check_output_path(const std::string& path);

/// check_output_path for each of `outputs` (empty ones skipped), then an OutputError when two
/// of them name one file (the same device and inode when the file exists, the same path through
/// the folder's real path when it does not) or when one of them is an existing file among
/// `inputs` (by device and inode, whatever the spelling: "./x", a symbolic or a hard link).
/// Writes nothing.
void check_outputs(const std::vector<std::string>& outputs,
                   const std::vector<std::string>& inputs = {});

/// True when `path` names the file the process's standard output goes to (/dev/stdout, or the
/// file or pipe stdout is redirected to). A program writing its result there prints its report
/// on stderr instead, so that the two do not mix.
bool is_standard_output(const std::string& path);

}  // namespace mbr
