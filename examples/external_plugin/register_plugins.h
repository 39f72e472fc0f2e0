// Registers the example plugins with quasiroll's registries. Idempotent and
// thread-safe (Register() replaces an entry of the same name under a lock),
// but call it once, before creating solvers or loading suites.
#pragma once

namespace example {

inline constexpr const char* kNlpName = "levenberg-marquardt";
inline constexpr const char* kDaeName = "midpoint-projection";

void RegisterExamplePlugins();

}  // namespace example
