// examples/common/cli.h - what every mbr program shares: a small command-line parser that
// rejects what it does not understand, a table that prints as aligned text or CSV, and the
// main() wrapper that turns exceptions into one stderr line and an exit code (STYLE.md B7):
// 0 on success, 2 for a bad command line or bad input (UsageError, InputError), 1 for a failure
// while running (OutputError from radiosity/output/output_file.h and anything else), including a
// failure to write the report or CSV on stdout.
#pragma once

#include <climits>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbr {

/// A bad command line; run_main prints the message on one line and exits with 2.
class UsageError : public std::runtime_error {
public:
    /// `help_hint`: the line ends with "(PROGRAM --help lists the options)"; off for a message
    /// that the options' list would not help with, such as an output path that cannot be written.
    explicit UsageError(const std::string& message, bool help_hint = true)
        : std::runtime_error(message), help_hint_(help_hint) {}
    bool help_hint() const { return help_hint_; }

private:
    bool help_hint_ = true;
};

/// Options are read by asking for them; finish() then rejects anything left unread.
/// "--name value", "--name=value" and flags "--name" are understood. "--help" or "-h" anywhere
/// on the line asks for the usage text, whatever else the line holds (run_main prints it and
/// exits 0 before the program reads a single option, so "--bogus --help" and "--help --bogus"
/// behave alike).
class Args {
public:
    Args(int argc, char** argv, std::string usage);
    const std::string& program() const { return program_; }
    const std::string& usage() const { return usage_; }
    /// True when "--name" is present (a flag takes no value).
    bool flag(const std::string& name);
    /// The string after "--name", or def when absent.
    std::string text(const std::string& name, const std::string& def);
    /// A finite number; UsageError on anything else.
    double number(const std::string& name, double def);
    /// An integer in min..max (def when absent, which need not be in the range). UsageError
    /// "NAME expects an integer" on anything but digits with an optional sign, and "NAME must be
    /// in MIN..MAX" on an integer outside, however large. Give each option its own range.
    int integer(const std::string& name, int def, int min = INT_MIN, int max = INT_MAX);
    /// "--name x1 x2 ... xn": exactly n numbers, or an empty vector when absent.
    std::vector<double> numbers(const std::string& name, int n);
    /// True when "--name" was given at all (with or without a value).
    bool has(const std::string& name) const;
    /// True when "--help" or "-h" is on the line (anywhere).
    bool help_requested() const { return help_; }
    /// The positional arguments (call after reading every option). UsageError "unknown option
    /// X" when a word nobody asked for starts with '-' (and is neither "-" nor a number): it is
    /// an option misspelt or unknown, not a file, and the words after it may be its values.
    std::vector<std::string> positional();
    /// Throws UsageError naming the first option nobody asked for.
    void finish();

private:
    int find(const std::string& name) const;
    std::string take_value(const std::string& name, int index);
    std::string program_, usage_;
    std::vector<std::string> tokens_;
    std::vector<bool> used_;
    bool help_ = false;
};

/// Parses a whole string as a finite double; UsageError naming `what` otherwise.
double parse_number(const std::string& text, const std::string& what);

/// A memory size: bytes, or a number with the suffix K, M, G or T (powers of 1024, an optional
/// "B" or "iB" after it): "4G", "512MiB", "1.5g", "100000". UsageError naming `what` otherwise.
double parse_memory_size(const std::string& text, const std::string& what);

struct CostEstimate;
/// Usage line of --memory-budget.
extern const char* memory_budget_usage;
/// "--memory-budget X" (parse_memory_size), default default_memory_budget()
/// (radiosity/solver/cost.h).
double read_memory_budget(Args& args);
/// Says the cost before it is spent: UsageError "<run> needs about N, more than the memory
/// budget B ...: lower <to_lower>, or raise --memory-budget" when cost.bytes exceeds the budget;
/// otherwise, when `slow`, one warning line on stderr with the expected memory and time.
void check_cost(const CostEstimate& cost, double budget, const std::string& run, bool slow,
                const std::string& to_lower = "the depth");

/// The program's output paths (empty ones skipped) checked before any work by check_outputs
/// (radiosity/output/output_file.h): a path that cannot be written (a missing folder, a folder,
/// a read-only file or folder), two outputs naming one file, or an output that is one of
/// `inputs` is a bad command line: UsageError (status 2) with the OutputError's message.
void refuse_bad_outputs(const std::vector<std::string>& outputs,
                        const std::vector<std::string>& inputs = {});

/// The folder of a program's images (-o DIR): created with its parents when missing; an
/// OutputError naming it when it cannot be (a file of that name, no permission). Returns dir.
std::string make_output_folder(const std::string& dir);

/// A results table: printed aligned for people, or as CSV with the exact column names.
class Table {
public:
    explicit Table(std::vector<std::string> columns) : columns_(std::move(columns)) {}
    /// Cells already formatted; use cell() for numbers.
    void add_row(std::vector<std::string> cells);
    void write_text(std::ostream& os) const;
    void write_csv(std::ostream& os) const;
    const std::vector<std::string>& columns() const { return columns_; }

private:
    std::vector<std::string> columns_;
    std::vector<std::vector<std::string>> rows_;
};

/// A number printed with `digits` decimals ("%.*f"); empty for NaN (a missing paper value).
std::string cell(double value, int digits);
/// A number with `digits` significant digits ("%.*g").
std::string cell_g(double value, int digits);

/// Starts the process again with OMP_WAIT_POLICY=passive unless the variable is set (so that
/// OpenMP's threads sleep, not spin, between parallel loops), when `argv` is the process's own
/// command line; run_main does it first. Returns (doing nothing) where it cannot restart.
void wait_passively(char** argv);

/// Runs body(args) and maps exceptions to exit codes: 2 for UsageError and InputError (bad
/// input), 1 for OutputError and any other failure, each with one line on stderr. With --help
/// on the line it prints the usage on stdout and returns 0 without running body. While body
/// runs, std::cout writes file descriptor 1 through a buffer that keeps the first write error:
/// if the report cannot be written completely (a full disk, a closed pipe) the status is 1 and
/// stderr says why, never 0 over a cut-off output.
int run_main(int argc, char** argv, const std::string& usage,
             const std::function<int(Args&)>& body);

/// Seconds on a monotonic clock, for the examples' own timings.
double now_seconds();

}  // namespace mbr
