#include "quasiroll/bench/harness/failure_causes.h"

#include <algorithm>
#include <cmath>

namespace quasiroll::bench {

namespace {
std::string PhysicalDetail(RunStatus s) {
  if (s == RunStatus::kInfeasibleFriction) return "friction_limit";
  if (s == RunStatus::kLiftOff) return "lift_off";
  return "degenerate_contact";
}
// Why a run that left the reference's path did so, from the evidence.
std::string DivergenceDetail(const FailureEvidence& e) {
  if (!e.known_instability.empty()) return e.known_instability;
  if (e.drift_max > e.drift_bound) return "drift_blowup";
  if (e.gap_max > e.gap_bound) return "gap_blowup";
  return "step_too_large";
}
// The reference stopped at a physical limit and the run went past it by
// more than the same-place tolerance (or reached t_end): the run stepped
// over the limit (docs/model.md §8.6).
bool MissedEvent(const FailureEvidence& e) {
  return e.has_reference && e.ref_status && IsPhysicalStop(*e.ref_status) &&
         e.t_reached > e.ref_t_reached + StopTolerance(e) + 1e-9;
}
// A run that blew up: its motion (and so its inertia) is the method's.
bool BlewUp(const FailureEvidence& e) {
  return !e.known_instability.empty() || e.drift_max > e.drift_bound ||
         e.gap_max > e.gap_bound;
}
}  // namespace

double StopTolerance(const FailureEvidence& e) {
  return 2.0 * std::max(e.dt * std::max(1, e.contact_check), e.ref_dt);
}

FailureCause ClassifyFailure(const FailureEvidence& e) {
  const RunStatus st = e.status;
  if (st == RunStatus::kError) return {"numerical", "error"};
  if (st == RunStatus::kSuccess)
    return MissedEvent(e) ? FailureCause{"numerical", "missed_event"}
                          : FailureCause{"", ""};
  // The motion left the quasi-static model's domain before the stop: what
  // follows (a limit, a solver giving up) is outside what the model can
  // claim, whichever method ran it.
  if (e.qs_inertia_ratio > e.qs_inertia_bound && !BlewUp(e))
    return {"model", "quasi_static_invalid"};
  // A run past its bounds: the root cause when it is known (e.g. sigma h
  // beyond RK4's stability interval), else the symptom.
  if (st == RunStatus::kDriftExceeded || st == RunStatus::kGapExceeded)
    return {"numerical", !e.known_instability.empty()      ? e.known_instability
                         : st == RunStatus::kDriftExceeded ? "drift_blowup"
                                                           : "gap_blowup"};
  if (MissedEvent(e)) return {"numerical", "missed_event"};
  const double tol_t = StopTolerance(e);
  const bool ref_stopped =
      e.has_reference && e.ref_status != RunStatus::kSuccess;
  const bool same_place =
      ref_stopped && std::abs(e.t_reached - e.ref_t_reached) <= tol_t + 1e-9;
  // The reference's twist diverges where the run stops (a breakaway,
  // model.md §8.8): whatever the run's own solves saw there, the stop is the
  // model's.
  if (same_place && e.ref_breakaway && !BlewUp(e))
    return {"model", "quasi_static_invalid"};
  if (IsPhysicalStop(st)) {
    // The reference stops there too (also where its own solver gave up
    // just short of the limit): the limit is the problem's.
    if (same_place) return {"physical", PhysicalDetail(st)};
    if (!e.has_reference) {
      // Nothing to compare with: only the method's own evidence can
      // overrule the solver's verdict.
      const std::string d = DivergenceDetail(e);
      if (d != "step_too_large") return {"numerical", d};
      return {"physical", PhysicalDetail(st)};
    }
    return {"numerical", DivergenceDetail(e)};
  }
  if (st == RunStatus::kSingular && same_place &&
      e.ref_status == RunStatus::kSingular)
    // Rank-deficient statics at the same place on the reference's path: a
    // property of the configuration, not of the method.
    return {"physical", "singular_point"};
  if (st == RunStatus::kSolverFailure || st == RunStatus::kSingular) {
    // SOLVER_FAILURE means mu > mu_min and regular statics at that state
    // (model.md §7): a solution may exist and the NLP did not find it (past
    // a breakaway none does, model.md §8.8: the ratio rule above). That the
    // reference (newton by default) fails there too does not make it
    // physical (another backend may pass); only a physical stop of the
    // reference at the same place does.
    if (same_place && e.ref_status && IsPhysicalStop(*e.ref_status))
      return {"physical", PhysicalDetail(*e.ref_status)};
    // The reference's own solver gives up at the same place: a hard point
    // of the quasi-static NLP (seen within 1 % of mu_min), not this
    // method's weakness alone. Still numerical: a solution exists.
    if (same_place && e.ref_status == RunStatus::kSolverFailure)
      return {"numerical", "shared_solver_failure"};
    return {"numerical", "solver_failure"};
  }
  // An implicit integrator whose residual could not be evaluated because the
  // NLP failed inside it, where the reference's solver fails too.
  if (st == RunStatus::kRhsFailure && same_place &&
      e.ref_status == RunStatus::kSolverFailure)
    return {"numerical", "shared_solver_failure"};
  return {"numerical", "integrator_failure"};
}

}  // namespace quasiroll::bench
