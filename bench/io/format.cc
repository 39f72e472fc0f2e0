#include "quasiroll/bench/io/format.h"

#include <cstdio>

#include "quasiroll/core/yaml_util.h"

namespace quasiroll::bench {

std::uint64_t Fnv1a64(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string Hex64(std::uint64_t value) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx",
                static_cast<unsigned long long>(value));
  return buf;
}

std::string Num(double v) { return yaml::FormatNumber(v); }

}  // namespace quasiroll::bench
