// The example as a loadable plugin (docs/plugins.md, "Loadable plugins"):
//   quasiroll --plugin quasiroll_example_plugin.so bench --suite ...
// The loader calls quasiroll_register_plugin() once; the optional
// quasiroll_plugin_version() is recorded with the plugin in meta.json.
#include "register_plugins.h"

extern "C" void quasiroll_register_plugin() {
  example::RegisterExamplePlugins();
}

extern "C" const char* quasiroll_plugin_version() { return "0.1.0"; }
