// Sliding and creep (docs/model.md §7.5, core/slip_regimes.h): the split of
// the integrated slip by the regularised friction law's two regimes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
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
  EXPECT_TRUE(IsSliding(10 * eps, eps));
  EXPECT_FALSE(IsSliding(9.99 * eps, eps));
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
// the sliding distance converges as eps -> 0 while the creep falls in
// proportion to eps (model.md §7.5). Measured 2026-11-26 (first 5 s, zoh,
// dt 0.05): sliding 2.17256e-4, 2.20175e-4, 2.20477e-4 m (2.20507e-4 at
// 1e-10) and creep / eps 22.96, 22.53, 22.37 s at eps 1e-7, 1e-8, 1e-9
// (22.37 s at 1e-10). Asserted: the sliding distance's distance to
// eps = 1e-9 falls at least tenfold per decade (measured: to 0.094) and is
// within 0.5 % at 1e-8 (0.14 %); creep proportional to eps within the
// issue's 5 % (0.7 %).
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

// An evaluator of slip(t) counting its calls in *calls.
template <class Slip>
SlipEvaluator Counting(const Slip& slip, int* calls) {
  return [&slip, calls](double t, std::array<double, 3>* f) {
    ++*calls;
    *f = slip(t);
    return true;
  };
}

// An interval with a located stick -> slide switch of wheel 1 at ts: before
// it the creep precursor |s| = eps / sqrt(2 r (tc - t)) (a wheel heading for
// its cone, switch_events.h), |s(ts)| = 100 eps (the switch: a kink); after
// it a slide ramping linearly to 1e-5 m/s. The precursor crosses the
// sliding level 10 eps at tx = tc - 1 / (200 r) inside the interval (r is
// chosen for tx = 0.02), which IntegrateSlipRegimes must locate by itself:
// creep before tx, sliding after. Wheel 2 creeps at 5 eps, wheel 3 slides
// at 1e-5. Analytic: the precursor's integral eps sqrt(2 / r) (sqrt(tc -
// ta) - sqrt(tc - tb)) over [t0, tx] (creep) and [tx, ts] (sliding, plus
// the ramp's trapezoid). Tolerance 1e-3: the quadrature's requested 1e-3
// of the piece (its extrapolated sum is far better than the estimate) and
// tx located to |s| within 2e-4 of the level (<= 3e-4 of the creep). The
// two-sample trapezoid's sliding errs by more than 100 % here.
TEST(SlipRegimes, SwitchIntervalIsIntegratedPiecewise) {
  const double eps = 1e-8, t0 = 0.0, t1 = 0.05, ts = 0.03, tx = 0.02;
  // tc - tx = 1 / (200 r) and tc - ts = 1 / (2e4 r).
  const double r = (0.005 - 0.00005) / (ts - tx);
  const double tc = ts + 1.0 / (2 * r * 1e4);
  auto slip = [&](double t) -> std::array<double, 3> {
    const double w1 =
        t < ts ? eps / std::sqrt(2 * r * (tc - t))
               : 100 * eps + (1e-5 - 100 * eps) * (t - ts) / (t1 - ts);
    return {w1, 5 * eps, 1e-5};
  };
  ASSERT_NEAR(slip(tx)[0], 10 * eps, 1e-12 * eps);
  int calls = 0;
  const SlipEvaluator evaluate = Counting(slip, &calls);
  SlipIncrements inc;
  int evaluations = 0;
  ASSERT_TRUE(IntegrateSlipRegimes(t0, t1, slip(t0), slip(t1), {ts}, eps,
                                   evaluate, &inc, &evaluations));
  EXPECT_EQ(evaluations, calls);
  auto precursor = [&](double ta, double tb) {
    return eps * std::sqrt(2 / r) * (std::sqrt(tc - ta) - std::sqrt(tc - tb));
  };
  const double creep = precursor(t0, tx);
  EXPECT_NEAR(inc[0].creep, creep, 1e-3 * creep);
  const double sliding =
      precursor(tx, ts) + 0.5 * (100 * eps + 1e-5) * (t1 - ts);
  EXPECT_NEAR(inc[0].sliding, sliding, 1e-3 * precursor(tx, ts));
  EXPECT_NEAR(inc[1].creep, 5 * eps * (t1 - t0), 1e-9 * eps);
  EXPECT_EQ(inc[1].sliding, 0.0);
  EXPECT_NEAR(inc[2].sliding, 1e-5 * (t1 - t0), 1e-15);
  EXPECT_EQ(inc[2].creep, 0.0);
  // What the trapezoid over the two samples gives wheel 1 instead.
  TrajectorySample a = At(t0, slip(t0)[0], 0, 0), b = At(t1, slip(t1)[0], 0, 0);
  AccumulateSlipDistances(a, eps, &b);
  EXPECT_GT(std::abs(b.contacts[0].sliding_distance - sliding), sliding);
  // A failed evaluation: false (the caller keeps the trapezoid).
  const SlipEvaluator failing = [](double, std::array<double, 3>*) {
    return false;
  };
  EXPECT_FALSE(IntegrateSlipRegimes(t0, t1, slip(t0), slip(t1), {ts}, eps,
                                    failing, &inc, &evaluations));
  // One failing probe (a stalled solve) is retried next to it: the same
  // integrals, not the trapezoid.
  const double bad = 0.5 * (ts + t1);
  int failed = 0;
  const SlipEvaluator once = [&](double t, std::array<double, 3>* f) {
    if (t == bad) return ++failed, false;
    *f = slip(t);
    return true;
  };
  SlipIncrements retried;
  ASSERT_TRUE(IntegrateSlipRegimes(t0, t1, slip(t0), slip(t1), {ts}, eps, once,
                                   &retried, &evaluations));
  EXPECT_EQ(failed, 1);
  EXPECT_NEAR(retried[0].sliding, sliding, 1e-3 * precursor(tx, ts));
  EXPECT_NEAR(retried[0].creep, creep, 1e-3 * creep);
  EXPECT_THROW(IntegrateSlipRegimes(t1, t0, slip(t0), slip(t1), {}, eps,
                                    evaluate, &inc, &evaluations),
               std::invalid_argument);
}

// A steep, smooth transition inside one piece (a sliding wheel's slip
// rising from 1e-6 to 1e-4 m/s over ~1 ms, as after the paper scene's
// first switch): its integral within the requested 1e-3 (the extrapolated
// sum is better than the estimate, except where the rule does not resolve
// the transition's tail: 9e-4 at tc = 0.0271) in at most 35 evaluations
// (measured: 27, 27, 35). A globally adaptive Simpson rule (halving the
// panel with the largest estimate until the estimates sum to the
// tolerance) needed 19 but erred by up to 2.1e-3 here.
TEST(SlipRegimes, ASteepTransitionIsIntegratedWithinTheTolerance) {
  const double eps = 1e-8, t0 = 0.0, t1 = 0.05;
  for (const double tc : {0.0123, 0.0271, 0.0388}) {
    const double w = 1e-3, lo = 1e-6, hi = 1e-4;
    auto slip = [&](double t) -> std::array<double, 3> {
      return {lo + 0.5 * (hi - lo) * (1 + std::tanh((t - tc) / w)), 5e-6,
              2e-5 * (1 + t)};
    };
    int calls = 0;
    const SlipEvaluator evaluate = Counting(slip, &calls);
    SlipIncrements inc;
    int evaluations = 0;
    ASSERT_TRUE(IntegrateSlipRegimes(t0, t1, slip(t0), slip(t1), {}, eps,
                                     evaluate, &inc, &evaluations));
    EXPECT_EQ(evaluations, calls);
    auto log_cosh = [&](double t) {
      const double x = std::abs(t - tc) / w;
      return x + std::log1p(std::exp(-2 * x)) - std::log(2.0);
    };
    const double exact =
        lo * (t1 - t0) +
        0.5 * (hi - lo) * ((t1 - t0) + w * (log_cosh(t1) - log_cosh(t0)));
    EXPECT_NEAR(inc[0].sliding, exact, 1e-3 * exact) << tc;
    EXPECT_EQ(inc[0].creep, 0.0);
    EXPECT_NEAR(inc[1].sliding, 5e-6 * (t1 - t0), 1e-15);
    EXPECT_NEAR(inc[2].sliding, 2e-5 * ((t1 - t0) + 0.5 * (t1 * t1 - t0 * t0)),
                1e-15);
    EXPECT_LE(evaluations, 35) << tc;
  }
}

// A reversal: a sliding wheel whose slip passes through zero at tr at a
// rate a, |s| = a |t - tr|, with its switches (100 eps) located on both
// sides. Between them, both ends slide by the split's 10 eps level, so the
// stick window below 10 eps (length 20 eps / a) is found from the piece's
// midpoint: creep (10 eps)^2 / a, the rest sliding. Relative tolerance
// 1e-3 as above (the window is located to 2e-4 of the level).
TEST(SlipRegimes, ReversalWindowCreepsOnlyBelowTheSlidingLevel) {
  const double eps = 1e-8, a = 1.4e-5, tr = 0.021, t0 = 0.0, t1 = 0.05;
  auto slip = [&](double t) -> std::array<double, 3> {
    return {a * std::abs(t - tr), 1e-5, 1e-5};
  };
  const SlipEvaluator evaluate = [&](double t, std::array<double, 3>* f) {
    *f = slip(t);
    return true;
  };
  const double w = 100 * eps / a;  // switch times tr -+ w
  SlipIncrements inc;
  int evaluations = 0;
  ASSERT_TRUE(IntegrateSlipRegimes(t0, t1, slip(t0), slip(t1), {tr - w, tr + w},
                                   eps, evaluate, &inc, &evaluations));
  const double creep = (10 * eps) * (10 * eps) / a;
  const double total =
      0.5 * a * (tr - t0) * (tr - t0) + 0.5 * a * (t1 - tr) * (t1 - tr);
  EXPECT_NEAR(inc[0].creep, creep, 1e-3 * creep);
  EXPECT_NEAR(inc[0].sliding, total - creep, 1e-3 * creep);
}

// Creep does not depend on the output grid (issue #21, "errors independent
// of the output grid"): paper scene, eps 1e-9, coupled DP5(4) at rtol 1e-10
// (the same trajectory on every grid), 20 s. Measured: 5.43e-8, 5.58e-8,
// 5.49e-8 m at dt 0.2, 0.1, 0.05 (sliding 1.06712e-3 ... 1.06748e-3 m);
// the trapezoid over the samples alone gave 4.62e-8, 5.96e-8, 6.00e-8 m
// (30 %): a sample next to a switch carried the creep peak, or a short
// stick window, with a weight set by where it fell. Asserted within 5 %.
TEST(SlipRegimes, PaperCreepDoesNotDependOnTheOutputGrid) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.epsilon = 1e-9;
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (double dt : {0.2, 0.1, 0.05}) {
    SimulationOptions o;
    o.coupling = Coupling::kCoupled;
    o.dt = dt;
    o.dae_options["rk_method"] = "dp54";
    o.integrator.rtol = 1e-10;
    const SimulationResult r = Simulator(scene, o).Run();
    ASSERT_TRUE(r.success()) << dt << " " << r.stop_reason;
    const double creep = TotalSlipDistances(r.samples).creep;
    lo = std::min(lo, creep);
    hi = std::max(hi, creep);
  }
  ASSERT_GT(lo, 0.0);
  EXPECT_LT(hi / lo, 1.05) << lo << " " << hi;
}

}  // namespace
}  // namespace quasiroll
