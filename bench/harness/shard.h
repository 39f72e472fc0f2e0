// Splitting a suite's run list across processes (docs/cluster.md): the
// deterministic partition of `bench --shard I/N` (balanced by the a-priori
// run costs of cost_model.h) and the `bench --plan` listing.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "quasiroll/bench/harness/cost_model.h"
#include "quasiroll/bench/harness/suite.h"

namespace quasiroll::bench {
struct HarnessOptions;
}

namespace quasiroll::bench {

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
