// radiosity/scene/line_reader.h - the one line reader of mbr's text inputs: the scene format and
// OBJ + MTL (scene_reader.h, obj_reader.h), solution files (radiosity/solver/solution_file.h) and
// probe CSVs (radiosity/reference/probe.h). Input plumbing rather than a part of the paper: it
// splits lines into tokens, parses numbers and files named in them, and turns every problem into
// one InputError naming the file and the line.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "math/check.h"

namespace mbr {

/// How a LineReader splits and filters lines. The defaults are the scene format's
/// (docs/scene-format.md); solution files and probe CSVs set what differs for them.
struct LineFormat {
    size_t max_length = 65536;    // bytes per line; a longer one is refused, not read; 0: none
    std::string too_long;         // its message; empty: "line is longer than N bytes"
    bool comments = true;         // '#' starts a comment that runs to the end of the line
    bool byte_order_mark = true;  // a UTF-8 byte order mark opening line 1 is dropped
    bool control_bytes = false;   // control bytes other than blanks pass (else refused)
    bool skip_blank = true;       // lines without tokens are skipped (else returned, empty)
    char separator = 0;           // 0: blank-separated tokens; else fields split at this byte,
                                  // trimmed of spaces and tabs, after one trailing '\r' is dropped
};

/// One statement: its file, line number and tokens.
struct Line {
    std::string file;
    int number = 0;
    std::vector<std::string> tokens;

    /// Throws InputError(file, number, message).
    [[noreturn]] void fail(const std::string& message) const {
        throw InputError(file, number, message);
    }
    /// The number of tokens.
    size_t size() const { return tokens.size(); }
    /// Token i.
    const std::string& operator[](size_t i) const { return tokens[i]; }
};

/// Reads statements from a stream: splits each line into tokens as `format` says, skips blank
/// (and comment) lines unless told not to, refuses over-long lines and control bytes. A line is
/// read byte by byte and refused as soon as it passes format.max_length, so an endless input
/// (a device, a line without end) costs at most that much memory. A stream that fails to read
/// (a folder opened as a file, an I/O error) is an InputError, not a stream exception.
class LineReader {
public:
    /// Reads `in`; `file` names it in every Line and message.
    LineReader(std::istream& in, std::string file, LineFormat format = {});

    /// The next statement, or false at the end of the input.
    bool next(Line& line);

    /// The number of the last line read (0 before the first); it stays there at the end.
    int number() const { return number_; }

private:
    /// One physical line without its '\n'; false when the input is exhausted.
    bool read_raw(std::string& raw);
    /// Refills pending_ with the bytes the stream holds buffered (at least one byte, waiting
    /// for it as a read does; never more than are buffered, so an interactive stream is not
    /// waited on beyond its line); false at the end of the input. `number` is for messages.
    bool refill(int number);
    /// Splits at blanks (' ', '\t', '\r', '\v', '\f'), refusing control bytes unless allowed.
    void split_at_blanks(const std::string& raw, Line& line) const;
    /// Splits at format_.separator, trimming each field of spaces and tabs.
    void split_at_separator(std::string raw, Line& line) const;

    std::istream& in_;
    std::string file_;
    LineFormat format_;
    int number_ = 0;
    bool done_ = false;
    std::string pending_;  // bytes taken from the stream and not yet returned
    size_t pos_ = 0;       // the first of them not yet returned
};

namespace detail {

/// A token for a message: quoted, at most 256 characters, bytes outside printable ASCII as \xHH.
std::string in_quotes(const std::string& s);

/// x for messages about numbers the user wrote, and about limits: the shortest text that reads
/// back as exactly x, so that a value just beyond a limit never prints as the limit itself
/// ("100000000.1 exceeds the limit 100000000"). Positional notation for magnitudes in
/// [1e-5, 1e16), where it is exact and readable; scientific notation outside.
std::string fmt(double x);

/// x for messages about derived quantities (a deviation, a percentage, an area), which the user
/// did not write and which need no more than six significant digits.
std::string fmt_approx(double x);

/// The extension of the file named by `path` in lower case, with its dot (".obj" for
/// "ROOM.OBJ"; "" without one), by which programs tell file formats apart.
std::string lowercase_extension(const std::string& path);

/// "1 word", "3 words": a count with its noun in the right number.
std::string counted(long n, const std::string& singular, const std::string& plural);

/// Parses a decimal number (no NaN, no infinity, no hex), naming `what` in messages.
double parse_double(const Line& line, const std::string& token, const std::string& what);

/// Parses an integer in [lo, hi], naming `what` in messages.
long long parse_integer(const Line& line, const std::string& token, const std::string& what,
                        long long lo, long long hi);

/// True for tokens meant as numbers (including NaN and infinity, which parse_double refuses
/// with their own message).
bool is_number_token(const std::string& t);

/// `file` relative to the folder of `from` (unless absolute).
std::string resolve(const std::string& from, const std::string& file);

/// Why `path` cannot be read as a regular file, or an empty string.
std::string file_problem(const std::string& path);

/// A canonical spelling of `path` for include-cycle detection and caches (lexical when the file
/// system cannot tell).
std::string canonical_name(const std::string& path);

/// Opens a file named on `line` (binary); the message names the line, `what` and the path.
void open_named(const Line& line, const std::string& what, const std::string& path,
                std::ifstream& in);

/// Opens a top-level file for reading (binary), or throws InputError(path, 0, ...).
void open_top(const std::string& path, std::ifstream& in);

/// Opens a top-level file of the kind `what` ("solution file", ...) for reading (binary): a
/// folder, a device or a FIFO is refused as open_top refuses it, before a byte is read; a file
/// that cannot be opened gets "cannot open the WHAT" and the system's reason. Throws
/// InputError(path, 0, ...).
void open_input(const std::string& path, const std::string& what, std::ifstream& in);

}  // namespace detail

}  // namespace mbr
