// Backends from shared libraries (docs/plugins.md, "Loadable plugins"): the
// standard programs (quasiroll, quasiroll-mpi, the Python module) load a
// plugin library with dlopen and call its one exported registration
// function, as CasADi loads its solver plugins.
//
// A plugin library defines
//
//   extern "C" void quasiroll_register_plugin();   // kPluginEntryPoint
//
// which calls NlpSolverRegistry::Register / IntegratorRegistry::Register. It
// is built as a MODULE library against the installed headers and links none
// of quasiroll's (static) libraries: the quasiroll symbols it uses resolve to
// the loading program's own, so that it registers into the program's
// registries (quasiroll_add_plugin in the installed CMake package).
#pragma once

#include <string>
#include <vector>

namespace quasiroll {

inline constexpr const char* kPluginEntryPoint = "quasiroll_register_plugin";
// Colon-separated plugin files loaded by LoadPluginsFromEnvironment().
inline constexpr const char* kPluginPathVariable = "QUASIROLL_PLUGIN_PATH";

struct LoadedPlugin {
  std::string file;     // as given
  std::string path;     // absolute
  std::string sha256;   // of the file's bytes (hex)
  std::string version;  // quasiroll_plugin_version() if exported, else ""
  std::vector<std::string> nlp_backends;  // registered by this plugin
  std::vector<std::string> integrators;
};

// Loads `file` and calls its registration function. Throws
// std::runtime_error naming the file when it cannot be loaded (dlerror's
// message), does not export kPluginEntryPoint ("not a quasiroll plugin"),
// registers nothing, or registers a name that is taken (a built-in or an
// earlier plugin). Loading the same path twice is a no-op that returns the
// first load's record. Thread-safe.
LoadedPlugin LoadPlugin(const std::string& file);

// Loads every file of $QUASIROLL_PLUGIN_PATH (colon-separated, empty
// entries skipped), then each of `files`.
std::vector<LoadedPlugin> LoadPlugins(const std::vector<std::string>& files);

// Every plugin loaded so far in this process, in load order.
std::vector<LoadedPlugin> LoadedPlugins();

// SHA-256 of a file's bytes as 64 hex digits; throws std::runtime_error
// naming the file when it cannot be read.
std::string FileSha256(const std::string& path);

}  // namespace quasiroll
