#include "quasiroll/bench/harness/shard.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::bench {

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
