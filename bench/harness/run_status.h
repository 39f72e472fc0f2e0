// Every value a runs.csv row's `status` takes (docs/harness.md, runs.csv):
// the simulator's stop (SimulationResult::status: "success", a quasi-static
// status, an integrator status) and the harness's verdicts on top of it.
// The text is runs.csv's public interface: ToString() is its one spelling.
#pragma once

#include <optional>
#include <string_view>

namespace quasiroll::bench {

enum class RunStatus {
  kSuccess,  // reached t_end within the suite's bounds
  // Quasi-static statuses (core/quasi_static.h, QuasiStaticStatus).
  kLiftOff,
  kInfeasibleFriction,
  kDegenerateContact,
  kSingular,
  kSolverFailure,
  // Integrator statuses (core/dae.h, IntegratorStatus).
  kStepSizeTooSmall,
  kConvergenceFailure,
  kConstraintFailure,
  kEvent,
  kInvalidInput,
  kRhsFailure,
  kNotRun,
  // The harness's verdicts: reached t_end beyond the suite's bounds, or the
  // run threw.
  kDriftExceeded,
  kGapExceeded,
  kError,
};

// The runs.csv spelling: "success", "INFEASIBLE_FRICTION", "rhs_failure",
// "drift_exceeded", "error", ...
const char* ToString(RunStatus status);
// The status spelled `text` by ToString(); nullopt for any other text.
std::optional<RunStatus> ParseRunStatus(std::string_view text);

// A stop at a limit of the problem's physics when it is the reference's too
// (INFEASIBLE_FRICTION, LIFT_OFF, DEGENERATE_CONTACT).
bool IsPhysicalStop(RunStatus status);

}  // namespace quasiroll::bench
