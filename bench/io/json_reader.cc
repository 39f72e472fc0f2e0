#include "quasiroll/bench/io/json_reader.h"

#include <cstdlib>

namespace quasiroll {

namespace {

[[noreturn]] void WrongType(const char* wanted, const JsonValue& v) {
  throw JsonError("JSON value " + v.raw() + " is not " + wanted);
}

void AppendUtf8(unsigned code, std::string* out) {
  if (code < 0x80) {
    *out += static_cast<char>(code);
  } else if (code < 0x800) {
    *out += static_cast<char>(0xC0 | (code >> 6));
    *out += static_cast<char>(0x80 | (code & 0x3F));
  } else if (code < 0x10000) {
    *out += static_cast<char>(0xE0 | (code >> 12));
    *out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    *out += static_cast<char>(0x80 | (code & 0x3F));
  } else {
    *out += static_cast<char>(0xF0 | (code >> 18));
    *out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
    *out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
    *out += static_cast<char>(0x80 | (code & 0x3F));
  }
}

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

bool JsonValue::boolean() const {
  if (type_ != Type::kBool) WrongType("a boolean", *this);
  return raw_ == "true";
}

double JsonValue::number() const {
  if (type_ != Type::kNumber) WrongType("a number", *this);
  return std::strtod(raw_.c_str(), nullptr);
}

const std::string& JsonValue::str() const {
  if (type_ != Type::kString) WrongType("a string", *this);
  return string_;
}

const std::vector<JsonValue>& JsonValue::items() const {
  if (type_ != Type::kArray) WrongType("an array", *this);
  return items_;
}

const std::vector<JsonValue::Member>& JsonValue::members() const {
  if (type_ != Type::kObject) WrongType("an object", *this);
  return members_;
}

const JsonValue* JsonValue::Find(std::string_view key) const {
  for (const auto& [k, v] : members_)
    if (k == key) return &v;
  return nullptr;
}

// Recursive descent over the text; `pos_` is the next unread character.
class JsonParser {
 public:
  JsonParser(std::string_view text, const std::string& source)
      : text_(text), source_(source) {}

  JsonValue ParseDocument() {
    SkipSpace();
    JsonValue v = ParseValue(0);
    SkipSpace();
    if (pos_ < text_.size()) Fail("unexpected text after the value");
    return v;
  }

 private:
  // Deeper nesting than the harness ever writes; guards the stack.
  static constexpr int kMaxDepth = 256;

  [[noreturn]] void Fail(const std::string& why) const {
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < pos_ && i < text_.size(); ++i) {
      if (text_[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    throw JsonError((source_.empty() ? "" : source_ + ": ") +
                    "malformed JSON at line " + std::to_string(line) +
                    ", column " + std::to_string(column) + ": " + why);
  }

  bool AtEnd() const { return pos_ >= text_.size(); }
  char Peek() const { return AtEnd() ? '\0' : text_[pos_]; }

  void SkipSpace() {
    while (!AtEnd() && (text_[pos_] == ' ' || text_[pos_] == '\n' ||
                        text_[pos_] == '\r' || text_[pos_] == '\t'))
      ++pos_;
  }

  void Expect(char c, const char* why) {
    if (Peek() != c) Fail(why);
    ++pos_;
  }

  JsonValue ParseValue(int depth) {
    if (depth > kMaxDepth) Fail("nested too deeply");
    const std::size_t start = pos_;
    JsonValue v;
    switch (Peek()) {
      case '{':
        ParseObject(depth, &v);
        break;
      case '[':
        ParseArray(depth, &v);
        break;
      case '"':
        v.type_ = JsonValue::Type::kString;
        v.string_ = ParseString();
        break;
      case 't':
        ParseWord("true", JsonValue::Type::kBool, &v);
        break;
      case 'f':
        ParseWord("false", JsonValue::Type::kBool, &v);
        break;
      case 'n':
        ParseWord("null", JsonValue::Type::kNull, &v);
        break;
      default:
        if (Peek() != '-' && !IsDigit(Peek()))
          Fail(AtEnd() ? "value expected at the end" : "value expected");
        ParseNumber(&v);
    }
    v.raw_ = std::string(text_.substr(start, pos_ - start));
    return v;
  }

  // The comma-separated items up to `close` of the object or array opened at
  // pos_; `read_item` reads one.
  template <typename ReadItem>
  void ParseItems(char close, const char* why, ReadItem read_item) {
    ++pos_;  // '{' or '['
    SkipSpace();
    if (Peek() == close) {
      ++pos_;
      return;
    }
    for (;;) {
      read_item();
      SkipSpace();
      if (Peek() != ',') break;
      ++pos_;
      SkipSpace();
    }
    Expect(close, why);
  }

  void ParseObject(int depth, JsonValue* v) {
    v->type_ = JsonValue::Type::kObject;
    ParseItems('}', "',' or '}' expected", [&] {
      if (Peek() != '"') Fail("key expected");
      std::string key = ParseString();
      SkipSpace();
      Expect(':', "':' expected");
      SkipSpace();
      v->members_.emplace_back(std::move(key), ParseValue(depth + 1));
    });
  }

  void ParseArray(int depth, JsonValue* v) {
    v->type_ = JsonValue::Type::kArray;
    ParseItems(']', "',' or ']' expected",
               [&] { v->items_.push_back(ParseValue(depth + 1)); });
  }

  void ParseWord(std::string_view word, JsonValue::Type type, JsonValue* v) {
    if (text_.substr(pos_, word.size()) != word) Fail("value expected");
    pos_ += word.size();
    v->type_ = type;
  }

  // -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?
  void ParseNumber(JsonValue* v) {
    v->type_ = JsonValue::Type::kNumber;
    if (Peek() == '-') ++pos_;
    if (Peek() == '0') {
      ++pos_;
    } else if (IsDigit(Peek())) {
      while (IsDigit(Peek())) ++pos_;
    } else {
      Fail("digit expected");
    }
    if (Peek() == '.') {
      ++pos_;
      if (!IsDigit(Peek())) Fail("digit expected after '.'");
      while (IsDigit(Peek())) ++pos_;
    }
    if (Peek() == 'e' || Peek() == 'E') {
      ++pos_;
      if (Peek() == '+' || Peek() == '-') ++pos_;
      if (!IsDigit(Peek())) Fail("digit expected in the exponent");
      while (IsDigit(Peek())) ++pos_;
    }
  }

  unsigned ParseHex4() {
    unsigned code = 0;
    for (int k = 0; k < 4; ++k, ++pos_) {
      const char c = Peek();
      code <<= 4;
      if (IsDigit(c))
        code |= static_cast<unsigned>(c - '0');
      else if (c >= 'a' && c <= 'f')
        code |= static_cast<unsigned>(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F')
        code |= static_cast<unsigned>(c - 'A' + 10);
      else
        Fail("four hex digits expected after \\u");
    }
    return code;
  }

  // \uXXXX (a surrogate pair is one code point); pos_ is after the 'u'.
  unsigned ParseUnicodeEscape() {
    const unsigned code = ParseHex4();
    if (code >= 0xDC00 && code <= 0xDFFF) Fail("unpaired low surrogate");
    if (code < 0xD800 || code > 0xDBFF) return code;
    if (text_.substr(pos_, 2) != "\\u") Fail("unpaired high surrogate");
    pos_ += 2;
    const unsigned low = ParseHex4();
    if (low < 0xDC00 || low > 0xDFFF) Fail("unpaired high surrogate");
    return 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
  }

  char SimpleEscape(char c) {
    switch (c) {
      case '"':
      case '\\':
      case '/':
        return c;
      case 'b':
        return '\b';
      case 'f':
        return '\f';
      case 'n':
        return '\n';
      case 'r':
        return '\r';
      case 't':
        return '\t';
    }
    Fail(std::string("unknown escape \\") + c);
  }

  std::string ParseString() {
    ++pos_;  // opening quote
    std::string out;
    for (;;) {
      if (AtEnd()) Fail("unterminated string");
      const char c = text_[pos_];
      if (c == '"') {
        ++pos_;
        return out;
      }
      if (static_cast<unsigned char>(c) < 0x20)
        Fail("control character in a string");
      ++pos_;
      if (c != '\\') {
        out += c;
        continue;
      }
      if (AtEnd()) Fail("unterminated string");
      const char e = text_[pos_++];
      if (e == 'u')
        AppendUtf8(ParseUnicodeEscape(), &out);
      else
        out += SimpleEscape(e);
    }
  }

  std::string_view text_;
  const std::string& source_;
  std::size_t pos_ = 0;
};

JsonValue ParseJson(std::string_view text, const std::string& source) {
  return JsonParser(text, source).ParseDocument();
}

}  // namespace quasiroll
