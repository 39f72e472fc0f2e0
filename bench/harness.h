// The benchmark harness (docs/harness.md): runs every grid point of a suite
// (in parallel threads), computes references and metrics, and writes
//   DIR/runs.csv                  one row per run, in grid order
//   DIR/runs/<run_id>.csv         the same row, written as the run finishes
//   DIR/trajectories/<run_id>.csv the run's trajectory (quasiroll run format)
//   DIR/references/<hash>.{csv,json}  cached reference trajectories
//   DIR/terrains/<terrain>.json   terrain description for the report
//   DIR/meta.json                 machine, commit, versions, suite, times
// Every file is written atomically.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "bench/reference.h"
#include "bench/suite.h"

namespace quasiroll::bench {

struct HarnessOptions {
  std::string out_dir;
  int jobs = 0;         // <= 0: std::thread::hardware_concurrency()
  std::string filter;   // ECMAScript regex on run_id; "" = every run
  bool resume = false;  // reuse DIR/runs/<run_id>.csv of finished runs
  // Progress on `log`: -1 auto (a TTY gets one updating line, anything else
  // one line per finished run), 0 never, 1 lines, 2 updating line.
  int progress = -1;
  std::FILE* log = stderr;
};

struct HarnessSummary {
  int total = 0;     // grid points of the suite
  int selected = 0;  // after --filter
  int executed = 0;  // run in this invocation
  int resumed = 0;   // taken from DIR/runs/
  int failures = 0;  // selected rows whose status is not "success"
  double wall_seconds = 0;
};

// runs.csv column names, in order.
const std::vector<std::string>& RunsCsvColumns();
// A CSV field: quoted (with doubled quotes) if it contains , " CR or LF.
std::string CsvField(const std::string& value);

// One runs.csv row (values in RunsCsvColumns() order) for a run whose
// simulation produced `result` (wall_s = the minimum over repeats), compared
// with `reference` (null if unavailable; `reference_error` then says why).
std::vector<std::string> MakeRow(const RunSpec& run,
                                 const std::string& terrain_id,
                                 const SimulationResult& result,
                                 double min_wall_seconds,
                                 const Reference* reference,
                                 const std::string& reference_error);
// Row of a run that threw (status "error", the message as stop_reason).
std::vector<std::string> ErrorRow(const RunSpec& run,
                                  const std::string& terrain_id,
                                  const std::string& message,
                                  const Reference* reference,
                                  const std::string& reference_error = "");

// Runs the suite. Throws SceneError for a bad filter; I/O errors propagate
// as std::runtime_error. Failing runs never stop the suite.
HarnessSummary RunSuite(const Suite& suite, const HarnessOptions& options);

// JSON description of a terrain for the report ("" for types it does not
// cover: sinusoid, heightmap).
std::string TerrainJson(const TerrainSpec& spec);

// <source dir>/reports/make_report.py (source dir fixed at build time).
std::string ReportScriptPath();

}  // namespace quasiroll::bench
