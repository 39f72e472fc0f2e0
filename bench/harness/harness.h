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
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/reference.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/csv.h"  // CsvField, JoinCsvRow (runs.csv rows)

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
  // --shard I/N (bench/harness/shard.h): run only slice shard_index of
  // shard_count; shard_count 0 = no sharding. runs.csv and meta.json then go to
  // DIR/shards/<I>-of-<N>/ so that the N shards may share DIR.
  int shard_index = 0;
  int shard_count = 0;
  // quasiroll-mpi: number of MPI ranks (meta.json "mpi"); 0 = not MPI.
  int mpi_ranks = 0;
};

struct HarnessSummary {
  int total = 0;     // grid points of the suite
  int selected = 0;  // after --filter
  int executed = 0;  // run in this invocation
  int resumed = 0;   // taken from DIR/runs/
  int failures = 0;  // selected rows whose status is not "success"
  double wall_seconds = 0;
};

// runs.csv column names, in order: the names of RunsCsvSchema()
// (bench/io/runs_columns.tsv).
const std::vector<std::string>& RunsCsvColumns();

// One runs.csv row (values in RunsCsvColumns() order) for a run of `scene`
// whose simulation produced `result` (the first repeat; `wall_seconds` has
// every repeat's wall time, in order: wall_s = their minimum), compared with
// `reference` (null if unavailable; `reference_error` then says why). The
// row's status is the harness's verdict: result.status, except that a run
// that reached t_end beyond run.bounds is drift_exceeded / gap_exceeded;
// cause / cause_detail from ClassifyFailure (bench/harness/failure_causes.h).
std::vector<std::string> MakeRow(const RunSpec& run,
                                 const std::string& terrain_id,
                                 const SimulationResult& result,
                                 const std::vector<double>& wall_seconds,
                                 const Scene& scene, const Reference* reference,
                                 const std::string& reference_error);
// Row of a run that threw (status "error", the message as stop_reason).
std::vector<std::string> ErrorRow(const RunSpec& run,
                                  const std::string& terrain_id,
                                  const std::string& message,
                                  const Reference* reference,
                                  const std::string& reference_error = "");

// Runs the suite. Throws SceneError for a bad filter, OutputLockedError
// (bench/io/output_lock.h) when another process writes the same output
// (DIR, or DIR/shards/I-of-N with --shard); I/O errors propagate as
// FileWriteError and stop the suite (no run starts after one). Failing runs
// never stop the suite.
HarnessSummary RunSuite(const Suite& suite, const HarnessOptions& options);

// The runner's scheduler: calls fn(k) once for every task k < classes.size().
// First the tasks with alone[k] false, in `jobs` threads, in order, except
// that a task of a non-zero class waits while another task of its class
// runs (NLP backends whose solver objects may not run concurrently); then
// the tasks with alone[k] true (group key `exclusive`), one at a time, each
// starting after every other task has finished: nothing shares the cores
// with them. The first exception thrown by fn is rethrown once the tasks
// running then have finished; no task starts after it.
void ScheduleTasks(const std::vector<int>& classes,
                   const std::vector<bool>& alone, int jobs,
                   const std::function<void(int)>& fn);

// ------------------------------------- pieces shared by the suite drivers ----
// RunSuite (threads), `bench --shard` (one slice per process) and
// quasiroll-mpi (runs handed out to MPI ranks) are the same steps:
// PlanSuite, BeginSuiteOutput, ReferenceJob::Compute for the references,
// ExecuteRun for every pending run, FinishSuiteOutput.

// The reference trajectory of one effective scene (docs/harness.md,
// References), needed by one or more runs.
struct ReferenceJob {
  Scene scene;
  TerrainSpec terrain;
  std::string digest, label, key, nlp;
  std::optional<Reference> reference;
  std::string error;  // why `reference` is empty ("" = not computed yet)
  // Loads DIR/references/<hash> or computes and caches it; a failure is
  // kept in `error`, except a FileWriteError (a full disk), which is thrown.
  void Compute(const std::string& dir, const ReferenceSettings& settings);
};

// The reference job of a run's effective scene (not computed yet).
ReferenceJob ReferenceJobFor(const Suite& suite, const RunSpec& run);
// Its cache key (ReferenceKey): runs with equal keys share a reference.
std::string RunReferenceKey(const Suite& suite, const RunSpec& run);

struct SuitePlan {
  std::vector<const RunSpec*> selected;  // --filter and --shard, grid order
  std::vector<std::string> terrain_ids;  // per selected run
  std::vector<std::string> rows;         // runs.csv lines ("" = not run yet)
  std::vector<int> pending;              // selected runs to execute
  int resumed = 0;                       // rows taken from DIR/runs/
  std::vector<ReferenceJob> references;  // needed by the pending runs
  std::vector<int> run_reference;        // per selected run; -1 if resumed
};

// Selection (filter, shard), --resume (rows of finished runs) and the
// references the pending runs need. Throws SceneError for a bad filter.
SuitePlan PlanSuite(const Suite& suite, const HarnessOptions& options);
// Creates DIR, writes meta.json (complete: false) and DIR/terrains/.
void BeginSuiteOutput(const Suite& suite, const HarnessOptions& options,
                      const SuitePlan& plan, int jobs,
                      const std::string& start_time);

struct RunOutcome {
  std::string row;     // runs.csv line (no newline)
  std::string status;  // its status column
  double t_reached = 0;
  double wall_seconds = 0;  // first repeat
};
// Runs one grid point (all repeats), compares it with its reference and
// writes DIR/trajectories/<run_id>.csv, then DIR/runs/<run_id>.csv. A run
// that fails or throws is a row (status "error" for an exception); only I/O
// errors propagate.
RunOutcome ExecuteRun(const Suite& suite, const RunSpec& run,
                      const std::string& terrain_id,
                      const ReferenceJob& reference, const std::string& dir);

// Writes runs.csv (plan.rows in grid order) and meta.json (complete).
HarnessSummary FinishSuiteOutput(const Suite& suite,
                                 const HarnessOptions& options,
                                 const SuitePlan& plan, int jobs,
                                 const std::string& start_time,
                                 double wall_seconds);

// "<I>-of-<N>" for a shard, "" otherwise.
std::string ShardName(const HarnessOptions& options);
// Where runs.csv and meta.json go: DIR, or DIR/shards/<I>-of-<N>.
std::string SuiteOutputDir(const HarnessOptions& options);

// Progress on a log stream (HarnessOptions::progress modes); thread-safe.
class Progress {
 public:
  Progress(std::FILE* log, int mode, int total);
  void Done(const std::string& run_id, const std::string& status,
            double t_reached, double wall);
  void Message(const std::string& text);

 private:
  std::mutex mutex_;
  std::FILE* log_;
  int mode_;
  int total_;
  int done_ = 0, failed_ = 0;
  double start_ = 0;  // steady clock, seconds
};

// quasiroll's run-time data directory (scenes, suites, the report
// generator): $QUASIROLL_DATA_DIR if set, else <exe dir>/../share/quasiroll
// when that exists (an installed prefix, or the build tree, where CMake
// links build/share/quasiroll to the sources), else the configured install
// prefix's share/quasiroll.
std::string DataDirectory();
// DataDirectory() + "/reports/make_report.py".
std::string ReportScriptPath();

}  // namespace quasiroll::bench
