// Initial consistent configuration and the validity checks of the
// single-point contact model (model.md §3).
//
// Given the planar placement (x0, y0, yaw0) and joint angles theta0, solve the
// 15 contact equations for q = (z, roll, pitch, {u_i, v_i, x_gi, y_gi}):
//   (C1) p_W + R_GW c_w(u, v) - c_g(x_g, y_g) = 0            (3 per wheel)
//   (C2) [x_g y_g]^T R_GW n_w(u, v) = 0                      (2 per wheel)
// with R = Rz(yaw0) Ry(pitch) Rx(roll), p = (x0, y0, z) and
// T_GW = (R, p) T_PW(theta0). Damped Newton with variable scaling until
// ||residual||_inf <= 1e-10 (unscaled Levenberg–Marquardt stalls near 1e-4
// on oblique inclines, model.md §3.1). Then psi_i follows
// from model.md §1.6 and ||H(Theta0)||_inf <= 1e-10 is checked.
#pragma once

#include <array>
#include <stdexcept>
#include <string>

#include "quasiroll/core/kinematics.h"

namespace quasiroll {

// The scene describes a geometry for which no valid initial contact exists.
class GeometryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct InitialConfigurationReport {
  double contact_residual = 0.0;  // ||C1, C2||_inf at the solution
  double loop_closure = 0.0;      // ||H(Theta0)||_inf
  int iterations = 0;
};

// Throws GeometryError with a clear message when no consistent contact is
// found or the result is not a valid single-point contact.
Configuration SolveInitialConfiguration(
    const KinematicModel& model, double x0, double y0, double yaw0,
    const std::array<double, 6>& joint_angles,
    InitialConfigurationReport* report = nullptr);

// Convenience: placement and joint angles from the scene.
Configuration SolveInitialConfiguration(
    const KinematicModel& model, const Scene& scene,
    InitialConfigurationReport* report = nullptr);

enum class ContactValidity {
  kValid,
  kTreadAngle,         // |v_w| >= pi/2 - 0.1: off the convex tread
  kCurvature,          // K_w + r_psi K_g r_psi not positive definite
  kSecondContact,      // another torus point lies below the terrain
  kNormalsNotOpposed,  // n_g . n_w >= 0
  kOutsideTerrain,     // contact left a bounded terrain (heightmap)
};
const char* ToString(ContactValidity validity);

struct ValidityReport {
  std::array<ContactValidity, 3> contact = {ContactValidity::kValid,
                                            ContactValidity::kValid,
                                            ContactValidity::kValid};
  bool ok() const;
  std::string Describe() const;  // "" if ok, else e.g. "wheel 2: tread_angle"
};

// Checks 1-2 of model.md §3 always; the sampled second-contact check (3) only
// when `check_second_contact` (it costs ~3 x 2000 terrain evaluations).
ValidityReport CheckValidity(const KinematicModel& model,
                             const Configuration& theta,
                             bool check_second_contact);

}  // namespace quasiroll
