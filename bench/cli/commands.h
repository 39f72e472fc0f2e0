// Subcommands of the quasiroll CLI (docs/cli.md documents each).
// Flag names are the suite keys with '_' -> '-' (docs/cli.md, "Names");
// an optional flag left out means "the scene's value" or the documented
// library default, never a 0 sentinel.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/bench/cli/atlas_command.h"
#include "quasiroll/bench/cli/bench_command.h"
#include "quasiroll/bench/cli/cli_support.h"
#include "quasiroll/bench/harness/run_request.h"

namespace quasiroll::cli {

struct PoseArgs {
  std::string scene;
  bool json = false;
};

// Scene-parameter overrides shared by solve and run.
struct SceneOverrides {
  std::optional<double> mu;         // friction coefficient
  std::optional<double> eps;        // friction regularisation velocity [m/s]
  std::optional<std::string> mode;  // actuation mode
};

struct SolveArgs {
  std::string scene;
  std::string nlp;  // "" until Commands::Register: the default NLP
  SceneOverrides overrides;
  std::optional<double> nlp_tol;
  std::optional<int> nlp_max_iter;
  std::vector<std::string> nlp_opts;  // --nlp-opt key=value
  bool json = false;
  bool sensitivities = false;  // --sensitivities (core/sensitivity.h)
  // --step-derivative (core/step_sensitivity.h): one interval from the
  // initial configuration and its derivative; --dt (default: the scene's),
  // --coupling, --dae ("": the step derivative's default), --substeps.
  bool step_derivative = false;
  std::optional<double> dt;
  std::string coupling = "zoh";
  std::string dae;
  int substeps = 1;
};

struct RunArgs {
  std::string scene;
  // The flags that are RunRequest keys of the same type; its nlp and dae are
  // "" until Commands::Register: the registry's default backends.
  bench::RunRequest request;
  // The flags RunRun converts into the request.
  std::string coupling = "zoh";
  SceneOverrides overrides;
  std::vector<std::string> nlp_opts, dae_opts;  // --nlp-opt / --dae-opt
  std::string out = "out/run";
  std::string progress = "auto";
};

struct ListArgs {
  bool options = false;  // --options: the backends' option tables
  bool json = false;
};

class Commands {
 public:
  void Register(CLI::App& app);
  // After a successful parse: rejects arguments the selected subcommand did
  // not recognise (UsageError) and prints deprecation notes.
  void CheckParsed(const CLI::App& app) const;
  // Runs the parsed subcommand; returns the process exit code.
  int Run();

 private:
  void RegisterRun(CLI::App& app, const std::vector<std::string>& nlps,
                   const std::vector<std::string>& daes);
  std::function<int()> selected_;
  PoseArgs pose_;
  SolveArgs solve_;
  RunArgs run_;
  ListArgs list_;
  BenchCommands bench_;
  AtlasCommand atlas_;
  std::vector<DeprecatedSpelling> deprecated_;
};

int RunPose(const PoseArgs& args);
int RunList(const ListArgs& args);
int RunSolve(const SolveArgs& args);
int RunRun(const RunArgs& args);
// `quasiroll --version`: version, commit, build type, compiled-in backends.
std::string VersionText();

}  // namespace quasiroll::cli
