// Registers the example plugins with quasiroll's registries, each with its
// BackendInfo. Call it once, before creating solvers or loading suites (a
// second registration of a name throws std::invalid_argument). As a
// loadable plugin the loader calls it through plugin_entry.cc.
#pragma once

namespace example {

inline constexpr const char* kNlpName = "levenberg-marquardt";
inline constexpr const char* kDaeName = "midpoint-projection";

void RegisterExamplePlugins();

}  // namespace example
