// Helpers shared by the bench/ tests that run suites end to end.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/run_output.h"

namespace quasiroll::bench {

// The scene files of the tree, with a trailing slash.
inline const std::string kScenes =
    std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/";

// The whole file ("" if it cannot be read).
inline std::string ReadAll(const std::filesystem::path& p) {
  std::string text;
  ReadTextFile(p.string(), &text);
  return text;
}

// Harness options writing to `out_dir` with `jobs` threads, no progress bar.
inline HarnessOptions QuietHarnessOptions(const std::filesystem::path& out_dir,
                                          int jobs) {
  HarnessOptions o;
  o.out_dir = out_dir.string();
  o.jobs = jobs;
  o.progress = 0;
  return o;
}

// An empty directory under the temporary directory, named `prefix` and this
// process's id (parallel ctest processes do not share one).
inline std::filesystem::path FreshTempDir(const std::string& prefix) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    (prefix + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Writes `text` to DIR/suite.yaml and runs that suite into DIR/out with
// `jobs` threads and no progress bar; returns DIR/out.
inline std::filesystem::path RunSuiteText(const std::filesystem::path& dir,
                                          const std::string& text, int jobs) {
  const std::string path = (dir / "suite.yaml").string();
  std::ofstream(path) << text;
  RunSuite(LoadSuite(path), QuietHarnessOptions(dir / "out", jobs));
  return dir / "out";
}

// Writes DIR/tiny.yaml, a suite named "tiny" of the paper and flat scenes
// cut to t_end 0.5 s with `groups` (the text under "groups:"); its path.
inline std::string WriteTinySuite(const std::filesystem::path& dir,
                                  const std::string& groups) {
  const std::string path = (dir / "tiny.yaml").string();
  std::ofstream(path) << "name: tiny\n"
                         "scenes:\n"
                         "  - {name: paper, file: "
                      << kScenes
                      << "paper.yaml, overrides: {time: {t_end: 0.5}}}\n"
                         "  - {name: flat, file: "
                      << kScenes
                      << "flat.yaml, overrides: {time: {t_end: 0.5}}}\n"
                         "groups:\n"
                      << groups;
  return path;
}

#ifdef QUASIROLL_CLI_PATH
// The exit code of `quasiroll ARGS` (output discarded); -1 if it did not exit.
inline int RunCli(const std::string& args) {
  const std::string cmd =
      std::string(QUASIROLL_CLI_PATH) + " " + args + " >/dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
#endif

}  // namespace quasiroll::bench
