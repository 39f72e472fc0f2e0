// RunStatus (bench/harness/run_status.h): one spelling per status, and every
// status the simulator can stop with is one of them.
#include "quasiroll/bench/harness/run_status.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/quasi_static.h"

namespace quasiroll::bench {
namespace {

TEST(RunStatus, ParseInvertsToStringAndSpellingsAreDistinct) {
  std::set<std::string> spellings;
  for (int i = 0; i <= static_cast<int>(RunStatus::kError); ++i) {
    const auto s = static_cast<RunStatus>(i);
    EXPECT_EQ(ParseRunStatus(ToString(s)), s) << ToString(s);
    EXPECT_TRUE(spellings.insert(ToString(s)).second) << ToString(s);
  }
  EXPECT_FALSE(ParseRunStatus("none").has_value());
  EXPECT_FALSE(ParseRunStatus("Success").has_value());
  EXPECT_FALSE(ParseRunStatus("").has_value());
}

// SimulationResult::status is "success", a failed quasi-static status or an
// integrator status (core/simulator.cc): the harness parses each of them.
TEST(RunStatus, CoversEverySimulatorStop) {
  for (QuasiStaticStatus q :
       {QuasiStaticStatus::kLiftOff, QuasiStaticStatus::kInfeasibleFriction,
        QuasiStaticStatus::kDegenerateContact, QuasiStaticStatus::kSingular,
        QuasiStaticStatus::kSolverFailure})
    EXPECT_TRUE(ParseRunStatus(ToString(q)).has_value()) << ToString(q);
  for (IntegratorStatus s :
       {IntegratorStatus::kSuccess, IntegratorStatus::kStepSizeTooSmall,
        IntegratorStatus::kConvergenceFailure,
        IntegratorStatus::kConstraintFailure, IntegratorStatus::kEvent,
        IntegratorStatus::kInvalidInput, IntegratorStatus::kRhsFailure,
        IntegratorStatus::kNotRun})
    EXPECT_TRUE(ParseRunStatus(ToString(s)).has_value()) << ToString(s);
  EXPECT_EQ(ParseRunStatus(ToString(IntegratorStatus::kSuccess)),
            RunStatus::kSuccess);
}

TEST(RunStatus, PhysicalStops) {
  EXPECT_TRUE(IsPhysicalStop(RunStatus::kInfeasibleFriction));
  EXPECT_TRUE(IsPhysicalStop(RunStatus::kLiftOff));
  EXPECT_TRUE(IsPhysicalStop(RunStatus::kDegenerateContact));
  EXPECT_FALSE(IsPhysicalStop(RunStatus::kSingular));
  EXPECT_FALSE(IsPhysicalStop(RunStatus::kSolverFailure));
  EXPECT_FALSE(IsPhysicalStop(RunStatus::kSuccess));
}

}  // namespace
}  // namespace quasiroll::bench
