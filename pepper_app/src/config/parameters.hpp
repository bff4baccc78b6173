#pragma once
// The configuration declared once (STYLE.md 2.12): one row per parameter of AppConfig with its
// dotted key, type, unit, range and a one-line doc. Everything else comes from this table: the
// JSON/YAML reader and `--set` (type checks, unknown keys with the closest known key), the
// range checks (AppConfig::validate runs them before the core's own validate()), config_to_json
// and `pepper_app config dump`, and the Markdown reference docs/configuration.md
// (`pepper_app config doc`).
//
// Defaults are NOT in the table: they are the options structs' in-class defaults, read from a
// default-constructed AppConfig, so each default is written once, next to the code that uses it.
//
// Ranges are written once as text and parsed once (when the table is built):
//   "[0, 1)", "(0, inf)", "[1, 100000]", "(0, pi/2]"   an interval; "inf", "pi" and "pi/N" allowed
//   "0 (off) or [1, inf)"                              alternatives joined by " or "; a single
//                                                      value may carry a label in parentheses
//   "320 (QVGA) or 640 (VGA)"                          a set of values
//   "[1, max_iterations]"                              a bound named by a parameter of the same
//                                                      section (cross-field rule)
//   ""                                                 any value (bool, string, enum)
// Thread-safety: the table is built once on first use (a function-local static) and read-only.

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace pepper::app {

struct AppConfig;

/// A parameter's allowed values, parsed from its text once.
class Range {
 public:
  Range() = default;  ///< any value
  /// Throws std::invalid_argument naming the text when it does not parse.
  explicit Range(std::string text);

  const std::string& text() const { return text_; }
  bool empty() const { return alternatives_.empty(); }
  /// Names of the parameters used as bounds (same section), in order of appearance.
  std::vector<std::string> references() const;
  /// Whether `value` is allowed; `lookup` gives the value of a referenced parameter.
  bool contains(double value, const std::function<double(const std::string&)>& lookup) const;
  /// "in [0, 1)", "0 (off) or in [1, inf)", "320 (QVGA) or 640 (VGA)".
  std::string describe() const;

 private:
  struct Bound {
    double value = 0.0;
    std::string reference;  ///< non-empty: the value of this parameter
  };
  struct Alternative {
    Bound low, high;  ///< equal (and both closed) for a single value
    bool low_open = false, high_open = false;
    bool single = false;
    std::string text;  ///< as written, e.g. "[1, inf)" or "0 (off)"
  };
  static Bound parse_bound(std::string_view text, const std::string& whole);
  static Alternative parse_alternative(std::string_view text, const std::string& whole);

  std::string text_;
  std::vector<Alternative> alternatives_;
};

enum class ParamType { kBool, kInt, kInt64, kUint64, kFloat, kDouble, kString, kEnum };

struct Parameter {
  std::string key;  ///< full dotted key, e.g. "navigator.vnhv.kp_1_m2"
  ParamType type = ParamType::kDouble;
  std::vector<std::string> enum_names;  ///< kEnum: the names accepted and written
  std::string unit;                     ///< "m/s", "rad", "px", "ns", ... ("" for none)
  Range range;
  std::string doc;  ///< one line
  /// The value in `config` as JSON (enums by name).
  std::function<nlohmann::json(const AppConfig&)> get;
  /// Stores `value` in `config` after checking its type; returns the problem ("must be a whole
  /// number, got \"fast\"") or "" when stored.
  std::function<std::string(AppConfig&, const nlohmann::json&)> set;

  std::string section() const;    ///< the key without its last component ("navigator.vnhv")
  std::string name() const;       ///< the last component ("kp_1_m2")
  std::string type_name() const;  ///< "bool", "int", "int64", "uint64", "float", "double", ...
  bool numeric() const;
};

/// Every parameter of AppConfig, in file order (sections together). Built once.
const std::vector<Parameter>& parameters();

/// The row with this dotted key, or nullptr.
const Parameter* find_parameter(std::string_view key);

/// Whether `key` is a section (a proper prefix of some parameter's key, e.g. "features.matcher").
bool is_section(std::string_view key);

/// The known key (parameter or section) closest to an unknown `key`: the parameter of that name
/// in another section ("navigator.kp_1_m2" -> "navigator.vnhv.kp_1_m2"); else, among the keys of
/// the same section, the shortest that begins with the typed name ("kp"), else the nearest by
/// edit distance ("gg1" -> "g1"); first in table order among equals.
std::string closest_key(std::string_view key);

/// One line per section, in table order: {section, what it configures}.
const std::vector<std::pair<std::string, std::string>>& section_docs();

/// Every numeric parameter outside its range, each as
/// "navigator.vnhv.kp_1_m2 = -1: must be in (0, inf) (1/m^2)"; empty when all are in range.
std::vector<std::string> check_ranges(const AppConfig& config);

/// A named set of values that travel together (OpenCV's presets), applied over the defaults
/// before the configuration file and --set.
struct Preset {
  std::string name;
  std::string doc;
  std::vector<std::string> sets;  ///< "dotted.key=value", as --set
};

const std::vector<Preset>& presets();

/// The preset called `name`, or nullptr.
const Preset* find_preset(std::string_view name);

}  // namespace pepper::app
