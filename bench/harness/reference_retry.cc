#include "quasiroll/bench/harness/reference_retry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/slip_regimes.h"

namespace quasiroll::bench {

bool IsPhysicalReferenceStatus(const std::string& status) {
  return status == "INFEASIBLE_FRICTION" || status == "LIFT_OFF" ||
         status == "DEGENERATE_CONTACT";
}

bool BreakawayStop(const SimulationResult& result, const Scene& scene) {
  return !result.success() && !IsPhysicalReferenceStatus(result.status) &&
         StopInertiaRatio(result, scene) > kQuasiStaticInertiaThreshold;
}

std::string ReferenceStopOf(const SimulationResult& result,
                            const Scene& scene) {
  if (result.success()) return "end";
  if (BreakawayStop(result, scene)) return "model:breakaway";
  if (!IsPhysicalReferenceStatus(result.status)) return "reference_failure";
  std::string limit = result.event.limit;
  if (limit.empty()) {
    if (result.status == "INFEASIBLE_FRICTION")
      limit = "friction_limit";
    else if (result.status == "LIFT_OFF")
      limit = "lift_off";
    else
      limit = "degenerate_contact";
  }
  return "physical:" + limit;
}

std::string SecondReferenceNlp(const std::string& primary) {
  const std::string family = NlpSolverRegistry::Info(primary).family;
  std::string best;
  std::tuple<bool, double, std::string> best_key;
  for (const std::string& name : NlpSolverRegistry::Names()) {
    if (name == primary) continue;
    const BackendInfo info = NlpSolverRegistry::Info(name);
    if (!info.thread_safe) continue;
    const double cost = info.cost_ratio > 0
                            ? info.cost_ratio
                            : std::numeric_limits<double>::infinity();
    const auto key = std::make_tuple(info.family == family, cost, name);
    if (best.empty() || key < best_key) {
      best = name;
      best_key = key;
    }
  }
  return best;
}

namespace {

// A run that the ladder retries: neither at its end nor at a physical limit
// nor at a breakaway.
bool NeedsRetry(const SimulationResult& r, const Scene& scene) {
  return ReferenceStopOf(r, scene) == "reference_failure";
}

// t rounded to the output grid k h when within 1e-9 s of it (so that stitched
// times equal those of an uninterrupted run), else t.
double Snap(double t, double h) {
  const double k = std::round(t / h);
  return std::abs(t - k * h) <= 1e-9 ? k * h : t;
}

// Index of the last sample on the grid, before t_end, whose solve succeeded
// (the state a rung restarts from); -1 if none.
int LastGoodSample(const SimulationResult& r, double h, double t_end) {
  for (int i = static_cast<int>(r.samples.size()) - 1; i >= 0; --i) {
    const TrajectorySample& s = r.samples[i];
    if (s.nlp_status == "OK" && Snap(s.t, h) == s.t && s.t < t_end - 1e-9 &&
        s.theta.allFinite())
      return i;
  }
  return -1;
}

// The cost of an attempt, added to the reference's counters.
void AddCosts(const SimulationResult& from, SimulationResult* to) {
  to->nlp_solves += from.nlp_solves;
  to->nlp_iterations += from.nlp_iterations;
  to->nlp_iterations_native += from.nlp_iterations_native;
  to->rhs_evaluations += from.rhs_evaluations;
  to->jacobian_evaluations += from.jacobian_evaluations;
  to->steps += from.steps;
  to->rejected_steps += from.rejected_steps;
  to->wall_seconds += from.wall_seconds;
}

// Appends the samples of `seg` (a run started at t_off from into's last
// sample, times relative to t_off) after into's last sample, and takes over
// its stop. The first sample of seg is into's last state and is dropped.
void Stitch(const SimulationResult& seg, double t_off, double h, double epsilon,
            SimulationResult* into) {
  for (std::size_t k = 1; k < seg.samples.size(); ++k) {
    TrajectorySample s = seg.samples[k];
    s.t = Snap(t_off + s.t, h);
    AccumulateSlipDistances(into->samples.back(), epsilon, &s);
    into->samples.push_back(std::move(s));
  }
  into->status = seg.status;
  into->stop_reason = seg.stop_reason.empty()
                          ? ""
                          : "after a restart at t=" + Num(t_off) +
                                " s (times relative to it): " + seg.stop_reason;
  into->t_reached = Snap(t_off + seg.t_reached, h);
  into->event = seg.event;
  for (double* t : {&into->event.t, &into->event.t_lower, &into->event.t_upper})
    *t += t_off;
  into->stop_configuration = seg.stop_configuration;
  into->mu_min_at_stop = seg.mu_min_at_stop;
  into->critical_contact = seg.critical_contact;
  into->stop_retry = seg.stop_retry;
  if (into->stop_retry) into->stop_retry->t += t_off;
  if (!std::isnan(seg.kkt_residual))
    into->kkt_residual = std::fmax(into->kkt_residual, seg.kkt_residual);
  into->step_drift_max = std::fmax(into->step_drift_max, seg.step_drift_max);
}

struct Rung {
  std::string name, detail;
  SimulationOptions options;
};

// The ladder's rungs for the primary configuration `base` (header).
std::vector<Rung> Ladder(const SimulationOptions& base) {
  std::vector<Rung> rungs;
  for (int f : {4, 16}) {
    Rung r{"step/" + std::to_string(f), "", base};
    r.options.integrator.step = base.integrator.step / f;
    r.detail = "step " + Num(r.options.integrator.step) + " s";
    rungs.push_back(std::move(r));
  }
  const std::string second = SecondReferenceNlp(base.nlp);
  if (!second.empty()) {
    Rung r{"nlp", "nlp " + second, base};
    r.options.nlp = second;
    r.options.nlp_options.clear();  // the primary's options are not its
    rungs.push_back(std::move(r));
  }
  Rung relaxed{"relaxed", "", base};
  relaxed.options.quasi_static.residual_tolerance *= kRelaxedToleranceFactor;
  relaxed.detail =
      "residual " + Num(relaxed.options.quasi_static.residual_tolerance);
  rungs.push_back(std::move(relaxed));
  return rungs;
}

ReferenceAttempt Attempt(const std::string& rung, const std::string& detail,
                         double t_start, double t_end,
                         const SimulationResult& r, double h) {
  return {rung,  detail,   t_start,
          t_end, r.status, Snap(t_start + r.t_reached, h)};
}

// Runs the ladder's rungs over [t0, t1] from theta0; true with *seg the first
// rung that reached t1 or met a physical limit.
bool RunLadder(const Scene& scene, const std::vector<Rung>& rungs, double t0,
               double t1, const Configuration& theta0, double h,
               SimulationResult* total, ReferenceRetryLog* log,
               SimulationResult* seg) {
  for (const Rung& rung : rungs) {
    SimulationOptions o = rung.options;
    o.t_end = t1 - t0;
    o.dt = std::min(o.dt, o.t_end);  // one interval (t1 - t0 <= h, rounded)
    *seg = Simulator(scene, o).Run(theta0);
    AddCosts(*seg, total);
    log->attempts.push_back(Attempt(rung.name, rung.detail, t0, t1, *seg, h));
    if (!NeedsRetry(*seg, scene)) return true;
  }
  return false;
}

}  // namespace

SimulationResult RunReferenceWithRetries(const Scene& scene,
                                         const SimulationOptions& options,
                                         ReferenceRetryLog* log) {
  Simulator sim(scene, options);
  const double h = sim.dt(), t_end = sim.t_end();
  SimulationResult result = sim.Run();
  log->attempts.push_back(Attempt("primary", "", 0, t_end, result, h));
  const std::vector<Rung> rungs = Ladder(options);
  while (NeedsRetry(result, scene) && log->rescues < kMaxReferenceRescues) {
    const int g = LastGoodSample(result, h, t_end);
    if (g < 0) break;
    const double t0 = result.samples[g].t;
    const double t1 = std::min(t_end, Snap(t0 + h, h));
    const Configuration theta0 = result.samples[g].theta;
    SimulationResult seg;
    if (!RunLadder(scene, rungs, t0, t1, theta0, h, &result, log, &seg)) break;
    ++log->rescues;
    result.samples.resize(g + 1);
    Stitch(seg, t0, h, scene.epsilon, &result);
    if (!seg.success() || t1 >= t_end - 1e-9) break;
    SimulationOptions rest = options;
    rest.t_end = t_end - t1;
    rest.dt = std::min(h, rest.t_end);
    const SimulationResult cont =
        Simulator(scene, rest).Run(result.samples.back().theta);
    AddCosts(cont, &result);
    log->attempts.push_back(Attempt("primary", "", t1, t_end, cont, h));
    Stitch(cont, t1, h, scene.epsilon, &result);
  }
  log->stop = ReferenceStopOf(result, scene);
  return result;
}

}  // namespace quasiroll::bench
