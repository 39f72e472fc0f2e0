// Subcommands of the quasiroll CLI (docs/cli.md documents each).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

#include "bench/cli/bench_command.h"

namespace quasiroll::cli {

struct PoseArgs {
  std::string scene;
  bool json = false;
};

struct SolveArgs {
  std::string scene;
  std::string nlp = "newton";
  double mu = 0;     // 0 = scene's
  std::string mode;  // "" = scene's
  bool json = false;
};

struct RunArgs {
  std::string scene;
  std::string nlp = "newton";
  std::string dae = "rk-projection";
  std::string coupling = "zoh";
  double dt = 0, t_end = 0, mu = 0;
  std::string mode;
  std::string rk_method = "rk4";
  double sigma = 5.0;
  double rtol = 1e-8, atol = 1e-10;
  int dae_index = 2;
  std::string out = "out/run";
};

class Commands {
 public:
  void Register(CLI::App& app);
  // Runs the parsed subcommand; returns the process exit code.
  int Run();

 private:
  std::function<int()> selected_;
  PoseArgs pose_;
  SolveArgs solve_;
  RunArgs run_;
  BenchCommands bench_;
};

int RunPose(const PoseArgs& args);
int RunList();
int RunSolve(const SolveArgs& args);
int RunRun(const RunArgs& args);

}  // namespace quasiroll::cli
