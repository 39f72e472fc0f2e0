#include "quasiroll/core/yaml_util.h"

#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <system_error>

namespace quasiroll::yaml {
namespace {

bool IsQuoted(const YAML::Node& node) {
  // yaml-cpp tags quoted (and otherwise non-plain) scalars with "!" and plain
  // ones with "?".
  return node.Tag() == "!";
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return s;
}

std::string Join(std::initializer_list<std::string_view> items) {
  std::string s;
  for (std::string_view item : items) {
    if (!s.empty()) s += ", ";
    s += item;
  }
  return s;
}

}  // namespace

std::string FormatNumber(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

std::string JoinKey(const std::string& path, std::string_view key) {
  if (path.empty()) return std::string(key);
  return path + "." + std::string(key);
}

std::string JoinIndex(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

std::string DescribeNode(const YAML::Node& node) {
  if (!node.IsDefined()) return "nothing";
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "null";
    case YAML::NodeType::Scalar: {
      std::string s = node.Scalar();
      if (s.size() > 60) s = s.substr(0, 57) + "...";
      return "\"" + s + "\"";
    }
    case YAML::NodeType::Sequence:
      return "a sequence of " + std::to_string(node.size());
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Undefined:
      break;
  }
  return "nothing";
}

void Fail(const std::string& path, const std::string& problem) {
  throw SceneError(path.empty() ? problem : path + ": " + problem);
}

namespace {
// Counts the documents of a stream without building nodes; records where the
// last one started.
class DocumentCounter final : public YAML::EventHandler {
 public:
  int documents = 0;
  YAML::Mark last_start;
  void OnDocumentStart(const YAML::Mark& mark) override {
    ++documents;
    last_start = mark;
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};
}  // namespace

YAML::Node ParseYaml(const std::string& text, const std::string& origin) {
  const std::string where = origin.empty() ? "<string>" : origin;
  auto syntax_error = [&where](const YAML::Mark& mark, const std::string& msg) {
    std::string loc = where;
    if (!mark.is_null()) {
      loc += ":" + std::to_string(mark.line + 1) + ":" +
             std::to_string(mark.column + 1);
    }
    return SceneError(loc + ": YAML syntax error: " + msg);
  };
  // Not YAML::LoadAll(): yaml-cpp 0.7 loops forever, allocating, on streams
  // with a token no document can start with (",}", ", a: b}";
  // jbeder/yaml-cpp#1040, fixed upstream after 0.8 by PR #1319): it returns
  // empty documents that all start at the same token. Found by
  // tests/fuzz/fuzz_scene. So count documents first, stopping when one starts
  // where the previous one did, then load the single document.
  YAML::Node root;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentCounter counter;
    int previous_start = 0;
    while (parser.HandleNextDocument(counter)) {
      if (counter.documents > 1 && counter.last_start.pos == previous_start)
        throw syntax_error(counter.last_start, "unexpected token");
      previous_start = counter.last_start.pos;
    }
    if (counter.documents == 0) return YAML::Node(YAML::NodeType::Null);
    if (counter.documents > 1) {
      throw SceneError(where + ": expected a single YAML document, got " +
                       std::to_string(counter.documents));
    }
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw syntax_error(e.mark, e.msg);
  }
  return root;
}

YAML::Node LoadYamlFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw SceneError(path + ": cannot read file");
  return ParseYaml(ss.str(), path);
}

void CheckKeys(const YAML::Node& node, const std::string& path,
               std::initializer_list<std::string_view> allowed) {
  if (node.IsNull()) return;
  if (!node.IsMap()) {
    Fail(path, "expected a mapping, got " + DescribeNode(node));
  }
  std::set<std::string> seen;
  for (const auto& kv : node) {
    if (!kv.first.IsScalar()) {
      Fail(path, "keys must be plain strings, got " + DescribeNode(kv.first));
    }
    const std::string key = kv.first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      Fail(JoinKey(path, key), "unknown key (allowed: " + Join(allowed) + ")");
    }
    if (!seen.insert(key).second) Fail(JoinKey(path, key), "duplicate key");
  }
}

std::optional<YAML::Node> Child(const YAML::Node& map, std::string_view key) {
  if (!map.IsMap()) return std::nullopt;
  const YAML::Node child = map[std::string(key)];
  if (!child.IsDefined()) return std::nullopt;
  return child;
}

YAML::Node Require(const YAML::Node& map, const std::string& path,
                   std::string_view key) {
  std::optional<YAML::Node> child = Child(map, key);
  if (!child) Fail(JoinKey(path, key), "required key missing");
  return *child;
}

void CheckNumber(double v, const std::string& path, const Bounds& b) {
  if (std::isnan(v)) {
    Fail(path,
         std::string(b.allow_inf ? "must be a number" : "must be finite") +
             ", got " + FormatNumber(v));
  }
  if (std::isinf(v) && !b.allow_inf) {
    Fail(path, "must be finite, got " + FormatNumber(v));
  }
  const bool lower_ok = (!b.gt || v > *b.gt) && (!b.ge || v >= *b.ge);
  const bool upper_ok = (!b.lt || v < *b.lt) && (!b.le || v <= *b.le);
  if (lower_ok && upper_ok) return;
  const bool has_lower = b.gt || b.ge;
  const bool has_upper = b.lt || b.le;
  std::string what;
  if (has_lower && has_upper) {
    what = "must be in ";
    what += b.gt ? "(" + FormatNumber(*b.gt) : "[" + FormatNumber(*b.ge);
    what += ", ";
    what += b.lt ? FormatNumber(*b.lt) + ")" : FormatNumber(*b.le) + "]";
  } else if (has_lower) {
    what = b.gt ? "must be > " + FormatNumber(*b.gt)
                : "must be >= " + FormatNumber(*b.ge);
  } else {
    what = b.lt ? "must be < " + FormatNumber(*b.lt)
                : "must be <= " + FormatNumber(*b.le);
  }
  Fail(path, what + ", got " + FormatNumber(v));
}

double ReadDouble(const YAML::Node& node, const std::string& path,
                  const Bounds& bounds) {
  if (!node.IsScalar() || IsQuoted(node)) {
    Fail(path, "expected a number, got " + DescribeNode(node));
  }
  const std::string& s = node.Scalar();
  const std::string low = Lower(s);
  double v = 0.0;
  if (low == ".nan") {
    v = std::numeric_limits<double>::quiet_NaN();
  } else if (low == ".inf" || low == "+.inf") {
    v = std::numeric_limits<double>::infinity();
  } else if (low == "-.inf") {
    v = -std::numeric_limits<double>::infinity();
  } else {
    const char* first = s.data();
    const char* last = s.data() + s.size();
    if (first != last && *first == '+') ++first;
    const auto res = std::from_chars(first, last, v);
    if (first == last || res.ec == std::errc::invalid_argument ||
        res.ptr != last) {
      Fail(path, "expected a number, got " + DescribeNode(node));
    }
    if (res.ec == std::errc::result_out_of_range) {
      Fail(path, "number out of range, got " + DescribeNode(node));
    }
  }
  CheckNumber(v, path, bounds);
  return v;
}

namespace {
// An unquoted integer scalar ("+" allowed) that fits T; `expected` names what
// the key takes in the message.
template <typename T>
T ParseInteger(const YAML::Node& node, const std::string& path,
               const char* expected) {
  if (!node.IsScalar() || IsQuoted(node)) {
    Fail(path,
         std::string("expected ") + expected + ", got " + DescribeNode(node));
  }
  const std::string& s = node.Scalar();
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (first != last && *first == '+') ++first;
  T v = 0;
  const auto res = std::from_chars(first, last, v);
  if (first == last || res.ec != std::errc() || res.ptr != last) {
    Fail(path,
         std::string("expected ") + expected + ", got " + DescribeNode(node));
  }
  return v;
}
}  // namespace

std::int64_t ReadInt(const YAML::Node& node, const std::string& path,
                     std::int64_t min, std::int64_t max) {
  const std::int64_t v = ParseInteger<std::int64_t>(node, path, "an integer");
  if (v < min || v > max) {
    Fail(path, "must be in [" + std::to_string(min) + ", " +
                   std::to_string(max) + "], got " + std::to_string(v));
  }
  return v;
}

std::uint64_t ReadUint64(const YAML::Node& node, const std::string& path) {
  return ParseInteger<std::uint64_t>(node, path, "a non-negative integer");
}

std::string ReadString(const YAML::Node& node, const std::string& path) {
  if (!node.IsScalar())
    Fail(path, "expected a string, got " + DescribeNode(node));
  return node.Scalar();
}

std::string ReadEnum(const YAML::Node& node, const std::string& path,
                     std::initializer_list<std::string_view> allowed) {
  const std::string s = ReadString(node, path);
  if (std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
    Fail(path, "must be one of " + Join(allowed) + ", got \"" + s + "\"");
  }
  return s;
}

std::vector<double> ReadVector(const YAML::Node& node, const std::string& path,
                               int size, const Bounds& bounds) {
  const std::string expected =
      size < 0 ? std::string("expected a sequence of numbers")
               : "expected a sequence of " + std::to_string(size) + " numbers";
  if (!node.IsSequence()) Fail(path, expected + ", got " + DescribeNode(node));
  if (size >= 0 && node.size() != static_cast<std::size_t>(size)) {
    Fail(path, expected + ", got " + std::to_string(node.size()));
  }
  std::vector<double> v;
  v.reserve(node.size());
  for (std::size_t i = 0; i < node.size(); ++i) {
    v.push_back(ReadDouble(node[i], JoinIndex(path, i), bounds));
  }
  return v;
}

std::pair<double, double> ReadInterval(const YAML::Node& node,
                                       const std::string& path,
                                       const Bounds& bounds) {
  const std::vector<double> v = ReadVector(node, path, 2, bounds);
  if (v[0] > v[1]) {
    Fail(path, "lo must be <= hi, got [" + FormatNumber(v[0]) + ", " +
                   FormatNumber(v[1]) + "]");
  }
  return {v[0], v[1]};
}

void ReadOptionalDouble(const YAML::Node& map, const std::string& path,
                        std::string_view key, double* out,
                        const Bounds& bounds) {
  if (std::optional<YAML::Node> n = Child(map, key)) {
    *out = ReadDouble(*n, JoinKey(path, key), bounds);
  }
}

}  // namespace quasiroll::yaml
