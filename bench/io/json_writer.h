// Minimal streaming JSON writer for the CLI's --json output and run.json.
// Doubles are written with 17 significant digits (round-trip exact); NaN and
// Inf, which JSON cannot hold, are written as null.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace quasiroll {

class JsonWriter {
 public:
  JsonWriter& BeginObject() { return Open('{'); }
  JsonWriter& EndObject() { return Close('}'); }
  JsonWriter& BeginArray() { return Open('['); }
  JsonWriter& EndArray() { return Close(']'); }

  JsonWriter& Key(const std::string& key) {
    Separator();
    AppendString(key);
    out_ += ':';
    after_key_ = true;
    return *this;
  }
  JsonWriter& Value(double v) {
    Separator();
    if (!std::isfinite(v)) {
      out_ += "null";
    } else {
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%.17g", v);
      out_ += buf;
    }
    return *this;
  }
  // An unknown value (docs/cli.md: null, never a zero that looks like data).
  JsonWriter& Null() {
    Separator();
    out_ += "null";
    return *this;
  }
  JsonWriter& Value(int v) {
    Separator();
    out_ += std::to_string(v);
    return *this;
  }
  JsonWriter& Value(long long v) {
    Separator();
    out_ += std::to_string(v);
    return *this;
  }
  JsonWriter& Value(bool v) {
    Separator();
    out_ += v ? "true" : "false";
    return *this;
  }
  JsonWriter& Value(const std::string& v) {
    Separator();
    AppendString(v);
    return *this;
  }
  JsonWriter& Value(const char* v) { return Value(std::string(v)); }
  template <typename Vector>
  JsonWriter& Array(const Vector& values) {
    BeginArray();
    for (Eigen_Index_t i = 0; i < static_cast<Eigen_Index_t>(values.size());
         ++i)
      Value(static_cast<double>(values[i]));
    return EndArray();
  }

  const std::string& str() const { return out_; }

 private:
  using Eigen_Index_t = long;
  JsonWriter& Open(char c) {
    Separator();
    out_ += c;
    first_.push_back(true);
    return *this;
  }
  JsonWriter& Close(char c) {
    out_ += c;
    first_.pop_back();
    return *this;
  }
  void Separator() {
    if (after_key_) {
      after_key_ = false;
      return;
    }
    if (!first_.empty()) {
      if (!first_.back()) out_ += ',';
      first_.back() = false;
    }
  }
  void AppendString(const std::string& s) {
    out_ += '"';
    for (char c : s) {
      switch (c) {
        case '"':
          out_ += "\\\"";
          break;
        case '\\':
          out_ += "\\\\";
          break;
        case '\n':
          out_ += "\\n";
          break;
        case '\t':
          out_ += "\\t";
          break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof(buf), "\\u%04x", c);
            out_ += buf;
          } else {
            out_ += c;
          }
      }
    }
    out_ += '"';
  }

  std::string out_;
  std::vector<bool> first_;
  bool after_key_ = false;
};

// `s` as a JSON string literal, quoted and escaped as JsonWriter writes it.
inline std::string JsonQuote(const std::string& s) {
  JsonWriter w;
  w.Value(s);
  return w.str();
}

}  // namespace quasiroll
