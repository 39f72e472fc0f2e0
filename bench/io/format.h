// Text forms shared by the harness, the CLI and the output files: the hash
// that names runs and references, and the number format of every output.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace quasiroll::bench {

// FNV-1a, 64 bit, of the bytes of `text`.
std::uint64_t Fnv1a64(std::string_view text);
// 16 lower-case hex digits.
std::string Hex64(std::uint64_t value);
// Shortest round-trip decimal of v ("0.05", "1e-08", "nan", "inf").
std::string Num(double v);

}  // namespace quasiroll::bench
