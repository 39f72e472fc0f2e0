// Subcommands of the quasiroll CLI (docs/cli.md documents each).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace quasiroll::cli {

struct PoseArgs {
  std::string scene;
  bool json = false;
};

class Commands {
 public:
  void Register(CLI::App& app);
  // Runs the parsed subcommand; returns the process exit code.
  int Run();

 private:
  std::function<int()> selected_;
  PoseArgs pose_;
};

int RunPose(const PoseArgs& args);
int RunList();

}  // namespace quasiroll::cli
