#include "quasiroll/core/initial_configuration.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

namespace quasiroll {

namespace {

using Vec15 = Eigen::Matrix<double, 15, 1>;
using Mat15 = Eigen::Matrix<double, 15, 15>;

constexpr double kResidualTolerance = 1e-10;
constexpr double kTreadMargin = 0.1;  // epsilon_v of model.md §3

struct Placement {
  double x0, y0, yaw0;
  std::array<double, 6> joints;
};

// Wheel pose in world for platform pose (R, p) and the scene's joint angles.
void WheelPose(const KinematicModel& model, const Placement& pl, const Mat3& R,
               const Vec3& p, int chain, Mat3* R_GW, Vec3* p_W) {
  Mat3 R_PW;
  Vec3 p_PW;
  std::array<Vec3, 2> axes, points;
  model.Mount(chain, pl.joints[2 * chain], pl.joints[2 * chain + 1], &R_PW,
              &p_PW, &axes, &points);
  *R_GW = R * R_PW;
  *p_W = p + R * p_PW;
}

// Wheel i at the contact variables q: its pose in world (platform pose from
// q(0..2)) and the wheel and ground forms at its contact coordinates
// q(k..k+3), k = 3 + 4 i. The ground point must be in the terrain's domain.
struct WheelContact {
  Mat3 R_GW;
  Vec3 p_W;
  SurfaceForms wheel, ground;
};
WheelContact EvaluateWheelContact(const KinematicModel& model,
                                  const Placement& pl, const Vec15& q, int i) {
  const Mat3 R = RotationFromRpy(q(1), q(2), pl.yaw0);
  const Vec3 p(pl.x0, pl.y0, q(0));
  const RobotGeometry& g = model.geometry();
  const int k = 3 + 4 * i;
  WheelContact c;
  WheelPose(model, pl, R, p, i, &c.R_GW, &c.p_W);
  c.wheel = TorusForms(g.major_radius, g.tube_radius, q(k), q(k + 1));
  c.ground = TerrainForms(model.terrain().Evaluate(q(k + 2), q(k + 3)),
                          q(k + 2), q(k + 3));
  return c;
}

// Residual of (C1), (C2) for all three wheels; false if a contact point left
// the terrain's domain.
bool ContactResidual(const KinematicModel& model, const Placement& pl,
                     const Vec15& q, Vec15* res) {
  for (int i = 0; i < 3; ++i) {
    const int k = 3 + 4 * i;
    if (!model.terrain().Contains(q(k + 2), q(k + 3))) return false;
    const WheelContact c = EvaluateWheelContact(model, pl, q, i);
    res->segment<3>(5 * i) = c.p_W + c.R_GW * c.wheel.point - c.ground.point;
    const Vec3 n_w = c.R_GW * c.wheel.frame.col(2);
    res->segment<2>(5 * i + 3) = c.ground.frame.leftCols<2>().transpose() * n_w;
  }
  return res->allFinite();
}

// Phases of SolveInitialConfiguration, in order. Each throws GeometryError
// with the message the caller would have seen before the split.

// A placement off the terrain has no height to start from.
void RequirePlacementOnTerrain(const Terrain& terrain, double x0, double y0) {
  if (!terrain.Contains(x0, y0)) {
    std::ostringstream os;
    os << "initial: placement (" << x0 << ", " << y0
       << ") is outside the terrain (" << terrain.Describe() << ")";
    throw GeometryError(os.str());
  }
}

// Initial guess of model.md §3: a level platform at nominal height above the
// terrain at (x0, y0), each wheel touching with its lowest point.
Vec15 InitialGuess(const KinematicModel& model, const Placement& pl) {
  const RobotGeometry& g = model.geometry();
  Vec15 q;
  q(0) = model.terrain().Height(pl.x0, pl.y0) + g.z_h + g.rho();
  q(1) = q(2) = 0.0;
  const Mat3 R = RotationFromRpy(0.0, 0.0, pl.yaw0);
  const Vec3 p(pl.x0, pl.y0, q(0));
  for (int i = 0; i < 3; ++i) {
    Mat3 R_GW;
    Vec3 p_W;
    WheelPose(model, pl, R, p, i, &R_GW, &p_W);
    const Vec3 d = R_GW.transpose() * Vec3(0, 0, -1);
    const double u = std::atan2(d.y(), d.x());
    const double v = std::asin(std::clamp(d.z(), -1.0, 1.0));
    const Vec3 c =
        p_W + R_GW * TorusForms(g.major_radius, g.tube_radius, u, v).point;
    q.segment<4>(3 + 4 * i) << u, v, c.x(), c.y();
  }
  return q;
}

// Variable scales: lengths in units of rho, tread angle v in units of
// r/rho so that a unit scaled step moves the contact by about rho.
Vec15 VariableScales(const RobotGeometry& g) {
  Vec15 scale;
  scale(0) = g.rho();
  scale(1) = scale(2) = 1.0;
  for (int i = 0; i < 3; ++i) {
    scale.segment<4>(3 + 4 * i) << 1.0, 1.0, g.rho(), g.rho();
  }
  return scale;
}

// Central-difference Jacobian in scaled variables (15 x 15, cheap; error
// O(h^2) only slows convergence, the residual itself is exact).
Mat15 ScaledContactJacobian(const KinematicModel& model, const Placement& pl,
                            const Vec15& q, const Vec15& scale) {
  Mat15 jac;
  for (int c = 0; c < 15; ++c) {
    const double h = 1e-6 * scale(c);
    Vec15 qp = q, qm = q, rp, rm;
    qp(c) += h;
    qm(c) -= h;
    if (!ContactResidual(model, pl, qp, &rp) ||
        !ContactResidual(model, pl, qm, &rm))
      throw GeometryError("initial: contact search left the terrain domain");
    jac.col(c) = (rp - rm) / (2 * h) * scale(c);
  }
  return jac;
}

// Damped Newton on the contact residual from q: backtracking line search on
// ||res||_2, stops at round-off level or on a singular Jacobian. Updates q and
// res; returns the number of Newton iterations taken.
int SolveContacts(const KinematicModel& model, const Placement& pl,
                  const Vec15& scale, Vec15* q, Vec15* res) {
  Vec15 trial_res, q_trial;
  if (!ContactResidual(model, pl, *q, res))
    throw GeometryError(
        "initial: a wheel's first contact guess is outside the terrain");
  int it = 0;
  const int kMaxIterations = 60;
  for (; it < kMaxIterations &&
         res->lpNorm<Eigen::Infinity>() > 0.01 * kResidualTolerance;
       ++it) {
    const Mat15 jac = ScaledContactJacobian(model, pl, *q, scale);
    Eigen::FullPivLU<Mat15> lu(jac);
    if (lu.rank() < 15) break;
    const Vec15 step = -(lu.solve(*res)).cwiseProduct(scale);
    double t = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 30; ++ls, t *= 0.5) {
      q_trial = *q + t * step;
      if (ContactResidual(model, pl, q_trial, &trial_res) &&
          trial_res.norm() < (1.0 - 1e-4 * t) * res->norm()) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      // Accept a full step once residual is at round-off level.
      if (res->lpNorm<Eigen::Infinity>() <= kResidualTolerance) break;
      throw GeometryError(
          "initial: contact search stalled (no descent) at residual " +
          std::to_string(res->lpNorm<Eigen::Infinity>()));
    }
    *q = q_trial;
    *res = trial_res;
  }
  return it;
}

// Assemble Theta0 from the solved contact variables: contact angles psi from
// model.md §1.6. A wheel whose normal points along the ground normal touches
// with its inner side, which the contact model does not describe.
Configuration AssembleConfiguration(const KinematicModel& model,
                                    const Placement& pl, const Vec15& q) {
  Configuration theta;
  for (int i = 0; i < 3; ++i) {
    const int k = 3 + 4 * i;
    const WheelContact c = EvaluateWheelContact(model, pl, q, i);
    const SurfaceForms& ground = c.ground;
    const Vec3 x_w = c.R_GW * c.wheel.frame.col(0);
    const Vec3 n_w = c.R_GW * c.wheel.frame.col(2);
    if (!(n_w.dot(ground.frame.col(2)) < 0)) {
      throw GeometryError("initial: wheel " + std::to_string(i + 1) +
                          " touches the terrain with its inner side "
                          "(normals not opposed)");
    }
    const double psi =
        std::atan2(-ground.frame.col(1).dot(x_w), ground.frame.col(0).dot(x_w));
    theta.segment<5>(ConfigIndex::Eta(i)) << q(k), q(k + 1), q(k + 2), q(k + 3),
        psi;
  }
  for (int j = 0; j < 6; ++j) theta(ConfigIndex::kTheta + j) = pl.joints[j];
  return theta;
}

// The contact solve closes the loop by construction; a residual here means
// the model and the contact equations disagree. Returns ||H||_inf.
double CheckLoopClosure(const KinematicModel& model,
                        const Configuration& theta) {
  LoopClosure h;
  model.Constraints(theta, &h);
  const double h_norm = h.lpNorm<Eigen::Infinity>();
  if (!(h_norm <= kResidualTolerance)) {
    std::ostringstream os;
    os << "initial: loop closure ||H||_inf = " << h_norm
       << " > 1e-10 after contact solve (internal inconsistency)";
    throw GeometryError(os.str());
  }
  return h_norm;
}

}  // namespace

Configuration SolveInitialConfiguration(
    const KinematicModel& model, double x0, double y0, double yaw0,
    const std::array<double, 6>& joint_angles,
    InitialConfigurationReport* report) {
  const Placement pl{x0, y0, yaw0, joint_angles};
  RequirePlacementOnTerrain(model.terrain(), x0, y0);

  Vec15 q = InitialGuess(model, pl);
  const Vec15 scale = VariableScales(model.geometry());
  Vec15 res;
  const int it = SolveContacts(model, pl, scale, &q, &res);
  const double residual = res.lpNorm<Eigen::Infinity>();
  if (!(residual <= kResidualTolerance)) {
    std::ostringstream os;
    os << "initial: no consistent contact found for placement (" << x0 << ", "
       << y0 << ", yaw " << yaw0 << "): contact residual " << residual
       << " after " << it << " Newton iterations";
    throw GeometryError(os.str());
  }

  const Configuration theta = AssembleConfiguration(model, pl, q);
  const double h_norm = CheckLoopClosure(model, theta);
  const ValidityReport validity = CheckValidity(model, theta, true);
  if (!validity.ok()) {
    throw GeometryError("initial: invalid single-point contact: " +
                        validity.Describe());
  }
  if (report) {
    report->contact_residual = residual;
    report->loop_closure = h_norm;
    report->iterations = it;
  }
  return theta;
}

Configuration SolveInitialConfiguration(const KinematicModel& model,
                                        const Scene& scene,
                                        InitialConfigurationReport* report) {
  return SolveInitialConfiguration(model, scene.x0, scene.y0, scene.yaw0,
                                   scene.joint_angles, report);
}

const char* ToString(ContactValidity validity) {
  switch (validity) {
    case ContactValidity::kValid:
      return "valid";
    case ContactValidity::kTreadAngle:
      return "tread_angle";
    case ContactValidity::kCurvature:
      return "relative_curvature";
    case ContactValidity::kSecondContact:
      return "second_contact";
    case ContactValidity::kNormalsNotOpposed:
      return "normals_not_opposed";
    case ContactValidity::kOutsideTerrain:
      return "outside_terrain";
  }
  return "unknown";
}

bool ValidityReport::ok() const {
  for (ContactValidity c : contact)
    if (c != ContactValidity::kValid) return false;
  return true;
}

std::string ValidityReport::Describe() const {
  std::string out;
  for (int i = 0; i < 3; ++i) {
    if (contact[i] == ContactValidity::kValid) continue;
    if (!out.empty()) out += "; ";
    out += "wheel " + std::to_string(i + 1) + ": " + ToString(contact[i]);
  }
  return out;
}

ValidityReport CheckValidity(const KinematicModel& model,
                             const Configuration& theta,
                             bool check_second_contact) {
  ValidityReport report;
  const RobotGeometry& g = model.geometry();
  const Terrain& terrain = model.terrain();
  for (int i = 0; i < 3; ++i) {
    const int e = ConfigIndex::Eta(i);
    if (!terrain.Contains(theta(e + 2), theta(e + 3))) {
      report.contact[i] = ContactValidity::kOutsideTerrain;
      continue;
    }
    if (!(std::abs(theta(e + 1)) < M_PI / 2 - kTreadMargin)) {
      report.contact[i] = ContactValidity::kTreadAngle;
      continue;
    }
    ChainState s;
    model.EvaluateChain(theta, i, &s);
    if (!(s.R_GW.col(2).allFinite())) {
      report.contact[i] = ContactValidity::kCurvature;
      continue;
    }
    const Mat2 k = s.wheel.K + s.r_psi * s.ground.K * s.r_psi;
    // Symmetric 2x2 is positive definite iff k00 > 0 and det > 0.
    if (!(k(0, 0) > 0 && k.determinant() > 0)) {
      report.contact[i] = ContactValidity::kCurvature;
      continue;
    }
    if (!check_second_contact) continue;
    // Sample the whole torus (inner side too): every point must lie on or
    // above the terrain. The contact is a strict local minimum of the gap
    // when K > 0, so exact zeros only occur at the contact itself.
    constexpr int kNu = 72, kNv = 36;
    const double tol = 1e-9;
    bool second = false;
    for (int a = 0; a < kNu && !second; ++a) {
      const double u = 2 * M_PI * a / kNu;
      for (int b = 0; b < kNv; ++b) {
        const double v = -M_PI + 2 * M_PI * b / kNv;
        const double rr = g.major_radius + g.tube_radius * std::cos(v);
        const Vec3 local(rr * std::cos(u), rr * std::sin(u),
                         g.tube_radius * std::sin(v));
        const Vec3 pt = s.p_W + s.R_GW * local;
        if (!terrain.Contains(pt.x(), pt.y())) continue;
        if (pt.z() - terrain.Height(pt.x(), pt.y()) < -tol) {
          second = true;
          break;
        }
      }
    }
    if (second) report.contact[i] = ContactValidity::kSecondContact;
  }
  return report;
}

}  // namespace quasiroll
