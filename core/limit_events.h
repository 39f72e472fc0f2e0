// Continuous indicators of the physical limits of the single-point contact
// model (model.md §3.2, §8.6), evaluated along the motion between output
// samples so that a run stops where a limit is met, not at the next sample.
//
// Per wheel i, from the configuration alone (the contact coordinates
// eta_i = (u, v, x_g, y_g, psi) of chain i; no joint kinematics):
//   tread angle         g_t = pi/2 - 0.1 - |v_i|                     [rad]
//                       (§3.2 item 1; violated when g_t <= 0)
//   relative curvature  g_k = lambda_min(K)  with
//                       K = K_w(u, v) + r_psi K_g(x_g, y_g) r_psi    [1/m]
//                       the 2x2 symmetric relative curvature form; for
//                       K = [[a, b], [b, c]]:
//                         lambda_min = (a + c)/2 - sqrt(((a - c)/2)^2 + b^2)
//                       (§3.2 item 2; violated when K is not positive
//                       definite, tested exactly as CheckValidity does,
//                       k00 > 0 and det K > 0, so that a located state and
//                       the quasi-static solve there agree)
//   second contact      g_s = 1e-9 m + min over the 72 x 36 (u, v) grid of
//                       (z - h(x, y)) of the torus points inside the
//                       terrain                                       [m]
//                       (§3.2 item 3, the same grid and tolerance as
//                       CheckValidity; violated when g_s < 0; costly, so
//                       only computed when the run's sampled check is on)
//   outside terrain     the contact (x_g, y_g) leaves a bounded terrain
//                       (§3.2 item 4; a boolean, no margin: NaN values).
// All are continuous in Theta (lambda_min of a continuous symmetric matrix,
// a minimum of continuous functions), so a sign change along a continuous
// motion brackets a crossing that bisection can locate. No derivative is
// used: detection is by sign on dense-output points, location by bisection.
//
// Dense output: the cubic Hermite interpolant of one hold interval
// [t0, t0 + h] from Theta_0, Theta_1 and the right-hand sides F_0, F_1 at
// both ends, s = (t - t0)/h:
//   Theta(s) = h00 Theta_0 + h10 h F_0 + h01 Theta_1 + h11 h F_1,
//   h00 = 2s^3 - 3s^2 + 1, h10 = s^3 - 2s^2 + s, h01 = -2s^3 + 3s^2,
//   h11 = s^3 - s^2.
#pragma once

#include <array>
#include <limits>
#include <string>

#include "quasiroll/core/kinematics.h"

namespace quasiroll {

// Indicator values at one configuration (per wheel, 0-based index).
struct LimitIndicators {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::array<double, 3> tread_angle = {kNaN, kNaN, kNaN};
  std::array<double, 3> relative_curvature = {kNaN, kNaN, kNaN};
  // NaN unless computed (EvaluateLimitIndicators with second_contact).
  std::array<double, 3> second_contact = {kNaN, kNaN, kNaN};
  // The first violated limit in wheel order, tread angle before curvature
  // before second contact as in CheckValidity: "" if none, else
  // "outside_terrain", "tread_angle", "relative_curvature" or
  // "second_contact"; wheel is 0-based (-1 if none).
  const char* violated = "";
  int wheel = -1;
  bool ok() const { return violated[0] == '\0'; }
};

// What EvaluateLimitIndicators computes: every value, or what decides
// `violated`: a wheel that RelativeCurvatureCertain() clears keeps
// relative_curvature NaN (no terrain evaluation); `violated` and `wheel`
// are the same either way.
enum class IndicatorDetail { kValues, kVerdict };

// Evaluates the indicators at theta (allocation-free). The second-contact
// clearance only when `second_contact`.
void EvaluateLimitIndicators(const KinematicModel& model,
                             const Configuration& theta, bool second_contact,
                             LimitIndicators* out,
                             IndicatorDetail detail = IndicatorDetail::kValues);

// Whether wheel i's relative-curvature test certainly passes at theta
// whatever the terrain under it (model.md §3.2): lambda_min(K_w) exceeds
// the terrain's Hessian norm bound B by a relative 1e-9 (the rounding of
// K is ~1e-16 |K|), so lambda_min(K_w + r K_g r) >= lambda_min(K_w) - B > 0.
bool RelativeCurvatureCertain(const KinematicModel& model,
                              const Configuration& theta, int wheel);

// lambda_min of K_w + r_psi K_g r_psi for wheel i [1/m]; NaN if the terrain
// does not contain the contact.
double RelativeCurvatureMargin(const KinematicModel& model,
                               const Configuration& theta, int wheel);

// 1e-9 m + the smallest clearance of the 72 x 36 torus grid of wheel i [m].
double SecondContactClearance(const KinematicModel& model,
                              const Configuration& theta, int wheel);

// The cubic Hermite interpolant above at s in [0, 1].
Configuration HermiteState(const Configuration& theta0, const Configuration& f0,
                           const Configuration& theta1, const Configuration& f1,
                           double h, double s);

}  // namespace quasiroll
