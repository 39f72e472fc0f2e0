// Per-run metrics of the benchmark harness (docs/harness.md, runs.csv):
// accuracy of a trajectory against a reference trajectory, constraint drift
// and geometric gap. Pure functions of the samples; no I/O.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "quasiroll/core/simulator.h"

namespace quasiroll::bench {

struct AccuracyMetrics {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  // Over the common output times (run samples whose t lies within the
  // reference's time span); NaN when there is none.
  double pos_rms = kNaN;  // sqrt(mean |p - p_ref|^2) [m]
  double pos_max = kNaN;  // max |p - p_ref| [m]
  double rot_max = kNaN;  // max angle of R_ref^T R [rad]
  // Normal forces: sqrt(mean over samples and wheels of (N - N_ref)^2) [N],
  // over the common samples where both have finite forces (a quasi-static
  // failure records NaN forces).
  double force_rms = kNaN;
  // Slip speeds: sqrt(mean (|s| - |s_ref|)^2) [m/s], same samples.
  double slip_rms = kNaN;
  // At the run's last sample, only if the run completed (reached t_end) and
  // the reference covers that time; NaN otherwise.
  double final_pos = kNaN;  // [m]
  double final_rot = kNaN;  // [rad]
  int common_samples = 0;
  double t_common = kNaN;  // last common time [s]
};

struct DriftMetrics {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double drift_max = kNaN;    // max ||H||_inf over the samples
  double drift_final = kNaN;  // ||H||_inf of the last sample
  double gap_max = kNaN;      // max geometric gap over the samples [m]
};

// Angle of R_a^T R_b in [0, pi] [rad].
double RotationAngle(const Mat3& ra, const Mat3& rb);

// The reference state at time t: linear interpolation in t between the two
// bracketing samples (slerp for the orientation); exact sample when t matches
// one within 1e-9 s. `t` must lie within [front().t, back().t] (+-1e-9).
TrajectorySample InterpolateSample(const std::vector<TrajectorySample>& ref,
                                   double t);

// `completed`: the run reached its t_end (status success).
AccuracyMetrics CompareTrajectories(const std::vector<TrajectorySample>& run,
                                    const std::vector<TrajectorySample>& ref,
                                    bool completed);

// The runs.csv accuracy metrics (docs/harness.md, "Errors at checkpoints"):
// CompareTrajectories over the run's checkpoint samples
// (SimulationResult::checkpoints, core/checkpoints.h) against the reference
// at the same times (its own samples there, or the exact solution), so
// every err_* is a mean / max over the checkpoints common to run and
// reference (common_samples = their number) and does not depend on the
// run's output grid. err_final / err_final_rot: at the run's last
// checkpoint when the run completed and that checkpoint is its end
// (t_reached), NaN otherwise.
AccuracyMetrics CompareAtCheckpoints(
    const std::vector<TrajectorySample>& checkpoints,
    const std::vector<TrajectorySample>& ref, bool completed, double t_reached);

// Run samples whose time lies within the reference's span (runs.csv
// common_samples).
int CountCommonSamples(const std::vector<TrajectorySample>& run,
                       const std::vector<TrajectorySample>& ref);

DriftMetrics ComputeDrift(const std::vector<TrajectorySample>& run);

// ------------------------------------------------- timing statistics ----

struct TimingStats {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double min = kNaN, median = kNaN, max = kNaN;  // over the repeats [s]
  double q1 = kNaN, q3 = kNaN;  // first and third quartiles [s]
};
// Median = middle value, or the mean of the two middle values. Quartiles of
// the sorted times w_0 <= .. <= w_{n-1} by linear interpolation between
// order statistics (Hyndman-Fan type 7, numpy's default): Q(p) = w_j +
// f (w_{j+1} - w_j) with j + f = p (n - 1); q1 = Q(1/4), q3 = Q(3/4), so the
// IQR q3 - q1 is 0 for one repeat and (w_1 - w_0) / 2 for two.
TimingStats ComputeTimingStats(std::vector<double> wall_seconds);

}  // namespace quasiroll::bench
