// examples/common/cli.cpp - command-line parsing, tables and the main() wrapper.
#include "examples/common/cli.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <new>
#include <streambuf>

#include "math/check.h"
#include "radiosity/output/output_file.h"
#include "radiosity/solver/cost.h"

namespace mbr {

Args::Args(int argc, char** argv, std::string usage) : usage_(std::move(usage)) {
    program_ = argc > 0 ? argv[0] : "mbr";
    auto slash = program_.find_last_of('/');
    if (slash != std::string::npos) program_ = program_.substr(slash + 1);
    for (int i = 1; i < argc; ++i) {
        std::string t = argv[i];
        auto eq = t.find('=');
        if (t.rfind("--", 0) == 0 && eq != std::string::npos) {
            tokens_.push_back(t.substr(0, eq));
            tokens_.push_back(t.substr(eq + 1));
        } else {
            tokens_.push_back(t);
        }
    }
    used_.assign(tokens_.size(), false);
    // DESIGN: a help request wins over everything else on the line, in any position, so that
    // "--bogus --help" prints the usage as "--help --bogus" does; its tokens count as read.
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (tokens_[i] == "--help" || tokens_[i] == "-h") help_ = used_[i] = true;
}

int Args::find(const std::string& name) const {
    int found = -1;
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (tokens_[i] == name) {
            if (found >= 0) throw UsageError(name + " is given more than once");
            found = static_cast<int>(i);
        }
    return found;
}

bool Args::has(const std::string& name) const { return find(name) >= 0; }

bool Args::flag(const std::string& name) {
    int i = find(name);
    if (i < 0) return false;
    used_[i] = true;
    return true;
}

std::string Args::take_value(const std::string& name, int index) {
    if (index + 1 >= static_cast<int>(tokens_.size()))
        throw UsageError(name + " needs a value");
    used_[index] = used_[index + 1] = true;
    return tokens_[index + 1];
}

std::string Args::text(const std::string& name, const std::string& def) {
    int i = find(name);
    return i < 0 ? def : take_value(name, i);
}

double parse_number(const std::string& text, const std::string& what) {
    const char* begin = text.c_str();
    char* end = nullptr;
    double v = std::strtod(begin, &end);
    if (text.empty() || end != begin + text.size())
        throw UsageError(what + " expects a number, got '" + text + "'");
    if (!std::isfinite(v)) throw UsageError(what + " must be finite, got '" + text + "'");
    return v;
}

double parse_memory_size(const std::string& text, const std::string& what) {
    std::string number = text;
    double unit = 1;
    // Strip an optional "B", then "i", then the power letter.
    auto ends_with = [&](char c) {
        return !number.empty() && std::tolower(static_cast<unsigned char>(number.back())) == c;
    };
    if (ends_with('b')) number.pop_back();
    const bool binary = ends_with('i');
    if (binary) number.pop_back();
    const std::string powers = "kmgt";
    if (!number.empty()) {
        const size_t p = powers.find(char(std::tolower(static_cast<unsigned char>(number.back()))));
        if (p != std::string::npos) {
            unit = std::ldexp(1.0, 10 * int(p + 1));
            number.pop_back();
        } else if (binary) {
            number = "";  // "iB" without a power letter
        }
    }
    const char* begin = number.c_str();
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (number.empty() || end != begin + number.size() || !std::isfinite(v) || !(v > 0))
        throw UsageError(what + " expects a positive size in bytes, with K, M, G or T for powers "
                                "of 1024 (e.g. 4G), got '" + text + "'");
    return v * unit;
}

const char* memory_budget_usage =
    "  --memory-budget X         refuse a run estimated to need more memory (bytes, or K, M,\n"
    "                            G, T: 4G; default half the physical memory)\n";

double read_memory_budget(Args& args) {
    if (!args.has("--memory-budget")) return default_memory_budget();
    return parse_memory_size(args.text("--memory-budget", ""), "--memory-budget");
}

void check_cost(const CostEstimate& cost, double budget, const std::string& run, bool slow,
                const std::string& to_lower) {
    if (cost.bytes > budget)
        throw UsageError(run + " needs about " + format_bytes(cost.bytes) + " (" + cost.detail +
                         "), more than the memory budget of " + format_bytes(budget) +
                         ": lower " + to_lower + ", or raise --memory-budget");
    if (slow)
        std::cerr << "warning: " << run << " is slow: expect about " << format_bytes(cost.bytes)
                  << " of memory and " << format_seconds(cost.seconds) << " of one core\n";
}

double Args::number(const std::string& name, double def) {
    int i = find(name);
    return i < 0 ? def : parse_number(take_value(name, i), name);
}

int Args::integer(const std::string& name, int def, int min, int max) {
    MBR_CHECK(min <= max);
    int i = find(name);
    if (i < 0) return def;
    const std::string v = take_value(name, i);
    // Digits with an optional sign and nothing else (strtoll alone would skip leading blanks).
    const size_t first = !v.empty() && (v[0] == '-' || v[0] == '+') ? 1 : 0;
    bool digits = v.size() > first;
    for (size_t k = first; k < v.size(); ++k) digits = digits && v[k] >= '0' && v[k] <= '9';
    if (!digits) throw UsageError(name + " expects an integer, got '" + v + "'");
    errno = 0;
    const long long x = std::strtoll(v.c_str(), nullptr, 10);
    if (errno == ERANGE || x < min || x > max)
        throw UsageError(name + " must be in " + std::to_string(min) + ".." + std::to_string(max) +
                         ", got " + v);
    return static_cast<int>(x);
}

std::vector<double> Args::numbers(const std::string& name, int n) {
    int i = find(name);
    if (i < 0) return {};
    used_[i] = true;
    std::vector<double> out;
    for (int k = 1; k <= n; ++k) {
        if (i + k >= static_cast<int>(tokens_.size()))
            throw UsageError(name + " needs " + std::to_string(n) + " numbers, got " +
                             std::to_string(k - 1));
        used_[i + k] = true;
        out.push_back(parse_number(tokens_[i + k], name));
    }
    return out;
}

namespace {

// A word that reads as an option: '-' and more, other than a number such as "-1" or "-.5".
bool looks_like_option(const std::string& word) {
    if (word.size() < 2 || word[0] != '-') return false;
    char* end = nullptr;
    std::strtod(word.c_str(), &end);
    return end != word.c_str() + word.size();
}

}  // namespace

std::vector<std::string> Args::positional() {
    // DESIGN: an option nobody asked for is named before the positional arguments are counted,
    // so that "SCENE -x" or "--camera 0 1 3" say "unknown option" rather than "one scene file,
    // please (got 4)": the words after an unknown option may be its values.
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (!used_[i] && looks_like_option(tokens_[i]))
            throw UsageError("unknown option " + tokens_[i]);
    std::vector<std::string> out;
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (!used_[i]) {
            used_[i] = true;
            out.push_back(tokens_[i]);
        }
    return out;
}

void Args::finish() {
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (!used_[i]) {
            if (tokens_[i].rfind("-", 0) == 0) throw UsageError("unknown option " + tokens_[i]);
            throw UsageError("unexpected argument '" + tokens_[i] + "'");
        }
}

void Table::add_row(std::vector<std::string> cells) {
    MBR_CHECK(cells.size() == columns_.size());
    rows_.push_back(std::move(cells));
}

void Table::write_text(std::ostream& os) const {
    std::vector<size_t> width(columns_.size());
    for (size_t c = 0; c < columns_.size(); ++c) {
        width[c] = columns_[c].size();
        for (const auto& r : rows_) width[c] = std::max(width[c], r[c].size());
    }
    auto line = [&](const std::vector<std::string>& cells) {
        for (size_t c = 0; c < cells.size(); ++c) {
            os << (c ? "  " : "");
            os << std::string(width[c] - cells[c].size(), ' ') << cells[c];
        }
        os << '\n';
    };
    line(columns_);
    for (const auto& r : rows_) line(r);
}

void Table::write_csv(std::ostream& os) const {
    for (size_t c = 0; c < columns_.size(); ++c) os << (c ? "," : "") << columns_[c];
    os << '\n';
    for (const auto& r : rows_) {
        for (size_t c = 0; c < r.size(); ++c) os << (c ? "," : "") << r[c];
        os << '\n';
    }
}

std::string cell(double value, int digits) {
    if (std::isnan(value)) return "";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, value);
    return buf;
}

std::string cell_g(double value, int digits) {
    if (std::isnan(value)) return "";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, value);
    return buf;
}

namespace {

// std::cout's buffer while run_main runs a program. It writes file descriptor 1 itself and
// keeps the first error, because stdio's buffer forgets errno once it drops a failed block: a
// report or CSV cut off by a full disk must end in status 1 with the reason, not status 0.
// Line-buffered on a terminal, so that progress lines show as they are printed.
class CheckedStdout : public std::streambuf {
public:
    CheckedStdout() : line_buffered_(::isatty(STDOUT_FILENO) == 1) { reset(); }
    /// The errno of the first failed write, 0 if none failed.
    int error() const { return error_; }

protected:
    int_type overflow(int_type c) override {
        if (!drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(c, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(c);
            pbump(1);
        }
        return traits_type::not_eof(c);
    }
    std::streamsize xsputn(const char* s, std::streamsize n) override {
        const std::streamsize done = std::streambuf::xsputn(s, n);
        if (line_buffered_ && std::memchr(s, '\n', size_t(done)) && !drain()) return 0;
        return done;
    }
    int sync() override { return drain() ? 0 : -1; }

private:
    void reset() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
    // Writes out the buffer; false (and the buffer dropped) once any write has failed.
    bool drain() {
        const char* p = pbase();
        size_t left = size_t(pptr() - pbase());
        reset();
        while (error_ == 0 && left > 0) {
            const ssize_t n = ::write(STDOUT_FILENO, p, left);
            if (n < 0 && errno != EINTR) error_ = errno;
            if (n > 0) p += n, left -= size_t(n);
        }
        return error_ == 0;
    }
    std::array<char, 1 << 16> buffer_;
    bool line_buffered_ = false;
    int error_ = 0;
};

// Runs body and turns its exceptions into one stderr line and a status.
int run_body(Args& args, const std::function<int(Args&)>& body) {
    const std::string& program = args.program();
    try {
        if (args.help_requested()) {
            std::cout << args.usage();
            return 0;
        }
        return body(args);
    } catch (const UsageError& e) {
        std::cerr << program << ": " << e.what();
        if (e.help_hint()) std::cerr << " (" << program << " --help lists the options)";
        std::cerr << "\n";
        return 2;
    } catch (const InputError& e) {
        std::cerr << program << ": " << e.what() << "\n";
        return 2;
    } catch (const OutputError& e) {
        std::cerr << program << ": " << e.what() << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << program << ": error: out of memory\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << program << ": error: " << e.what() << "\n";
        return 1;
    } catch (...) {
        std::cerr << program << ": error: an unknown exception\n";
        return 1;
    }
}

}  // namespace

/// DESIGN: OpenMP's threads wait passively (they sleep) at the end of a parallel loop unless the
/// user chose a policy with OMP_WAIT_POLICY. The solver runs many short parallel loops; threads
/// that spin between them cost little on an idle machine but take the cores a loaded machine's
/// other processes need (docs/method.md, "Threads on a busy machine"). The GNU runtime reads
/// the variable once, when it loads, before main: so the program sets it and starts itself
/// again, once (the variable is then set). Where it cannot (no /proc), it goes on as it is. Only
/// a process's own command line restarts it (glibc's program_invocation_name is its argv[0]):
/// run_main called with a made-up one, as the tests do, runs in place.
void wait_passively(char** argv) {
#ifdef _OPENMP
    if (argv == nullptr || argv[0] != program_invocation_name) return;
    if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
    if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
    std::cout.flush();
    std::fflush(nullptr);
    execv("/proc/self/exe", argv);
#else
    (void)argv;
#endif
}

int run_main(int argc, char** argv, const std::string& usage,
             const std::function<int(Args&)>& body) {
    wait_passively(argv);
    Args args(argc, argv, usage);
    // Whatever was printed before goes out first, through the old buffer.
    std::cout.flush();
    std::fflush(stdout);
    CheckedStdout out;
    std::streambuf* const previous = std::cout.rdbuf(&out);
    int status = run_body(args, body);
    std::cout.flush();
    std::cout.rdbuf(previous);  // also clears a bad state left by a failed write
    if (out.error() != 0) {
        std::cerr << args.program()
                  << ": standard output: cannot write: " << std::strerror(out.error()) << "\n";
        if (status == 0) status = 1;
    }
    return status;
}

double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

void refuse_bad_outputs(const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs) {
    try {
        check_outputs(outputs, inputs);
    } catch (const OutputError& e) {
        throw UsageError(e.what(), false);
    }
}

std::string make_output_folder(const std::string& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir))
        throw OutputError(dir, ec ? "cannot create the folder: " + ec.message()
                                  : "is not a folder");
    return dir;
}

}  // namespace mbr
