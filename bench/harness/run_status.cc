#include "quasiroll/bench/harness/run_status.h"

#include <array>

namespace quasiroll::bench {

namespace {
constexpr std::array kAll = {
    RunStatus::kSuccess,
    RunStatus::kLiftOff,
    RunStatus::kInfeasibleFriction,
    RunStatus::kDegenerateContact,
    RunStatus::kSingular,
    RunStatus::kSolverFailure,
    RunStatus::kStepSizeTooSmall,
    RunStatus::kConvergenceFailure,
    RunStatus::kConstraintFailure,
    RunStatus::kEvent,
    RunStatus::kInvalidInput,
    RunStatus::kRhsFailure,
    RunStatus::kNotRun,
    RunStatus::kDriftExceeded,
    RunStatus::kGapExceeded,
    RunStatus::kError,
};
}  // namespace

const char* ToString(RunStatus status) {
  switch (status) {
    case RunStatus::kSuccess:
      return "success";
    case RunStatus::kLiftOff:
      return "LIFT_OFF";
    case RunStatus::kInfeasibleFriction:
      return "INFEASIBLE_FRICTION";
    case RunStatus::kDegenerateContact:
      return "DEGENERATE_CONTACT";
    case RunStatus::kSingular:
      return "SINGULAR";
    case RunStatus::kSolverFailure:
      return "SOLVER_FAILURE";
    case RunStatus::kStepSizeTooSmall:
      return "step_size_too_small";
    case RunStatus::kConvergenceFailure:
      return "convergence_failure";
    case RunStatus::kConstraintFailure:
      return "constraint_failure";
    case RunStatus::kEvent:
      return "event";
    case RunStatus::kInvalidInput:
      return "invalid_input";
    case RunStatus::kRhsFailure:
      return "rhs_failure";
    case RunStatus::kNotRun:
      return "not_run";
    case RunStatus::kDriftExceeded:
      return "drift_exceeded";
    case RunStatus::kGapExceeded:
      return "gap_exceeded";
    case RunStatus::kError:
      return "error";
  }
  return "error";
}

std::optional<RunStatus> ParseRunStatus(std::string_view text) {
  for (RunStatus s : kAll)
    if (text == ToString(s)) return s;
  return std::nullopt;
}

bool IsPhysicalStop(RunStatus status) {
  return status == RunStatus::kInfeasibleFriction ||
         status == RunStatus::kLiftOff ||
         status == RunStatus::kDegenerateContact;
}

}  // namespace quasiroll::bench
