// math/check.h - the two tiers of errors (pbrt, deal.II): MBR_CHECK for broken promises between
// parts of the program (always on, names file:line and the failed condition), and InputError
// for data that came from outside (scene files, command lines, images), carrying file and line.
#pragma once

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

namespace mbr {

/// A programming error: a precondition of a library function did not hold.
class CheckFailure : public std::logic_error {
public:
    using std::logic_error::logic_error;
};

/// Bad input from outside the program. what() reads "file:line: message" (or "file: message"
/// when line is 0, or just the message when there is no file), ready to print on stderr.
class InputError : public std::runtime_error {
public:
    InputError(std::string file, int line, const std::string& message)
        : std::runtime_error(format(file, line, message)),
          file_(std::move(file)),
          line_(line),
          message_(message) {}
    explicit InputError(const std::string& message) : InputError("", 0, message) {}
    const std::string& file() const { return file_; }
    int line() const { return line_; }
    /// The message without the file and line prefix.
    const std::string& message() const { return message_; }

private:
    static std::string format(const std::string& file, int line, const std::string& message) {
        std::ostringstream os;
        if (!file.empty()) {
            os << file;
            if (line > 0) os << ':' << line;
            os << ": ";
        }
        os << message;
        return os.str();
    }
    std::string file_;
    int line_ = 0;
    std::string message_;
};

namespace detail {
[[noreturn]] inline void check_failed(const char* file, int line, const char* condition,
                                      const std::string& detail) {
    std::ostringstream os;
    os << file << ':' << line << ": check failed: " << condition;
    if (!detail.empty()) os << " (" << detail << ')';
    throw CheckFailure(os.str());
}
}  // namespace detail

/// ": REASON" from errno after a failed open (": Permission denied"), or "" when the failure
/// set none: the tail of an InputError's message. Set errno to 0 before the open.
inline std::string system_reason() {
    const int err = errno;
    return err != 0 ? std::string(": ") + std::strerror(err) : std::string();
}

}  // namespace mbr

/// Always-on precondition check; throws mbr::CheckFailure naming the condition.
#define MBR_CHECK(condition)                                                     \
    do {                                                                         \
        if (!(condition)) ::mbr::detail::check_failed(__FILE__, __LINE__, #condition, ""); \
    } while (0)

/// Like MBR_CHECK, with a streamed explanation: MBR_CHECK_MSG(m >= 1, "m = " << m).
#define MBR_CHECK_MSG(condition, stream_expr)                                  \
    do {                                                                       \
        if (!(condition)) {                                                    \
            std::ostringstream mbr_check_os_;                                  \
            mbr_check_os_ << stream_expr;                                      \
            ::mbr::detail::check_failed(__FILE__, __LINE__, #condition,        \
                                        mbr_check_os_.str());                  \
        }                                                                      \
    } while (0)

/// Debug-only check for hot loops; compiled out when NDEBUG is defined.
#ifdef NDEBUG
#define MBR_DCHECK(condition) ((void)0)
#else
#define MBR_DCHECK(condition) MBR_CHECK(condition)
#endif
