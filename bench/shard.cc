#include "quasiroll/bench/shard.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "quasiroll/bench/harness.h"
#include "quasiroll/bench/reference.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::bench {

namespace {

// Calibration (docs/cluster.md, "Cost model"): scripts/fit_run_costs.py on
// default.yaml run with --jobs 1 (334 runs; the machine was shared, so the
// seconds are ~2.4x those of an idle machine: only ratios matter).
constexpr double kOverheadSeconds = 0.011;  // per run, outside the run loop
constexpr double kTolExponent = 0.041;      // f_tol = (1e-8 / tol)^p
constexpr double kUnknownSecondsPerHold = 0.002;  // median of the table

struct MethodCost {
  const char* nlp;
  const char* dae;
  Coupling coupling;
  double seconds_per_hold;
};
constexpr MethodCost kMeasured[] = {
    {"ceres", "ida", Coupling::kCoupled, 0.0339},
    {"ceres", "ida", Coupling::kZoh, 0.00214},
    {"ceres", "rk-baumgarte", Coupling::kCoupled, 0.00135},
    {"ceres", "rk-baumgarte", Coupling::kZoh, 0.000523},
    {"ceres", "rk-projection", Coupling::kCoupled, 0.00151},
    {"ceres", "rk-projection", Coupling::kZoh, 0.000403},
    {"ipopt", "ida", Coupling::kCoupled, 0.283},
    {"ipopt", "ida", Coupling::kZoh, 0.00569},
    {"ipopt", "rk-baumgarte", Coupling::kCoupled, 0.016},
    {"ipopt", "rk-baumgarte", Coupling::kZoh, 0.00237},
    {"ipopt", "rk-projection", Coupling::kCoupled, 0.0208},
    {"ipopt", "rk-projection", Coupling::kZoh, 0.00136},
    {"ipopt-mumps", "rk-projection", Coupling::kZoh, 0.00978},
    {"newton", "ida", Coupling::kCoupled, 0.00559},
    {"newton", "ida", Coupling::kZoh, 0.00216},
    {"newton", "rk-baumgarte", Coupling::kCoupled, 0.000387},
    {"newton", "rk-baumgarte", Coupling::kZoh, 0.000107},
    {"newton", "rk-projection", Coupling::kCoupled, 0.000204},
    {"newton", "rk-projection", Coupling::kZoh, 0.000111},
    {"slsqp", "ida", Coupling::kCoupled, 0.0157},
    {"slsqp", "ida", Coupling::kZoh, 0.00193},
    {"slsqp", "rk-baumgarte", Coupling::kCoupled, 0.00107},
    {"slsqp", "rk-baumgarte", Coupling::kZoh, 0.000231},
    {"slsqp", "rk-projection", Coupling::kCoupled, 0.000965},
    {"slsqp", "rk-projection", Coupling::kZoh, 0.000236},
};

const MethodCost* Find(const std::string& nlp, const std::string& dae,
                       Coupling coupling) {
  for (const MethodCost& m : kMeasured)
    if (nlp == m.nlp && dae == m.dae && coupling == m.coupling) return &m;
  return nullptr;
}

// Seconds per hold interval: measured, else the NLP's ratio to newton (zoh,
// rk-projection) times newton's cost with this integrator and coupling, else
// the median of the table (a backend never measured, e.g. a plugin).
double SecondsPerHold(const std::string& nlp, const std::string& dae,
                      Coupling coupling) {
  if (const MethodCost* m = Find(nlp, dae, coupling))
    return m->seconds_per_hold;
  const MethodCost* nlp_zoh = Find(nlp, "rk-projection", Coupling::kZoh);
  const MethodCost* newton_zoh =
      Find("newton", "rk-projection", Coupling::kZoh);
  const MethodCost* newton_here = Find("newton", dae, coupling);
  if (nlp_zoh && newton_here)
    return nlp_zoh->seconds_per_hold / newton_zoh->seconds_per_hold *
           newton_here->seconds_per_hold;
  return kUnknownSecondsPerHold;
}

}  // namespace

double EstimatedRunCost(const RunSpec& run) {
  const double holds = run.t_end / run.dt * run.substeps;
  const bool adaptive = run.dae == "ida" || run.dae == "cvode-projection" ||
                        run.rk_method != "rk4";
  const double f_tol = adaptive ? std::pow(1e-8 / run.tol, kTolExponent) : 1.0;
  return run.repeats *
         (kOverheadSeconds +
          holds * SecondsPerHold(run.nlp, run.dae, run.coupling) * f_tol);
}

double EstimatedReferenceCost(double scene_dt, double t_end,
                              const ReferenceSettings& settings) {
  RunSpec r;
  r.nlp = settings.nlp;
  r.dae = "rk-projection";
  r.coupling = Coupling::kCoupled;
  r.dt = scene_dt / settings.dt_divisor;
  r.substeps = settings.substeps;
  r.t_end = t_end;
  r.tol = 1e-8;
  return EstimatedRunCost(r);
}

std::pair<int, int> ParseShard(const std::string& text) {
  auto fail = [&text]() -> std::pair<int, int> {
    throw SceneError(
        "--shard: expected I/N with integers 0 <= I < N <= 1000000 (shards "
        "are numbered from 0, like SLURM_ARRAY_TASK_ID of --array=0-(N-1)), "
        "got \"" +
        text + "\"");
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos || slash == 0 || slash + 1 == text.size())
    return fail();
  auto parse = [](const std::string& s, long long* v) {
    if (s.empty() || s.size() > 7) return false;
    for (char c : s)
      if (c < '0' || c > '9') return false;
    *v = std::stoll(s);
    return true;
  };
  long long i = 0, n = 0;
  if (!parse(text.substr(0, slash), &i) || !parse(text.substr(slash + 1), &n))
    return fail();
  if (n < 1 || n > 1000000 || i >= n) return fail();
  return {static_cast<int>(i), static_cast<int>(n)};
}

std::vector<int> AssignShards(const std::vector<double>& costs,
                              const std::vector<std::string>& reference_keys,
                              int count) {
  const std::size_t n = costs.size();
  // Order: stretches of equal reference key, by first occurrence.
  std::map<std::string, int> stretch_of;
  std::vector<std::vector<std::size_t>> stretches;
  for (std::size_t k = 0; k < n; ++k) {
    auto [it, inserted] = stretch_of.emplace(
        reference_keys[k], static_cast<int>(stretches.size()));
    if (inserted) stretches.emplace_back();
    stretches[it->second].push_back(k);
  }
  double total = 0;
  for (double c : costs) total += c;
  std::vector<int> shard(n, 0);
  if (count <= 1 || total <= 0) return shard;
  double before = 0;
  for (const auto& stretch : stretches) {
    for (std::size_t k : stretch) {
      const double mid = before + costs[k] / 2;
      const int s = static_cast<int>(std::floor(count * mid / total));
      shard[k] = std::min(std::max(s, 0), count - 1);
      before += costs[k];
    }
  }
  return shard;
}

std::string PlanCsv(const Suite& suite, const HarnessOptions& options) {
  HarnessOptions selection = options;
  selection.resume = false;  // every selected run, finished or not
  const SuitePlan plan = PlanSuite(suite, selection);
  std::string csv =
      "run_id,suite_group,scene,nlp,dae,coupling,dt,t_end,repeats,"
      "estimated_cost_s,reference,reference_cost_s\n";
  for (std::size_t i = 0; i < plan.selected.size(); ++i) {
    const RunSpec& r = *plan.selected[i];
    const ReferenceJob& ref = plan.references[plan.run_reference[i]];
    csv += r.run_id + "," + r.group + "," + r.scene + "," + r.nlp + "," +
           r.dae + "," + ToString(r.coupling) + "," + Num(r.dt) + "," +
           Num(r.t_end) + "," + std::to_string(r.repeats) + "," +
           Num(EstimatedRunCost(r)) + "," + Hex64(Fnv1a64(ref.key)) + "," +
           Num(EstimatedReferenceCost(ref.scene.dt, ref.scene.t_end,
                                      suite.reference)) +
           "\n";
  }
  return csv;
}

}  // namespace quasiroll::bench
