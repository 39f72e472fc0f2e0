#include "quasiroll/bench/harness/harness.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "quasiroll/bench/harness/failure_causes.h"
#include "quasiroll/bench/harness/method_id.h"
#include "quasiroll/bench/harness/metrics.h"
#include "quasiroll/bench/harness/run_status.h"
#include "quasiroll/bench/harness/shard.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/output_lock.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/bench/io/runs_schema.h"
#include "quasiroll/bench/io/terrain_json.h"
#include "quasiroll/core/checkpoints.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/slip_regimes.h"

namespace quasiroll::bench {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const std::vector<std::string>& RunsCsvColumns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> names;
    for (const RunsColumn& c : RunsCsvSchema()) names.push_back(c.name);
    return names;
  }();
  return columns;
}

namespace {

std::string OneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

std::string Header() { return JoinCsvRow(RunsCsvColumns()); }

std::size_t ColumnIndex(const std::string& column) {
  const auto& cols = RunsCsvColumns();
  const auto it = std::find(cols.begin(), cols.end(), column);
  if (it == cols.end()) throw std::logic_error("unknown column " + column);
  return static_cast<std::size_t>(it - cols.begin());
}

class RowBuilder {
 public:
  RowBuilder() : values_(RunsCsvColumns().size(), "") {}
  void Set(const std::string& column, const std::string& value) {
    const auto& cols = RunsCsvColumns();
    const auto it = std::find(cols.begin(), cols.end(), column);
    if (it == cols.end()) throw std::logic_error("unknown column " + column);
    values_[it - cols.begin()] = value;
  }
  void Set(const std::string& column, double v) { Set(column, Num(v)); }
  void SetInt(const std::string& column, long long v) {
    Set(column, std::to_string(v));
  }
  std::vector<std::string> values() const { return values_; }

 private:
  std::vector<std::string> values_;
};

// A YAML flow value (scene_fields) as JSON: numbers and [..] sequences of
// numbers are JSON already; anything else (mode: pvc) becomes a string.
std::string ValueAsJson(const std::string& flow) {
  const bool numeric =
      !flow.empty() &&
      flow.find_first_not_of("0123456789+-.eE[], ") == std::string::npos;
  return numeric ? flow : "\"" + flow + "\"";
}

void SetParameters(const RunSpec& run, const std::string& terrain_id,
                   RowBuilder* b) {
  b->Set("run_id", run.run_id);
  b->Set("suite_group", run.group);
  b->Set("scene", run.scene);
  b->Set("terrain", terrain_id);
  b->Set("nlp", run.nlp);
  b->Set("dae", run.dae);
  b->Set("coupling", ToString(run.coupling));
  b->Set("method", MethodId(run));
  b->Set("rk_method", run.rk_method);
  b->Set("dt", run.dt);
  b->Set("tol", run.tol);
  b->Set("atol", run.atol);
  b->Set("nlp_tol", run.nlp_tol);
  b->Set("sigma", run.sigma);
  b->Set("eps", run.eps);
  b->SetInt("dae_index", run.dae_index);
  b->SetInt("substeps", run.substeps);
  b->SetInt("contact_check", run.contact_check);
  b->SetInt("nlp_max_iter", run.nlp_max_iter);
  b->Set("locate_events", run.locate_events ? "true" : "false");
  b->SetInt("event_points", run.event_points);
  b->Set("event_tolerance", run.event_tolerance);
  b->Set("locate_switches", run.locate_switches ? "true" : "false");
  b->Set("mu", run.mu);
  b->Set("seed", run.seed ? std::to_string(*run.seed) : "");
  b->Set("roughness", run.roughness);
  b->Set("t_end", run.t_end);
  b->SetInt("repeats", run.repeats);
  b->SetInt("timing_exclusive", run.exclusive ? 1 : 0);
  b->Set("host", ThisMachine().hostname);
  b->Set("cpu_model", ThisMachine().cpu);
  std::string fields = "{";
  for (const auto& [field, value] : run.scene_fields) {
    if (fields.size() > 1) fields += ",";
    fields += "\"" + field + "\":" + ValueAsJson(value);
  }
  b->Set("scene_fields", run.scene_fields.empty() ? "" : fields + "}");
}

void SetReference(const Reference* ref, const std::string& error,
                  RowBuilder* b) {
  if (ref) {
    b->Set("ref_kind", ref->kind);
    b->Set("ref_status", ref->status);
    b->Set("ref_hash", ref->hash);
    b->Set("reference_stop", ref->stop);
    if (!std::isnan(ref->mu_min_max)) b->Set("ref_mu_min", ref->mu_min_max);
    if (!std::isnan(ref->err_est)) b->Set("ref_err_est", ref->err_est);
    if (!std::isnan(ref->check_t_diff))
      b->Set("ref_check_t_diff", ref->check_t_diff);
  } else {
    b->Set("ref_kind", "none");
    b->Set("ref_status", error.empty() ? "none" : "error");
  }
}

void SetNanMetrics(RowBuilder* b) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const char* c :
       {"err_pos_rms", "err_pos_max", "err_final", "err_final_rot",
        "err_rot_max", "err_force_rms", "err_slip", "drift_max", "drift_final",
        "gap_max", "err_stop_t"})
    b->Set(c, nan);
  b->SetInt("common_samples", 0);
  b->SetInt("checkpoints", 0);
}

FailureEvidence Evidence(const RunSpec& run, RunStatus status, double t_reached,
                         const Reference* reference) {
  FailureEvidence e;
  e.status = status;
  e.t_reached = t_reached;
  e.dt = run.dt;
  std::unique_ptr<Integrator> dae = IntegratorRegistry::Create(run.dae);
  dae->SetBackendOptions(run.dae_options);
  e.known_instability = IntegratorRegistry::Info(run.dae).KnownInstability(
      dae->backend_options(), run.dt / run.substeps);
  e.contact_check = run.contact_check;
  e.drift_bound = run.bounds.drift;
  e.gap_bound = run.bounds.gap;
  if (reference && !reference->samples.empty()) {
    e.has_reference = true;
    e.ref_status = ParseRunStatus(reference->status);
    e.ref_t_reached = reference->samples.back().t;
    e.ref_breakaway = reference->stop == "model:breakaway";
    if (reference->samples.size() >= 2)
      e.ref_dt = reference->samples[1].t - reference->samples[0].t;
  }
  return e;
}

// The simulator's stop as a RunStatus. Its statuses are the quasi-static and
// integrator enums' spellings, all of them RunStatus values
// (tests/bench/run_status_test.cc): another text is a bug.
RunStatus SimulatedStatus(const SimulationResult& result) {
  const std::optional<RunStatus> s = ParseRunStatus(result.status);
  if (!s) throw std::logic_error("unknown simulation status " + result.status);
  return *s;
}

}  // namespace

std::vector<std::string> MakeRow(const RunSpec& run,
                                 const std::string& terrain_id,
                                 const SimulationResult& result,
                                 const std::vector<double>& wall_seconds,
                                 const Scene& scene, const Reference* reference,
                                 const std::string& reference_error) {
  RowBuilder b;
  SetParameters(run, terrain_id, &b);
  // The harness's verdict: a run that reached t_end is a success only with
  // its constraint drift and geometric gap within the suite's bounds.
  const DriftMetrics d = ComputeDrift(result.samples);
  const RunStatus simulated = SimulatedStatus(result);
  RunStatus status = simulated;
  std::string stop_reason = result.stop_reason;
  if (result.success() && d.drift_max > run.bounds.drift) {
    status = RunStatus::kDriftExceeded;
    stop_reason = "drift_max " + Num(d.drift_max) + " > bounds.drift " +
                  Num(run.bounds.drift);
  } else if (result.success() && d.gap_max > run.bounds.gap) {
    status = RunStatus::kGapExceeded;
    stop_reason = "gap_max " + Num(d.gap_max) + " m > bounds.gap " +
                  Num(run.bounds.gap) + " m";
  }
  b.Set("status", ToString(status));
  b.Set("stop_reason", OneLine(stop_reason));
  b.Set("t_reached", result.t_reached);
  b.Set("mu_min", simulated == RunStatus::kInfeasibleFriction
                      ? Num(result.mu_min_at_stop)
                      : std::string());
  b.Set("critical_wheel", result.critical_contact > 0
                              ? std::to_string(result.critical_contact)
                              : "");
  const TimingStats timing = ComputeTimingStats(wall_seconds);
  b.Set("wall_s", timing.min);
  b.SetInt("nlp_solves", result.nlp_solves);
  b.SetInt("nlp_iters", result.nlp_iterations);
  b.SetInt("nlp_iters_native", result.nlp_iterations_native);
  b.SetInt("rhs_evals", result.rhs_evaluations);
  b.SetInt("jac_evals", result.jacobian_evaluations);
  b.SetInt("steps", result.steps);
  b.SetInt("rejected_steps", result.rejected_steps);
  b.SetInt("samples", static_cast<long long>(result.samples.size()));
  b.Set("nlp_options", result.nlp_options.Json());
  b.Set("dae_options", result.dae_options.Json());
  SetReference(reference, reference_error, &b);
  SetNanMetrics(&b);
  if (reference) {
    // At the checkpoints (core/checkpoints.h), not the run's own samples.
    std::vector<double> times;
    times.reserve(result.checkpoints.size());
    for (const TrajectorySample& s : result.checkpoints) times.push_back(s.t);
    const AccuracyMetrics a =
        CompareAtCheckpoints(result.checkpoints, reference->ForTimes(times),
                             result.success(), result.t_reached);
    b.SetInt("common_samples",
             CountCommonSamples(result.samples, reference->samples));
    b.SetInt("checkpoints", a.common_samples);
    b.Set("err_pos_rms", a.pos_rms);
    b.Set("err_pos_max", a.pos_max);
    b.Set("err_final", a.final_pos);
    b.Set("err_final_rot", a.final_rot);
    b.Set("err_rot_max", a.rot_max);
    b.Set("err_force_rms", a.force_rms);
    b.Set("err_slip", a.slip_rms);
  }
  b.Set("drift_max", d.drift_max);
  b.Set("drift_final", d.drift_final);
  b.Set("drift_step_max", result.step_drift_max);
  b.Set("gap_max", d.gap_max);
  b.Set("kkt_residual", result.kkt_residual);
  FailureEvidence e = Evidence(run, status, result.t_reached, reference);
  e.drift_max = d.drift_max;
  e.gap_max = d.gap_max;
  // The run's own motion up to its stop, on its own output grid (with the
  // stop's state solved again after a SOLVER_FAILURE: a breakaway's twist,
  // model.md §8.8): the value the row shows. (The reference's motion would be
  // measured on its finer grid, where a velocity jump at a slide switch reads
  // as a larger acceleration: not comparable with the bound.)
  const double qs_ratio = QuasiStaticInertiaRatio(result, scene);
  e.qs_inertia_bound = run.bounds.qs_inertia;
  e.qs_inertia_ratio = qs_ratio;
  const FailureCause cause = ClassifyFailure(e);
  b.Set("cause", cause.cause);
  b.Set("cause_detail", cause.detail);
  // Both stopped at the limit: how far apart (the reference's last sample
  // is its located stop).
  if (cause.cause == "physical" && e.has_reference && e.ref_status &&
      *e.ref_status != RunStatus::kSuccess)
    b.Set("err_stop_t", result.t_reached - e.ref_t_reached);
  b.Set("t_reached_frac", result.t_reached / run.t_end);
  b.Set("wall_s_median", timing.median);
  b.Set("wall_s_min", timing.min);
  b.Set("wall_s_max", timing.max);
  b.Set("wall_s_q1", timing.q1);
  b.Set("wall_s_q3", timing.q3);
  b.Set("wall_s_iqr", timing.q3 - timing.q1);
  std::string all;
  for (double w : wall_seconds) all += (all.empty() ? "" : ";") + Num(w);
  b.Set("wall_s_all", all);
  b.Set("wall_per_sim_s", result.t_reached > 0
                              ? timing.median / result.t_reached
                              : std::numeric_limits<double>::quiet_NaN());
  b.Set("qs_inertia_ratio", qs_ratio);
  const SlipDistances slip = TotalSlipDistances(result.samples);
  b.Set("sliding_distance", slip.sliding);
  b.Set("creep_distance", slip.creep);
  return b.values();
}

std::vector<std::string> ErrorRow(const RunSpec& run,
                                  const std::string& terrain_id,
                                  const std::string& message,
                                  const Reference* reference,
                                  const std::string& reference_error) {
  RowBuilder b;
  SetParameters(run, terrain_id, &b);
  b.Set("status", ToString(RunStatus::kError));
  b.Set("stop_reason", OneLine(message));
  b.Set("t_reached", std::numeric_limits<double>::quiet_NaN());
  b.Set("wall_s", std::numeric_limits<double>::quiet_NaN());
  for (const char* c :
       {"nlp_solves", "nlp_iters", "rhs_evals", "jac_evals", "steps",
        "rejected_steps", "samples", "nlp_iters_native"})
    b.SetInt(c, 0);
  SetReference(reference, reference_error, &b);
  SetNanMetrics(&b);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const char* c :
       {"kkt_residual", "drift_step_max", "t_reached_frac", "wall_s_median",
        "wall_s_min", "wall_s_max", "wall_per_sim_s", "qs_inertia_ratio",
        "sliding_distance", "creep_distance", "wall_s_q1", "wall_s_q3",
        "wall_s_iqr"})
    b.Set(c, nan);
  const FailureCause cause =
      ClassifyFailure(Evidence(run, RunStatus::kError, nan, reference));
  b.Set("cause", cause.cause);
  b.Set("cause_detail", cause.detail);
  return b.values();
}

std::string DataDirectory() {
  if (const char* env = std::getenv("QUASIROLL_DATA_DIR"); env && *env)
    return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = exe.parent_path().parent_path() / "share/quasiroll";
    if (fs::is_directory(beside, ec)) return beside.string();
  }
#ifdef QUASIROLL_INSTALL_DATA_DIR
  return QUASIROLL_INSTALL_DATA_DIR;
#else
  return "share/quasiroll";
#endif
}

std::string ReportScriptPath() {
  return DataDirectory() + "/reports/make_report.py";
}

// ---------------------------------------------------------------- runner
// ----

namespace {

// Exclusive class of a run's NLP backend: 0 if solver objects of the backend
// may run in parallel threads (NlpSolver::SupportsConcurrentInstances()),
// otherwise a class > 0 of its own, so that two runs of that backend (e.g.
// ipopt-mumps: sequential MUMPS is not thread-safe) never run at once.
class ExclusiveClasses {
 public:
  int Of(const std::string& nlp) {
    auto [it, inserted] = classes_.emplace(nlp, 0);
    if (inserted && NlpSolverRegistry::Has(nlp) &&
        !NlpSolverRegistry::Create(nlp)->SupportsConcurrentInstances())
      it->second = static_cast<int>(classes_.size());
    return it->second;
  }

 private:
  std::map<std::string, int> classes_;
};

std::string ReadFileOr(const std::string& path, bool* ok) {
  std::ifstream in(path, std::ios::binary);
  *ok = static_cast<bool>(in);
  if (!in) return "";
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string FormatDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long total = std::lround(s);
  char buf[32];
  if (total >= 3600)
    std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", total / 3600,
                  (total / 60) % 60, total % 60);
  else
    std::snprintf(buf, sizeof(buf), "%ld:%02ld", total / 60, total % 60);
  return buf;
}

// A pool of `jobs` threads taking tasks in order, except that a task of a
// non-zero exclusive class waits while another task of its class runs (and
// is preferred when its class is free, so that serial chains start early).
class Scheduler {
 public:
  Scheduler(std::vector<int> classes, int jobs)
      : classes_(std::move(classes)),
        jobs_(std::max(1, jobs)),
        taken_(classes_.size(), false),
        remaining_(static_cast<int>(classes_.size())) {}

  // Runs fn(task) for every task; the first exception thrown by fn is
  // rethrown after all threads have finished. No task starts after one has
  // thrown: a write failure (a full disk) would fail every later run too,
  // after computing it.
  template <typename Fn>
  void Run(Fn fn) {
    std::vector<std::thread> threads;
    const int n = std::min<int>(jobs_, static_cast<int>(classes_.size()));
    for (int i = 0; i < n; ++i) threads.emplace_back([this, &fn] { Work(fn); });
    for (std::thread& t : threads) t.join();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  template <typename Fn>
  void Work(Fn& fn) {
    for (;;) {
      int task = -1;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] {
          if (error_) return true;
          task = Pick();
          return task >= 0 || remaining_ == 0;
        });
        if (error_) return;
        if (task < 0) {
          if (remaining_ == 0) return;
          continue;
        }
        taken_[task] = true;
        --remaining_;
        if (classes_[task]) busy_.insert(classes_[task]);
      }
      std::exception_ptr error;
      try {
        fn(task);
      } catch (...) {
        error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (classes_[task]) busy_.erase(classes_[task]);
        if (error && !error_) error_ = error;
      }
      cv_.notify_all();
    }
  }
  // First untaken task, preferring a free exclusive class; -1 if none is
  // runnable now.
  int Pick() const {
    int first_plain = -1;
    for (std::size_t i = 0; i < classes_.size(); ++i) {
      if (taken_[i]) continue;
      const int c = classes_[i];
      if (c == 0) {
        if (first_plain < 0) first_plain = static_cast<int>(i);
      } else if (!busy_.count(c)) {
        return static_cast<int>(i);
      }
    }
    return first_plain;
  }
  std::vector<int> classes_;
  int jobs_;
  std::vector<bool> taken_;
  int remaining_;
  std::set<int> busy_;
  std::exception_ptr error_;
  std::mutex mutex_;
  std::condition_variable cv_;
};

// The reference configurations in words (meta.json `reference_method`); the
// per-reference method, ref_mu_min and ref_err_est are in
// references/<hash>.json (not here: a merged directory's meta.json must not
// depend on which process computed which reference).
void WriteReferenceMethod(const Suite& suite, JsonWriter* w) {
  const ReferenceSettings& r = suite.reference;
  const int per_output = r.dt_divisor * r.substeps;
  w->Key("reference_method").BeginObject();
  w->Key("primary").Value("coupled rk-projection rk4, step = scene dt / " +
                          std::to_string(per_output) +
                          ", output every scene dt / " +
                          std::to_string(r.dt_divisor) + ", " + r.nlp +
                          " at residual " + Num(r.residual_tolerance));
  w->Key("fallback")
      .Value(
          "coupled rk-projection dp54 rtol 1e-10 atol 1e-12 (kind "
          "numerical:dp54), when the primary breaks down numerically");
  w->Key("check").Value(
      "coupled rk-projection dp54 rtol 1e-10 atol 1e-12 for an rk4 "
      "reference, coupled ida (index 2) rtol 1e-10 atol 1e-12 for a dp54 "
      "one; ref_err_est = max |p_ref - p_check| over common times");
  w->Key("analytic").Value(r.analytic);
  w->EndObject();
}

void WriteMeta(const Suite& suite, const HarnessOptions& options, int jobs,
               const std::string& start, const std::string& end,
               const HarnessSummary* summary) {
  JsonWriter w;
  w.BeginObject();
  w.Key("suite").BeginObject();
  w.Key("name").Value(suite.name);
  w.Key("path").Value(suite.path);
  w.Key("absolute_path")
      .Value(suite.path.empty() ? std::string()
                                : fs::absolute(suite.path).string());
  w.Key("hash").Value(Hex64(suite.text_hash));
  w.Key("groups").BeginArray();
  for (const std::string& g : suite.groups) w.Value(g);
  w.EndArray();
  w.Key("runs_total").Value(static_cast<int>(suite.runs.size()));
  w.EndObject();
  w.Key("suite_hash").Value(Hex64(suite.text_hash));
  w.Key("reference").Value(suite.reference.Canonical());
  // The suite's validity bound (groups may override it: their runs' rows
  // carry the verdict); the report's threshold.
  w.Key("qs_inertia_threshold").Value(suite.bounds.qs_inertia);
  WriteReferenceMethod(suite, &w);
  w.Key("commit").Value(GitCommit());
  w.Key("library_versions");
  WriteLibraryVersions(&w);
  w.Key("numerical_libraries");
  WriteNumericalLibraries(&w);
  w.Key("build");
  WriteBuildOptions(&w);
  w.Key("backends");
  WriteBackends(&w);
  w.Key("plugins");
  WritePlugins(&w);
  if (!Invocation().empty()) w.Key("command").Value(Invocation());
  w.Key("machine");
  WriteMachine(&w);
  w.Key("jobs").Value(jobs);
  w.Key("filter").Value(options.filter);
  w.Key("resume").Value(options.resume);
  w.Key("options").BeginObject();
  w.Key("out").Value(options.out_dir);
  w.Key("jobs").Value(jobs);
  w.Key("filter").Value(options.filter);
  w.Key("resume").Value(options.resume);
  w.EndObject();
  if (options.mpi_ranks > 0) {
    w.Key("mpi").BeginObject();
    w.Key("ranks").Value(options.mpi_ranks);
    w.EndObject();
  }
  if (options.shard_count > 0) {
    w.Key("shard").BeginObject();
    w.Key("index").Value(options.shard_index);
    w.Key("count").Value(options.shard_count);
    w.EndObject();
  }
  w.Key("start_time").Value(start);
  if (summary) {
    w.Key("end_time").Value(end);
    w.Key("wall_s").Value(summary->wall_seconds);
    w.Key("runs_selected").Value(summary->selected);
    w.Key("runs_executed").Value(summary->executed);
    w.Key("runs_resumed").Value(summary->resumed);
    w.Key("failures").Value(summary->failures);
    w.Key("complete").Value(true);
  } else {
    w.Key("complete").Value(false);
  }
  w.EndObject();
  AtomicWriteFile(SuiteOutputDir(options) + "/meta.json", w.str() + "\n");
}

double SteadySeconds() {
  return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

}  // namespace

Progress::Progress(std::FILE* log, int mode, int total)
    : log_(log), mode_(mode), total_(total), start_(SteadySeconds()) {
  if (mode_ < 0) mode_ = (log_ && ::isatty(::fileno(log_))) ? 2 : 1;
  if (!log_) mode_ = 0;
}

void Progress::Done(const std::string& run_id, const std::string& status,
                    double t_reached, double wall) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++done_;
  if (ParseRunStatus(status) != RunStatus::kSuccess) ++failed_;
  const double elapsed = SteadySeconds() - start_;
  const double eta = done_ > 0 ? elapsed / done_ * (total_ - done_) : NAN;
  if (mode_ == 1) {
    std::fprintf(log_, "[%d/%d] %s: %s (t=%s s, %.3f s wall)\n", done_, total_,
                 run_id.c_str(), status.c_str(), Num(t_reached).c_str(), wall);
  } else if (mode_ == 2) {
    std::fprintf(log_, "\r\033[K%d/%d runs, %d failed, elapsed %s, ETA %s",
                 done_, total_, failed_, FormatDuration(elapsed).c_str(),
                 FormatDuration(eta).c_str());
    if (done_ == total_) std::fprintf(log_, "\n");
  }
  if (mode_) std::fflush(log_);
}

void Progress::Message(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!log_ || mode_ == 0) return;
  std::fprintf(log_, "%s\n", text.c_str());
  std::fflush(log_);
}

void ReferenceJob::Compute(const std::string& dir,
                           const ReferenceSettings& settings) {
  try {
    reference =
        LoadOrComputeReference(dir, scene, terrain, digest, settings, label);
  } catch (const FileWriteError&) {
    // Not a property of the reference: its runs' rows would be kept by
    // --resume without their accuracy (a full disk stops the suite).
    throw;
  } catch (const std::exception& e) {
    error = e.what();
  }
}

std::string ShardName(const HarnessOptions& options) {
  if (options.shard_count <= 0) return "";
  return std::to_string(options.shard_index) + "-of-" +
         std::to_string(options.shard_count);
}

std::string SuiteOutputDir(const HarnessOptions& options) {
  if (options.shard_count <= 0) return options.out_dir;
  return options.out_dir + "/shards/" + ShardName(options);
}

ReferenceJob ReferenceJobFor(const Suite& suite, const RunSpec& run) {
  const SuiteScene& sc = suite.scenes[run.scene_index];
  ReferenceJob job;
  job.scene = ReferenceScene(suite, run);
  job.terrain = SweptTerrain(sc, run.seed, run.roughness);
  job.digest = sc.heightmap_digest;
  job.label = sc.name;
  job.nlp = suite.reference.Nlp();
  job.key = ReferenceKey(job.scene, job.terrain, job.digest, suite.reference);
  return job;
}

std::string RunReferenceKey(const Suite& suite, const RunSpec& run) {
  return ReferenceJobFor(suite, run).key;
}

SuitePlan PlanSuite(const Suite& suite, const HarnessOptions& options) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  SuitePlan plan;
  const std::string& dir = options.out_dir;

  // Selection: --filter, then --shard.
  {
    std::optional<std::regex> re;
    if (!options.filter.empty()) {
      try {
        re.emplace(options.filter, std::regex::ECMAScript);
      } catch (const std::regex_error& e) {
        throw SceneError("--filter: invalid regular expression (" +
                         std::string(e.what()) + "), got \"" + options.filter +
                         "\"");
      }
    }
    for (const RunSpec& r : suite.runs)
      if (!re || std::regex_search(r.run_id, *re)) plan.selected.push_back(&r);
  }
  if (options.shard_count > 0) {
    if (options.shard_index < 0 || options.shard_index >= options.shard_count)
      throw SceneError("--shard: expected I/N with 0 <= I < N, got " +
                       ShardName(options));
    std::vector<double> costs;
    std::vector<std::string> keys;
    for (const RunSpec* r : plan.selected) {
      costs.push_back(EstimatedRunCost(*r));
      keys.push_back(RunReferenceKey(suite, *r));
    }
    const std::vector<int> shard =
        AssignShards(costs, keys, options.shard_count);
    std::vector<const RunSpec*> mine;
    for (std::size_t k = 0; k < plan.selected.size(); ++k)
      if (shard[k] == options.shard_index) mine.push_back(plan.selected[k]);
    plan.selected = std::move(mine);
  }

  const std::string header = Header();
  plan.rows.assign(plan.selected.size(), "");
  plan.terrain_ids.resize(plan.selected.size());
  plan.run_reference.assign(plan.selected.size(), -1);
  for (std::size_t i = 0; i < plan.selected.size(); ++i) {
    const RunSpec& r = *plan.selected[i];
    plan.terrain_ids[i] = TerrainId(r, suite.scenes[r.scene_index]);
    if (options.resume) {
      bool ok_row = false, ok_traj = false;
      const std::string text =
          ReadFileOr(dir + "/runs/" + r.run_id + ".csv", &ok_row);
      ReadFileOr(dir + "/trajectories/" + r.run_id + ".csv", &ok_traj);
      const std::string prefix = header + "\n" + r.run_id + ",";
      if (ok_row && ok_traj && text.rfind(prefix, 0) == 0 &&
          text.back() == '\n') {
        std::string row = text.substr(header.size() + 1);
        row.pop_back();
        if (row.find('\n') == std::string::npos) {
          plan.rows[i] = row;
          ++plan.resumed;
          continue;
        }
      }
    }
    plan.pending.push_back(static_cast<int>(i));
  }

  // References needed by the pending runs, one job per distinct key.
  std::map<std::string, int> ref_index;  // key -> references index
  for (int i : plan.pending) {
    ReferenceJob job = ReferenceJobFor(suite, *plan.selected[i]);
    auto [it, inserted] =
        ref_index.emplace(job.key, static_cast<int>(plan.references.size()));
    if (inserted) plan.references.push_back(std::move(job));
    plan.run_reference[i] = it->second;
  }
  return plan;
}

void BeginSuiteOutput(const Suite& suite, const HarnessOptions& options,
                      const SuitePlan& plan, int jobs,
                      const std::string& start_time) {
  const std::string& dir = options.out_dir;
  fs::create_directories(dir);
  WriteMeta(suite, options, jobs, start_time, "", nullptr);
  // Terrains for the report (one file per terrain id).
  std::set<std::string> written;
  for (std::size_t i = 0; i < plan.selected.size(); ++i) {
    if (!written.insert(plan.terrain_ids[i]).second) continue;
    const RunSpec& r = *plan.selected[i];
    const std::string json = TerrainJson(
        SweptTerrain(suite.scenes[r.scene_index], r.seed, r.roughness));
    if (!json.empty())
      AtomicWriteFile(dir + "/terrains/" + plan.terrain_ids[i] + ".json", json);
  }
}

RunOutcome ExecuteRun(const Suite& suite, const RunSpec& run,
                      const std::string& terrain_id,
                      const ReferenceJob& reference, const std::string& dir) {
  const Reference* ref = reference.reference ? &*reference.reference : nullptr;
  std::vector<std::string> row;
  SimulationResult result;
  try {
    ResolvedRun resolved = ResolveRun(suite, run);
    if (ref) {
      std::vector<double> ref_times;
      for (const TrajectorySample& s : ref->samples) ref_times.push_back(s.t);
      resolved.options.checkpoints =
          CheckpointTimes(ref_times, run.checkpoint_interval);
    }
    const Scene& scene = resolved.scene;
    Simulator sim(scene, resolved.options);
    result = sim.Run();
    std::vector<double> walls = {result.wall_seconds};
    for (int rep = 1; rep < run.repeats; ++rep)
      walls.push_back(sim.Run().wall_seconds);
    row = MakeRow(run, terrain_id, result, walls, scene, ref, reference.error);
  } catch (const std::exception& e) {
    result = SimulationResult{};
    result.status = ToString(RunStatus::kError);
    row = ErrorRow(run, terrain_id, e.what(), ref, reference.error);
  }
  RunOutcome outcome;
  outcome.row = JoinCsvRow(row);
  outcome.status = row[ColumnIndex("status")];
  outcome.t_reached = result.t_reached;
  outcome.wall_seconds = result.wall_seconds;
  AtomicWriteFile(dir + "/trajectories/" + run.run_id + ".csv",
                  TrajectoryCsv(result));
  AtomicWriteFile(dir + "/checkpoints/" + run.run_id + ".csv",
                  TrajectoryCsv(result.checkpoints));
  AtomicWriteFile(dir + "/switches/" + run.run_id + ".csv",
                  SwitchesCsv(result.switches));
  AtomicWriteFile(dir + "/runs/" + run.run_id + ".csv",
                  Header() + "\n" + outcome.row + "\n");
  return outcome;
}

HarnessSummary FinishSuiteOutput(const Suite& suite,
                                 const HarnessOptions& options,
                                 const SuitePlan& plan, int jobs,
                                 const std::string& start_time,
                                 double wall_seconds) {
  HarnessSummary summary;
  summary.total = static_cast<int>(suite.runs.size());
  summary.selected = static_cast<int>(plan.selected.size());
  summary.executed = static_cast<int>(plan.pending.size());
  summary.resumed = plan.resumed;
  // runs.csv in grid order.
  std::string csv = Header() + "\n";
  const std::size_t status_col = ColumnIndex("status");
  for (const std::string& row : plan.rows) {
    csv += row + "\n";
    // The status field never needs quoting; find it by counting fields up to
    // it (earlier fields never contain commas either: names and numbers).
    std::size_t pos = 0;
    for (std::size_t c = 0; c < status_col && pos != std::string::npos; ++c)
      pos = row.find(',', pos) + 1;
    const std::string status = row.substr(pos, row.find(',', pos) - pos);
    if (ParseRunStatus(status) != RunStatus::kSuccess) ++summary.failures;
  }
  AtomicWriteFile(SuiteOutputDir(options) + "/runs.csv", csv);
  summary.wall_seconds = wall_seconds;
  WriteMeta(suite, options, jobs, start_time, IsoTimeNow(), &summary);
  return summary;
}

void ScheduleTasks(const std::vector<int>& classes,
                   const std::vector<bool>& alone, int jobs,
                   const std::function<void(int)>& fn) {
  if (alone.size() != classes.size())
    throw std::invalid_argument("ScheduleTasks: classes and alone differ");
  for (const bool phase : {false, true}) {
    std::vector<int> tasks, phase_classes;
    for (std::size_t k = 0; k < classes.size(); ++k) {
      if (alone[k] != phase) continue;
      tasks.push_back(static_cast<int>(k));
      phase_classes.push_back(classes[k]);
    }
    Scheduler(phase_classes, phase ? 1 : jobs).Run([&](int j) {
      fn(tasks[j]);
    });
  }
}

HarnessSummary RunSuite(const Suite& suite, const HarnessOptions& options) {
  const auto t_start = Clock::now();
  const std::string start_time = IsoTimeNow();
  const std::string& dir = options.out_dir;
  int jobs = options.jobs > 0
                 ? options.jobs
                 : static_cast<int>(std::thread::hardware_concurrency());
  if (jobs <= 0) jobs = 1;

  // One writer per output (bench/io/output_lock.h), before resume reads it.
  const std::vector<OutputLock> locks = LockOutputDirectory(
      dir, options.shard_count > 0 ? SuiteOutputDir(options) : "", "--out");
  SuitePlan plan = PlanSuite(suite, options);
  BeginSuiteOutput(suite, options, plan, jobs, start_time);

  Progress progress(options.log, options.progress,
                    static_cast<int>(plan.pending.size()));
  if (plan.resumed > 0)
    progress.Message("resume: " + std::to_string(plan.resumed) + " of " +
                     std::to_string(plan.selected.size()) +
                     " runs already done");

  ExclusiveClasses exclusive;
  {
    std::vector<int> classes;
    for (const ReferenceJob& j : plan.references)
      classes.push_back(exclusive.Of(j.nlp));
    Scheduler(classes, jobs).Run([&](int k) {
      ReferenceJob& j = plan.references[k];
      j.Compute(dir, suite.reference);
      if (!j.error.empty())
        progress.Message("reference for scene " + j.label +
                         " failed: " + j.error);
    });
  }

  // Runs: the shared ones in `jobs` threads, then the exclusive ones
  // (group key `exclusive`) one at a time with nothing else running.
  {
    std::vector<int> classes;
    std::vector<bool> alone;
    for (int i : plan.pending) {
      classes.push_back(exclusive.Of(plan.selected[i]->nlp));
      alone.push_back(plan.selected[i]->exclusive);
    }
    ScheduleTasks(classes, alone, jobs, [&](int k) {
      const int i = plan.pending[k];
      const RunOutcome out =
          ExecuteRun(suite, *plan.selected[i], plan.terrain_ids[i],
                     plan.references[plan.run_reference[i]], dir);
      plan.rows[i] = out.row;
      progress.Done(plan.selected[i]->run_id, out.status, out.t_reached,
                    out.wall_seconds);
    });
  }

  return FinishSuiteOutput(
      suite, options, plan, jobs, start_time,
      std::chrono::duration<double>(Clock::now() - t_start).count());
}

}  // namespace quasiroll::bench
