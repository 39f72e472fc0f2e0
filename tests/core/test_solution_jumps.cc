// Solution jumps (docs/model.md §8.6, core/solution_jumps.h): the
// continuation that follows a root in time and brackets where it ends, the
// events of a jump, and the paper scene's one jump (the end of the root
// whose two-root window tests/core/test_solution_branches.cc establishes
// from states of the same run).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "quasiroll/core/simulator.h"
#include "quasiroll/core/solution_jumps.h"
#include "quasiroll/core/switch_events.h"
#include "simulation_support.h"
#include "tests/test_names.h"

namespace quasiroll {
namespace {

constexpr double kTolerance = 1e-9;

// A root that exists up to t_end, and a local solve that converges only
// over steps no longer than `basin` (a step further fails as Newton's
// basin would).
struct SyntheticRoot {
  double t_end, basin;
  double last = 0;  // the last accepted time
  int calls = 0;
  bool Step(double t) {
    ++calls;
    if (t > t_end || t - last > basin) return false;
    last = t;
    return true;
  }
};

BranchEnd Follow(SyntheticRoot* root, double t0, double t1) {
  root->last = t0;
  return FollowBranch(t0, t1, kTolerance,
                      [root](double t) { return root->Step(t); });
}

TEST(FollowBranch, ARootThatGoesOnIsFollowedInOneStep) {
  SyntheticRoot root{1.0, 1.0};
  const BranchEnd end = Follow(&root, 0.0, 0.05);
  EXPECT_EQ(end.outcome, BranchEnd::Outcome::kContinues);
  EXPECT_EQ(end.steps, 1);
}

TEST(FollowBranch, TheEndIsBracketedToTheTolerance) {
  for (const double t_end : {0.0123456789, 0.0499999, 1e-8, 0.025}) {
    SyntheticRoot root{t_end, 1.0};
    const BranchEnd end = Follow(&root, 0.0, 0.05);
    ASSERT_EQ(end.outcome, BranchEnd::Outcome::kEnds) << t_end;
    EXPECT_LE(end.t_lower, t_end) << t_end;
    EXPECT_GT(end.t_upper, t_end) << t_end;
    EXPECT_LE(end.t_upper - end.t_lower, kTolerance) << t_end;
    // Bisection of 0.05 s to 1e-9 s takes 26 halvings; the retries of a
    // failed end after three successes add a few.
    EXPECT_LE(end.steps, 40) << t_end;
  }
}

// A basin shorter than the interval makes early steps fail where the root
// goes on: neither an end nor an endless loop.
TEST(FollowBranch, BasinFailuresAreNotAnEnd) {
  for (const double basin : {0.02, 0.003}) {
    SyntheticRoot root{1.0, basin};
    const BranchEnd end = Follow(&root, 0.0, 0.05);
    EXPECT_EQ(end.outcome, BranchEnd::Outcome::kContinues) << basin;
    EXPECT_LE(end.steps, 120) << basin;
  }
  // A basin that needs more than max_steps (500 steps of 1e-4 s): given up,
  // not an end.
  SyntheticRoot tiny{1.0, 1e-4};
  EXPECT_EQ(Follow(&tiny, 0.0, 0.05).outcome,
            BranchEnd::Outcome::kUndetermined);
  // The basin and an end together: the end, still to the tolerance.
  SyntheticRoot root{0.0311, 0.003};
  const BranchEnd end = Follow(&root, 0.0, 0.05);
  ASSERT_EQ(end.outcome, BranchEnd::Outcome::kEnds);
  EXPECT_LE(end.t_lower, 0.0311);
  EXPECT_GT(end.t_upper, 0.0311);
  EXPECT_LE(end.t_upper - end.t_lower, kTolerance);
}

TEST(FollowBranch, GivesUpAfterMaxSteps) {
  SyntheticRoot root{1.0, 1e-6};
  const BranchEnd end = FollowBranch(
      0.0, 0.05, kTolerance, [&root](double t) { return root.Step(t); }, 10);
  EXPECT_EQ(end.outcome, BranchEnd::Outcome::kUndetermined);
  EXPECT_EQ(end.steps, 10);
  EXPECT_EQ(root.calls, 10);
}

TEST(FollowBranch, RejectsBadArguments) {
  const BranchStep step = [](double) { return true; };
  EXPECT_THROW(FollowBranch(1.0, 1.0, kTolerance, step), std::invalid_argument);
  EXPECT_THROW(FollowBranch(0.0, 1.0, 0.0, step), std::invalid_argument);
  EXPECT_THROW(FollowBranch(0.0, 1.0, kTolerance, step, 0),
               std::invalid_argument);
}

// One event per wheel whose slip speed changes by more than 10 %, at
// least one; classes from each side's slip.
TEST(AppendSolutionJump, OneEventPerWheelThatJumps) {
  const double eps = 1e-8;
  const std::array<Eigen::Vector2d, 3> before{Eigen::Vector2d(8.5e-6, 0),
                                              Eigen::Vector2d(0, 5e-7),
                                              Eigen::Vector2d(2.0e-5, 0)};
  const std::array<Eigen::Vector2d, 3> after{Eigen::Vector2d(2.2e-5, 0),
                                             Eigen::Vector2d(0, 5.2e-7),
                                             Eigen::Vector2d(0.5e-6, 0)};
  std::vector<SwitchEvent> events;
  ASSERT_EQ(
      AppendSolutionJump(1.0, 1.0 + 1e-9, true, before, after, eps, &events),
      2);
  EXPECT_EQ(events[0].wheel, 1);
  EXPECT_EQ(events[1].wheel, 3);
  for (const SwitchEvent& e : events) {
    EXPECT_TRUE(e.jump);
    EXPECT_FALSE(e.reversal);
    EXPECT_TRUE(e.located);
    EXPECT_EQ(e.t, 1.0 + 1e-9);
    EXPECT_EQ(e.t_lower, 1.0);
    EXPECT_STREQ(SwitchKindName(e), "solution_jump");
  }
  // Wheel 1: 850 -> 2200 eps, sliding on both sides (kappa = 100); wheel 3
  // 2000 -> 50 eps: slide -> stick.
  EXPECT_TRUE(events[0].from_sliding);
  EXPECT_TRUE(events[0].to_sliding);
  EXPECT_TRUE(events[1].from_sliding);
  EXPECT_FALSE(events[1].to_sliding);

  // No wheel above 10 %: the one that changes most.
  std::array<Eigen::Vector2d, 3> small = before;
  small[1] *= 1.05;
  events.clear();
  ASSERT_EQ(
      AppendSolutionJump(1.0, 1.0 + 1e-9, true, before, small, eps, &events),
      1);
  EXPECT_EQ(events[0].wheel, 2);
}

// The slip quadrature across a jump's bracket: the pieces on either side
// end on their own roots' slips, the bracket itself by the trapezoid (never
// evaluated inside).
TEST(IntegrateSlipRegimes, AJumpsBracketIsNotEvaluated) {
  const double eps = 1e-8, t0 = 0.0, t1 = 0.05, tl = 0.02, tu = 0.02 + 1e-9;
  // 3e-6 m/s before the jump, 2e-5 m/s after (sliding), constant per side.
  const SlipEvaluator slips = [&](double t, std::array<double, 3>* f) {
    EXPECT_FALSE(t > tl && t < tu) << t;
    const double v = t <= tl ? 3e-6 : 2e-5;
    *f = {v, v, v};
    return true;
  };
  SlipIncrements out;
  int evaluations = 0;
  ASSERT_TRUE(IntegrateSlipRegimes(t0, t1, {3e-6, 3e-6, 3e-6},
                                   {2e-5, 2e-5, 2e-5}, {tl, tu}, eps, slips,
                                   &out, &evaluations, {{tl, tu}}));
  // Exact: 3e-6 tl + 2e-5 (t1 - tu) plus the bracket's trapezoid.
  const double exact = 3e-6 * tl + 2e-5 * (t1 - tu) + 0.5 * 1e-9 * 2.3e-5;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(out[i].sliding, exact, 1e-18) << i;  // all above 10 eps
    EXPECT_EQ(out[i].creep, 0.0) << i;
  }
}

// The paper scene (zoh, newton + rk-projection, eps = 1e-8): one jump, at
// the end of the lower root of the two-root window that
// tests/core/test_solution_branches.cc finds with every backend from
// states of this run: two roots at 2.907206 s, only the upper one at
// 2.907230 s. All three wheels' slips jump (wheel 1 up 2.6x, wheels 2 and 3
// down 2.5x); nothing else in the first 3.2 s is a jump (the hard solves at
// 2.95 and 3.00 s are followed to their samples).
TEST(SolutionJumps, PaperSceneJumpIsTheEndOfTheLowerRoot) {
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
  o.t_end = 3.2;
  const SimulationResult r = Simulator(PaperScene(), o).Run();
  ASSERT_TRUE(r.success()) << r.stop_reason;
  std::vector<SwitchEvent> jumps;
  for (const SwitchEvent& e : r.switches)
    if (e.jump) jumps.push_back(e);
  ASSERT_EQ(jumps.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const SwitchEvent& e = jumps[i];
    EXPECT_EQ(e.wheel, i + 1);
    EXPECT_TRUE(e.located);
    EXPECT_EQ(e.t_lower, jumps[0].t_lower);
    EXPECT_EQ(e.t_upper, jumps[0].t_upper);
    EXPECT_LE(e.t_upper - e.t_lower, o.event_tolerance);
    EXPECT_GT(e.t_lower, 2.907206);
    EXPECT_LT(e.t_upper, 2.907230);
  }
  // The events are in time order with the switches around them.
  for (std::size_t k = 1; k < r.switches.size(); ++k)
    EXPECT_LE(r.switches[k - 1].t, r.switches[k].t) << k;
  // The sample after the jump's interval starts from that interval's end
  // root, not from the linear predictor through the ended root (model.md
  // §7.3): measured 10 Newton iterations, 41 (with the homotopy) before.
  for (const TrajectorySample& sample : r.samples) {
    if (std::abs(sample.t - 3.0) < 1e-9) {
      EXPECT_LE(sample.nlp_iterations, kBranchStepIterations);
    }
  }
}

// The located jump as the regularisation vanishes (zoh, first 3.2 s): at
// eps = 1e-9 and 1e-10 it is still there and its time converges (measured
// 2.9072174, 2.9072811, 2.9072952 s for eps = 1e-8, 1e-9, 1e-10: steps
// 6.4e-5 then 1.4e-5 s), the onset of wheel 1's sliding in the limit; at
// eps = 1e-7 the regularisation smooths the fold pair away (model.md §7.5)
// and nothing is found.
TEST(SolutionJumps, PaperSceneJumpConvergesAsEpsilonVanishes) {
  std::vector<double> times;
  for (const double eps : {1e-7, 1e-8, 1e-9, 1e-10}) {
    Scene scene = PaperScene();
    scene.epsilon = eps;
    SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
    o.t_end = 3.2;
    const SimulationResult r = Simulator(scene, o).Run();
    ASSERT_TRUE(r.success()) << eps << " " << r.stop_reason;
    std::vector<double> at;
    for (const SwitchEvent& e : r.switches)
      if (e.jump && e.wheel == 1) at.push_back(e.t);
    if (eps > 5e-8) {
      EXPECT_TRUE(at.empty()) << eps;
      continue;
    }
    ASSERT_EQ(at.size(), 1u) << eps;
    times.push_back(at[0]);
  }
  ASSERT_EQ(times.size(), 3u);
  EXPECT_LT(times[0], times[1]);
  EXPECT_LT(times[1], times[2]);
  // Converging: each decade's step at most half the one before.
  EXPECT_LT(times[2] - times[1], 0.5 * (times[1] - times[0]));
  EXPECT_LT(times[2] - times[1], 3e-5);
}

// Every backend's run gets the same jump: the continuation runs with the
// backend of the continuation role (newton) from the run's own roots, so
// the bracket is the same to the roots' spread (measured: identical to
// 1e-9 s for newton, slsqp, ceres and ipopt).
class SolutionJumpsPerBackend : public ::testing::TestWithParam<std::string> {};

TEST_P(SolutionJumpsPerBackend, EveryBackendFindsThePaperScenesJump) {
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
  o.nlp = GetParam();
  o.t_end = 3.2;
  const SimulationResult r = Simulator(PaperScene(), o).Run();
  ASSERT_TRUE(r.success()) << r.stop_reason;
  int jumps = 0;
  for (const SwitchEvent& e : r.switches) {
    if (!e.jump || e.wheel != 1) continue;
    ++jumps;
    EXPECT_GT(e.t_lower, 2.907206);
    EXPECT_LT(e.t_upper, 2.907230);
  }
  EXPECT_EQ(jumps, 1);
}

INSTANTIATE_TEST_SUITE_P(AllBackends, SolutionJumpsPerBackend,
                         ::testing::ValuesIn(BuiltinNlpBackendNames()),
                         testing_util::ParamName());

// An event tolerance as long as the interval cannot narrow the end inside
// it: nothing is recorded, and the run goes on (no exception).
TEST(SolutionJumps, ATolerancePastTheIntervalLocatesNothing) {
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
  o.t_end = 3.2;
  o.event_tolerance = 0.1;
  const SimulationResult r = Simulator(PaperScene(), o).Run();
  ASSERT_TRUE(r.success()) << r.stop_reason;
  for (const SwitchEvent& e : r.switches) EXPECT_FALSE(e.jump) << e.t;
}

// Coupled mode finds its own jump in the same interval: its states differ
// from zoh's by the hold's error, which moves the fold (2.9070686 s, the
// same to 4e-7 s at dt 0.1, 0.05, 0.025 and 0.0125 s). It is recorded; the
// interval is not restarted there (model.md §8.6).
TEST(SolutionJumps, CoupledRunRecordsItsOwnJump) {
  SimulationOptions o =
      BuiltinOptions("rk-projection", Coupling::kCoupled, 0.05);
  o.t_end = 3.0;
  const SimulationResult r = Simulator(PaperScene(), o).Run();
  ASSERT_TRUE(r.success()) << r.stop_reason;
  int jumps = 0;
  for (const SwitchEvent& e : r.switches) {
    if (!e.jump) continue;
    ++jumps;
    EXPECT_GT(e.t_lower, 2.9070);
    EXPECT_LT(e.t_upper, 2.9072);
    EXPECT_LE(e.t_upper - e.t_lower, o.event_tolerance);
  }
  EXPECT_EQ(jumps, 3);
}

// A solve at t starts from the root stored at the latest time <= t, the
// latest stored among equal times; the oldest entry goes first once full;
// a NaN time is neither stored nor matched.
TEST(PastRoots, StartsFromTheLatestRootAtOrBeforeTheTime) {
  PastRoots past;
  const auto root = [](double v) { return Eigen::VectorXd::Constant(3, v); };
  EXPECT_EQ(past.StartFor(1.0), nullptr);
  past.Remember(1.0, root(10));
  past.Remember(2.0, root(20));  // a later stage evaluated first
  past.Remember(1.5, root(15));
  EXPECT_EQ(past.StartFor(0.5), nullptr);
  ASSERT_NE(past.StartFor(1.7), nullptr);
  EXPECT_EQ((*past.StartFor(1.7))(0), 15);  // not the latest stored (20)
  EXPECT_EQ((*past.StartFor(2.0))(0), 20);
  past.Remember(1.5, root(16));  // the same time again: the newer wins
  EXPECT_EQ((*past.StartFor(1.9))(0), 16);
  past.Remember(std::numeric_limits<double>::quiet_NaN(), root(99));
  EXPECT_EQ(past.StartFor(std::numeric_limits<double>::quiet_NaN()), nullptr);
  EXPECT_EQ((*past.StartFor(1e9))(0), 20);
  // 4 stored: 4 more fill the slots, the 9th replaces t = 1.0's root.
  for (int i = 0; i < PastRoots::kCapacity - 4; ++i)
    past.Remember(3.0 + i, root(30 + i));
  EXPECT_EQ((*past.StartFor(1.2))(0), 10);
  past.Remember(0.1, root(1));
  EXPECT_EQ((*past.StartFor(1.2))(0), 1);  // t = 1.0's root was evicted
  past.Clear();
  EXPECT_EQ(past.StartFor(1e9), nullptr);
}

}  // namespace
}  // namespace quasiroll
