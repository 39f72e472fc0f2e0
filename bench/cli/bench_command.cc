#include "quasiroll/bench/cli/bench_command.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <regex>
#include <sstream>
#include <vector>

#include "quasiroll/bench/cli/cli_support.h"
#include "quasiroll/bench/cluster/merge.h"
#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/shard.h"
#include "quasiroll/bench/harness/suite.h"

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
      ->check(IntegerIn(1, 1024));
  bench->add_option(
      "--filter", bench_.filter,
      "Keep only runs whose run_id matches this regex (ECMAScript); "
      "matching no run is an error");
  bench->add_flag(
      "--resume", bench_.resume,
      "Skip runs already finished in DIR/runs/ (interrupted suite)");
  bench->add_option("--shard", bench_.shard,
                    "I/N: run only slice I (0-based) of N cost-balanced "
                    "slices; runs.csv and meta.json go to DIR/shards/I-of-N/ "
                    "(then 'quasiroll merge')");
  bench->add_flag("--plan", bench_.plan,
                  "Print the selected runs with their estimated cost (CSV) "
                  "and exit without running anything (docs/cluster.md)");
  bench
      ->add_option("--progress", bench_.progress,
                   "auto (bar on a TTY, else lines) | bar | lines | none")
      ->check(OneOf({"auto", "bar", "lines", "none"}))
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
      "report",
      "Render a bench output directory as HTML + figures (the report "
      "generator in share/quasiroll/reports, run by Python 3 with "
      "matplotlib)");
  report
      ->add_option("dir", report_.dir, "Output directory of 'quasiroll bench'")
      ->required();
  report->add_option("--out", report_.out,
                     "Report directory (default: DIR/report)");
  report->add_flag("--strict", report_.strict,
                   "Fail (exit 2) when a figure has no data, instead of "
                   "drawing a placeholder");
  report->callback(
      [this, selected] { *selected = [this] { return RunReport(report_); }; });
}

namespace {

// The number of runs of `suite` whose run id matches `filter`; UsageError
// naming --filter for a bad regex.
int CountMatching(const bench::Suite& suite, const std::string& filter) {
  std::regex re;
  try {
    re = std::regex(filter, std::regex::ECMAScript);
  } catch (const std::regex_error& e) {
    throw UsageError("--filter", "invalid regular expression (" +
                                     std::string(e.what()) + "), got '" +
                                     filter + "'");
  }
  int count = 0;
  for (const bench::RunSpec& r : suite.runs)
    count += std::regex_search(r.run_id, re) ? 1 : 0;
  return count;
}

}  // namespace

int RunBench(const BenchArgs& args) {
  CheckOutputDirectory("--out", args.out);
  const bench::Suite suite = bench::LoadSuite(args.suite);
  if (args.filter && CountMatching(suite, *args.filter) == 0)
    throw UsageError(
        "--filter", "matches none of the " + std::to_string(suite.runs.size()) +
                        " run ids of suite '" + suite.name + "' (e.g. '" +
                        (suite.runs.empty() ? "" : suite.runs.front().run_id) +
                        "'), got '" + *args.filter + "'");
  bench::HarnessOptions options;
  options.out_dir = args.out;
  options.jobs = args.jobs.value_or(0);  // harness: <= 0 = hardware threads
  options.filter = args.filter.value_or("");
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
  if (args.plan) {
    std::fputs(bench::PlanCsv(suite, options).c_str(), stdout);
    return kExitOk;
  }
  // Every finished run is already on disk (atomic files), so Ctrl-C can end
  // the process at once; the message says how to continue.
  std::string resume = "quasiroll bench --suite " + ShellQuote(args.suite) +
                       " --out " + ShellQuote(args.out) + " --resume";
  if (args.filter) resume += " --filter " + ShellQuote(*args.filter);
  if (!args.shard.empty()) resume += " --shard " + ShellQuote(args.shard);
  if (args.jobs) resume += " --jobs " + std::to_string(*args.jobs);
  InstallInterruptMessage(
      "\nquasiroll bench: interrupted (SIGINT); the runs finished so far are "
      "kept in " +
      args.out + "/runs/. Continue with --resume:\n  " + resume + "\n");
  const bench::HarnessSummary s = bench::RunSuite(suite, options);
  std::fprintf(
      stderr,
      "suite %s: %d runs (%d selected, %d executed, %d resumed), %d not "
      "successful, %.1f s\n",
      suite.name.c_str(), s.total, s.selected, s.executed, s.resumed,
      s.failures, s.wall_seconds);
  std::printf("%s/runs.csv\n", bench::SuiteOutputDir(options).c_str());
  return kExitOk;
}

int RunMerge(const MergeArgs& args) {
  CheckOutputDirectory("--out", args.out);
  bench::MergeOptions options;
  options.inputs = args.inputs;
  options.out = args.out;
  options.suite = args.suite;
  const bench::MergeSummary s = bench::MergeOutputs(options);
  std::string hosts;
  for (const std::string& h : s.hosts) hosts += (hosts.empty() ? "" : ", ") + h;
  if (s.atlas) {
    std::fprintf(
        stderr,
        "merge: atlas of %d cells from %d meta.json, %d not ok; hosts: %s\n",
        s.runs, s.metas, s.failures, hosts.c_str());
    std::printf("%s/atlas.csv\n", args.out.c_str());
    return kExitOk;
  }
  std::fprintf(stderr,
               "merge: %d runs from %d meta.json (%d duplicates, %d of them "
               "differing), %d not successful; hosts: %s\n",
               s.runs, s.metas, s.duplicates, s.differing, s.failures,
               hosts.c_str());
  std::printf("%s/runs.csv\n", args.out.c_str());
  return kExitOk;
}

namespace {

// Runs argv[0] with `argv` (execv) and returns its exit code (128 + signal
// if it was killed); `quiet` sends its stdout and stderr to /dev/null.
int RunProgram(const std::vector<std::string>& argv, bool quiet) {
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    std::perror("error: fork");
    return kExitInternal;
  }
  if (pid == 0) {
    if (quiet) {
      std::FILE* null = std::freopen("/dev/null", "w", stdout);
      if (null != nullptr) ::dup2(STDOUT_FILENO, STDERR_FILENO);
    }
    std::vector<char*> args;
    for (const std::string& a : argv)
      args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      std::perror("error: waitpid");
      return kExitInternal;
    }
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return kExitInternal;
}

// python3 on PATH, or "".
std::string Python3OnPath() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::string candidate = dir + "/python3";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return "";
}

bool HasReportModules(const std::string& python) {
  return RunProgram({python, "-c", "import matplotlib, numpy"}, true) == 0;
}

}  // namespace

std::optional<std::string> FindReportPython(std::string* tried) {
  // An explicit choice is used as given, or not at all.
  if (const char* env = std::getenv("QUASIROLL_PYTHON"); env && *env) {
    *tried = std::string(env) + " (QUASIROLL_PYTHON)";
    if (::access(env, X_OK) == 0 && HasReportModules(env)) return env;
    return std::nullopt;
  }
  tried->clear();
  for (const std::string& python :
       {std::string("/usr/bin/python3"), Python3OnPath()}) {
    if (python.empty() || ::access(python.c_str(), X_OK) != 0) continue;
    *tried += (tried->empty() ? "" : ", ") + python;
    if (HasReportModules(python)) return python;
  }
  if (tried->empty()) *tried = "no python3 (/usr/bin/python3 or on PATH)";
  return std::nullopt;
}

int RunReport(const ReportArgs& args) {
  const std::string script = bench::ReportScriptPath();
  std::error_code ec;
  if (!std::filesystem::exists(script, ec)) {
    std::fprintf(stderr,
                 "error: the report generator %s is missing (set "
                 "QUASIROLL_DATA_DIR to the share/quasiroll directory of the "
                 "installation); runs.csv and the other files in %s can be "
                 "used directly\n",
                 script.c_str(), args.dir.c_str());
    return kExitMissingTool;
  }
  std::string tried;
  const std::optional<std::string> python = FindReportPython(&tried);
  if (!python) {
    std::fprintf(stderr,
                 "error: quasiroll report needs Python 3 with matplotlib and "
                 "numpy (Debian: apt-get install python3-matplotlib "
                 "python3-numpy); tried %s. Set QUASIROLL_PYTHON to a "
                 "python3 that has them.\n",
                 tried.c_str());
    return kExitMissingTool;
  }
  std::vector<std::string> argv = {*python, script, args.dir};
  if (args.out) {
    argv.push_back("--out");
    argv.push_back(*args.out);
  }
  if (args.strict) argv.push_back("--strict");
  const int code = RunProgram(argv, false);
  if (code == 127)
    std::fprintf(stderr, "error: cannot execute %s\n", python->c_str());
  return code;
}

}  // namespace quasiroll::cli
