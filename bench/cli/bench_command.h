// `quasiroll bench` (run a benchmark suite) and `quasiroll report` (render a
// suite's output directory with reports/make_report.py). docs/harness.md.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace quasiroll::cli {

struct BenchArgs {
  std::string suite;
  std::string out;
  int jobs = 0;  // 0 = hardware concurrency
  std::string filter;
  bool resume = false;
  std::string progress = "auto";
};

struct ReportArgs {
  std::string dir;
};

class BenchCommands {
 public:
  // Adds the `bench` and `report` subcommands; a parsed one stores its
  // action in *selected.
  void Register(CLI::App& app, std::function<int()>* selected);

 private:
  BenchArgs bench_;
  ReportArgs report_;
};

int RunBench(const BenchArgs& args);
int RunReport(const ReportArgs& args);

}  // namespace quasiroll::cli
