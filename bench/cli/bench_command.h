// `quasiroll bench` (run a benchmark suite) and `quasiroll report` (render a
// suite's output directory with reports/make_report.py). docs/harness.md.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace quasiroll::cli {

struct BenchArgs {
  std::string suite;
  std::string out;
  std::optional<int> jobs;  // default: hardware concurrency
  std::optional<std::string> filter;
  bool resume = false;
  std::string shard;  // "I/N", "" = the whole suite
  bool plan = false;  // print the selected runs and their costs, run nothing
  std::string progress = "auto";
};

struct MergeArgs {
  std::vector<std::string> inputs;
  std::string out;
  std::string suite;
};

struct ReportArgs {
  std::string dir;
  std::optional<std::string> out;  // passed to make_report.py --out
  bool strict = false;             // passed to make_report.py --strict
};

class BenchCommands {
 public:
  // Adds the `bench`, `merge` and `report` subcommands; a parsed one stores its
  // action in *selected.
  void Register(CLI::App& app, std::function<int()>* selected);

 private:
  BenchArgs bench_;
  MergeArgs merge_;
  ReportArgs report_;
};

int RunBench(const BenchArgs& args);
int RunMerge(const MergeArgs& args);
int RunReport(const ReportArgs& args);
// The Python that runs the report generator: $QUASIROLL_PYTHON if set (and
// only it), else the first of /usr/bin/python3 and python3 on PATH that can
// import matplotlib and numpy. nullopt if none; *tried lists the candidates.
std::optional<std::string> FindReportPython(std::string* tried);

}  // namespace quasiroll::cli
