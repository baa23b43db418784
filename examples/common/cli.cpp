// examples/common/cli.cpp - command-line parsing, tables and the main() wrapper.
#include "examples/common/cli.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "math/check.h"

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

double Args::number(const std::string& name, double def) {
    int i = find(name);
    return i < 0 ? def : parse_number(take_value(name, i), name);
}

int Args::integer(const std::string& name, int def) {
    int i = find(name);
    if (i < 0) return def;
    std::string v = take_value(name, i);
    char* end = nullptr;
    long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || end != v.c_str() + v.size() || x < -1000000000L || x > 1000000000L)
        throw UsageError(name + " expects an integer, got '" + v + "'");
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

std::vector<std::string> Args::positional() {
    std::vector<std::string> out;
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (!used_[i] && tokens_[i].rfind("--", 0) != 0) {
            used_[i] = true;
            out.push_back(tokens_[i]);
        }
    return out;
}

void Args::finish() {
    for (size_t i = 0; i < tokens_.size(); ++i)
        if (!used_[i]) {
            if (tokens_[i] == "--help" || tokens_[i] == "-h") {
                std::cout << usage_;
                std::exit(0);
            }
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

int run_main(int argc, char** argv, const std::string& usage,
             const std::function<int(Args&)>& body) {
    Args args(argc, argv, usage);
    try {
        return body(args);
    } catch (const UsageError& e) {
        std::cerr << args.program() << ": " << e.what() << "\n" << usage;
        return 2;
    } catch (const InputError& e) {
        std::cerr << args.program() << ": " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << args.program() << ": error: " << e.what() << "\n";
        return 1;
    }
}

double now_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

}  // namespace mbr
