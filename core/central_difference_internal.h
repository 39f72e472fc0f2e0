// Central differences of a field along one state coordinate: the step rule
// of the field derivatives, KinematicModel::RhsStateDerivative (dF/dTheta
// of the kinematic field F, chain by chain) and the step derivative's
// Baumgarte field (core/step_sensitivity.cc), written once.
//
// Internal header: core's .cc files only; not installed.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "quasiroll/core/kinematics.h"

namespace quasiroll::internal {

// d f / d theta_k at theta (model.md §8.9, §7.9) by the central difference
//   (f(theta + h_+ e_k) - f(theta - h_- e_k)) / (h_+ + h_-),
//   h = cbrt(eps_mach) max(1, |theta_k|),
// h_+ and h_- the steps actually taken, (theta_k + h) - theta_k and
// theta_k - (theta_k - h): exact where |theta_k| >= h (Sterbenz), so the
// rounding of theta_k +- h does not enter the divisor. Why this h: the
// truncation h^2 f'''/6 and the round-off eps_mach f / h balance at
// h ~ cbrt(eps_mach) times the scale on which f varies (1 for angles and
// metres, |theta_k| beyond), both ~eps_mach^(2/3) ~ 4e-11 relative.
// field(const Configuration& at, Column* value) -> bool, evaluated at
// theta + h_+ e_k, then at theta - h_- e_k; false as soon as one fails.
template <class Column, class Field>
bool CentralDifference(const Configuration& theta, int k, const Field& field,
                       Column* column) {
  const double root = std::cbrt(std::numeric_limits<double>::epsilon());
  const double h = root * std::max(1.0, std::abs(theta(k)));
  Configuration moved = theta;
  Column plus, minus;
  moved(k) = theta(k) + h;
  const double h_plus = moved(k) - theta(k);
  if (!field(moved, &plus)) return false;
  moved(k) = theta(k) - h;
  const double h_minus = theta(k) - moved(k);
  if (!field(moved, &minus)) return false;
  *column = (plus - minus) / (h_plus + h_minus);
  return true;
}

}  // namespace quasiroll::internal
