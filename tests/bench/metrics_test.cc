// Accuracy and drift metrics on synthetic trajectories with known
// differences.
#include "quasiroll/bench/harness/metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "quasiroll/core/so3.h"

namespace quasiroll::bench {
namespace {

// A smooth synthetic trajectory: a curve with changing attitude and forces.
std::vector<TrajectorySample> Curve(double dt, double t_end) {
  std::vector<TrajectorySample> out;
  const int n = static_cast<int>(std::llround(t_end / dt));
  for (int k = 0; k <= n; ++k) {
    TrajectorySample s;
    s.t = k * dt;
    s.position = Vec3(0.06 * s.t, 0.01 * std::sin(s.t), 0.15 + 0.001 * s.t);
    s.rpy = Vec3(0.01 * std::sin(s.t), -0.02 * std::cos(s.t), 0.05 * s.t);
    for (int i = 0; i < 3; ++i) {
      s.contacts[i].normal_force = 12.25 + i + std::sin(s.t);
      s.contacts[i].slip = 1e-5 * (i + 1);
    }
    s.drift = 1e-12 * (k + 1);
    s.gap_max = 1e-10 * k;
    s.nlp_status = "OK";
    out.push_back(s);
  }
  return out;
}

TEST(BenchMetrics, IdenticalTrajectoriesHaveZeroError) {
  const auto ref = Curve(0.05, 2.0);
  const AccuracyMetrics m = CompareTrajectories(ref, ref, true);
  EXPECT_EQ(m.common_samples, 41);
  EXPECT_EQ(m.pos_rms, 0);
  EXPECT_EQ(m.pos_max, 0);
  EXPECT_EQ(m.final_pos, 0);
  EXPECT_NEAR(m.rot_max, 0, 1e-15);
  EXPECT_EQ(m.force_rms, 0);
  EXPECT_EQ(m.slip_rms, 0);
}

TEST(BenchMetrics, ConstantOffsetGivesRmsEqualMaxEqualOffset) {
  const auto ref = Curve(0.05, 2.0);
  auto run = ref;
  for (auto& s : run) s.position += Vec3(0.003, -0.004, 0.0);  // |d| = 0.005
  const AccuracyMetrics m = CompareTrajectories(run, ref, true);
  EXPECT_NEAR(m.pos_rms, 0.005, 1e-15);
  EXPECT_NEAR(m.pos_max, 0.005, 1e-15);
  EXPECT_NEAR(m.final_pos, 0.005, 1e-15);
}

TEST(BenchMetrics, LinearlyGrowingErrorHasKnownRmsAndMax) {
  // e(t) = c t on t_k = k h, k = 0..n: max = c t_n, rms^2 = c^2 h^2 sum
  // k^2/(n+1).
  const auto ref = Curve(0.1, 1.0);
  auto run = ref;
  const double c = 1e-3;
  for (auto& s : run) s.position.x() += c * s.t;
  const AccuracyMetrics m = CompareTrajectories(run, ref, true);
  double sum = 0;
  for (int k = 0; k <= 10; ++k) sum += std::pow(c * 0.1 * k, 2);
  EXPECT_NEAR(m.pos_max, c * 1.0, 1e-15);
  EXPECT_NEAR(m.pos_rms, std::sqrt(sum / 11), 1e-15);
  EXPECT_NEAR(m.final_pos, c, 1e-15);
}

TEST(BenchMetrics, RotationByKnownAngleAboutArbitraryAxis) {
  const auto ref = Curve(0.05, 1.0);
  auto run = ref;
  const double angle = 0.123;
  const Vec3 axis = Vec3(1, -2, 0.5).normalized();
  const Mat3 delta = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  for (auto& s : run) {
    const Mat3 r = RotationFromRpy(s.rpy(0), s.rpy(1), s.rpy(2)) * delta;
    s.rpy = RpyFromRotation(r);
  }
  const AccuracyMetrics m = CompareTrajectories(run, ref, true);
  EXPECT_NEAR(m.rot_max, angle, 1e-12);
  EXPECT_NEAR(m.final_rot, angle, 1e-12);
  EXPECT_NEAR(m.pos_max, 0, 1e-15);
}

TEST(BenchMetrics, RotationAngleNearPi) {
  const Mat3 a = Mat3::Identity();
  const Mat3 b = Eigen::AngleAxisd(3.1, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(RotationAngle(a, b), 3.1, 1e-12);
}

TEST(BenchMetrics, ForceAndSlipOffsets) {
  const auto ref = Curve(0.05, 1.0);
  auto run = ref;
  for (auto& s : run) {
    s.contacts[0].normal_force += 0.3;
    s.contacts[1].normal_force -= 0.3;
    s.contacts[2].normal_force += 0.3;
    for (auto& c : s.contacts) c.slip += 2e-6;
  }
  const AccuracyMetrics m = CompareTrajectories(run, ref, true);
  EXPECT_NEAR(m.force_rms, 0.3, 1e-12);
  EXPECT_NEAR(m.slip_rms, 2e-6, 1e-15);
}

TEST(BenchMetrics, ReferenceOnFinerGridIsInterpolatedLinearly) {
  // Reference on dt/4; run on dt with positions exactly linear in t between
  // the reference samples: interpolation reproduces them exactly.
  auto ref = Curve(0.0125, 1.0);
  for (auto& s : ref) s.position = Vec3(0.06 * s.t, -0.02 * s.t, 0.15);
  std::vector<TrajectorySample> run;
  for (int k = 0; k <= 9; ++k) {
    TrajectorySample s = ref[0];
    s.t = 0.1 * k + 0.003;  // off the reference grid
    s.position = Vec3(0.06 * s.t, -0.02 * s.t, 0.15) + Vec3(0, 0, 1e-3);
    s.rpy = InterpolateSample(ref, s.t).rpy;
    run.push_back(s);
  }
  const AccuracyMetrics m = CompareTrajectories(run, ref, true);
  EXPECT_EQ(m.common_samples, 10);
  EXPECT_NEAR(m.pos_rms, 1e-3, 1e-14);
  EXPECT_NEAR(m.pos_max, 1e-3, 1e-14);
  EXPECT_NEAR(m.rot_max, 0, 1e-12);
}

TEST(BenchMetrics, SlerpInterpolatesYawAcrossPi) {
  std::vector<TrajectorySample> ref(2);
  ref[0].t = 0;
  ref[0].rpy = Vec3(0, 0, 3.1);
  ref[1].t = 1;
  ref[1].rpy = Vec3(0, 0, -3.1);  // 3.1 + (2 pi - 6.2) = the short way round
  const TrajectorySample mid = InterpolateSample(ref, 0.5);
  EXPECT_NEAR(std::abs(mid.rpy(2)), std::numbers::pi, 1e-12);
}

TEST(BenchMetrics, FailedRunIsMeasuredOverTheTimeReachedOnly) {
  const auto ref = Curve(0.05, 2.0);
  std::vector<TrajectorySample> run(ref.begin(), ref.begin() + 21);  // to t = 1
  for (auto& s : run) s.position.y() += 0.01;
  // The failing sample carries NaN forces (a failed quasi-static solve).
  run.back().contacts[0].normal_force = std::nan("");
  const AccuracyMetrics m = CompareTrajectories(run, ref, false);
  EXPECT_EQ(m.common_samples, 21);
  EXPECT_NEAR(m.t_common, 1.0, 1e-12);
  EXPECT_NEAR(m.pos_max, 0.01, 1e-15);
  EXPECT_TRUE(std::isnan(m.final_pos));  // did not complete
  EXPECT_TRUE(std::isnan(m.final_rot));
  EXPECT_EQ(m.force_rms, 0);  // NaN sample skipped
}

TEST(BenchMetrics, ReferenceEndingEarlyLimitsTheCommonTimes) {
  const auto full = Curve(0.05, 2.0);
  std::vector<TrajectorySample> ref(full.begin(),
                                    full.begin() + 11);  // to 0.5 s
  const AccuracyMetrics m = CompareTrajectories(full, ref, true);
  EXPECT_EQ(m.common_samples, 11);
  EXPECT_TRUE(std::isnan(m.final_pos));  // run end not covered
}

TEST(BenchMetrics, EmptyInputsGiveNaN) {
  const auto ref = Curve(0.05, 1.0);
  const AccuracyMetrics m = CompareTrajectories({}, ref, false);
  EXPECT_EQ(m.common_samples, 0);
  EXPECT_TRUE(std::isnan(m.pos_rms));
  EXPECT_TRUE(std::isnan(m.rot_max));
  const DriftMetrics d = ComputeDrift({});
  EXPECT_TRUE(std::isnan(d.drift_max));
}

// Metrics at checkpoints: rms and max over the checkpoints only (the run's
// own samples play no part), final errors at the last checkpoint only when
// it is the run's end.
TEST(BenchMetrics, CheckpointMetricsAreOverTheCheckpoints) {
  const auto ref = Curve(0.0125, 2.0);
  // Three checkpoints on the reference grid with position errors 3, 4, 0 mm
  // and normal-force errors 0.6, 0, 0 N on wheel 1.
  std::vector<TrajectorySample> cp = {ref[25], ref[50], ref[160]};
  cp[0].position.x() += 3e-3;
  cp[1].position.y() += 4e-3;
  cp[0].contacts[0].normal_force += 0.6;
  AccuracyMetrics m = CompareAtCheckpoints(cp, ref, true, 2.0);
  EXPECT_EQ(m.common_samples, 3);
  EXPECT_NEAR(m.pos_max, 4e-3, 1e-15);
  EXPECT_NEAR(m.pos_rms, std::sqrt((9e-6 + 16e-6) / 3), 1e-15);
  EXPECT_NEAR(m.force_rms, std::sqrt(0.36 / 9), 1e-14);  // 3 cp x 3 wheels
  EXPECT_EQ(m.final_pos, 0);                             // at t = 2 = t_end
  // The run reached 2.0 but its last checkpoint is at 1.25: no final error.
  cp.pop_back();
  m = CompareAtCheckpoints(cp, ref, true, 2.0);
  EXPECT_EQ(m.common_samples, 2);
  EXPECT_TRUE(std::isnan(m.final_pos));
  // A failed run has none either.
  m = CompareAtCheckpoints({ref[25], ref[50]}, ref, false, 0.625);
  EXPECT_TRUE(std::isnan(m.final_pos));
  EXPECT_EQ(CountCommonSamples(Curve(0.05, 3.0), ref), 41);
  EXPECT_EQ(CountCommonSamples(Curve(0.05, 3.0), {}), 0);
}

// The failure the checkpoints remove, in a synthetic fixture: the reference
// force has a spike (+5 N, width 0.03 s) at t = 0.95 s, between the samples
// 0.8 and 1.2 of a coarse zoh run (dt 0.4) and resolved by a fine one
// (dt 0.025). Both track the state exactly and apply, as zoh does, the force
// of the last sample (computed exactly there) until the next: measured at
// their own samples both are exact (0 error: a coarse grid "wins" a tie by
// not looking); at the checkpoints (every 0.3125 s: 0.9375 s is on the spike)
// the coarse run pays for the spike it held through and the fine one, whose
// held force is at most 0.025 s old, errs much less.
TEST(BenchMetrics, CoarseGridSkippingASpikeCannotWin) {
  auto force = [](double t) {
    return 10.0 + 5.0 * std::exp(-std::pow((t - 0.95) / 0.03, 2));
  };
  auto ref = Curve(0.0125, 2.0);
  for (auto& s : ref) s.contacts[0].normal_force = force(s.t);
  auto zoh = [&](double dt, bool at_checkpoints) {
    std::vector<TrajectorySample> run;
    for (std::size_t k = 0; k < ref.size(); ++k) {
      const double t = ref[k].t;
      const bool sample = std::abs(t / dt - std::round(t / dt)) < 1e-9;
      const bool checkpoint =
          k > 0 && (k % 25 == 0 || k + 1 == ref.size());  // 0.3125 s
      if (at_checkpoints ? !checkpoint : !sample) continue;
      TrajectorySample s = ref[k];
      s.contacts[0].normal_force = force(std::floor(t / dt + 1e-9) * dt);
      run.push_back(s);
    }
    return CompareAtCheckpoints(run, ref, true, 2.0).force_rms;
  };
  EXPECT_EQ(zoh(0.4, false), 0);  // own samples: blind to the spike
  EXPECT_EQ(zoh(0.025, false), 0);
  const double coarse = zoh(0.4, true), fine = zoh(0.025, true);
  EXPECT_GT(coarse, 0.5);  // 4.2 N missed at 0.9375 s, over 7 x 3 values
  EXPECT_GT(coarse, 2 * fine) << coarse << " vs " << fine;
}

TEST(BenchMetrics, DriftAndGap) {
  auto run = Curve(0.05, 1.0);  // drift = 1e-12 (k + 1), gap = 1e-10 k
  DriftMetrics d = ComputeDrift(run);
  EXPECT_DOUBLE_EQ(d.drift_max, 21e-12);
  EXPECT_DOUBLE_EQ(d.drift_final, 21e-12);
  EXPECT_DOUBLE_EQ(d.gap_max, 20e-10);
  run[5].drift = 1e-3;
  d = ComputeDrift(run);
  EXPECT_DOUBLE_EQ(d.drift_max, 1e-3);
  EXPECT_DOUBLE_EQ(d.drift_final, 21e-12);
  run[7].drift = std::nan("");
  EXPECT_TRUE(std::isnan(ComputeDrift(run).drift_max));  // NaN is not hidden
}

}  // namespace
}  // namespace quasiroll::bench
