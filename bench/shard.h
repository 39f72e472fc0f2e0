// Splitting a suite's run list across processes (docs/cluster.md): the
// a-priori run cost that balances `bench --shard I/N` slices and orders the
// MPI driver's dispatch (biggest first), and the deterministic partition.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "quasiroll/bench/suite.h"

namespace quasiroll::bench {
struct HarnessOptions;
}

namespace quasiroll::bench {

// Estimated cost of a run in seconds (docs/cluster.md, "Cost model"):
//
//   cost = repeats * (c0 + holds * s[nlp, dae, coupling] * f_tol)
//
// holds = t_end / dt * substeps; s = measured seconds per hold interval of
// each method (scripts/fit_run_costs.py on default.yaml; for an unmeasured
// combination the NLP's ratio to newton times newton's cost with that
// integrator and coupling, for an unknown backend the table's median);
// f_tol = (1e-8 / tol)^p for the adaptive schemes (DP5(4), BS3(2), IDA),
// 1 for fixed-step RK4; c0 the per-run overhead. The run's physics may end
// it early (a failure): the estimate cannot know that. Deterministic
// arithmetic on the run's parameters only: every shard computes the same
// partition.
double EstimatedRunCost(const RunSpec& run);

// Estimated cost of computing a numerical reference (docs/harness.md,
// References) of a scene with hold interval `scene_dt` up to `t_end`: a
// coupled rk-projection run of settings.nlp at step scene_dt / (dt_divisor *
// substeps), by the same model.
double EstimatedReferenceCost(double scene_dt, double t_end,
                              const ReferenceSettings& settings);

// "I/N" -> {I, N}: 0 <= I < N <= 1000000, decimal integers. Throws
// SceneError naming --shard and the value otherwise.
std::pair<int, int> ParseShard(const std::string& text);

// Shard (0..count-1) of each of the given runs. Runs that share a reference
// trajectory (equal `reference_keys`) are kept together in one contiguous
// stretch, stretches in order of their first run, runs within a stretch in
// the given (grid) order; the stretch is cut into `count` slices of nearly
// equal total cost: run k goes to shard floor(count * (C_k + c_k / 2) / C)
// where C_k is the cost before it and C the total. A slice's cost is within
// one run's cost of C / count, and a shard needs only the references of its
// stretch (a reference split across shards is computed by each of them
// unless they share DIR/references and one of them has finished it).
std::vector<int> AssignShards(const std::vector<double>& costs,
                              const std::vector<std::string>& reference_keys,
                              int count);

// `bench --plan`: the runs the options select (--filter, --shard), in grid
// order, as CSV: run_id, suite_group, scene, nlp, dae, coupling, dt, t_end,
// repeats, estimated_cost_s, reference (the ref_hash the run will have),
// reference_cost_s (EstimatedReferenceCost). Runs nothing.
std::string PlanCsv(const Suite& suite, const HarnessOptions& options);

}  // namespace quasiroll::bench
