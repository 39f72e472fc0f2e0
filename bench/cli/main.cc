// quasiroll command-line interface. Exit codes (docs/cli.md): 0 success,
// 1 a run/solve that ended with a non-OK status, 2 bad input (one line on
// stderr naming the flag or key), 3 internal or I/O error, 4 a missing
// external tool (report), 130 interrupted (SIGINT).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "quasiroll/bench/cli/cli_support.h"
#include "quasiroll/bench/cli/commands.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/plugin_loader.h"
#include "quasiroll/core/scene.h"

namespace {

int BadInput(const std::string& message) {
  std::cerr << "error: " << message << "\n";
  return quasiroll::cli::kExitBadInput;
}

// The values of every `--plugin FILE` / `--plugin=FILE`: plugins register
// backends, so they are loaded before the commands check backend names.
std::vector<std::string> PluginFlags(int argc, char** argv) {
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--plugin" && i + 1 < argc)
      files.push_back(argv[++i]);
    else if (arg.rfind("--plugin=", 0) == 0)
      files.push_back(arg.substr(9));
  }
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace quasiroll::cli;
  CLI::App app{
      "quasiroll: quasi-static forward motion of a wheeled mobile robot on "
      "uneven terrain, and a testbed comparing the numerical methods that "
      "simulate it. Exit codes and every flag: docs/cli.md."};
  app.require_subcommand(1);
  app.set_version_flag(
      "--version", [] { return VersionText(); },
      "Print version, commit, build type and backends");
  quasiroll::SetInvocation(argc, argv);
  try {
    quasiroll::RegisterBuiltinNlpSolvers();
    quasiroll::RegisterBuiltinIntegrators();
    quasiroll::LoadPlugins(PluginFlags(argc, argv));
  } catch (const std::exception& e) {
    return BadInput(e.what());
  }
  Commands commands;
  commands.Register(app);
  // --plugin is accepted before and after the command (loaded above).
  std::vector<std::string> plugins;
  const char* plugin_help =
      "Load backends from a plugin library (repeatable; also "
      "$QUASIROLL_PLUGIN_PATH, colon-separated; docs/plugins.md)";
  app.add_option("--plugin", plugins, plugin_help);
  for (CLI::App* command : app.get_subcommands({}))
    command->add_option("--plugin", plugins, plugin_help);

  std::vector<std::string> names;
  for (const CLI::App* command : app.get_subcommands({}))
    names.push_back(command->get_name());
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  // `quasiroll` alone or `quasiroll <typo>`: name the commands.
  if (argc < 2) return BadInput("a command is required (" + known + ")");
  if (argv[1][0] != '-' &&
      std::find(names.begin(), names.end(), argv[1]) == names.end()) {
    const std::string hint = ClosestName(argv[1], names);
    return BadInput("unknown command '" + std::string(argv[1]) + "'" +
                    (hint.empty() ? "" : " (did you mean " + hint + "?)") +
                    "; commands: " + known);
  }
  try {
    app.parse(argc, argv);
    commands.CheckParsed(app);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr &&
        app.get_subcommands().empty())
      return BadInput("a command is required (" + known + ")");
    return BadInput(e.what());  // one line, see --help
  } catch (const UsageError& e) {
    return BadInput(e.what());
  }
  try {
    return commands.Run();
  } catch (const quasiroll::SceneError& e) {
    return BadInput(e.what());
  } catch (const quasiroll::GeometryError& e) {
    return BadInput(e.what());
  } catch (const std::invalid_argument& e) {
    return BadInput(e.what());
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\n";
    return kExitInternal;
  }
}
