// radiosity/scene/settings.cpp - the option table: every solver setting once (settings.h).
#include "radiosity/scene/settings.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "math/check.h"
#include "radiosity/scene/line_reader.h"

namespace mbr {

namespace {

using detail::fmt;
using detail::in_quotes;
using detail::parse_double;
using detail::parse_integer;
using Kind = OptionSpec::Kind;

OptionSpec integer_option(std::string name, int SolverSettings::*field, int lo, int hi,
                          std::string unit, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.kind = Kind::Integer;
    o.lo = lo;
    o.hi = hi;
    o.unit = std::move(unit);
    o.doc = std::move(doc);
    o.set = [field](SolverSettings& s, double x) { s.*field = int(x); };
    o.get = [field](const SolverSettings& s) { return double(s.*field); };
    return o;
}

OptionSpec real_option(std::string name, double SolverSettings::*field, double lo, double hi,
                       bool open_lo, bool open_hi, std::string unit, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.kind = Kind::Real;
    o.lo = lo;
    o.hi = hi;
    o.open_lo = open_lo;
    o.open_hi = open_hi;
    o.unit = std::move(unit);
    o.doc = std::move(doc);
    o.set = [field](SolverSettings& s, double x) { s.*field = x; };
    o.get = [field](const SolverSettings& s) { return s.*field; };
    return o;
}

template <class E>
OptionSpec choice_option(std::string name, E SolverSettings::*field,
                         std::vector<std::string> choices, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.kind = Kind::Choice;
    o.choices = std::move(choices);
    o.unit = "M";
    o.doc = std::move(doc);
    o.set = [field](SolverSettings& s, double i) { s.*field = static_cast<E>(int(i)); };
    o.get = [field](const SolverSettings& s) { return double(static_cast<int>(s.*field)); };
    return o;
}

OptionSpec switch_option(std::string name, bool SolverSettings::*field, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.kind = Kind::Switch;
    o.choices = {"true", "false"};
    o.unit = "on|off";
    o.doc = std::move(doc);
    o.set = [field](SolverSettings& s, double x) { s.*field = x != 0; };
    o.get = [field](const SolverSettings& s) { return s.*field ? 1.0 : 0.0; };
    return o;
}

OptionSpec with_aliases(OptionSpec o, std::vector<std::string> aliases) {
    o.aliases = std::move(aliases);
    return o;
}

std::vector<OptionSpec> make_option_table() {
    using S = SolverSettings;
    return {
        integer_option("order", &S::order, 2, 8, "m",
                       "B-spline order m (degree m - 1); the paper uses 4 and 3"),
        integer_option("min_depth", &S::min_depth, 0, 12, "d",
                       "oracle quadtree: minimum subdivisions below the root"),
        integer_option("max_depth", &S::max_depth, 0, 12, "d",
                       "oracle quadtree: maximum subdivisions, at least min_depth; min = max "
                       "= d gives uniform leaves 2^-d wide (Tables 1, 2)"),
        real_option("oracle_tolerance", &S::oracle_tolerance, 0, 1, true, false, "x",
                    "relative agreement of the oracle's two Gauss-Legendre rules"),
        choice_option("oracle", &S::oracle, {"hybrid", "interpolation", "means"},
                      "the oracle's test of a cell: the paper's two means where the relative "
                      "tolerance governs and, where the absolute one does, the polynomial "
                      "through the m^2 samples predicting the others within two absolute "
                      "tolerances (hybrid: a dim shot's shadows stay sharp; docs/method.md), "
                      "that fit everywhere, or the paper's two means everywhere"),
        real_option("truncation_eps", &S::truncation_eps, 0, 1, true, true, "eps",
                    "relative cut-off of the dual basis (the rhombus of Figure 3)"),
        real_option("rhombus_radius", &S::rhombus_radius, 0, 1000, false, false, "r",
                    "fixed rhombus radius in cells; 0 derives it from truncation_eps"),
        choice_option("extrapolation", &S::extrapolation, {"linear", "higher"},
                      "the increment beyond the domain: eqs. (23)-(25), or (26)-(27)"),
        with_aliases(integer_option("shadow_rays", &S::shadow_rays, 1, 4096, "R",
                                    "paper shadows: rays per fulcrum per shooter patch, eq. (28)"),
                     {"--rays"}),
        with_aliases(integer_option("max_shots", &S::max_shots, 0, 10000000, "n",
                                    "cap on progressive-refinement shots"),
                     {"--shots"}),
        real_option("convergence", &S::convergence, 0, 1, false, true, "c",
                    "stop when the largest unshot power of one surface is below this fraction "
                    "of the emitted power (the total unshot, reported at the end, is larger)"),
        switch_option("self_transfer", &S::self_transfer,
                      "a surface that can see itself (an inward cylinder or sphere patch) receives "
                      "from itself; planar surfaces never do"),
        switch_option("cluster_shots", &S::cluster_shots,
                      "beyond the paper: the surfaces next to the shooter in its plane, facing "
                      "its way, with at least a tenth of its unshot power shoot with it (a "
                      "planar cluster); a receiver farther than the cluster's diagonal takes one "
                      "transfer of their sum"),
        integer_option("tessellation", &S::tessellation, 1, 1024, "T",
                       "facets per curved parameter direction when rays are cast at curved "
                       "surfaces (at least 3 along an angle; one along a cylinder's height or a "
                       "disk's radius, which are straight)"),
        choice_option("shadows", &S::shadows, {"exact", "paper", "none", "auto"},
                      "visibility inside (21) (beyond the paper), the paper's fractions (28) "
                      "with masking, no shadows, or auto: exact, but the paper's for a pair "
                      "with more than 16 shadow casters between its two (convex solids, and the "
                      "surfaces of other occluders), unless it has more than 24 and at most 12 "
                      "meet the pyramid from each of 3 x 3 points of the receiver to a planar "
                      "shooter (a small lamp)"),
        real_option("tolerance", &S::tolerance, 0, 1, true, true, "x",
                    "accuracy relative to the scene's radiosity scale (emitted power / total "
                    "area): every transfer's absolute tolerance"),
        choice_option("unify", &S::unify, {"projection", "paper"},
                      "every finest-scale coefficient projected on the fine grid, or the "
                      "paper's (17) from the selected fulcrums"),
        switch_option("ambient", &S::ambient,
                      "at the end, the power still unshot is sent on through the measured "
                      "coupling of the surfaces (an ambient term)"),
        integer_option("ambient_rays", &S::ambient_rays, 0, 4096, "R",
                       "the ambient correction is gathered at each surface's Gauss points (see "
                       "ambient_level) by this many cosine-distributed rays per point, fewer "
                       "when all of them would pass "
                       "16.8 M (the unshot light lands where it falls, shadows included); 0: a "
                       "constant radiosity per surface"),
        integer_option("ambient_level", &S::ambient_level, 0, 4, "L",
                       "the ambient gather's points: the m x m Gauss points of every cell of "
                       "this level of each surface, and the field it adds at this level"),
        switch_option("ambient_final", &S::ambient_final,
                      "after the ambient gather, a surface whose gathered radiosity reaches 10 "
                      "absolute tolerances, and whose cells are wider than 1/16 of the scene's "
                      "diagonal, gathers once more at the finer level of such cells (at most 4), "
                      "with a quarter of the rays, one bounce from what the gather makes every "
                      "surface send (the final gather: the ambient light follows the shadows "
                      "near a large surface)"),
        switch_option("limiter", &S::limiter,
                      "where a shot's increment rings above rho_max x the shooter's largest "
                      "coefficient its covering coefficients are clipped to that bound, and "
                      "pictures and probes read the fields lifted to zero where they ring "
                      "below it: radiosity is never negative (docs/method.md); off is the "
                      "paper's"),
        switch_option("hidden", &S::hidden,
                      "points that see no front face of the scene take their nearest visible "
                      "neighbour's value"),
        integer_option("shooter_level", &S::shooter_level, 0, 12, "L",
                       "a shooter's unshot field is coarsened to at most this level before it "
                       "shoots (section 6's \"lower resolution version\")"),
        integer_option("contact_depth", &S::contact_depth, 0, 12, "D",
                       "receiver cells that touch a planar shooter (within half their size: "
                       "shared edges, a block standing on the floor) split down to at least "
                       "this level, whatever the oracle says"),
        real_option("weak_transfer", &S::weak_transfer, 0, 1000, false, false, "w",
                    "a transfer whose m x m samples over the whole receiver are all below w "
                    "absolute tolerances keeps the root as its only cell and takes the "
                    "polynomial through them (no edgefill, no extrapolated ring); 0: the full "
                    "pipeline for every transfer"),
        choice_option("contact_oracle", &S::contact_oracle, {"hybrid", "interpolation", "means"},
                      "the oracle's test in receiver cells that touch a planar shooter (come "
                      "within a quarter of their size of it; see oracle): interpolation follows "
                      "B at shared edges and corners (a block's foot on a floor); the paper's "
                      "means cost least (docs/method.md)"),
        choice_option("fraction_rays", &S::fraction_rays, {"kernel", "area"},
                      "paper shadows: how a fraction (28) counts its rays to a shooter patch: "
                      "each weighted by the shooter's radiosity times the kernel (3) at its end "
                      "(beyond the paper: the visible share of what the patch sends), or each "
                      "counting one (the paper's: the visible share of its area)"),
        choice_option("texture_field", &S::texture_field, {"irradiance", "radiosity"},
                      "what a surface with a textured reflectance stores as its spline field: "
                      "the irradiance H, with B = E + rho H formed at every sample and pixel "
                      "(the texture at its own resolution, never ringing below zero), or the "
                      "radiosity B itself (the paper's)"),
    };
}

/// A number as the documentation writes it: the shortest text that reads back as x, with
/// exponents without leading zeros ("0.001", "1e-6", "10000000").
std::string number_text(double x) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    std::string s(buf, r.ptr);
    const size_t e = s.find('e');
    if (e != std::string::npos) {
        size_t digits = e + 1;
        if (digits < s.size() && (s[digits] == '-' || s[digits] == '+')) ++digits;
        while (digits + 1 < s.size() && s[digits] == '0') s.erase(digits, 1);
        if (s[e + 1] == '+') s.erase(e + 1, 1);
    }
    return s;
}

/// "'a' or 'b'", "'a', 'b' or 'c'": the words of a choice, quoted when asked.
std::string word_list(const std::vector<std::string>& words, const std::string& quote) {
    std::string out;
    for (size_t i = 0; i < words.size(); ++i) {
        if (i > 0) out += i + 1 == words.size() ? " or " : ", ";
        out += quote + words[i] + quote;
    }
    return out;
}

/// The message of a word that is none of a choice's: "is neither 'a' nor 'b'" for two words,
/// "is not 'a', 'b' or 'c'" for more.
std::string not_a_choice(const std::vector<std::string>& words) {
    if (words.size() == 2) return "is neither '" + words[0] + "' nor '" + words[1] + "'";
    return "is not " + word_list(words, "'");
}

}  // namespace

std::string OptionSpec::flag() const {
    std::string f = "--" + name;
    std::replace(f.begin(), f.end(), '_', '-');
    return f;
}

std::string OptionSpec::range_text() const {
    switch (kind) {
        case Kind::Integer:
            return "integer " + std::to_string((long long)lo) + ".." +
                   std::to_string((long long)hi);
        case Kind::Real:
            return std::string(open_lo ? "(" : "[") + number_text(lo) + ", " + number_text(hi) +
                   (open_hi ? ")" : "]");
        case Kind::Choice:
            return word_list(choices, "");
        case Kind::Switch:
            return "true or false (on or off)";
    }
    return "";
}

std::string OptionSpec::value_text(const SolverSettings& s) const {
    const double x = get(s);
    switch (kind) {
        case Kind::Integer:
            return std::to_string((long long)x);
        case Kind::Real:
            return number_text(x);
        case Kind::Choice:
            return choices[size_t(x)];
        case Kind::Switch:
            return x != 0 ? "true" : "false";
    }
    return "";
}

const std::vector<OptionSpec>& option_table() {
    static const std::vector<OptionSpec> table = make_option_table();
    return table;
}

const OptionSpec* find_option(const std::string& name) {
    for (const OptionSpec& o : option_table())
        if (o.name == name) return &o;
    return nullptr;
}

const OptionSpec* find_flag(const std::string& flag) {
    for (const OptionSpec& o : option_table()) {
        if (o.flag() == flag) return &o;
        for (const std::string& alias : o.aliases)
            if (alias == flag) return &o;
    }
    return nullptr;
}

void apply_setting(SolverSettings& s, const OptionSpec& option, const std::string& value,
                   const std::string& what, const std::string& file, int line_number) {
    const Line line{file, line_number, {}};
    switch (option.kind) {
        case Kind::Integer:
            option.set(s, double(parse_integer(line, value, what, (long long)option.lo,
                                               (long long)option.hi)));
            return;
        case Kind::Real: {
            const double x = parse_double(line, value, what);
            if (x < option.lo || x > option.hi || (option.open_lo && x == option.lo) ||
                (option.open_hi && x == option.hi))
                line.fail(what + " " + fmt(x) + " is outside " + (option.open_lo ? "(" : "[") +
                          fmt(option.lo) + ", " + fmt(option.hi) + (option.open_hi ? ")" : "]"));
            option.set(s, x);
            return;
        }
        case Kind::Choice: {
            const auto it = std::find(option.choices.begin(), option.choices.end(), value);
            if (it == option.choices.end())
                line.fail(what + " " + in_quotes(value) + " " + not_a_choice(option.choices));
            option.set(s, double(it - option.choices.begin()));
            return;
        }
        case Kind::Switch:
            // DESIGN: one switch, two spellings: scene files wrote true|false, flags on|off.
            if (value == "true" || value == "on") {
                option.set(s, 1);
            } else if (value == "false" || value == "off") {
                option.set(s, 0);
            } else {
                line.fail(what + " " + in_quotes(value) +
                          " is neither 'true' nor 'false' (or 'on', 'off')");
            }
            return;
    }
}

std::string option_usage() {
    const SolverSettings defaults;
    const size_t indent = 28, width = 100;
    std::ostringstream os;
    for (const OptionSpec& o : option_table()) {
        std::string head = "  " + o.flag() + " " + o.unit;
        for (const std::string& alias : o.aliases) head += ", " + alias + " " + o.unit;
        // The meaning, then the range and default, wrapped at `width` below `indent`.
        const std::string text = o.doc + "; " + o.range_text() + ", default " +
                                 o.value_text(defaults) + " (`set " + o.name + "`)";
        std::string line = head.size() + 1 < indent ? head + std::string(indent - head.size(), ' ')
                                                    : head + "\n" + std::string(indent, ' ');
        size_t filled = indent;  // the current output line's length
        std::istringstream words(text);
        bool first = true;
        for (std::string word; words >> word;) {
            if (!first && filled + 1 + word.size() > width) {
                line += "\n" + std::string(indent, ' ');
                filled = indent;
            } else if (!first) {
                line += ' ';
                ++filled;
            }
            line += word;
            filled += word.size();
            first = false;
        }
        os << line << "\n";
    }
    return os.str();
}

std::string option_table_markdown() {
    const SolverSettings defaults;
    std::ostringstream os;
    os << "| name | flag | type, range | default | meaning |\n"
       << "| --- | --- | --- | --- | --- |\n";
    for (const OptionSpec& o : option_table()) {
        std::string flags = "`" + o.flag() + "`";
        for (const std::string& alias : o.aliases) flags += ", `" + alias + "`";
        std::string range = o.range_text();
        if (o.kind == Kind::Choice) range = word_list(o.choices, "`");
        if (o.kind == Kind::Switch) range = "`true` or `false` (`on` or `off`)";
        os << "| `" << o.name << "` | " << flags << " | " << range << " | "
           << o.value_text(defaults) << " | " << o.doc << " |\n";
    }
    return os.str();
}

}  // namespace mbr
