// examples/common/cli.h - what every mbr program shares: a small command-line parser that
// rejects what it does not understand, a table that prints as aligned text or CSV, and the
// main() wrapper that turns exceptions into one stderr line and an exit code (STYLE.md B7).
#pragma once

#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbr {

/// A bad command line; main prints the message and the usage text and exits with 2.
class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Options are read by asking for them; finish() then rejects anything left unread.
/// "--name value", "--name=value" and flags "--name" are understood.
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
    /// An integer; UsageError on anything else.
    int integer(const std::string& name, int def);
    /// "--name x1 x2 ... xn": exactly n numbers, or an empty vector when absent.
    std::vector<double> numbers(const std::string& name, int n);
    /// True when "--name" was given at all (with or without a value).
    bool has(const std::string& name) const;
    /// The positional arguments (call after reading every option).
    std::vector<std::string> positional();
    /// Throws UsageError naming the first option nobody asked for; prints usage on --help.
    void finish();

private:
    int find(const std::string& name) const;
    std::string take_value(const std::string& name, int index);
    std::string program_, usage_;
    std::vector<std::string> tokens_;
    std::vector<bool> used_;
};

/// Parses a whole string as a finite double; UsageError naming `what` otherwise.
double parse_number(const std::string& text, const std::string& what);

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

/// Runs body(args) and maps exceptions to exit codes: 2 for UsageError and InputError (bad
/// input), 1 for any other failure. Writes one line to stderr, never a partial result.
int run_main(int argc, char** argv, const std::string& usage,
             const std::function<int(Args&)>& body);

/// Seconds on a monotonic clock, for the examples' own timings.
double now_seconds();

}  // namespace mbr
