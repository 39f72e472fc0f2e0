#include "quasiroll/core/options.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "quasiroll/core/backend_info.h"

namespace quasiroll {
namespace {

std::string Number(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

OptionSpec Make(std::string name, OptionType type, OptionValue def,
                std::string doc) {
  OptionSpec s;
  s.name = std::move(name);
  s.type = type;
  s.default_value = std::move(def);
  s.doc = std::move(doc);
  return s;
}

}  // namespace

const char* ToString(OptionType type) {
  switch (type) {
    case OptionType::kBool:
      return "bool";
    case OptionType::kInt:
      return "int";
    case OptionType::kDouble:
      return "double";
    case OptionType::kString:
      return "string";
  }
  return "unknown";
}

OptionSpec OptionSpec::Double(std::string name, double default_value,
                              std::string doc) {
  return Make(std::move(name), OptionType::kDouble, default_value,
              std::move(doc));
}
OptionSpec OptionSpec::Int(std::string name, long long default_value,
                           std::string doc) {
  return Make(std::move(name), OptionType::kInt, default_value, std::move(doc));
}
OptionSpec OptionSpec::Bool(std::string name, bool default_value,
                            std::string doc) {
  return Make(std::move(name), OptionType::kBool, default_value,
              std::move(doc));
}
OptionSpec OptionSpec::Choice(std::string name, std::string default_value,
                              std::vector<std::string> choices,
                              std::string doc) {
  OptionSpec s = Make(std::move(name), OptionType::kString,
                      std::move(default_value), std::move(doc));
  s.choices = std::move(choices);
  return s;
}
OptionSpec& OptionSpec::AtLeast(double lo) {
  lower = lo;
  lower_open = false;
  return *this;
}
OptionSpec& OptionSpec::GreaterThan(double lo) {
  lower = lo;
  lower_open = true;
  return *this;
}
OptionSpec& OptionSpec::AtMost(double hi) {
  upper = hi;
  upper_open = false;
  return *this;
}
OptionSpec& OptionSpec::LessThan(double hi) {
  upper = hi;
  upper_open = true;
  return *this;
}

std::string OptionSpec::RangeText() const {
  switch (type) {
    case OptionType::kBool:
      return "true|false";
    case OptionType::kString: {
      if (choices.empty()) return "any";
      std::string out;
      for (const std::string& c : choices) out += (out.empty() ? "" : "|") + c;
      return out;
    }
    case OptionType::kInt:
    case OptionType::kDouble: {
      auto bound = [](double v) {
        if (std::isinf(v)) return std::string(v < 0 ? "-inf" : "inf");
        return Number(v);
      };
      return std::string(lower_open || std::isinf(lower) ? "(" : "[") +
             bound(lower) + ", " + bound(upper) +
             (upper_open || std::isinf(upper) ? ")" : "]");
    }
  }
  return "";
}

bool OptionSpec::Accepts(const OptionValue& v, std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  switch (type) {
    case OptionType::kBool:
      if (!std::holds_alternative<bool>(v)) return fail("expected true|false");
      return true;
    case OptionType::kString: {
      if (!std::holds_alternative<std::string>(v))
        return fail("expected a string");
      if (choices.empty()) return true;
      for (const std::string& c : choices)
        if (c == std::get<std::string>(v)) return true;
      return fail("expected one of " + RangeText());
    }
    case OptionType::kInt:
    case OptionType::kDouble: {
      double x = 0;
      if (type == OptionType::kInt) {
        if (!std::holds_alternative<long long>(v))
          return fail("expected an integer");
        x = static_cast<double>(std::get<long long>(v));
      } else {
        if (!std::holds_alternative<double>(v))
          return fail("expected a number");
        x = std::get<double>(v);
        if (!std::isfinite(x)) return fail("expected a finite number");
      }
      const bool lo_ok = lower_open ? x > lower : x >= lower;
      const bool hi_ok = upper_open ? x < upper : x <= upper;
      if (!lo_ok || !hi_ok) return fail("must be in " + RangeText());
      return true;
    }
  }
  return fail("unknown type");
}

std::string OptionValueText(const OptionValue& value) {
  if (std::holds_alternative<bool>(value))
    return std::get<bool>(value) ? "true" : "false";
  if (std::holds_alternative<long long>(value))
    return std::to_string(std::get<long long>(value));
  if (std::holds_alternative<double>(value))
    return Number(std::get<double>(value));
  return std::get<std::string>(value);
}

std::string OptionValueJson(const OptionValue& value) {
  if (std::holds_alternative<std::string>(value))
    return JsonString(std::get<std::string>(value));
  return OptionValueText(value);
}

namespace {
const OptionValue& Lookup(const std::map<std::string, OptionValue>& values,
                          const std::string& name) {
  const auto it = values.find(name);
  if (it == values.end())
    throw std::logic_error("backend option '" + name + "' is not in its table");
  return it->second;
}
template <typename T>
const T& Typed(const std::map<std::string, OptionValue>& values,
               const std::string& name) {
  const OptionValue& v = Lookup(values, name);
  if (!std::holds_alternative<T>(v))
    throw std::logic_error("backend option '" + name + "' has another type");
  return std::get<T>(v);
}
}  // namespace

bool OptionValues::GetBool(const std::string& name) const {
  return Typed<bool>(values_, name);
}
long long OptionValues::GetInt(const std::string& name) const {
  return Typed<long long>(values_, name);
}
double OptionValues::GetDouble(const std::string& name) const {
  return Typed<double>(values_, name);
}
const std::string& OptionValues::GetString(const std::string& name) const {
  return Typed<std::string>(values_, name);
}
void OptionValues::Set(const std::string& name, OptionValue value) {
  values_[name] = std::move(value);
}

std::string OptionValues::Json() const {
  std::string out = "{";
  for (const auto& [name, value] : values_) {
    if (out.size() > 1) out += ",";
    out += JsonString(name) + ":" + OptionValueJson(value);
  }
  return out + "}";
}

OptionValue ParseOptionValue(const OptionSpec& spec, const std::string& text,
                             const std::string& context) {
  auto fail = [&](const std::string& problem) -> OptionValue {
    throw std::invalid_argument(context + ": option '" + spec.name +
                                "': " + problem + ", got \"" + text + "\"");
  };
  OptionValue v;
  switch (spec.type) {
    case OptionType::kBool:
      if (text == "true" || text == "1") {
        v = true;
      } else if (text == "false" || text == "0") {
        v = false;
      } else {
        return fail("expected true|false");
      }
      break;
    case OptionType::kInt: {
      long long x = 0;
      const char* end = text.data() + text.size();
      const auto res = std::from_chars(text.data(), end, x);
      if (text.empty() || res.ec != std::errc() || res.ptr != end)
        return fail("expected an integer");
      v = x;
      break;
    }
    case OptionType::kDouble: {
      double x = 0;
      const char* end = text.data() + text.size();
      const auto res = std::from_chars(text.data(), end, x);
      if (text.empty() || res.ec != std::errc() || res.ptr != end ||
          !std::isfinite(x))
        return fail("expected a finite number");
      v = x;
      break;
    }
    case OptionType::kString:
      v = text;
      break;
  }
  std::string why;
  if (!spec.Accepts(v, &why)) return fail(why);
  return v;
}

std::string OptionNames(const OptionTable& table) {
  std::string out;
  for (const OptionSpec& s : table) out += (out.empty() ? "" : ", ") + s.name;
  return out;
}

const OptionSpec* FindOption(const OptionTable& table,
                             const std::string& name) {
  for (const OptionSpec& s : table)
    if (s.name == name) return &s;
  return nullptr;
}

OptionValues ResolveOptions(const OptionTable& table, const GivenOptions& given,
                            const std::string& context) {
  for (const auto& [name, text] : given) {
    if (FindOption(table, name) == nullptr) {
      throw std::invalid_argument(
          context + ": unknown option '" + name + "' (known: " +
          (table.empty() ? std::string("none") : OptionNames(table)) + ")");
    }
  }
  OptionValues out;
  for (const OptionSpec& s : table) {
    const auto it = given.find(s.name);
    out.Set(s.name, it == given.end()
                        ? s.default_value
                        : ParseOptionValue(s, it->second, context));
  }
  return out;
}

std::string OptionTableJson(const OptionTable& table) {
  std::string out = "[";
  for (const OptionSpec& s : table) {
    if (out.size() > 1) out += ",";
    out += "{\"name\":" + JsonString(s.name) +
           ",\"type\":" + JsonString(ToString(s.type)) +
           ",\"default\":" + OptionValueJson(s.default_value) +
           ",\"range\":" + JsonString(s.RangeText()) +
           ",\"doc\":" + JsonString(s.doc) + "}";
  }
  return out + "]";
}

std::pair<std::string, std::string> SplitKeyValue(const std::string& text,
                                                  const std::string& flag) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument(flag + ": expected key=value, got \"" + text +
                                "\"");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

BackendInfo ThreadSafeBackendInfo(std::string description, std::string family,
                                  std::string library,
                                  std::string library_version) {
  BackendInfo info;
  info.description = std::move(description);
  info.family = std::move(family);
  info.library = std::move(library);
  info.library_version = std::move(library_version);
  info.thread_safe = true;
  return info;
}

const char* ToString(BackendRole role) {
  switch (role) {
    case BackendRole::kDefault:
      return "default";
    case BackendRole::kReference:
      return "reference";
    case BackendRole::kReferenceCheck:
      return "reference_check";
    case BackendRole::kContinuation:
      return "continuation";
  }
  return "?";
}

const std::vector<std::string>& RunSettingNames() {
  static const std::vector<std::string> names = {"mu",
                                                 "eps",
                                                 "mode",
                                                 "nlp",
                                                 "dae",
                                                 "coupling",
                                                 "dt",
                                                 "t_end",
                                                 "tol",
                                                 "atol",
                                                 "nlp_tol",
                                                 "nlp_max_iter",
                                                 "substeps",
                                                 "contact_check",
                                                 "locate_events",
                                                 "event_points",
                                                 "event_tolerance",
                                                 "locate_switches"};
  return names;
}

std::string ShadowedRunSetting(const OptionTable& table) {
  for (const std::string& name : RunSettingNames())
    if (FindOption(table, name) != nullptr) return name;
  return "";
}

}  // namespace quasiroll
