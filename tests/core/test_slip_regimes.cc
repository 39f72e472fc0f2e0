// Sliding and creep (docs/model.md §7.5, core/slip_regimes.h): the split of
// the integrated slip by the regularised friction law's two regimes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/slip_regimes.h"

namespace quasiroll {
namespace {

TrajectorySample At(double t, double s1, double s2, double s3) {
  TrajectorySample s;
  s.t = t;
  s.contacts[0].slip = s1;
  s.contacts[1].slip = s2;
  s.contacts[2].slip = s3;
  return s;
}

// Trapezoid rule by hand, eps = 1e-8: 1e-5 m/s slides (1000 eps), 5e-8
// creeps (5 eps), a NaN slip (failed solve) adds nothing.
TEST(SlipRegimes, TrapezoidSplitByRegime) {
  const double eps = 1e-8, nan = std::numeric_limits<double>::quiet_NaN();
  TrajectorySample a = At(0.0, 1e-5, 5e-8, 1e-5);
  a.contacts[0].sliding_distance = 1.0;  // carried over
  TrajectorySample b = At(0.5, 3e-5, 7e-8, nan);
  AccumulateSlipDistances(a, eps, &b);
  EXPECT_DOUBLE_EQ(b.contacts[0].sliding_distance, 1.0 + 0.25 * (1e-5 + 3e-5));
  EXPECT_EQ(b.contacts[0].creep_distance, 0.0);
  EXPECT_DOUBLE_EQ(b.contacts[1].creep_distance, 0.25 * (5e-8 + 7e-8));
  EXPECT_EQ(b.contacts[1].sliding_distance, 0.0);
  EXPECT_DOUBLE_EQ(b.contacts[2].sliding_distance, 0.25 * 1e-5);
  // A wheel that starts to slide: each end's half to its own regime.
  TrajectorySample c = At(1.0, 3e-5, 2e-6, 1e-5);
  AccumulateSlipDistances(b, eps, &c);
  EXPECT_DOUBLE_EQ(c.contacts[1].creep_distance - b.contacts[1].creep_distance,
                   0.25 * 7e-8);
  EXPECT_DOUBLE_EQ(
      c.contacts[1].sliding_distance - b.contacts[1].sliding_distance,
      0.25 * 2e-6);
  EXPECT_TRUE(IsSliding(100 * eps, eps));
  EXPECT_FALSE(IsSliding(99 * eps, eps));
  const SlipDistances total = TotalSlipDistances({a, b, c});
  EXPECT_DOUBLE_EQ(total.sliding, c.contacts[0].sliding_distance +
                                      c.contacts[1].sliding_distance +
                                      c.contacts[2].sliding_distance);
  EXPECT_EQ(TotalSlipDistances({}).sliding, 0.0);
}

SlipDistances Simulate(ActuationMode mode, double eps) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.mode = mode;
  scene.epsilon = eps;
  scene.t_end = 5.0;
  const SimulationResult r = Simulator(scene, SimulationOptions{}).Run();
  EXPECT_TRUE(r.success()) << r.stop_reason;
  return TotalSlipDistances(r.samples);
}

// pvc never slides (model.md §7.5: its statics are determinate, so the
// friction use does not depend on eps and the slip eps u / sqrt(1 - u^2) is
// all creep): creep proportional to eps. The forces move with the path only
// through the O(eps) creep itself, so the ratio is 10 to far better than the
// issue's 5 %; 1e-3 leaves room for that second-order effect.
TEST(SlipRegimes, PvcCreepsInProportionToEpsilonAndNeverSlides) {
  const SlipDistances coarse = Simulate(ActuationMode::kPvc, 1e-7);
  const SlipDistances fine = Simulate(ActuationMode::kPvc, 1e-8);
  EXPECT_EQ(coarse.sliding, 0.0);
  EXPECT_EQ(fine.sliding, 0.0);
  ASSERT_GT(fine.creep, 0.0);
  EXPECT_NEAR(coarse.creep / fine.creep, 10.0, 10.0 * 1e-3);
}

// Paper mode slides (the over-actuated chains' incompatibility, ~1e-5 m/s):
// the sliding distance converges as eps -> 0 (model.md §7.5's table of the
// total slip over the first 5 s) while the creep falls in proportion to eps
// once the slides are resolved (eps <= 1e-3 of the slip speeds, §7.2).
// Measured 2026-11-26: sliding 2.0892e-4, 2.2049e-4, 2.2097e-4 m and creep
// 1.09e-5, 4.02e-7, 3.90e-8 m at eps 1e-7, 1e-8, 1e-9: each decade of eps
// moves the sliding distance 25x less than the one before.
TEST(SlipRegimes, PaperSlidingConvergesAsEpsilonFalls) {
  const SlipDistances e7 = Simulate(ActuationMode::kPaper, 1e-7);
  const SlipDistances e8 = Simulate(ActuationMode::kPaper, 1e-8);
  const SlipDistances e9 = Simulate(ActuationMode::kPaper, 1e-9);
  ASSERT_GT(e9.sliding, 0.0);
  EXPECT_LT(std::abs(e8.sliding - e9.sliding),
            0.1 * std::abs(e7.sliding - e9.sliding));
  EXPECT_NEAR(e8.sliding / e9.sliding, 1.0, 5e-3);
  // Creep proportional to eps within the 5 %.
  EXPECT_NEAR(e8.creep / e9.creep, 10.0, 0.5);
}

}  // namespace
}  // namespace quasiroll
