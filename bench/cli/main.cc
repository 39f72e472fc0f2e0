// quasiroll command-line interface. Exit codes: 0 success, 1 a run/solve that
// ended with a non-OK status, 2 bad input (message on stderr).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "bench/cli/commands.h"
#include "core/initial_configuration.h"
#include "core/scene.h"

int main(int argc, char** argv) {
  CLI::App app{
      "quasiroll: quasi-static forward motion of a wheeled mobile robot on "
      "uneven terrain, and a testbed comparing the numerical methods that "
      "simulate it."};
  app.require_subcommand(1);
  quasiroll::cli::Commands commands;
  commands.Register(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::cerr << "error: " << e.what() << "\n";      // one line, see --help
    return 2;
  }
  try {
    return commands.Run();
  } catch (const quasiroll::SceneError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const quasiroll::GeometryError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\n";
    return 3;
  }
}
