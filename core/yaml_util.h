// Strict YAML reading helpers shared by the scene loader and the suite loader.
//
// Every helper takes the node and its key path ("terrain.bumps[3].sigma";
// sequence indices are 0-based) and throws SceneError with one line
// "<path>: <problem>, got <value>" on any problem. This is the only header
// that exposes yaml-cpp types; targets including it must link yaml-cpp
// themselves (quasiroll::core links it privately).
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/terrains.h"

namespace quasiroll::yaml {

// ------------------------------------------------------------ messages ----

// Shortest round-trip decimal ("0.1", "-0.2", "nan", "inf").
std::string FormatNumber(double v);
// "a" + "b" -> "a.b"; "" + "b" -> "b".
std::string JoinKey(const std::string& path, std::string_view key);
// "a" + 3 -> "a[3]".
std::string JoinIndex(const std::string& path, std::size_t index);
// For "got ...": a scalar quoted ("\"abc\""), "null", "a mapping",
// "a sequence of N".
std::string DescribeNode(const YAML::Node& node);
// Throws SceneError("<path>: <problem>") ("<problem>" alone if path is "").
[[noreturn]] void Fail(const std::string& path, const std::string& problem);

// ------------------------------------------------------------- loading ----

// Parses YAML text. Syntax errors become SceneError
// "<origin>:<line>:<column>: YAML syntax error: <detail>" (1-based; origin
// "<string>" if empty). Multiple documents are rejected.
YAML::Node ParseYaml(const std::string& text, const std::string& origin);
// Reads and parses a file; a missing/unreadable file is
// SceneError "<path>: cannot open file".
YAML::Node LoadYamlFile(const std::string& path);

// ---------------------------------------------------------- structure ----

// Requires a mapping (a null node counts as an empty mapping) whose keys are
// all in `allowed` and appear once. Errors: "<path>: expected a mapping, got
// ...", "<path.key>: unknown key (allowed: ...)", "<path.key>: duplicate key".
void CheckKeys(const YAML::Node& node, const std::string& path,
               std::initializer_list<std::string_view> allowed);
// Child of a mapping, or nullopt if the key is absent (a present key with an
// empty value is returned: readers then fail with "got null").
std::optional<YAML::Node> Child(const YAML::Node& map, std::string_view key);
// Like Child() but a missing key fails with "<path.key>: required key missing".
YAML::Node Require(const YAML::Node& map, const std::string& path,
                   std::string_view key);

// ------------------------------------------------------------- scalars ----

// Constraints on a number. NaN is always rejected; +-inf unless allow_inf.
struct Bounds {
  std::optional<double> gt, ge, lt, le;
  bool allow_inf = false;

  static Bounds Any() { return {}; }
  static Bounds Positive() { return Bounds{}.Gt(0.0); }
  static Bounds NonNegative() { return Bounds{}.Ge(0.0); }
  Bounds& Gt(double v) {
    gt = v;
    return *this;
  }
  Bounds& Ge(double v) {
    ge = v;
    return *this;
  }
  Bounds& Lt(double v) {
    lt = v;
    return *this;
  }
  Bounds& Le(double v) {
    le = v;
    return *this;
  }
  Bounds& AllowInf(bool on = true) {
    allow_inf = on;
    return *this;
  }
};

// Checks v against b; throws "<path>: must be finite|> x|in (a, b], got v".
void CheckNumber(double v, const std::string& path, const Bounds& b);

// A plain (unquoted) YAML number: decimal, exponent, optional sign, or the
// YAML 1.2 specials .nan/.NaN/.NAN, .inf/+.inf/-.inf (any case variant).
// Quoted scalars ("5") are rejected: "expected a number, got \"5\"".
double ReadDouble(const YAML::Node& node, const std::string& path,
                  const Bounds& bounds = {});
// A plain decimal integer in [min, max].
std::int64_t ReadInt(const YAML::Node& node, const std::string& path,
                     std::int64_t min, std::int64_t max);
// A plain decimal integer in [0, 2^64 - 1] (e.g. an RNG seed).
std::uint64_t ReadUint64(const YAML::Node& node, const std::string& path);
// Any scalar (quoted or not) as text.
std::string ReadString(const YAML::Node& node, const std::string& path);
// A scalar that must be one of `allowed`:
// "<path>: must be one of a, b, got \"c\"".
std::string ReadEnum(const YAML::Node& node, const std::string& path,
                     std::initializer_list<std::string_view> allowed);

// A sequence of numbers; `size` < 0 accepts any length. Wrong length:
// "<path>: expected a sequence of N numbers, got M". Elements are checked
// against `bounds` with paths "<path>[i]".
std::vector<double> ReadVector(const YAML::Node& node, const std::string& path,
                               int size = -1, const Bounds& bounds = {});
template <std::size_t N>
std::array<double, N> ReadArray(const YAML::Node& node, const std::string& path,
                                const Bounds& bounds = {}) {
  const std::vector<double> v =
      ReadVector(node, path, static_cast<int>(N), bounds);
  std::array<double, N> a{};
  for (std::size_t i = 0; i < N; ++i) a[i] = v[i];
  return a;
}
// [lo, hi] with lo <= hi: "<path>: lo must be <= hi, got [2, 1]".
std::pair<double, double> ReadInterval(const YAML::Node& node,
                                       const std::string& path,
                                       const Bounds& bounds = {});

// Optional-key convenience: if `key` is present in `map`, *out = ReadDouble().
void ReadOptionalDouble(const YAML::Node& map, const std::string& path,
                        std::string_view key, double* out,
                        const Bounds& bounds = {});

// ------------------------------------------------------ scene sections ----
// (implemented in scene.cc; reusable by the suite loader for inline scenes
// and per-case overrides)

// Applies the keys present in a scene mapping to *scene (absent keys keep
// their current values), then re-checks the cross-key constraints
// (tube_radius < major_radius, dt <= t_end, start inside the terrain).
// `path` prefixes every key in messages ("" at a document root); relative
// heightmap files resolve against `base_dir` ("" = current directory).
void ReadSceneNode(const YAML::Node& node, const std::string& path,
                   const std::string& base_dir, Scene* scene);
// Parses a `terrain:` mapping into a spec (heightmap path resolved against
// base_dir) without building it.
TerrainSpec ReadTerrainSpec(const YAML::Node& node, const std::string& path,
                            const std::string& base_dir);
// ReadTerrainSpec + MakeTerrain; construction errors are prefixed with path.
std::shared_ptr<const Terrain> ReadTerrain(const YAML::Node& node,
                                           const std::string& path,
                                           const std::string& base_dir);

}  // namespace quasiroll::yaml
