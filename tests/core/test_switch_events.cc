// Switches (model.md §8.6, core/switch_events.h): the stick/slide indicator,
// switches placed between two samples located to the stated tolerance, the
// resolved integration across a kink, and the switches of the paper scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "quasiroll/bench/harness/reference.h"
#include "quasiroll/bench/harness/reference_retry.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/slip_regimes.h"
#include "quasiroll/core/switch_events.h"
#include "simulation_support.h"

namespace quasiroll {
namespace {

constexpr double kEps = 1e-8;

TEST(SwitchEvents, IndicatorSignIsTheSlidingClassification) {
  const double at = kSwitchSlipOverEpsilon * kEps;
  EXPECT_EQ(SwitchIndicator(at, kEps), 0.0);
  EXPECT_EQ(SwitchIndicator(0.0, kEps), -1.0);
  EXPECT_TRUE(std::isnan(SwitchIndicator(std::nan(""), kEps)));
  // (|s| - k eps)/(|s| + k eps) at |s| = 3 k eps: 2/4.
  EXPECT_DOUBLE_EQ(SwitchIndicator(3 * at, kEps), 0.5);
  double previous = -2;
  for (double s = 0; s < 1e-3; s = 2 * s + 1e-10) {
    const double g = SwitchIndicator(s, kEps);
    EXPECT_GT(g, previous) << s;  // increasing in |s|
    EXPECT_EQ(g >= 0, s >= kSwitchSlipOverEpsilon * kEps) << s;
    // A switch lies inside the sliding/creep split's sliding regime.
    EXPECT_TRUE(g < 0 || IsSliding(s, kEps)) << s;
    previous = g;
  }
}

// Slips that cross kappa eps at known times between two samples: wheel 2
// starts sliding at t2, wheel 3 stops at t3, wheel 1 keeps its class.
TEST(SwitchEvents, SwitchesBetweenSamplesAreLocatedToTheTolerance) {
  const double t0 = 2.0, t1 = 2.4, t2 = 2.123456789, t3 = 2.0333333333;
  const double at = kSwitchSlipOverEpsilon * kEps;
  auto slips = [&](double t) -> std::array<double, 3> {
    return {0.5 * at, at * std::exp(40.0 * (t - t2)),
            at * (1.0 - 3.0 * (t - t3))};
  };
  int evaluations = 0;
  SlipEvaluator evaluate = [&](double t, std::array<double, 3>* s) {
    EXPECT_GT(t, t0);
    EXPECT_LT(t, t1);
    ++evaluations;
    *s = slips(t);
    return true;
  };
  const double tolerance = 1e-9;
  std::vector<SwitchEvent> out;
  ASSERT_EQ(LocateSwitches(t0, t1, slips(t0), slips(t1), kEps, tolerance,
                           evaluate, &out),
            2);
  // Bisection: 0.4 s / 2^k <= 1e-9 takes 29 halvings per switch (measured:
  // 10 for both; 46 with bisection to 1e-6 s, then Illinois).
  EXPECT_LE(evaluations, 2 * 6);
  const SwitchEvent& a = out[0];  // sorted by time: wheel 3 first
  EXPECT_EQ(a.wheel, 3);
  EXPECT_TRUE(a.from_sliding);
  EXPECT_FALSE(a.to_sliding);
  const SwitchEvent& b = out[1];
  EXPECT_EQ(b.wheel, 2);
  EXPECT_FALSE(b.from_sliding);
  EXPECT_TRUE(b.to_sliding);
  for (const SwitchEvent& e : out) {
    const double exact = e.wheel == 2 ? t2 : t3;
    EXPECT_TRUE(e.located);
    EXPECT_LE(e.t_upper - e.t_lower, tolerance);
    // The bracket contains the crossing (up to round-off in slips(t)).
    EXPECT_LE(e.t_lower, exact + 1e-15);
    EXPECT_GE(e.t_upper, exact - 1e-15);
    EXPECT_EQ(e.t, e.t_upper);
    EXPECT_NEAR(e.t, exact, tolerance);
  }
}

// A steep, smooth transition like the paper scene's (the slip rises over
// ~1 ms by decades, creeping as eps / sqrt(2 r D) before it): located to
// the tolerance with the bracket's ends in their classes, in far fewer
// evaluations than bisection's 26 over 0.05 s (measured: 10, of them 2
// to check bisection's bracket; bisection to 1e-6 s, then Illinois: 20).
TEST(SwitchEvents, ASteepSmoothTransitionIsLocatedInFewEvaluations) {
  const double at = kSwitchSlipOverEpsilon * kEps;
  for (const double tc : {2.9012345678, 2.9234567891, 2.9487654321}) {
    for (const bool rising : {true, false}) {
      const double t0 = 2.9, t1 = 2.95, width = 3e-4;
      // |s| from ~1e-8 (creep) to ~1e-4 m/s (sliding) through a tanh in
      // log|s| over ~width.
      auto slip = [&](double t) {
        const double x = (rising ? t - tc : tc - t) / width;
        return std::exp(std::log(1e-6) + 4.6 * std::tanh(x) + 0.1 * x);
      };
      // |s| = kappa eps = 1e-6 m/s at x = 0, t = tc.
      int evaluations = 0;
      SlipEvaluator evaluate = [&](double t, std::array<double, 3>* s) {
        ++evaluations;
        *s = {slip(t), 0.0, 2 * at};
        return true;
      };
      std::vector<SwitchEvent> out;
      ASSERT_EQ(
          LocateSwitches(t0, t1, {slip(t0), 0.0, 2 * at},
                         {slip(t1), 0.0, 2 * at}, kEps, 1e-9, evaluate, &out),
          1);
      const SwitchEvent& e = out[0];
      EXPECT_TRUE(e.located);
      EXPECT_EQ(e.to_sliding, rising);
      EXPECT_LE(e.t_upper - e.t_lower, 1e-9);
      EXPECT_EQ(SwitchIndicator(slip(e.t_lower), kEps) >= 0, !rising);
      EXPECT_EQ(SwitchIndicator(slip(e.t_upper), kEps) >= 0, rising);
      EXPECT_NEAR(e.t, tc, 1e-9);
      EXPECT_LE(evaluations, 11) << tc << " " << rising;
      // The bracket is bisection's.
      double lo = t0, hi = t1;
      while (hi - lo > 1e-9) {
        const double m = 0.5 * (lo + hi);
        ((SwitchIndicator(slip(m), kEps) >= 0) == rising ? hi : lo) = m;
      }
      EXPECT_EQ(e.t_lower, lo);
      EXPECT_EQ(e.t_upper, hi);
    }
  }
}

// Wheel 2 slides with s(t) = a (t - tr) (1, 0.3): its slip reverses at tr,
// where |s| < kappa eps for |t - tr| < kappa eps / (a |(1, 0.3)|), so it
// sticks briefly between two class changes that both lie inside [t0, t1]
// (same class at the ends: LocateSwitches sees nothing). Wheel 3 creeps
// and reverses (a sticking wheel: no split), wheel 1 starts sliding at t2.
TEST(SwitchEvents, AReversalOfASlidingWheelIsSplitAndBothChangesLocated) {
  const double t0 = 15.2, t1 = 15.6, tr = 15.4567891, t2 = 15.3333333;
  const double a = 1.4e-3, at = kSwitchSlipOverEpsilon * kEps;
  const Eigen::Vector2d dir(1.0, 0.3);
  auto slips = [&](double t) -> std::array<Eigen::Vector2d, 3> {
    return {Eigen::Vector2d(at * std::exp(40.0 * (t - t2)), 0.0),
            a * (t - tr) * dir, Eigen::Vector2d(0.0, 1e-9 * (t - tr))};
  };
  SlipVectorEvaluator evaluate = [&](double t,
                                     std::array<Eigen::Vector2d, 3>* s) {
    EXPECT_GT(t, t0);
    EXPECT_LT(t, t1);
    *s = slips(t);
    return true;
  };
  auto norms = [](const std::array<Eigen::Vector2d, 3>& v) {
    return std::array<double, 3>{v[0].norm(), v[1].norm(), v[2].norm()};
  };
  SlipEvaluator evaluate_norms = [&](double t, std::array<double, 3>* s) {
    *s = norms(slips(t));
    return true;
  };
  const double tolerance = 1e-9;
  std::vector<SwitchEvent> plain, out;
  ASSERT_EQ(LocateSwitches(t0, t1, norms(slips(t0)), norms(slips(t1)), kEps,
                           tolerance, evaluate_norms, &plain),
            1);  // wheel 1 only
  bool reversed = false;
  ASSERT_EQ(LocateSwitchesAndReversals(t0, t1, slips(t0), slips(t1), kEps,
                                       tolerance, evaluate, &out, &reversed),
            3);
  EXPECT_TRUE(reversed);
  const double half = at / (a * dir.norm());  // |s| = kappa eps there
  const double expected[3] = {t2, tr - half, tr + half};
  const int wheel[3] = {1, 2, 2};
  const bool to_sliding[3] = {true, false, true};
  for (int j = 0; j < 3; ++j) {
    const SwitchEvent& e = out[j];
    EXPECT_EQ(e.wheel, wheel[j]) << j;
    EXPECT_EQ(e.to_sliding, to_sliding[j]) << j;
    EXPECT_TRUE(e.located) << j;
    EXPECT_LE(e.t_upper - e.t_lower, tolerance) << j;
    // The crossing lies in the bracket (up to round-off in t - tr).
    EXPECT_LE(e.t_lower, expected[j] + 1e-12) << j;
    EXPECT_GE(e.t_upper, expected[j] - 1e-12) << j;
  }
  // Without a reversal it is LocateSwitches.
  std::vector<SwitchEvent> none;
  EXPECT_EQ(
      LocateSwitchesAndReversals(t0, tr - 0.01, slips(t0), slips(tr - 0.01),
                                 kEps, tolerance, evaluate, &none, &reversed),
      1);
  EXPECT_FALSE(reversed);
}

// A creep_reversal of `wheel` (stick -> stick) located to 1e-9 s around t
// (up to round-off in t).
void ExpectCreepReversalAt(const SwitchEvent& e, int wheel, double t) {
  EXPECT_TRUE(e.reversal);
  EXPECT_STREQ(SwitchKindName(e), "creep_reversal");
  EXPECT_EQ(e.wheel, wheel);
  EXPECT_FALSE(e.from_sliding);
  EXPECT_FALSE(e.to_sliding);
  EXPECT_TRUE(e.located);
  EXPECT_LE(e.t_upper - e.t_lower, 1e-9);
  EXPECT_LE(e.t_lower, t + 1e-12);
  EXPECT_GE(e.t_upper, t - 1e-12);
}

// A creeping wheel whose slip reverses (|s| well below the sliding level at
// both ends) is split at the reversal and recorded as a creep_reversal
// event (stick -> stick); below kCreepReversalSlipOverEpsilon eps at an end
// it is not (its direction is then set near round-off).
TEST(SwitchEvents, ACreepingWheelsReversalIsLocatedAboveTheNoiseFloor) {
  const double t0 = 9.05, t1 = 9.10, tr = 9.0933333;
  // Wheel 3 creeps with s(t) = 2 eps (t - tr)/0.025 (0.6, -0.8): |s| = 3.5
  // and 0.53 eps at the ends; wheels 1 and 2 keep their slips.
  auto slips = [&](double t) -> std::array<Eigen::Vector2d, 3> {
    return {Eigen::Vector2d(3e-9, 1e-9), Eigen::Vector2d(6e-5, 0.0),
            2 * kEps * (t - tr) / 0.025 * Eigen::Vector2d(0.6, -0.8)};
  };
  SlipVectorEvaluator evaluate = [&](double t,
                                     std::array<Eigen::Vector2d, 3>* s) {
    *s = slips(t);
    return true;
  };
  std::vector<SwitchEvent> out;
  bool reversed = false;
  ASSERT_EQ(LocateSwitchesAndReversals(t0, t1, slips(t0), slips(t1), kEps, 1e-9,
                                       evaluate, &out, &reversed),
            1);
  EXPECT_TRUE(reversed);
  ExpectCreepReversalAt(out[0], 3, tr);
  // Below the floor at an end: no reversal.
  const Eigen::Vector2d small(0.05 * kEps, 0.0), large(-2.0 * kEps, 0.0);
  EXPECT_FALSE(IsReversal(small, large, kEps));
  EXPECT_FALSE(IsReversal(large, small, kEps));
  EXPECT_TRUE(IsReversal(-large, large, kEps));
  // One end sliding: a class change, not a reversal.
  EXPECT_FALSE(IsReversal(Eigen::Vector2d(200 * kEps, 0), large, kEps));
}

// A creeping wheel's slip that passes near 0 with a sample at its closest
// approach: each interval turns by less than 90 degrees, so neither is a
// reversal by itself (the work_precision run of the paper scene, rk-baumgarte
// zoh dt 0.025, wheel 2 at 15.5 s: 124.5 -> 62.2 -> 13.7 degrees). With the
// slips of the sample before, the turn is located in the second interval
// where s(t) is perpendicular to them.
TEST(SwitchEvents, ATurnTheGridSplitsOverTwoIntervalsIsLocated) {
  // Wheel 2: s(t) = (rate (t - tc), miss) in m/s, closest to 0 (0.5 eps)
  // at tc, 2e-6 s after the sample t0 (within miss^2 / (rate^2 dt) of it,
  // so both intervals turn by less than 90 degrees), |s| 34 eps at the
  // outer samples; wheels 1 and 3 creep and slide steadily.
  const double t_before = 15.475, t0 = 15.5, t1 = 15.525, tc = t0 + 2e-6;
  const double rate = 1.37e-5, miss = 0.5 * kEps;
  auto slips = [&](double t) -> std::array<Eigen::Vector2d, 3> {
    return {Eigen::Vector2d(6e-10, 1e-10),
            Eigen::Vector2d(rate * (t - tc), miss), Eigen::Vector2d(3e-5, 0.0)};
  };
  SlipVectorEvaluator evaluate = [&](double t,
                                     std::array<Eigen::Vector2d, 3>* s) {
    *s = slips(t);
    return true;
  };
  const auto before = slips(t_before), start = slips(t0), end = slips(t1);
  ASSERT_FALSE(IsReversal(before[1], start[1], kEps));
  ASSERT_FALSE(IsReversal(start[1], end[1], kEps));
  EXPECT_TRUE(IsSplitReversal(before[1], start[1], end[1], kEps));
  std::vector<SwitchEvent> plain;
  EXPECT_EQ(LocateSwitchesAndReversals(t0, t1, start, end, kEps, 1e-9, evaluate,
                                       &plain),
            0);
  std::vector<SwitchEvent> out;
  bool reversed = false;
  ASSERT_EQ(LocateSwitchesAndReversals(t0, t1, start, end, kEps, 1e-9, evaluate,
                                       &out, &reversed, &before),
            1);
  EXPECT_TRUE(reversed);
  // s(t) . s(t_before) = 0: rate^2 (t - tc)(t_before - tc) + miss^2 = 0.
  ExpectCreepReversalAt(out[0], 2,
                        tc - miss * miss / (rate * rate * (t_before - tc)));
  // A wheel that slides at an end, or turns in the first interval already,
  // is no split turn.
  EXPECT_FALSE(IsSplitReversal(-end[1], start[1], end[1], kEps));
  EXPECT_FALSE(IsSplitReversal(before[1], start[1],
                               Eigen::Vector2d(200 * kEps, 0.0), kEps));
  EXPECT_FALSE(
      IsSplitReversal(Eigen::Vector2d::Zero(), start[1], end[1], kEps));
}

// The same turn in a run: the paper scene (rk-baumgarte, zoh, dt 0.025 s)
// records wheel 2's turn inside its stick window at ~15.5 s as a
// creep_reversal; before, only the window's two switches.
TEST(SwitchEvents, PaperScenesTurnInsideWheel2sStickWindowIsLocated) {
  const Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  SimulationOptions o = BuiltinOptions("rk-baumgarte", Coupling::kZoh, 0.025);
  o.t_end = 15.6;
  const SimulationResult r = Simulator(scene, o).Run();
  ASSERT_TRUE(r.success()) << r.stop_reason;
  std::vector<double> window, turns;
  for (const SwitchEvent& e : r.switches) {
    if (e.wheel != 2 || e.t < 15.0) continue;
    (e.reversal ? turns : window).push_back(e.t);
  }
  ASSERT_EQ(window.size(), 2u);
  ASSERT_EQ(turns.size(), 1u);
  EXPECT_GT(turns[0], window[0]);
  EXPECT_LT(turns[0], window[1]);
  EXPECT_NEAR(turns[0], 15.5, 0.0025);
}

// A creeping wheel's slip that turns steeply (its traction's turn, width ~
// eps/|s'|) is already past 0.1 eps at the far end b of the located
// bracket, so the piece before the split, [t0, b], holds the same sign
// change: it is one reversal, recorded once. Searching that piece again
// recorded it twice (overlapping brackets: 39 runs of the default suite),
// or, when the second search could not narrow, ended the piece's search
// and hid another wheel's reversal there (the bumpy scene's wheel 2 at
// 0.154 and 0.177 s, Delta t = 0.4 s). Wheel 2 here slides through a
// reversal at 9.0801 s: its stick window, |s| < 100 eps, is located too.
TEST(SwitchEvents, ASteepCreepReversalIsRecordedOnce) {
  const double t0 = 9.05, t1 = 9.10, t2 = 9.0801;
  const double half_window = 100.0 / 300.0 * 0.01;  // |s2| < kappa eps
  for (int k = 0; k < 40; ++k) {
    const double tr = 9.0512345 + 0.00123 * k;
    auto slips = [&](double t) -> std::array<Eigen::Vector2d, 3> {
      return {
          3 * kEps * std::tanh((t - tr) / 1e-10) * Eigen::Vector2d(0.6, -0.8),
          300 * kEps * (t - t2) / 0.01 * Eigen::Vector2d(1.0, 0.0),
          Eigen::Vector2d(6e-5, 0.0)};
    };
    SlipVectorEvaluator evaluate = [&](double t,
                                       std::array<Eigen::Vector2d, 3>* s) {
      *s = slips(t);
      return true;
    };
    std::vector<SwitchEvent> out;
    LocateSwitchesAndReversals(t0, t1, slips(t0), slips(t1), kEps, 1e-9,
                               evaluate, &out);
    std::vector<SwitchEvent> reversals, changes;
    for (const SwitchEvent& e : out)
      (e.reversal ? reversals : changes).push_back(e);
    ASSERT_EQ(reversals.size(), 1u) << "tr = " << tr;
    EXPECT_EQ(reversals[0].wheel, 1);
    EXPECT_LE(reversals[0].t_lower, tr + 1e-12);
    EXPECT_GE(reversals[0].t_upper, tr - 1e-12);
    ASSERT_EQ(changes.size(), 2u) << "tr = " << tr;
    EXPECT_EQ(changes[0].wheel, 2);
    EXPECT_TRUE(changes[0].from_sliding);
    EXPECT_NEAR(changes[0].t, t2 - half_window, 1e-8);
    EXPECT_EQ(changes[1].wheel, 2);
    EXPECT_TRUE(changes[1].to_sliding);
    EXPECT_NEAR(changes[1].t, t2 + half_window, 1e-8);
  }
}

TEST(SwitchEvents, TheCreepBandLiesBelowTheSlidingThreshold) {
  const double at = kSwitchSlipOverEpsilon * kEps;
  EXPECT_FALSE(InSwitchBand(0.5 * kSwitchBandSlipOverEpsilon * kEps, kEps));
  EXPECT_TRUE(InSwitchBand(kSwitchBandSlipOverEpsilon * kEps, kEps));
  EXPECT_TRUE(InSwitchBand(0.99 * at, kEps));
  EXPECT_FALSE(InSwitchBand(at, kEps));  // sliding
  EXPECT_FALSE(InSwitchBand(std::nan(""), kEps));
}

TEST(SwitchEvents, AFailedEvaluationLeavesTheSwitchUnlocated) {
  const double at = kSwitchSlipOverEpsilon * kEps;
  SlipEvaluator fails = [](double, std::array<double, 3>*) { return false; };
  std::vector<SwitchEvent> out;
  ASSERT_EQ(
      LocateSwitches(0.0, 1.0, {at, 0, 0}, {0, 0, 0}, kEps, 1e-9, fails, &out),
      1);
  EXPECT_FALSE(out[0].located);
  EXPECT_EQ(out[0].wheel, 1);
  EXPECT_EQ(out[0].t_lower, 0.0);
  EXPECT_EQ(out[0].t_upper, 1.0);
  // No class change, no event, no evaluation.
  EXPECT_EQ(LocateSwitches(0.0, 1.0, {at, 0, 0}, {2 * at, 0, 0}, kEps, 1e-9,
                           fails, &out),
            0);
  EXPECT_THROW(LocateSwitches(1.0, 1.0, {}, {}, kEps, 1e-9, fails, &out),
               std::invalid_argument);
  EXPECT_THROW(LocateSwitches(0.0, 1.0, {}, {}, kEps, 0.0, fails, &out),
               std::invalid_argument);
}

// A probe that cannot be solved (a backend that stalls near a switch) is
// replaced by one beside it: the switch is still located to the tolerance.
// Failing every evaluation in a band of the interval left it unlocated in
// the bracket narrowed so far.
TEST(SwitchEvents, AFailedProbeIsReplacedByOneBesideIt) {
  const double ts = 0.3141, at = kSwitchSlipOverEpsilon * kEps;
  // Wheel 1's slip falls through the sliding level at ts (log |s| is not
  // linear in t, so the location probes the interval's inside).
  auto slip = [&](double t) {
    return at * std::exp(-std::sinh((t - ts) / 0.05));
  };
  int bands = 0, probed = 0;
  for (const double side : {-1.0, 1.0}) {
    for (const double dist : {3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 1e-5}) {
      // Every evaluation fails in a band dist .. 2 dist from ts.
      const double lo = ts + side * dist, hi = ts + side * 2 * dist;
      int failed = 0;
      SlipEvaluator evaluate = [&](double t, std::array<double, 3>* s) {
        if (t > std::min(lo, hi) && t < std::max(lo, hi)) {
          ++failed;
          return false;
        }
        *s = {slip(t), 0.0, 0.0};
        return true;
      };
      std::vector<SwitchEvent> out;
      ASSERT_EQ(LocateSwitches(0.0, 1.0, {slip(0.0), 0, 0}, {slip(1.0), 0, 0},
                               kEps, 1e-9, evaluate, &out),
                1);
      ++bands;
      probed += failed > 0;
      EXPECT_TRUE(out[0].located) << side * dist;
      EXPECT_LE(out[0].t_upper - out[0].t_lower, 1e-9) << side * dist;
      EXPECT_LE(out[0].t_lower, ts + 1e-12) << side * dist;
      EXPECT_GE(out[0].t_upper, ts - 1e-12) << side * dist;
    }
  }
  // Brent's steps jump over most bands: 3 of the 14 were probed (the one
  // at -3e-4 left the switch unlocated before EvalNearby).
  EXPECT_EQ(bands, 14);
  EXPECT_GE(probed, 3);
}

// y' = max(0, t - c): y'' jumps at c, so one classical RK4 step across c
// errs by O(h^3); resolved, the pieces that do not straddle c are exact
// (y is piecewise quadratic) and the one that does is refined until the
// step-doubling difference is below the tolerance.
TEST(SwitchEvents, ResolvedIntegrationAcrossAKinkMeetsTheTolerance) {
  const double c = 0.1234, a = 0.0, b = 0.4;
  auto f = [c](double t) { return std::max(0.0, t - c); };
  int calls = 0;
  SegmentAdvance rk4 = [&](double t0, double t1, Eigen::VectorXd* y) {
    ++calls;
    const double h = t1 - t0;
    (*y)(0) += h / 6 * (f(t0) + 4 * f(t0 + h / 2) + f(t1));
    return true;
  };
  const double exact = 0.5 * (b - c) * (b - c);
  Eigen::VectorXd one = Eigen::VectorXd::Zero(1);
  rk4(a, b, &one);
  EXPECT_GT(std::abs(one(0) - exact), 1e-4);
  for (double tolerance : {1e-8, 1e-12}) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(1);
    ASSERT_TRUE(IntegrateResolved(a, b, tolerance, 1e-9, rk4, &y));
    // Accepted pieces keep the two-half-step value, whose error is at most
    // the accepted difference (Simpson's error halves by 2^3 per halving
    // of a straddling piece); a few pieces straddle c over the march.
    EXPECT_LE(std::abs(y(0) - exact), 4 * tolerance) << tolerance;
  }
  Eigen::VectorXd y = Eigen::VectorXd::Zero(1);
  calls = 0;
  ASSERT_TRUE(IntegrateResolved(a, b, std::numeric_limits<double>::infinity(),
                                1e-9, rk4, &y));
  EXPECT_EQ(calls, 1);  // adaptive methods: one call
  SegmentAdvance fails = [](double, double, Eigen::VectorXd*) { return false; };
  EXPECT_FALSE(IntegrateResolved(a, b, 1e-8, 1e-3, fails, &y));
  EXPECT_THROW(IntegrateResolved(b, a, 1e-8, 1e-3, fails, &y),
               std::invalid_argument);
}

// A limit that no step passes (y' = 1/sqrt(t_s - t), no state beyond t_s:
// the creep's square-root blow-up as a wheel's friction use -> 1): the
// march fails within min_step of it with the state where it stood, instead
// of crawling towards t_s in ever shorter pieces until they are a few ulps
// long (which used to count as reaching b).
TEST(SwitchEvents, ResolvedIntegrationStopsShortOfALimitNoStepPasses) {
  const double ts = 0.3, a = 0.0, b = 0.5, min_step = 1e-7;
  auto f = [ts](double t) { return 1.0 / std::sqrt(ts - t); };
  int calls = 0;
  SegmentAdvance simpson = [&](double t0, double t1, Eigen::VectorXd* y) {
    ++calls;
    if (!(t1 < ts)) return false;
    const double h = t1 - t0;
    (*y)(0) += h / 6 * (f(t0) + 4 * f(t0 + h / 2) + f(t1));
    return true;
  };
  Eigen::VectorXd y = Eigen::VectorXd::Zero(1);
  ResolvedStop stop;
  EXPECT_FALSE(IntegrateResolved(a, b, 1e-10, min_step, simpson, &y, &stop));
  EXPECT_LT(stop.t, ts);
  EXPECT_GE(stop.t_failed, ts);
  EXPECT_LE(stop.t_failed - stop.t, min_step);
  // y is the state at stop.t: the integral 2 (sqrt(ts) - sqrt(ts - t)).
  // The pieces within a few min_step of ts are accepted without the test;
  // the integrand's whole mass there, int_{ts-h}^{ts} f = 2 sqrt(h), bounds
  // their error.
  const double exact = 2 * (std::sqrt(ts) - std::sqrt(ts - stop.t));
  EXPECT_NEAR(y(0), exact, 2 * std::sqrt(min_step));
  EXPECT_LT(calls, 3000);
}

SimulationResult RunPaper(double dt, Coupling coupling, bool locate,
                          double t_end = 3.2) {
  SimulationOptions o = BuiltinOptions("rk-projection", coupling, dt);
  o.t_end = t_end;
  o.locate_switches = locate;
  return Simulator(PaperScene(), o).Run();
}

// At a loose nlp_tol (1e-6) a sample's root fixes a slip near the sliding
// level only to about that level, so the class test reads refined copies of
// the samples (ClassSlips, model.md §8.6): the run has the default
// tolerance's class changes, none of them closing onto a sample. Reading
// the samples' own slips, wheel 3 "switched" at 2.95 s and at each sample
// from 3.05 to 3.55 s and back, and wheel 1 at t = 0.
TEST(SwitchEvents, ALooseToleranceRunSwitchesWhereTheDefaultOneDoes) {
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
  o.t_end = 3.6;
  const SimulationResult exact = Simulator(PaperScene(), o).Run();
  o.quasi_static.residual_tolerance = 1e-6;
  const SimulationResult loose = Simulator(PaperScene(), o).Run();
  ASSERT_TRUE(exact.success()) << exact.stop_reason;
  ASSERT_TRUE(loose.success()) << loose.stop_reason;
  auto changes = [](const SimulationResult& r) {
    std::vector<SwitchEvent> out;
    for (const SwitchEvent& e : r.switches)
      if (!e.jump) out.push_back(e);
    return out;
  };
  const std::vector<SwitchEvent> a = changes(exact), b = changes(loose);
  ASSERT_EQ(a.size(), 2u);  // wheel 1 starts to slide, wheel 3 stops
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t j = 0; j < a.size(); ++j) {
    EXPECT_EQ(b[j].wheel, a[j].wheel);
    EXPECT_EQ(b[j].from_sliding, a[j].from_sliding);
    EXPECT_EQ(b[j].to_sliding, a[j].to_sliding);
    // The loose roots move the path itself: 2.9030289 vs 2.9030305 s and
    // 2.9194294 vs 2.9194309 s measured (the samples are 0.05 s apart).
    EXPECT_NEAR(b[j].t, a[j].t, 1e-5);
    // Neither end of the bracket is a sample.
    auto from_sample = [](double t) {
      return std::abs(t - std::round(t / 0.05) * 0.05);
    };
    EXPECT_GT(from_sample(b[j].t_lower), 1e-12) << b[j].t;
    EXPECT_GT(from_sample(b[j].t_upper), 1e-12) << b[j].t;
  }
}

// The paper scene's first switch: wheel 1 starts sliding at ~2.9029 s
// (coupled RK4 at dt = 1e-4 s without location: its slip passes 1e-6 m/s
// between the samples 2.9025 and 2.9030 s), then wheel 3 stops at ~2.919 s.
TEST(SwitchEvents, PaperSceneFirstSwitchIsLocatedInsideTheInterval) {
  for (Coupling coupling : {Coupling::kCoupled, Coupling::kZoh}) {
    const SimulationResult r = RunPaper(0.4, coupling, true);
    ASSERT_TRUE(r.success()) << r.stop_reason;
    // The class changes (the solution jump between them, ~4 ms after the
    // first, is tests/core/test_solution_jumps.cc's).
    std::vector<SwitchEvent> changes;
    for (const SwitchEvent& e : r.switches)
      if (!e.jump && !e.reversal) changes.push_back(e);
    ASSERT_GE(changes.size(), 2u) << ToString(coupling);
    const SwitchEvent& e = changes[0];
    EXPECT_EQ(e.wheel, 1);
    EXPECT_FALSE(e.from_sliding);
    EXPECT_TRUE(e.to_sliding);
    EXPECT_TRUE(e.located);
    EXPECT_LE(e.t_upper - e.t_lower, 1e-9);
    // zoh at dt = 0.4 s is first order, its path off the coupled one: the
    // switch is its own (2.9047 s), checked against a wider window.
    const double slack = coupling == Coupling::kZoh ? 0.01 : 0.0;
    EXPECT_GT(e.t, 2.9025 - slack);
    EXPECT_LT(e.t, 2.9030 + slack);
    EXPECT_EQ(changes[1].wheel, 3);
    EXPECT_TRUE(changes[1].from_sliding);
    EXPECT_GT(changes[1].t, 2.91);
    EXPECT_LT(changes[1].t, 2.93);
    const SimulationResult off = RunPaper(0.4, coupling, false);
    EXPECT_TRUE(off.switches.empty());
    if (coupling == Coupling::kZoh) {
      // zoh records only: the trajectory is the same with and without.
      ASSERT_EQ(off.samples.size(), r.samples.size());
      EXPECT_EQ((off.samples.back().theta - r.samples.back().theta).norm(), 0);
    }
  }
}

// The paper scene's traction turn between the samples 9.05 and 9.10 s
// (docs/model.md §8.6): wheel 3 creeps at both samples with its slip
// reversed and its longitudinal traction flipped (4.3 -> -3.0 N); the
// reversal is located in between, the run's only creep_reversal event up
// to 9.2 s.
TEST(SwitchEvents, PaperScenesCreepReversalIsLocatedAtTheTractionTurn) {
  const SimulationResult r = RunPaper(0.05, Coupling::kZoh, true, 9.2);
  ASSERT_TRUE(r.success()) << r.stop_reason;
  std::vector<SwitchEvent> reversals;
  for (const SwitchEvent& e : r.switches)
    if (e.reversal) reversals.push_back(e);
  ASSERT_EQ(reversals.size(), 1u);
  const SwitchEvent& e = reversals[0];
  EXPECT_EQ(e.wheel, 3);
  EXPECT_TRUE(e.located);
  EXPECT_GT(e.t_lower, 9.05);
  EXPECT_LT(e.t_upper, 9.10);
  const auto at = [&](double t) -> const TrajectorySample& {
    for (const TrajectorySample& s : r.samples)
      if (std::abs(s.t - t) < 1e-9) return s;
    ADD_FAILURE() << "no sample at " << t;
    return r.samples.front();
  };
  EXPECT_GT(at(9.05).contacts[2].traction_lon, 1.0);
  EXPECT_LT(at(9.10).contacts[2].traction_lon, -1.0);
}

// Without a switch, a reversal, a wheel crossing the sliding/creep level
// or in the creep band nothing changes: the first 2.4 s have none (wheel 1
// enters the band, |s| = 10 eps, at ~2.48 s, 0.43 s before its switch).
TEST(SwitchEvents, NoSwitchNoChange) {
  const SimulationResult on = RunPaper(0.4, Coupling::kCoupled, true, 2.4);
  const SimulationResult off = RunPaper(0.4, Coupling::kCoupled, false, 2.4);
  ASSERT_TRUE(on.success());
  EXPECT_TRUE(on.switches.empty());
  ASSERT_EQ(on.samples.size(), off.samples.size());
  for (std::size_t k = 0; k < on.samples.size(); ++k)
    EXPECT_EQ((on.samples[k].theta - off.samples[k].theta).norm(), 0) << k;
  // + the probe and continuation solvers' warm-up solves at the first
  // sample.
  EXPECT_EQ(on.nlp_solves, off.nlp_solves + 2);
  EXPECT_EQ(on.steps, off.steps);
}

// The paper scene's first 3.2 s (zoh, dt 0.05 s, rk-projection, across its
// first switches) twice, run k's options set by vary(k, &options).
std::array<SimulationResult, 2> FirstSwitchesTwice(
    const std::function<void(int, SimulationOptions*)>& vary) {
  std::array<SimulationResult, 2> r;
  for (int k = 0; k < 2; ++k) {
    SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
    o.t_end = 3.2;
    vary(k, &o);
    r[k] = Simulator(PaperScene(), o).Run();
    EXPECT_TRUE(r[k].success()) << r[k].stop_reason;
  }
  return r;
}

// A negative stall watch is rejected, naming its field.
void ExpectNegativeRejected(int SimulationOptions::*field,
                            const std::string& name) {
  SimulationOptions o;
  o.*field = -1;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why)) << name;
  EXPECT_NE(why.find(name), std::string::npos) << why;
}

// The probe solves' stall watch (model.md §7.3; off by default since the
// probes start from interpolated solutions) changes no trajectory: zoh on
// the paper scene across its first switches (2.903 and 2.919 s), the
// states, switch times and slip integrals are bit-identical with and
// without it. (It no longer saves iterations there: the whole 20 s run
// takes 1923 Newton iterations patient and 1975 watched; 3924 watched with
// the nearest-solution starts before.)
TEST(SwitchEvents, ProbeStallWatchLeavesTheTrajectory) {
  const auto r = FirstSwitchesTwice([](int watch, SimulationOptions* o) {
    o->probe_stall_iterations = watch ? 10 : 0;
  });
  ASSERT_EQ(r[0].samples.size(), r[1].samples.size());
  for (std::size_t k = 0; k < r[0].samples.size(); ++k) {
    const TrajectorySample &a = r[0].samples[k], &b = r[1].samples[k];
    ASSERT_EQ((a.theta - b.theta).norm(), 0) << a.t;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(a.contacts[i].normal_force, b.contacts[i].normal_force);
      EXPECT_EQ(a.contacts[i].sliding_distance, b.contacts[i].sliding_distance)
          << "t " << a.t << " wheel " << i + 1;
      EXPECT_EQ(a.contacts[i].creep_distance, b.contacts[i].creep_distance)
          << "t " << a.t << " wheel " << i + 1;
    }
  }
  ASSERT_EQ(r[0].switches.size(), r[1].switches.size());
  ASSERT_GE(r[0].switches.size(), 2u);
  for (std::size_t j = 0; j < r[0].switches.size(); ++j)
    EXPECT_EQ(r[0].switches[j].t, r[1].switches[j].t) << j;
  std::printf("nlp iterations without / with the watch: %lld / %lld\n",
              r[0].nlp_iterations, r[1].nlp_iterations);
  ExpectNegativeRejected(&SimulationOptions::probe_stall_iterations,
                         "probe_stall_iterations");
}

// The zoh sample solves' stall watch (SimulationOptions::
// zoh_stall_iterations): on the paper scene's first 3.2 s the solves at
// 2.95 s (a line-search failure after 78 iterations, then the homotopy) and
// 3.00 s (73 patient iterations) take the homotopy after 10 stalled ones.
// Measured: the run's Newton iterations 678 -> 500 (20 s: 2241 -> 1977),
// states within 4.5e-15 m (the homotopy's root instead of the patient one at
// 3.00 s; round-off). Asserted: fewer iterations, states within 1e-13 m.
TEST(SwitchEvents, ZohStallWatchSavesIterationsAtRoundOff) {
  const auto r = FirstSwitchesTwice([](int watch, SimulationOptions* o) {
    o->zoh_stall_iterations = watch ? 10 : 0;
  });
  ASSERT_EQ(r[0].samples.size(), r[1].samples.size());
  double worst = 0;
  for (std::size_t k = 0; k < r[0].samples.size(); ++k)
    worst = std::max(worst, (r[0].samples[k].theta - r[1].samples[k].theta)
                                .lpNorm<Eigen::Infinity>());
  std::printf("Newton iterations patient / watched: %lld / %lld, states %.2e\n",
              r[0].nlp_iterations, r[1].nlp_iterations, worst);
  EXPECT_LT(r[1].nlp_iterations, r[0].nlp_iterations);
  EXPECT_LT(worst, 1e-13);
  ExpectNegativeRejected(&SimulationOptions::zoh_stall_iterations,
                         "zoh_stall_iterations");
}

// The probes start from the interpolation between the nearest known
// solutions on either side (RestartAtSwitches), not from the nearest one:
// across the paper scene's first switches (zoh, 3.2 s, stall watch off so
// that a creeping Newton shows in full) the probes (the run's solves minus
// those of the same run without switch location) took 151 solves and 1390
// Newton iterations from the nearest solution (9.2 per solve, with the
// location by bisection then) and take 88 and 188 (2.1; the location by
// Brent's method, its refinement to 1e-14 counted as a solve of its own).
// Asserted: <= 3 per solve.
TEST(SwitchEvents, ProbesStartFromInterpolatedSolutions) {
  const auto r = FirstSwitchesTwice([](int locate, SimulationOptions* o) {
    o->probe_stall_iterations = 0;
    o->locate_switches = locate == 1;
  });
  ASSERT_GE(r[1].switches.size(), 2u);
  const int solves = r[1].nlp_solves - r[0].nlp_solves;
  const long long iterations = r[1].nlp_iterations - r[0].nlp_iterations;
  ASSERT_GT(solves, 0);
  std::printf("probe solves %d, Newton iterations %lld\n", solves, iterations);
  EXPECT_LE(iterations, 3LL * solves);
}

// Max over t = 0.4 k of |COM position - reference| [m].
double LadderError(const SimulationResult& r, const SimulationResult& ref) {
  double worst = 0;
  for (const TrajectorySample& a : r.samples) {
    const double k = a.t / 0.4;
    if (std::abs(k - std::round(k)) > 1e-9) continue;
    for (const TrajectorySample& b : ref.samples)
      if (std::abs(b.t - a.t) < 1e-9)
        worst = std::max(worst, (a.position - b.position).norm());
  }
  return worst;
}

// Least-squares slope of log(err) against log(dt).
double FittedOrder(const std::vector<double>& dt, const std::vector<double>& e,
                   std::size_t from, std::size_t to) {
  double mx = 0, my = 0;
  const double n = static_cast<double>(to - from);
  for (std::size_t j = from; j < to; ++j) {
    mx += std::log(dt[j]) / n;
    my += std::log(e[j]) / n;
  }
  double sxy = 0, sxx = 0;
  for (std::size_t j = from; j < to; ++j) {
    sxy += (std::log(dt[j]) - mx) * (std::log(e[j]) - my);
    sxx += (std::log(dt[j]) - mx) * (std::log(dt[j]) - mx);
  }
  return sxy / sxx;
}

// Coupled dp54 on the 20 s paper scene at rtol (atol 1e-15, 1e-16 below
// rtol 1e-12) and output interval dt, run with the harness's retry ladder
// (bench/harness/reference_retry.h): at rtol 1e-12 the error control asks
// for less than the NLP's residual floor at the first switch (2.907 s,
// ~1.5e-11), where a round-off-level change of the right-hand side once
// made a plain run stop. The rtol 1e-12, dt 0.003125 run is the ladders'
// reference (computed once).
const SimulationResult& PaperReference(double rtol, double dt) {
  static SimulationResult cached;
  static bool have = false;
  const bool main_reference = rtol == 1e-12 && dt == 0.003125;
  if (main_reference && have) return cached;
  const Scene scene = PaperScene();
  SimulationOptions ro =
      BuiltinOptions("rk-projection", Coupling::kCoupled, dt);
  ro.t_end = 20;
  ro.dae_options["rk_method"] = "dp54";
  ro.integrator.rtol = rtol;
  ro.integrator.atol = rtol >= 1e-12 ? 1e-15 : 1e-16;
  static SimulationResult other;
  SimulationResult& out = main_reference ? cached : other;
  bench::ReferenceRetryLog log;
  out = bench::RunReferenceWithRetries(scene, ro, &log);
  if (log.rescues > 0)
    std::printf("dp54 rtol %g dt %g: %d interval(s) rescued by the ladder\n",
                rtol, dt, log.rescues);
  have = have || main_reference;
  return out;
}

// The coupled RK4 dt ladder of the whole 20 s paper scene (issue #21).
// Without switch location it is not monotone (the error at 0.2 s exceeds
// the one at 0.4 s: 1.75e-6 vs 1.25e-6 m). With it (located class changes
// and slip reversals, the creep band integrated resolved; model.md §8.6)
// the rungs above the error floor fall at RK4's order. Measured (model.md
// §8.6): 1.36e-7, 1.53e-8, 1.01e-9, 1.54e-10 m at dt = 1.6, 0.8, 0.4, 0.2
// (fitted slope 3.33; 3.54 over the first three), then 3.0e-11, 5.6e-11,
// 3.6e-11 m at 0.1, 0.05, 0.025: at the floor.
// The floor (the reference's own error plus the NLP's residual noise) is
// the largest of three estimates that do not share the reference's error
// control: its spread against dp54 at rtol 1e-13, dt = 0.05 (3.9e-11 m,
// made at the first switch, 2.907 s, where the slip jumps within 0.5 ms)
// and against the harness's RK4 reference (step 0.003125 s: 1.0e-11 m), and
// the finest rung's error, whose RK4 truncation is ~1e4 smaller. (The dp54
// spread alone fell to 5.3e-12 after a round-off-level change of the
// contact velocities while the plateau stayed at ~2e-11: the 0.05 and 0.025
// rungs then counted as above the floor.)
// Asserted: every rung above 2x the floor is below the one before; those
// rungs (at least 4) fit a slope >= 3.3 and the three coarsest >= 3.35; the
// rungs below stay within 3x the floor. The 0.4 s rung carries ~2e-10 m of
// the switch handling (restarts at the located times): switch times moved
// within the location tolerance (location tolerance 5e-10 s, or Brent's
// bracket instead of bisection's) give 1.09e-9-1.24e-9 m there and slopes
// 3.39-3.48 over the three coarsest (3.40 with the round-off change above),
// so the three coarsest are asserted at 3.35, below that spread and above
// order 3.
TEST(SwitchEvents, PaperSceneCoupledRk4LadderHasOrderFourAboveTheFloor) {
  const SimulationResult& ref = PaperReference(1e-12, 0.003125);
  const SimulationResult check = PaperReference(1e-13, 0.05);
  const SimulationResult rk4 = bench::ComputeNumericalReference(
      PaperScene(), bench::ReferenceSettings{});
  ASSERT_TRUE(ref.success()) << ref.stop_reason;
  ASSERT_TRUE(check.success()) << check.stop_reason;
  ASSERT_TRUE(rk4.success()) << rk4.stop_reason;
  const double spread_dp54 = LadderError(check, ref);
  const double spread_rk4 = LadderError(rk4, ref);
  const double spread = std::max(spread_dp54, spread_rk4);
  EXPECT_GT(spread, 0.0);
  EXPECT_LT(spread, 2e-10);
  const std::vector<double> dts = {1.6, 0.8, 0.4, 0.2, 0.1, 0.05, 0.025};
  std::vector<double> on;
  for (double dt : dts) {
    const SimulationResult r = RunPaper(dt, Coupling::kCoupled, true, 20.0);
    ASSERT_TRUE(r.success()) << dt << " " << r.stop_reason;
    on.push_back(LadderError(r, ref));
  }
  // RK4's own error at the finest rung is ~1e4 below what is measured there
  // (slope 4 from the 0.2 s rung), so that rung measures the floor as well.
  const double floor = std::max(spread, on.back());
  EXPECT_LT(on.back(), 3 * spread);  // the plateau agrees with the spread
  std::printf("floor %.3e m: spread dp54 rtol 1e-13 %.3e m, rk4 %.3e m\n",
              floor, spread_dp54, spread_rk4);
  for (std::size_t j = 0; j < on.size(); ++j)
    std::printf("dt %g: error %.3e m\n", dts[j], on[j]);
  std::size_t above = 0;
  while (above < on.size() && on[above] > 2 * floor) ++above;
  EXPECT_GE(above, 4u) << "floor " << floor;
  for (std::size_t j = 1; j < above; ++j) EXPECT_LT(on[j], on[j - 1]) << j;
  EXPECT_GE(FittedOrder(dts, on, 0, above), 3.3);
  EXPECT_GE(FittedOrder(dts, on, 0, 3), 3.35);
  for (std::size_t j = above; j < on.size(); ++j)
    EXPECT_LT(on[j], 3 * floor) << j;
  // The defect the location removes.
  const double off_04 =
      LadderError(RunPaper(0.4, Coupling::kCoupled, false, 20.0), ref);
  const double off_02 =
      LadderError(RunPaper(0.2, Coupling::kCoupled, false, 20.0), ref);
  EXPECT_GT(off_02, off_04);
  EXPECT_LT(100 * on[2], off_04);
}

// Runs scene to t_end, coupled newton + rk-projection (RK4) at dt.
SimulationResult RunCoupledRk4(const Scene& scene, double dt, double t_end) {
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kCoupled, dt);
  o.t_end = t_end;
  return Simulator(scene, o).Run();
}

// pvc mode at mu = 0.3: wheel 2's friction use reaches 1 at ~14.2569 s
// (the paper's Fig. 14 stop). A coupled run approaches it in resolved steps
// that shrink like the creep's square root; the stop is located where the
// path meets the limit, independent of the output grid (it used to be
// recorded at the next sample time, 14.3 s at dt 0.05 and 14.2625 s at
// dt 0.0125, with the state of the limit). Agreement of the two grids to
// 1e-6 s: ten of the resolved march's shortest pieces (kSwitchMinStep).
TEST(SwitchEvents, CoupledRunStopsWhereAWheelsFrictionSaturates) {
  Scene scene = PaperScene();
  scene.mode = ActuationMode::kPvc;
  scene.mu = 0.3;
  std::vector<double> stops;
  for (double dt : {0.05, 0.0125}) {
    const SimulationResult r = RunCoupledRk4(scene, dt, 15.0);
    ASSERT_EQ(r.status, "INFEASIBLE_FRICTION") << dt << ": " << r.stop_reason;
    EXPECT_EQ(r.critical_contact, 2);
    EXPECT_TRUE(r.event.located) << dt;
    EXPECT_NEAR(r.mu_min_at_stop, scene.mu, 1e-8) << dt;
    const double off_grid = std::remainder(r.t_reached, dt);
    EXPECT_GT(std::abs(off_grid), 1e-3) << dt << ": " << r.t_reached;
    stops.push_back(r.t_reached);
  }
  EXPECT_NEAR(stops[0], stops[1], 1e-6);
  EXPECT_NEAR(stops[0], 14.2569, 1e-3);
}

// The paper scene on its terrain at 8x the bumps' heights (the default
// suite's stability_roughness), coupled RK4. At dt = 0.1 s the step over
// [5.8, 5.9] s fails on a solve that gives up (SOLVER_FAILURE: Newton
// stalls at a scaled residual ~3e-8, mu_min ~0.49988 < mu); at dt = 0.05 s
// the step's stages certify INFEASIBLE_FRICTION with mu_min - mu = 5.8e-5
// at the located stop, past the point the path's solves reach. Both runs
// used to stop where their grid put them (5.8 s at the sample; 5.84771 s
// past it); marched resolved, both stop with SOLVER_FAILURE where the
// march cannot go on, inside the ~2e-5 s window where IDA's and CVODE's
// stage solves fail too (5.845638 s), with the stop's sample there.
// That is the quasi-static breakaway (model.md §8.8): the stop's state
// solved again from a cold start has a twist of tens of m/s against
// 0.067 m/s at 5.8 s (the path's twist grows without bound), so the motion
// up to the stop exceeds the validity threshold 0.01 of §8.8 by orders of
// magnitude, which the samples alone (0.0027) do not show.
// The paper scene with its bumps' heights times `factor` (the default
// suite's roughness axis).
Scene RoughenedPaperScene(double factor) {
  Scene scene = PaperScene();
  std::vector<GaussianBump> bumps =
      dynamic_cast<const GaussianTerrain&>(*scene.terrain).bumps();
  for (GaussianBump& b : bumps) b.amplitude *= factor;
  scene.terrain = std::make_shared<GaussianTerrain>(bumps);
  return scene;
}

TEST(SwitchEvents, CoupledRunStopsWhereItsSolvesGiveUpNotAtTheSample) {
  const Scene scene = RoughenedPaperScene(8);
  for (double dt : {0.1, 0.05}) {
    const SimulationResult r = RunCoupledRk4(scene, dt, 6.0);
    ASSERT_EQ(r.status, "SOLVER_FAILURE") << dt << ": " << r.stop_reason;
    EXPECT_GT(r.t_reached, 5.8455) << dt << ": " << r.stop_reason;
    EXPECT_LT(r.t_reached, 5.8457) << dt << ": " << r.stop_reason;
    ASSERT_FALSE(r.samples.empty());
    EXPECT_EQ(r.samples.back().t, r.t_reached) << dt;
    EXPECT_NE(r.stop_reason.find("resolved march"), std::string::npos)
        << r.stop_reason;
    ASSERT_TRUE(r.stop_retry.has_value()) << dt << ": " << r.stop_reason;
    EXPECT_EQ(r.stop_retry->t, r.t_reached) << dt;
    const double before = r.samples[r.samples.size() - 2].velocity.norm();
    EXPECT_LT(before, 0.1) << dt;
    EXPECT_GT(r.stop_retry->velocity.norm(), 100 * before)
        << dt << ": " << r.stop_reason;
    EXPECT_LT(QuasiStaticInertiaRatio(r.samples, scene), 0.01) << dt;
    EXPECT_GT(QuasiStaticInertiaRatio(r, scene), 1.0) << dt;
  }
}

// The same scene, zoh: the held twist carries the path past the point where
// the quasi-static twist diverges (the coupled stop above) to the friction
// limit at 5.85628 s, located, and no sample sees the growth (their ratio
// 0.0024). Following the root from the 5.8 s sample's along the held path
// towards the limit (Simulator::ApproachStop) brackets its end at
// ~5.8546 s, 1.7 ms before the limit, with a twist of thousands of m/s
// against 0.067 m/s at 5.8 s (its size only says how close to the
// divergence the bracket lies), so the run's ratio is
// over 1 like the coupled runs': the verdict no longer depends on the
// coupling (model.md §8.8).
TEST(SwitchEvents, ZohRunSeesTheTwistDivergeBeforeTheFrictionLimit) {
  const Scene scene = RoughenedPaperScene(8);
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.1);
  o.t_end = 6.0;
  const SimulationResult r = Simulator(scene, o).Run();
  ASSERT_EQ(r.status, "INFEASIBLE_FRICTION") << r.stop_reason;
  EXPECT_TRUE(r.event.located);
  EXPECT_NEAR(r.t_reached, 5.85628, 1e-5);
  ASSERT_TRUE(r.stop_retry.has_value()) << r.stop_reason;
  EXPECT_GT(r.stop_retry->t, 5.8);
  EXPECT_LT(r.stop_retry->t, r.t_reached);
  // The root's end is bracketed (FollowBranch to the event tolerance), not
  // left where the continuation's steps ran out.
  EXPECT_NE(r.stop_reason.find("ends after"), std::string::npos)
      << r.stop_reason;
  ASSERT_GE(r.samples.size(), 2u);
  const double before = r.samples[r.samples.size() - 2].velocity.norm();
  EXPECT_LT(before, 0.1);
  EXPECT_GT(r.stop_retry->velocity.norm(), 100 * before) << r.stop_reason;
  EXPECT_LT(QuasiStaticInertiaRatio(r.samples, scene), 0.01);
  EXPECT_GT(QuasiStaticInertiaRatio(r, scene), 1.0);
}

// The control: a friction limit the quasi-static model does reach (pvc,
// mu = 0.3, wheel 2 at ~14.2582 s, zoh dt 0.05). The root is followed to
// the stop, so nothing is added to the samples: the twist's steep but
// bounded change right at the limit (model.md §8.8) depends on how close to
// it each integrator's located stop lies, and on stability_mu's pvc
// mu = 0.1 rows it moved their ratios over 5.7e-5 .. 8.3e-3 when it counted.
TEST(SwitchEvents, ZohApproachToAFrictionLimitAddsNothing) {
  Scene scene = PaperScene();
  scene.mode = ActuationMode::kPvc;
  scene.mu = 0.3;
  SimulationOptions o = BuiltinOptions("rk-projection", Coupling::kZoh, 0.05);
  o.t_end = 15.0;
  const SimulationResult r = Simulator(scene, o).Run();
  ASSERT_EQ(r.status, "INFEASIBLE_FRICTION") << r.stop_reason;
  EXPECT_TRUE(r.event.located);
  EXPECT_FALSE(r.stop_retry.has_value()) << r.stop_reason;
  EXPECT_EQ(r.stop_reason.find("root followed"), std::string::npos);
  EXPECT_LT(QuasiStaticInertiaRatio(r, scene), 1e-3);
}

// IDA keeps its history across the output times in coupled mode (model.md
// §8.6, "IDA"): on the paper scene (rtol 1e-8, dt 0.05) it rejects 4.5 %
// of its steps (27.7 % when it was re-initialised at every output time,
// issue #21: at least halved is the goal, asserted < 10 %) and is more
// accurate against the dp54 reference (1.3e-8 m; 8.3e-8 m before: asserted
// < 3e-8 m). zoh re-initialises at every hold interval (the held twist
// jumps): 28.2 % rejections when each restart tried h0 = dt; with the carried
// initial step (model.md §8.5) one per restart remains, the one ending IDA's
// order-raising start (10.8 %, asserted in [5 %, 20 %]).
TEST(SwitchEvents, PaperSceneIdaKeepsItsHistoryInCoupledMode) {
  RegisterBuiltinIntegrators();
  if (!IntegratorRegistry::Has("ida")) GTEST_SKIP() << "built without SUNDIALS";
  const Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  const SimulationResult& ref = PaperReference(1e-12, 0.003125);
  ASSERT_TRUE(ref.success()) << ref.stop_reason;
  for (Coupling coupling : {Coupling::kCoupled, Coupling::kZoh}) {
    SimulationOptions o;
    o.dae = "ida";
    o.coupling = coupling;
    const SimulationResult r = Simulator(scene, o).Run();
    ASSERT_TRUE(r.success()) << r.stop_reason;
    ASSERT_GT(r.steps, 0);
    const double rejected = static_cast<double>(r.rejected_steps) / r.steps;
    if (coupling == Coupling::kCoupled) {
      EXPECT_LT(rejected, 0.10);
      EXPECT_LT(LadderError(r, ref), 3e-8);
    } else {
      EXPECT_GT(rejected, 0.05);
      EXPECT_LT(rejected, 0.20);
    }
  }
}

}  // namespace
}  // namespace quasiroll
