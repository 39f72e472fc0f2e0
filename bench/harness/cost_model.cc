#include "quasiroll/bench/harness/cost_model.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll::bench {

namespace {

// Calibration (docs/cluster.md, "Cost model"): scripts/fit_run_costs.py on
// default.yaml run with --jobs 1.
constexpr double kOverheadSeconds = 0.011;  // per run, outside the run loop
constexpr double kTolExponent = 0.041;      // f_tol = (1e-8 / tol)^p

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The hint, else the median of the registered backends' hints (a backend
// that gives none, e.g. a plugin).
double NlpCostRatio(const std::string& nlp) {
  const double own = NlpSolverRegistry::Info(nlp).cost_ratio;
  if (own > 0) return own;
  std::vector<double> known;
  for (const std::string& name : NlpSolverRegistry::Names())
    if (const double r = NlpSolverRegistry::Info(name).cost_ratio; r > 0)
      known.push_back(r);
  return known.empty() ? 1.0 : Median(known);
}

double HoldSeconds(const BackendInfo& info, Coupling coupling) {
  return coupling == Coupling::kCoupled ? info.seconds_per_hold_coupled
                                        : info.seconds_per_hold_zoh;
}

double IntegratorSecondsPerHold(const std::string& dae, Coupling coupling) {
  const double own = HoldSeconds(IntegratorRegistry::Info(dae), coupling);
  if (own > 0) return own;
  std::vector<double> known;
  for (const std::string& name : IntegratorRegistry::Names())
    if (const double s = HoldSeconds(IntegratorRegistry::Info(name), coupling);
        s > 0)
      known.push_back(s);
  return known.empty() ? 1e-3 : Median(known);
}

// The integrator's options with the run's given ones applied (tables cached:
// a plan asks for thousands of runs).
bool Adaptive(const std::string& dae, const GivenOptions& given) {
  static std::mutex mutex;
  static std::map<std::string, OptionTable> tables;
  OptionTable table;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = tables.find(dae);
    if (it == tables.end())
      it = tables.emplace(dae, IntegratorRegistry::Create(dae)->option_table())
               .first;
    table = it->second;
  }
  return IntegratorRegistry::Info(dae).IsAdaptive(
      ResolveOptions(table, given, "integrator '" + dae + "'"));
}

}  // namespace

double EstimatedRunCost(const RunSpec& run) {
  // The hints live in the registries (idempotent: a plan may be asked for
  // before anything else registered the built-ins).
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  const double holds = run.t_end / run.dt * run.substeps;
  const double f_tol = Adaptive(run.dae, run.dae_options)
                           ? std::pow(1e-8 / run.tol, kTolExponent)
                           : 1.0;
  return run.repeats *
         (kOverheadSeconds +
          holds * NlpCostRatio(run.nlp) *
              IntegratorSecondsPerHold(run.dae, run.coupling) * f_tol);
}

double EstimatedReferenceCost(double scene_dt, double t_end,
                              const ReferenceSettings& settings) {
  RunSpec r;
  r.nlp = settings.Nlp();
  r.dae = ReferenceSettings::Integrator();
  r.coupling = Coupling::kCoupled;
  r.dt = scene_dt / settings.dt_divisor;
  r.substeps = settings.substeps;
  r.t_end = t_end;
  r.tol = 1e-8;
  r.dae_options = {{"rk_method", "rk4"}};
  return EstimatedRunCost(r);
}

}  // namespace quasiroll::bench
