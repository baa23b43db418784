// radiosity/scene/line_reader.cpp - the shared line reader (line_reader.h): lines to tokens,
// tokens to numbers, file names to open files, each problem one InputError with file and line.
#include "radiosity/scene/line_reader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <sstream>

namespace mbr {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// === Lines and tokens

LineReader::LineReader(std::istream& in, std::string file, LineFormat format)
    : in_(in), file_(std::move(file)), format_(std::move(format)) {}

bool LineReader::next(Line& line) {
    std::string raw;
    while (read_raw(raw)) {
        line.file = file_;
        line.number = number_;
        line.tokens.clear();
        if (format_.byte_order_mark && number_ == 1 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0)
            raw.erase(0, 3);
        if (format_.comments) {
            size_t hash = raw.find('#');
            if (hash != std::string::npos) raw.erase(hash);
        }
        if (format_.separator != 0)
            split_at_separator(std::move(raw), line);
        else
            split_at_blanks(raw, line);
        if (!line.tokens.empty() || !format_.skip_blank) return true;
    }
    return false;
}

void LineReader::split_at_blanks(const std::string& raw, Line& line) const {
    std::string token;
    for (char ch : raw) {
        unsigned char c = static_cast<unsigned char>(ch);
        bool space = c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
        if (!format_.control_bytes && !space && (c < 0x20 || c == 0x7f)) {
            line.fail("unexpected control byte " + detail::in_quotes(std::string(1, ch)) +
                      " (is this a text file?)");
        }
        if (space) {
            if (!token.empty()) line.tokens.push_back(std::move(token));
            token.clear();
        } else {
            token += ch;
        }
    }
    if (!token.empty()) line.tokens.push_back(std::move(token));
}

void LineReader::split_at_separator(std::string raw, Line& line) const {
    if (!raw.empty() && raw.back() == '\r') raw.pop_back();
    const auto blank = [](char c) { return c == ' ' || c == '\t'; };
    // A line of blanks has no fields (it is skipped); any other has at least one.
    bool all_blank = true;
    for (char c : raw) all_blank = all_blank && blank(c);
    if (all_blank) return;
    for (size_t start = 0;;) {
        size_t end = raw.find(format_.separator, start);
        size_t b = start, e = end == std::string::npos ? raw.size() : end;
        while (b < e && blank(raw[b])) ++b;
        while (e > b && blank(raw[e - 1])) --e;
        line.tokens.push_back(raw.substr(b, e - b));
        if (end == std::string::npos) return;
        start = end + 1;
    }
}

bool LineReader::read_raw(std::string& raw) {
    raw.clear();
    if (!in_.rdbuf() || done_) return false;
    const int number = number_ + 1;
    for (;;) {
        if (pos_ == pending_.size() && !refill(number)) {
            done_ = true;
            if (raw.empty()) return false;
            number_ = number;
            return true;
        }
        const size_t end = pending_.find('\n', pos_);
        const size_t stop = end == std::string::npos ? pending_.size() : end;
        if (format_.max_length > 0 && raw.size() + (stop - pos_) > format_.max_length)
            throw InputError(
                file_, number,
                !format_.too_long.empty()
                    ? format_.too_long
                    : "line is longer than " + std::to_string(format_.max_length) + " bytes");
        raw.append(pending_, pos_, stop - pos_);
        pos_ = stop;
        if (end != std::string::npos) {
            ++pos_;
            number_ = number;
            return true;
        }
    }
}

bool LineReader::refill(int number) {
    std::streambuf* buf = in_.rdbuf();
    pending_.clear();
    pos_ = 0;
    try {
        errno = 0;
        const std::streamsize buffered = buf->in_avail();
        if (buffered > 0) {
            pending_.resize(size_t(std::min<std::streamsize>(buffered, 1 << 16)));
            pending_.resize(size_t(buf->sgetn(&pending_[0], std::streamsize(pending_.size()))));
            return !pending_.empty();
        }
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) return false;
        pending_.assign(1, char(c));
        return true;
    } catch (const std::exception&) {
        // A file stream throws from its buffer when reading fails: a folder opened as a file
        // (Linux opens it; the first read gives EISDIR) or an I/O error.
        const int err = errno;
        done_ = true;
        if (err == EISDIR) throw InputError(file_, 0, "is a folder, not a file");
        throw InputError(file_, number, "cannot read the file" + system_reason());
    }
}

namespace detail {

// ---------------------------------------------------------------------------------------------
// === Messages

std::string in_quotes(const std::string& s) {
    std::string out = "'";
    size_t n = 0;
    for (unsigned char c : s) {
        if (++n > 256) {
            out += "...";
            break;
        }
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out + "'";
}

std::string fmt(double x) {
    char buf[64];
    const double a = std::fabs(x);
    const bool positional = a == 0 || (a >= 1e-5 && a < 1e16);
    auto r = positional ? std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed)
                        : std::to_chars(buf, buf + sizeof buf, x);
    return r.ec == std::errc() ? std::string(buf, r.ptr) : std::string("?");
}

std::string fmt_approx(double x) {
    std::ostringstream os;
    os.precision(6);
    os << x;
    return os.str();
}

std::string lowercase_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string counted(long n, const std::string& singular, const std::string& plural) {
    return std::to_string(n) + " " + (n == 1 ? singular : plural);
}

// ---------------------------------------------------------------------------------------------
// === Numbers

double parse_double(const Line& line, const std::string& token, const std::string& what) {
    std::string lower;
    for (char c : token) lower += char(std::tolower(static_cast<unsigned char>(c)));
    size_t start = (!lower.empty() && (lower[0] == '+' || lower[0] == '-')) ? 1 : 0;
    if (lower.compare(start, 3, "nan") == 0 || lower.compare(start, 3, "inf") == 0)
        line.fail(what + " is " + in_quotes(token) + ": NaN and infinity are not allowed");
    const char* b = token.data();
    const char* e = b + token.size();
    if (b != e && *b == '+') ++b;  // from_chars takes '-' but not '+'
    double x = 0;
    auto result = std::from_chars(b, e, x, std::chars_format::general);
    if (b == e || *b == '+' || result.ptr != e ||
        (result.ec != std::errc() && result.ec != std::errc::result_out_of_range))
        line.fail("expected a number for " + what + ", found " + in_quotes(token));
    if (result.ec == std::errc::result_out_of_range || !std::isfinite(x))
        line.fail(what + " " + in_quotes(token) + " is out of range");
    return x;
}

long long parse_integer(const Line& line, const std::string& token, const std::string& what,
                        long long lo, long long hi) {
    const char* b = token.data();
    const char* e = b + token.size();
    if (b != e && *b == '+') ++b;
    long long x = 0;
    auto result = std::from_chars(b, e, x);
    if (b == e || *b == '+' || result.ptr != e ||
        (result.ec != std::errc() && result.ec != std::errc::result_out_of_range))
        line.fail("expected an integer for " + what + ", found " + in_quotes(token));
    if (result.ec == std::errc::result_out_of_range || x < lo || x > hi)
        line.fail(what + " " + in_quotes(token) + " is outside [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "]");
    return x;
}

bool is_number_token(const std::string& t) {
    if (t.empty()) return false;
    char c = t[0];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.')
        return true;
    std::string lower;
    for (char ch : t) lower += char(std::tolower(static_cast<unsigned char>(ch)));
    return lower == "nan" || lower == "inf" || lower == "infinity" ||
           lower.compare(0, 4, "nan(") == 0;
}

// ---------------------------------------------------------------------------------------------
// === Files

std::string resolve(const std::string& from, const std::string& file) {
    fs::path p(file);
    if (p.is_absolute()) return p.string();
    return (fs::path(from).parent_path() / p).string();
}

std::string file_problem(const std::string& path) {
    std::error_code ec;
    fs::file_status st = fs::status(path, ec);
    // Only a missing file is "not found"; anything else (a folder on the way that may not be
    // searched, a file name used as a folder) gets the system's reason, e.g. "Permission denied".
    if (ec && ec != std::errc::no_such_file_or_directory) return ec.message();
    if (ec || !fs::exists(st)) return "file not found";
    if (fs::is_directory(st)) return "is a folder, not a file";
    if (!fs::is_regular_file(st)) return "is not a regular file";
    return "";
}

std::string canonical_name(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::path(path), ec);
    if (ec) p = fs::absolute(fs::path(path), ec).lexically_normal();
    return p.string();
}

void open_named(const Line& line, const std::string& what, const std::string& path,
                std::ifstream& in) {
    std::string problem = file_problem(path);
    if (!problem.empty()) line.fail(what + " " + in_quotes(path) + ": " + problem);
    errno = 0;
    in.open(path, std::ios::binary);
    if (!in) line.fail(what + " " + in_quotes(path) + ": cannot open it" + system_reason());
}

void open_top(const std::string& path, std::ifstream& in) {
    std::string problem = file_problem(path);
    if (!problem.empty()) throw InputError(path, 0, problem);
    errno = 0;
    in.open(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "cannot open the file" + system_reason());
}

void open_input(const std::string& path, const std::string& what, std::ifstream& in) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!ec && fs::exists(st) && !fs::is_regular_file(st))
        throw InputError(path, 0, file_problem(path));
    errno = 0;
    in.open(path, std::ios::binary);
    if (!in) throw InputError(path, 0, "cannot open the " + what + system_reason());
}

}  // namespace detail

}  // namespace mbr
