#include "quasiroll/bench/harness/metrics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "quasiroll/core/so3.h"

namespace quasiroll::bench {

namespace {
constexpr double kTimeTol = 1e-9;

Mat3 Rotation(const TrajectorySample& s) {
  return RotationFromRpy(s.rpy(0), s.rpy(1), s.rpy(2));
}
}  // namespace

double RotationAngle(const Mat3& ra, const Mat3& rb) {
  const Mat3 q = ra.transpose() * rb;
  const double s = (0.5 * Vee(q - q.transpose())).norm();  // sin(angle)
  const double c = 0.5 * (q.trace() - 1.0);                // cos(angle)
  return std::atan2(s, c);
}

TrajectorySample InterpolateSample(const std::vector<TrajectorySample>& ref,
                                   double t) {
  auto it = std::lower_bound(
      ref.begin(), ref.end(), t,
      [](const TrajectorySample& s, double v) { return s.t < v; });
  if (it != ref.end() && std::abs(it->t - t) <= kTimeTol) return *it;
  if (it != ref.begin() && std::abs(std::prev(it)->t - t) <= kTimeTol)
    return *std::prev(it);
  if (it == ref.end()) return ref.back();
  if (it == ref.begin()) return ref.front();
  const TrajectorySample& a = *std::prev(it);
  const TrajectorySample& b = *it;
  const double w = (t - a.t) / (b.t - a.t);
  TrajectorySample s = a;
  s.t = t;
  s.position = (1 - w) * a.position + w * b.position;
  const Eigen::Quaterniond qa(Rotation(a)), qb(Rotation(b));
  s.rpy = RpyFromRotation(qa.slerp(w, qb).toRotationMatrix());
  s.velocity = (1 - w) * a.velocity + w * b.velocity;
  s.angular_velocity = (1 - w) * a.angular_velocity + w * b.angular_velocity;
  for (int j = 0; j < 6; ++j)
    s.joints[j] = (1 - w) * a.joints[j] + w * b.joints[j];
  for (int i = 0; i < 3; ++i) {
    ContactSample& c = s.contacts[i];
    const ContactSample &ca = a.contacts[i], &cb = b.contacts[i];
    c.point = (1 - w) * ca.point + w * cb.point;
    c.normal_force = (1 - w) * ca.normal_force + w * cb.normal_force;
    c.traction_lon = (1 - w) * ca.traction_lon + w * cb.traction_lon;
    c.traction_lat = (1 - w) * ca.traction_lat + w * cb.traction_lat;
    c.slip = (1 - w) * ca.slip + w * cb.slip;
    c.friction_use = (1 - w) * ca.friction_use + w * cb.friction_use;
  }
  s.drift = (1 - w) * a.drift + w * b.drift;
  s.gap_max = (1 - w) * a.gap_max + w * b.gap_max;
  return s;
}

AccuracyMetrics CompareTrajectories(const std::vector<TrajectorySample>& run,
                                    const std::vector<TrajectorySample>& ref,
                                    bool completed) {
  AccuracyMetrics m;
  if (run.empty() || ref.empty()) return m;
  const double t0 = ref.front().t - kTimeTol, t1 = ref.back().t + kTimeTol;
  double sum_p2 = 0, max_p = 0, max_r = 0, sum_f2 = 0, sum_s2 = 0;
  int n = 0, n_contacts = 0;
  for (const TrajectorySample& s : run) {
    if (s.t < t0 || s.t > t1) continue;
    const TrajectorySample r = InterpolateSample(ref, s.t);
    const double dp = (s.position - r.position).norm();
    const double dr = RotationAngle(Rotation(r), Rotation(s));
    if (!std::isfinite(dp) || !std::isfinite(dr)) continue;
    sum_p2 += dp * dp;
    max_p = std::max(max_p, dp);
    max_r = std::max(max_r, dr);
    ++n;
    m.t_common = s.t;
    bool forces_ok = true;
    for (int i = 0; i < 3; ++i)
      forces_ok = forces_ok && std::isfinite(s.contacts[i].normal_force) &&
                  std::isfinite(r.contacts[i].normal_force) &&
                  std::isfinite(s.contacts[i].slip) &&
                  std::isfinite(r.contacts[i].slip);
    if (forces_ok) {
      for (int i = 0; i < 3; ++i) {
        const double df =
            s.contacts[i].normal_force - r.contacts[i].normal_force;
        const double ds = s.contacts[i].slip - r.contacts[i].slip;
        sum_f2 += df * df;
        sum_s2 += ds * ds;
      }
      n_contacts += 3;
    }
  }
  m.common_samples = n;
  if (n == 0) return m;
  m.pos_rms = std::sqrt(sum_p2 / n);
  m.pos_max = max_p;
  m.rot_max = max_r;
  if (n_contacts > 0) {
    m.force_rms = std::sqrt(sum_f2 / n_contacts);
    m.slip_rms = std::sqrt(sum_s2 / n_contacts);
  }
  const TrajectorySample& last = run.back();
  if (completed && last.t >= t0 && last.t <= t1) {
    const TrajectorySample r = InterpolateSample(ref, last.t);
    m.final_pos = (last.position - r.position).norm();
    m.final_rot = RotationAngle(Rotation(r), Rotation(last));
  }
  return m;
}

AccuracyMetrics CompareAtCheckpoints(
    const std::vector<TrajectorySample>& checkpoints,
    const std::vector<TrajectorySample>& ref, bool completed,
    double t_reached) {
  const bool at_end = completed && !checkpoints.empty() &&
                      std::abs(checkpoints.back().t - t_reached) <= kTimeTol;
  return CompareTrajectories(checkpoints, ref, at_end);
}

int CountCommonSamples(const std::vector<TrajectorySample>& run,
                       const std::vector<TrajectorySample>& ref) {
  if (ref.empty()) return 0;
  const double t0 = ref.front().t - kTimeTol, t1 = ref.back().t + kTimeTol;
  int n = 0;
  for (const TrajectorySample& s : run) n += s.t >= t0 && s.t <= t1;
  return n;
}

DriftMetrics ComputeDrift(const std::vector<TrajectorySample>& run) {
  DriftMetrics d;
  if (run.empty()) return d;
  d.drift_max = 0;
  d.gap_max = 0;
  for (const TrajectorySample& s : run) {
    // NaN propagates (a blown-up state must not look drift-free).
    if (std::isnan(s.drift) || std::isnan(d.drift_max))
      d.drift_max = DriftMetrics::kNaN;
    else
      d.drift_max = std::max(d.drift_max, s.drift);
    if (std::isnan(s.gap_max) || std::isnan(d.gap_max))
      d.gap_max = DriftMetrics::kNaN;
    else
      d.gap_max = std::max(d.gap_max, s.gap_max);
  }
  d.drift_final = run.back().drift;
  return d;
}

TimingStats ComputeTimingStats(std::vector<double> wall_seconds) {
  TimingStats t;
  if (wall_seconds.empty()) return t;
  std::sort(wall_seconds.begin(), wall_seconds.end());
  const std::size_t n = wall_seconds.size();
  t.min = wall_seconds.front();
  t.max = wall_seconds.back();
  t.median = n % 2 ? wall_seconds[n / 2]
                   : 0.5 * (wall_seconds[n / 2 - 1] + wall_seconds[n / 2]);
  const auto quantile = [&](double p) {
    const double pos = p * static_cast<double>(n - 1);
    const std::size_t j = static_cast<std::size_t>(pos);
    const double f = pos - static_cast<double>(j);
    return j + 1 < n
               ? wall_seconds[j] + f * (wall_seconds[j + 1] - wall_seconds[j])
               : wall_seconds[j];
  };
  t.q1 = quantile(0.25);
  t.q3 = quantile(0.75);
  return t;
}

}  // namespace quasiroll::bench
