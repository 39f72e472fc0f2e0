#include "quasiroll/bench/metrics.h"

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
  return t;
}

Vec3 EstimatedInertia(const Scene& scene) {
  const RobotGeometry& g = scene.geometry;
  const double l = g.wheelbase(), w = g.track, h = g.z_h + g.rho();
  const double k = scene.mass / 12.0;
  return Vec3(k * (w * w + h * h), k * (l * l + h * h), k * (l * l + w * w));
}

double QuasiStaticInertiaRatio(const std::vector<TrajectorySample>& run,
                               const Scene& scene) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto usable = [](const TrajectorySample& s) {
    if (!s.velocity.allFinite() || !s.angular_velocity.allFinite())
      return false;
    for (const ContactSample& c : s.contacts)
      if (!std::isfinite(c.normal_force) || !std::isfinite(c.traction_lon) ||
          !std::isfinite(c.traction_lat))
        return false;
    return true;
  };
  std::vector<std::size_t> ok;
  for (std::size_t k = 0; k < run.size(); ++k)
    if (usable(run[k])) ok.push_back(k);
  if (ok.size() < 2) return nan;
  const Vec3 inertia = EstimatedInertia(scene);
  const double l0 = scene.geometry.wheelbase();
  double worst = 0.0;
  for (std::size_t j = 0; j < ok.size(); ++j) {
    const TrajectorySample& s = run[ok[j]];
    // Central difference over the usable neighbours (one-sided at the ends).
    const TrajectorySample& lo = run[ok[j == 0 ? 0 : j - 1]];
    const TrajectorySample& hi = run[ok[j + 1 == ok.size() ? j : j + 1]];
    const double span = hi.t - lo.t;
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

namespace {
bool IsPhysicalStatus(const std::string& s) {
  return s == "INFEASIBLE_FRICTION" || s == "LIFT_OFF" ||
         s == "DEGENERATE_CONTACT";
}
std::string PhysicalDetail(const std::string& s) {
  if (s == "INFEASIBLE_FRICTION") return "friction_limit";
  if (s == "LIFT_OFF") return "lift_off";
  return "degenerate_contact";
}
// Why a run that left the reference's path did so, from the evidence.
bool BaumgarteUnstable(const FailureEvidence& e) {
  return e.dae == "rk-baumgarte" && e.rk_method == "rk4" &&
         e.sigma * e.step > kRk4RealStabilityBound;
}

std::string DivergenceDetail(const FailureEvidence& e) {
  if (BaumgarteUnstable(e)) return "baumgarte_instability";
  if (e.drift_max > e.drift_bound) return "drift_blowup";
  if (e.gap_max > e.gap_bound) return "gap_blowup";
  return "step_too_large";
}
}  // namespace

FailureCause ClassifyFailure(const FailureEvidence& e) {
  const std::string& st = e.status;
  if (st == "success") return {"", ""};
  if (st == "error") return {"numerical", "error"};
  // A run past its bounds: the root cause when it is known (sigma h beyond
  // RK4's stability interval), else the symptom.
  if (st == "drift_exceeded" || st == "gap_exceeded")
    return {"numerical", BaumgarteUnstable(e)     ? "baumgarte_instability"
                         : st == "drift_exceeded" ? "drift_blowup"
                                                  : "gap_blowup"};
  // Stops are detected on the output grid (dt), the sampled second-contact
  // check only every contact_check samples: two detection intervals.
  const double tol_t =
      2.0 * std::max(e.dt * std::max(1, e.contact_check), e.ref_dt);
  const bool ref_stopped = e.has_reference && e.ref_status != "success";
  const bool same_place =
      ref_stopped && std::abs(e.t_reached - e.ref_t_reached) <= tol_t + 1e-9;
  if (IsPhysicalStatus(st)) {
    // The reference stops there too (also where its own solver gave up
    // just short of the limit): the limit is the problem's.
    if (same_place) return {"physical", PhysicalDetail(st)};
    if (!e.has_reference) {
      // Nothing to compare with: only the method's own evidence can
      // overrule the solver's verdict.
      const std::string d = DivergenceDetail(e);
      if (d != "step_too_large") return {"numerical", d};
      return {"physical", PhysicalDetail(st)};
    }
    return {"numerical", DivergenceDetail(e)};
  }
  if (st == "SINGULAR" && same_place && e.ref_status == "SINGULAR")
    // Rank-deficient statics at the same place on the reference's path: a
    // property of the configuration, not of the method.
    return {"physical", "singular_point"};
  if (st == "SOLVER_FAILURE" || st == "SINGULAR") {
    // SOLVER_FAILURE means mu > mu_min and regular statics at that state
    // (model.md §7): a solution exists and the NLP did not find it. That the
    // reference (newton by default) fails there too does not make it
    // physical (another backend may pass); only a physical stop of the
    // reference at the same place does.
    if (same_place && IsPhysicalStatus(e.ref_status))
      return {"physical", PhysicalDetail(e.ref_status)};
    // The reference's own solver gives up at the same place: a hard point
    // of the quasi-static NLP (seen within 1 % of mu_min), not this
    // method's weakness alone. Still numerical: a solution exists.
    if (same_place && e.ref_status == "SOLVER_FAILURE")
      return {"numerical", "shared_solver_failure"};
    return {"numerical", "solver_failure"};
  }
  // An implicit integrator whose residual could not be evaluated because the
  // NLP failed inside it, where the reference's solver fails too.
  if (st == "rhs_failure" && same_place && e.ref_status == "SOLVER_FAILURE")
    return {"numerical", "shared_solver_failure"};
  return {"numerical", "integrator_failure"};
}

}  // namespace quasiroll::bench
