// Backend option tables (docs/plugins.md, "Backend options").
//
// Every NLP backend and integrator declares the settings it owns as a table
// of OptionSpec (name, type, default, range, one-line doc), in the manner of
// CasADi's plugin options and Ceres' documented Options structs. Users give
// options as text (CLI `--nlp-opt key=value`, suite `nlp_options: {...}`);
// ResolveOptions() checks them against the table (an unknown name or an
// ill-typed / out-of-range value is std::invalid_argument naming the option
// and the known ones) and returns the options actually used: every option of
// the table, the given ones parsed and the others at their defaults (the
// "given vs used" of Ceres' Solver::Summary).
#pragma once

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace quasiroll {

enum class OptionType { kBool, kInt, kDouble, kString };
const char* ToString(OptionType type);  // "bool", "int", "double", "string"

using OptionValue = std::variant<bool, long long, double, std::string>;

struct OptionSpec {
  std::string name;  // [a-z0-9_]+, what users type
  OptionType type = OptionType::kDouble;
  OptionValue default_value = 0.0;
  // Numeric range (kInt, kDouble); an open end excludes its bound.
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool lower_open = false, upper_open = false;
  // kString: the allowed values (empty = any string).
  std::vector<std::string> choices;
  std::string doc;  // one line

  static OptionSpec Double(std::string name, double default_value,
                           std::string doc);
  static OptionSpec Int(std::string name, long long default_value,
                        std::string doc);
  static OptionSpec Bool(std::string name, bool default_value, std::string doc);
  static OptionSpec Choice(std::string name, std::string default_value,
                           std::vector<std::string> choices, std::string doc);
  // Range builders: v >= lo, v > lo, v <= hi, v < hi.
  OptionSpec& AtLeast(double lo);
  OptionSpec& GreaterThan(double lo);
  OptionSpec& AtMost(double hi);
  OptionSpec& LessThan(double hi);

  // "[0, inf)", "(0, 1]", "rk4|dp54|bs32", "true|false", "any".
  std::string RangeText() const;
  // True if v has this option's type and lies in its range / choices;
  // otherwise *why says what is wrong.
  bool Accepts(const OptionValue& v, std::string* why) const;
};

using OptionTable = std::vector<OptionSpec>;

// Options as a user gives them: name -> value text ("0.5", "adaptive",
// "true"). Ordered, so that everything printed from it is canonical.
using GivenOptions = std::map<std::string, std::string>;

// The options a backend runs with: a typed value for every option of its
// table. The getters throw std::logic_error for a name that is not there or
// has another type (a backend asking for an option it did not declare).
class OptionValues {
 public:
  bool GetBool(const std::string& name) const;
  long long GetInt(const std::string& name) const;
  double GetDouble(const std::string& name) const;
  const std::string& GetString(const std::string& name) const;

  void Set(const std::string& name, OptionValue value);
  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  bool empty() const { return values_.empty(); }
  const std::map<std::string, OptionValue>& values() const { return values_; }
  // Compact JSON object in name order, e.g. {"max_iter":50,"mu":"adaptive"};
  // numbers in shortest round-trip form. "{}" when empty.
  std::string Json() const;

 private:
  std::map<std::string, OptionValue> values_;
};

// Text of a value as it is given / printed ("0.5", "true", "adaptive").
std::string OptionValueText(const OptionValue& value);
// JSON of a value ("0.5", "true", "\"adaptive\"").
std::string OptionValueJson(const OptionValue& value);

// Parses `text` as a value of `spec` and checks its range. Throws
// std::invalid_argument "<context>: option '<name>': <problem>, got "<text>"".
OptionValue ParseOptionValue(const OptionSpec& spec, const std::string& text,
                             const std::string& context);

// Checks `given` against `table` and returns every option of the table (the
// given ones parsed, the others at their defaults). Throws
// std::invalid_argument naming the first unknown option and the known ones
// ("<context>: unknown option 'foo' (known: a, b)"), or the first ill-typed /
// out-of-range one (as ParseOptionValue). `context` names the backend, e.g.
// "NLP backend 'ipopt'".
OptionValues ResolveOptions(const OptionTable& table, const GivenOptions& given,
                            const std::string& context);

// The names of a run's own settings (the keys of the harness's RunRequest:
// dt, t_end, tol, substeps, ...). A backend option may not use one: it
// would act next to the run's setting of that name (the harness refuses
// such a backend; the conformance kit checks option tables).
const std::vector<std::string>& RunSettingNames();
// The first name of RunSettingNames() that `table` declares, "" if none.
std::string ShadowedRunSetting(const OptionTable& table);

// Names of the table, comma separated ("" for an empty table).
std::string OptionNames(const OptionTable& table);
// Finds an option by name (nullptr if absent).
const OptionSpec* FindOption(const OptionTable& table, const std::string& name);
// JSON array of the table: [{"name":..,"type":..,"default":..,"range":..,
// "doc":..}, ...] (for `quasiroll list --options --json`).
std::string OptionTableJson(const OptionTable& table);

// Splits "key=value" (CLI --nlp-opt / --dae-opt). Throws
// std::invalid_argument naming `flag` if there is no '=' or the key is empty.
std::pair<std::string, std::string> SplitKeyValue(const std::string& text,
                                                  const std::string& flag);

}  // namespace quasiroll
