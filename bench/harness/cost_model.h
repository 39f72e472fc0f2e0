// A-priori run costs (docs/cluster.md, "Cost model"): they balance the
// `bench --shard I/N` slices and order the MPI driver's dispatch (biggest
// first). Every number comes from the backends' own BackendInfo cost hints
// (core/backend_info.h); nothing here names a backend.
#pragma once

#include "quasiroll/bench/harness/suite.h"

namespace quasiroll::bench {

// Estimated cost of a run in seconds:
//
//   cost = repeats * (c0 + holds * r[nlp] * s[dae, coupling] * f_tol)
//
// holds = t_end / dt * substeps; r = the NLP's cost_ratio (its quasi-static
// solve relative to the default NLP's); s = the integrator's seconds per hold
// interval with the default NLP in that coupling; a backend without a hint
// gets the median of the registered backends' hints. f_tol = (1e-8 / tol)^p
// when the integrator is adaptive with the run's options
// (BackendInfo::adaptive), else 1; c0 the per-run overhead. The run's
// physics may end it early (a failure): the estimate cannot know that.
// Deterministic arithmetic on the run's parameters and the registered hints
// only: every shard computes the same partition.
double EstimatedRunCost(const RunSpec& run);

// Estimated cost of computing a numerical reference (docs/harness.md,
// References) of a scene with hold interval `scene_dt` up to `t_end`: a
// coupled run of the reference integrator (BackendRole::kReference) with
// settings.nlp at step scene_dt / (dt_divisor * substeps), by the same model.
double EstimatedReferenceCost(double scene_dt, double t_end,
                              const ReferenceSettings& settings);

}  // namespace quasiroll::bench
