// Why a run did not succeed (docs/harness.md, "Failure causes"): physical
// (the problem's limit, where the reference stops too) or numerical (the
// method's), with a detail name. Pure functions of the evidence; no I/O.
#pragma once

#include <limits>
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
  // The reference stopped at a breakaway (reference_stop model:breakaway,
  // reference_retry.h): its twist diverges there.
  bool ref_breakaway = false;
  // Quasi-static inertia ratio of the run's motion up to its stop (runs.csv
  // qs_inertia_ratio; NaN when unknown) and the suite's bound on it.
  double qs_inertia_ratio = std::numeric_limits<double>::quiet_NaN();
  double qs_inertia_bound = std::numeric_limits<double>::infinity();
};

// How far apart two stops may be and still be the same stop: stops are
// detected on the output grid (dt), the sampled second-contact check only
// every contact_check samples, the reference on its own grid; two detection
// intervals, 2 max(dt max(1, contact_check), ref_dt).
double StopTolerance(const FailureEvidence& e);

struct FailureCause {
  std::string cause;   // "", "physical", "numerical" or "model"
  std::string detail;  // "", friction_limit, ... (docs/harness.md)
};

// Classifies a row (rules in docs/harness.md, Failure causes); a success has
// no cause unless it went past its reference's physical stop (then, like
// any run that stops more than StopTolerance after that stop, numerical /
// missed_event):
// model (quasi_static_invalid) when the motion up to the stop exceeds the
// quasi-static inertia bound and the run did not blow up; else physical when
// the reference stops at the same place (|t_reached - t_ref| <=
// StopTolerance) with a physical status, numerical when the method stops
// where the reference goes on, breaks the bounds, or its NLP fails
// (SOLVER_FAILURE).
FailureCause ClassifyFailure(const FailureEvidence& e);

}  // namespace quasiroll::bench
