// Why a run did not succeed (docs/harness.md, "Failure causes"): physical
// (the problem's limit, where the reference stops too) or numerical (the
// method's), with a detail name. Pure functions of the evidence; no I/O.
#pragma once

#include <optional>
#include <string>

#include "quasiroll/bench/harness/run_status.h"

namespace quasiroll::bench {

// Everything ClassifyFailure() looks at (docs/harness.md, Failure causes).
struct FailureEvidence {
  RunStatus status = RunStatus::kSuccess;  // after the suite's bounds
  double t_reached = 0;
  // Method.
  double dt = 0;  // hold / output interval
  // A failure cause the integrator's BackendInfo knows a priori for the
  // run's options and step (e.g. "baumgarte_instability"), "" if none.
  std::string known_instability;
  int contact_check = 0;  // sampled second-contact check every N samples
  // Constraint health over the samples, and the suite's bounds.
  double drift_max = 0, gap_max = 0, drift_bound = 0, gap_bound = 0;
  // Reference: has_reference false when none could be computed.
  bool has_reference = false;
  // The reference run's status; nullopt for a text that is no RunStatus
  // (then it compares unequal to every status, success included).
  std::optional<RunStatus> ref_status;
  double ref_t_reached = 0;
  double ref_dt = 0;  // spacing of the reference's samples
};

struct FailureCause {
  std::string cause;   // "", "physical" or "numerical"
  std::string detail;  // "", friction_limit, ... (docs/harness.md)
};

// Classifies a non-success row (rules in docs/harness.md, Failure causes):
// physical when the reference stops at the same place
// (|t_reached - t_ref| <= 2 max(dt max(1, contact_check), ref_dt)) with a
// physical status, numerical when the method stops where the reference goes
// on, breaks the bounds, or its NLP fails (SOLVER_FAILURE).
FailureCause ClassifyFailure(const FailureEvidence& e);

}  // namespace quasiroll::bench
