// radiosity/scene/settings.h - the solver settings a user can give, and the option table that
// says each one once: its name, kind, range, default and meaning. The scene's `set NAME VALUE`
// lines, the command-line flags (`--NAME` with '-' for '_', plus older spellings kept as
// aliases), the usage text and the table in docs/scene-format.md all come from option_table();
// radiosity/solver/solver.h turns the settings into the solver's options (solver_options()).
//
// DESIGN: the table lives here, beside the settings it fills, and not in radiosity/solver/: the
// scene reader reads `set` lines, and scene/ is below solver/ (docs/method.md, "Layout").
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace mbr {

/// How visibility enters a transfer (radiosity/transfer's ShadowMethod, as the user names it).
enum class ShadowSetting {
    Exact,  // "exact": visibility inside (21), the visible part of the shooter (beyond the paper)
    Paper,  // "paper": fractions (28) at the fulcrums, shadow subdivision and masking
    None,   // "none": no shadows
    Auto    // "auto": exact, except for a pair with many shadow casters between it, which
            //   takes the paper's (SolverOptions::exact_shadow_casters)
};
/// How the increment is continued outside [0,1]^2 (section 6, "Extrapolation").
enum class ExtrapolationSetting {
    Linear,  // "linear": eqs. (23)-(25)
    Higher   // "higher": eqs. (26)-(27)
};
/// How stage 8 brings the coefficients to one scale.
enum class UnifySetting {
    Projection,  // "projection": every finest-scale coefficient projected on the fine grid
    Paper        // "paper": (17) from the selected fulcrums
};
/// The oracle's test (OracleTest), everywhere and in receiver cells that touch a planar shooter.
enum class OracleSetting {
    Hybrid,         // "hybrid": the means where the relative tolerance governs, the fit where
                    //   the absolute tolerance does
    Interpolation,  // "interpolation": the polynomial through the m^2 samples predicts the others
    Means           // "means": the paper's two means
};

/// How a fraction (28) counts the rays to one patch of the shooter.
enum class FractionRaysSetting {
    Kernel,  // "kernel": each ray weighted by the kernel (3) times A (4) at its end
    Area     // "area": the share of rays that arrive (the paper's)
};

/// What a surface with a textured reflectance stores as its spline field.
enum class TextureFieldSetting {
    Irradiance,  // "irradiance": H, with B = E + rho H formed at samples and pixels
    Radiosity    // "radiosity": B itself (the paper's representation)
};

/// The settings of the progressive loop (section 4) and of one transfer (section 5). The
/// initial values are the defaults; option_table() describes each field.
struct SolverSettings {
    int order = 4;                   // B-spline order m (degree m - 1); the paper uses 4 and 3
    int min_depth = 1;               // oracle quadtree bounds; min = max = d is uniform
    int max_depth = 6;               //   (d = subdivisions below the root: leaves 2^-d wide)
    double oracle_tolerance = 1e-3;  // relative agreement of the two Gauss-Legendre rules
    double truncation_eps = 1e-6;    // relative cut-off of |DN x DN| (rhombus, Figure 3)
    double rhombus_radius = 0;       // in cells; 0: derived from truncation_eps
    ExtrapolationSetting extrapolation = ExtrapolationSetting::Linear;
    int shadow_rays = 4;        // rays per fulcrum per shooter patch, eq. (28)
    int max_shots = 100;        // cap on progressive shots
    double convergence = 1e-3;  // stop when the largest unshot power < this x emitted
    bool self_transfer = true;  // a surface that can see itself (concave curved) lights itself
    bool cluster_shots = false;  // coplanar neighbours with a share of the shooter's unshot
                                 //   power shoot with it (a planar cluster)
    int tessellation = 16;      // facets per parameter direction for ray casting
    ShadowSetting shadows = ShadowSetting::Auto;
    double tolerance = 2e-3;  // accuracy relative to the scene's radiosity scale
    UnifySetting unify = UnifySetting::Projection;
    bool ambient = true;        // ambient correction of the unshot power at the end
    int ambient_rays = 256;     //   gathered by this many rays per Gauss point (0: a constant)
    int ambient_level = 1;      //   at the Gauss points of this level's cells
    bool ambient_final = true;  //   and bright surfaces once more, finer (the final gather)
    bool limiter = true;        // increments and final fields clipped to their physical bounds
    bool hidden = true;         // hidden regions take their visible neighbours' values
    int shooter_level = 4;      // a shooter's unshot field coarsened to at most this level
    int contact_depth = 2;      // receiver cells touching a planar shooter split to at
                                //   least this level (0: off)
    OracleSetting oracle = OracleSetting::Hybrid;
    OracleSetting contact_oracle = OracleSetting::Interpolation;
    double weak_transfer = 0.3;  // a transfer whose root samples are below this many
                                 //   tolerances takes the level-0 field through them (0: off)
    TextureFieldSetting texture_field = TextureFieldSetting::Irradiance;
    FractionRaysSetting fraction_rays = FractionRaysSetting::Kernel;
};

/// One row of the option table.
struct OptionSpec {
    enum class Kind {
        Integer,  // a whole number in [lo, hi]
        Real,     // a finite number in the interval lo..hi, open at an end when asked
        Choice,   // one of `choices`, in the order of the field's enum
        Switch    // true or false (on and off are accepted too)
    };
    std::string name;                  // `set NAME VALUE`; the flag is --NAME with '-' for '_'
    std::vector<std::string> aliases;  // further flags accepted (the older spellings)
    Kind kind = Kind::Integer;
    double lo = 0, hi = 0;                  // Integer and Real: the range
    bool open_lo = false, open_hi = false;  // Real: the range excludes lo, hi
    std::vector<std::string> choices;       // Choice: the words
    std::string unit;                       // placeholder in the usage text ("m", "d", "x", ...)
    std::string doc;                        // one line: what it means
    /// Writes a parsed value into the settings: Integer and Real the number, Choice the index
    /// of the word, Switch 1 or 0.
    std::function<void(SolverSettings&, double)> set;
    /// Reads the field back in the same form.
    std::function<double(const SolverSettings&)> get;

    /// The command-line flag: "--" + name with '_' written '-' ("--max-shots").
    std::string flag() const;
    /// The range as a reader sees it: "integer 2..8", "(0, 1]", "exact, paper or none",
    /// "true or false".
    std::string range_text() const;
    /// The field's value in `s` as a `set` line would spell it ("4", "0.001", "exact", "true").
    std::string value_text(const SolverSettings& s) const;
};

/// Every option, in the order the documentation lists them.
const std::vector<OptionSpec>& option_table();

/// The row called `name` (a `set` name), or nullptr.
const OptionSpec* find_option(const std::string& name);

/// The row whose flag or alias is `flag` ("--max-shots", "--shots"), or nullptr.
const OptionSpec* find_flag(const std::string& flag);

/// Parses `value` for `option` and writes it into `s`. On a bad value throws InputError(file,
/// line, message) with the message naming the option as `what` (a `set` name or the flag
/// used): "order '9' is outside [2, 8]", "shadows 'soft' is not 'exact', 'paper' or 'none'".
void apply_setting(SolverSettings& s, const OptionSpec& option, const std::string& value,
                   const std::string& what, const std::string& file = "", int line = 0);

/// The usage lines of every option's flag: flag and placeholder, meaning, range, default and the
/// `set` name.
std::string option_usage();

/// The documentation table (Markdown: name, flag, type and range, default, meaning), as
/// docs/scene-format.md holds it between its option-table markers.
std::string option_table_markdown();

}  // namespace mbr
