// A shared library that is not a quasiroll plugin: it exports no
// quasiroll_register_plugin() (tests/plugins/plugin_cli_test.sh).
extern "C" int not_a_quasiroll_plugin() { return 42; }
