// Reads the JSON the harness writes (meta.json, run.json, the reference
// cache's .json; bench/io/json_writer.h) into a small value tree.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace quasiroll {

// Malformed JSON, or a value read as the wrong type. The message names the
// source (a file path, when given) and the line and column.
class JsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JsonValue {
 public:
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };
  using Member = std::pair<std::string, JsonValue>;

  Type type() const { return type_; }
  bool is_null() const { return type_ == Type::kNull; }
  bool is_bool() const { return type_ == Type::kBool; }
  bool is_number() const { return type_ == Type::kNumber; }
  bool is_string() const { return type_ == Type::kString; }
  bool is_array() const { return type_ == Type::kArray; }
  bool is_object() const { return type_ == Type::kObject; }

  // The exact text the value was read from (a number as written, a string
  // with its quotes and escapes, an object with its spacing): merged outputs
  // copy values byte for byte through it.
  const std::string& raw() const { return raw_; }
  // Typed access; each throws JsonError on a value of another type.
  bool boolean() const;
  double number() const;           // strtod of the text: exact for %.17g output
  const std::string& str() const;  // escapes decoded (\uXXXX to UTF-8)
  const std::vector<JsonValue>& items() const;
  const std::vector<Member>& members() const;  // in file order

  // The first member named `key`; null if there is none or this is not an
  // object.
  const JsonValue* Find(std::string_view key) const;

 private:
  friend class JsonParser;
  Type type_ = Type::kNull;
  std::string raw_;
  std::string string_;  // kString: the decoded text
  std::vector<JsonValue> items_;
  std::vector<Member> members_;
};

// Parses one JSON value (surrounding white space allowed, nothing else).
// Throws JsonError "SOURCE: malformed JSON at line L, column C: WHY" (no
// "SOURCE: " when `source` is empty).
JsonValue ParseJson(std::string_view text, const std::string& source = "");

}  // namespace quasiroll
