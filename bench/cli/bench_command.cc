#include "bench/cli/bench_command.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "bench/harness.h"
#include "bench/merge.h"
#include "bench/shard.h"
#include "bench/suite.h"

namespace quasiroll::cli {

void BenchCommands::Register(CLI::App& app, std::function<int()>* selected) {
  CLI::App* bench =
      app.add_subcommand("bench",
                         "Run a benchmark suite; writes DIR/runs.csv, "
                         "DIR/trajectories/, DIR/meta.json");
  bench->add_option("--suite", bench_.suite, "Suite YAML file")->required();
  bench->add_option("--out", bench_.out, "Output directory")->required();
  bench
      ->add_option("--jobs", bench_.jobs,
                   "Parallel runs (default: hardware concurrency)")
      ->check(CLI::NonNegativeNumber);
  bench->add_option(
      "--filter", bench_.filter,
      "Keep only runs whose run_id matches this regex (ECMAScript)");
  bench->add_flag(
      "--resume", bench_.resume,
      "Skip runs already finished in DIR/runs/ (interrupted suite)");
  bench->add_option("--shard", bench_.shard,
                    "I/N: run only slice I (0-based) of N cost-balanced "
                    "slices; runs.csv and meta.json go to DIR/shards/I-of-N/ "
                    "(then 'quasiroll merge')");
  bench
      ->add_option("--progress", bench_.progress,
                   "auto (bar on a TTY, else lines) | bar | lines | none")
      ->check(CLI::IsMember({"auto", "bar", "lines", "none"}))
      ->capture_default_str();
  bench->callback(
      [this, selected] { *selected = [this] { return RunBench(bench_); }; });

  CLI::App* merge = app.add_subcommand(
      "merge",
      "Join shard / partial outputs of one suite into DIR/runs.csv and "
      "DIR/meta.json as one run writes them (docs/cluster.md)");
  merge->add_option("inputs", merge_.inputs, "Output directories of bench")
      ->required();
  merge->add_option("--out", merge_.out, "Merged output directory")->required();
  merge->add_option("--suite", merge_.suite,
                    "Suite file (default: the one the inputs' meta.json name)");
  merge->callback(
      [this, selected] { *selected = [this] { return RunMerge(merge_); }; });

  CLI::App* report = app.add_subcommand(
      "report", "Render a bench output directory (reports/make_report.py DIR)");
  report
      ->add_option("dir", report_.dir, "Output directory of 'quasiroll bench'")
      ->required();
  report->callback(
      [this, selected] { *selected = [this] { return RunReport(report_); }; });
}

int RunBench(const BenchArgs& args) {
  const bench::Suite suite = bench::LoadSuite(args.suite);
  bench::HarnessOptions options;
  options.out_dir = args.out;
  options.jobs = args.jobs;
  options.filter = args.filter;
  options.resume = args.resume;
  if (!args.shard.empty()) {
    const auto [index, count] = bench::ParseShard(args.shard);
    options.shard_index = index;
    options.shard_count = count;
  }
  options.progress = args.progress == "auto"    ? -1
                     : args.progress == "none"  ? 0
                     : args.progress == "lines" ? 1
                                                : 2;
  const bench::HarnessSummary s = bench::RunSuite(suite, options);
  std::fprintf(
      stderr,
      "suite %s: %d runs (%d selected, %d executed, %d resumed), %d not "
      "successful, %.1f s\n",
      suite.name.c_str(), s.total, s.selected, s.executed, s.resumed,
      s.failures, s.wall_seconds);
  std::printf("%s/runs.csv\n", bench::SuiteOutputDir(options).c_str());
  return 0;
}

int RunMerge(const MergeArgs& args) {
  bench::MergeOptions options;
  options.inputs = args.inputs;
  options.out = args.out;
  options.suite = args.suite;
  const bench::MergeSummary s = bench::MergeOutputs(options);
  std::string hosts;
  for (const std::string& h : s.hosts) hosts += (hosts.empty() ? "" : ", ") + h;
  std::fprintf(stderr,
               "merge: %d runs from %d meta.json (%d duplicates, %d of them "
               "differing), %d not successful; hosts: %s\n",
               s.runs, s.metas, s.duplicates, s.differing, s.failures,
               hosts.c_str());
  std::printf("%s/runs.csv\n", args.out.c_str());
  return 0;
}

int RunReport(const ReportArgs& args) {
  const std::string script = bench::ReportScriptPath();
  const std::string python = "/usr/bin/python3";
  std::error_code ec;
  if (!std::filesystem::exists(script, ec)) {
    std::fprintf(
        stderr,
        "error: the report generator %s does not exist (yet); runs.csv and "
        "the other files in %s can be used directly\n",
        script.c_str(), args.dir.c_str());
    return 1;
  }
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    std::perror("error: fork");
    return 1;
  }
  if (pid == 0) {
    const char* argv[] = {python.c_str(), script.c_str(), args.dir.c_str(),
                          nullptr};
    ::execv(python.c_str(), const_cast<char* const*>(argv));
    std::perror(("error: cannot execute " + python).c_str());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      std::perror("error: waitpid");
      return 1;
    }
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 1;
}

}  // namespace quasiroll::cli
