#include "quasiroll/core/quasi_static_validity.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "quasiroll/core/so3.h"

namespace quasiroll {

Vec3 EstimatedInertia(const Scene& scene) {
  const RobotGeometry& g = scene.geometry;
  const double l = g.wheelbase(), w = g.track, h = g.z_h + g.rho();
  const double k = scene.mass / 12.0;
  return Vec3(k * (w * w + h * h), k * (l * l + h * h), k * (l * l + w * w));
}

namespace {
// A sample with velocities and contact forces.
bool Usable(const TrajectorySample& s) {
  if (!s.velocity.allFinite() || !s.angular_velocity.allFinite()) return false;
  for (const ContactSample& c : s.contacts)
    if (!std::isfinite(c.normal_force) || !std::isfinite(c.traction_lon) ||
        !std::isfinite(c.traction_lat))
      return false;
  return true;
}

// The ratio over run's usable samples from the first_usable-th on; the
// last one's one-sided difference spans at least last_span_floor.
double InertiaRatio(const std::vector<TrajectorySample>& run,
                    const Scene& scene, double last_span_floor,
                    std::size_t first_usable = 0) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::size_t> ok;
  for (std::size_t k = 0; k < run.size(); ++k)
    if (Usable(run[k])) ok.push_back(k);
  if (ok.size() < 2) return nan;
  const Vec3 inertia = EstimatedInertia(scene);
  const double l0 = scene.geometry.wheelbase();
  double worst = 0.0;
  for (std::size_t j = first_usable; j < ok.size(); ++j) {
    const TrajectorySample& s = run[ok[j]];
    // Central difference over the usable neighbours (one-sided at the ends).
    const TrajectorySample& lo = run[ok[j == 0 ? 0 : j - 1]];
    const TrajectorySample& hi = run[ok[j + 1 == ok.size() ? j : j + 1]];
    double span = hi.t - lo.t;
    if (j + 1 == ok.size()) span = std::max(span, last_span_floor);
    if (!(span > 0)) continue;
    const Vec3 a = (hi.velocity - lo.velocity) / span;
    const Vec3 alpha = (hi.angular_velocity - lo.angular_velocity) / span;
    const Mat3 r = RotationFromRpy(s.rpy(0), s.rpy(1), s.rpy(2));
    const Mat3 iw = r * inertia.asDiagonal() * r.transpose();
    const Vec3 w = s.angular_velocity;
    const Vec3 torque = iw * alpha + w.cross(iw * w);
    double load = 0.0;
    for (const ContactSample& c : s.contacts)
      load += Vec3(c.normal_force, c.traction_lon, c.traction_lat).norm();
    if (!(load > 0)) continue;
    worst =
        std::max(worst, (scene.mass * a.norm() + torque.norm() / l0) / load);
  }
  return worst;
}
}  // namespace

double QuasiStaticInertiaRatio(const std::vector<TrajectorySample>& run,
                               const Scene& scene) {
  return InertiaRatio(run, scene, 0.0);
}

namespace {
// The samples before result.stop_retry and the retry after them; *spacing
// the interval between the last two of those samples (0 with fewer).
std::vector<TrajectorySample> WithStopRetry(const SimulationResult& result,
                                            double* spacing) {
  std::vector<TrajectorySample> run = result.samples;
  while (!run.empty() && run.back().t >= result.stop_retry->t) run.pop_back();
  *spacing = 0.0;
  if (run.size() >= 2) *spacing = run.back().t - run[run.size() - 2].t;
  run.push_back(*result.stop_retry);
  return run;
}
}  // namespace

double QuasiStaticInertiaRatio(const SimulationResult& result,
                               const Scene& scene) {
  if (!result.stop_retry) return QuasiStaticInertiaRatio(result.samples, scene);
  // The retry replaces the stop's sample (at its time, or just before it:
  // a located stop's approach), or follows the last sample when the stop
  // has none of its own. Its difference spans at least the last two
  // samples' interval: a twist that changes steeply but stays bounded right
  // at a limit (a stall's retry next to a friction limit) then counts at the
  // samples' resolution, not by how close to the limit the last sample
  // happens to lie; a diverging one (a breakaway) exceeds any bound either
  // way.
  double spacing = 0.0;
  const std::vector<TrajectorySample> run = WithStopRetry(result, &spacing);
  return InertiaRatio(run, scene, spacing);
}

double StopInertiaRatio(const SimulationResult& result, const Scene& scene) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!result.stop_retry) return nan;
  double spacing = 0.0;
  const std::vector<TrajectorySample> run = WithStopRetry(result, &spacing);
  // The retry's own point: the last usable one, if it is usable at all.
  const auto usable =
      static_cast<std::size_t>(std::count_if(run.begin(), run.end(), Usable));
  if (usable < 2 || !Usable(run.back())) return nan;
  return InertiaRatio(run, scene, spacing, usable - 1);
}

}  // namespace quasiroll
