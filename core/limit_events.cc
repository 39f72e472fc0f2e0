#include "quasiroll/core/limit_events.h"

#include <cmath>
#include <limits>

#include "quasiroll/core/surface_forms.h"

namespace quasiroll {

namespace {
constexpr double kTreadMargin = 0.1;              // epsilon_v of model.md §3.2
constexpr double kSecondContactTolerance = 1e-9;  // [m], as CheckValidity
constexpr int kGridU = 72, kGridV = 36;           // as CheckValidity

// K = K_w + r_psi K_g r_psi of wheel i (contact assumed inside the terrain).
// From the chain cache when theta's chain is there (an interval's end state:
// no terrain evaluation), else from the two surfaces' forms alone; the same
// operations on the same values either way.
Mat2 RelativeCurvature(const KinematicModel& model, const Configuration& theta,
                       int wheel) {
  ChainState s;
  if (model.CachedChain(theta, wheel, &s))
    return s.wheel.K + s.r_psi * s.ground.K * s.r_psi;
  const int e = ConfigIndex::Eta(wheel);
  const RobotGeometry& g = model.geometry();
  const SurfaceForms w =
      TorusForms(g.major_radius, g.tube_radius, theta(e), theta(e + 1));
  const double xg = theta(e + 2), yg = theta(e + 3);
  const SurfaceForms t =
      TerrainForms(model.terrain().EvaluateSecondOrder(xg, yg), xg, yg);
  const Mat2 r = ContactRotation2(theta(e + 4));
  return w.K + r * t.K * r;
}

double SmallestEigenvalue(const Mat2& k) {
  const double a = k(0, 0), c = k(1, 1);
  const double b = 0.5 * (k(0, 1) + k(1, 0));
  return 0.5 * (a + c) - std::hypot(0.5 * (a - c), b);
}
}  // namespace

double RelativeCurvatureMargin(const KinematicModel& model,
                               const Configuration& theta, int wheel) {
  const int e = ConfigIndex::Eta(wheel);
  if (!model.terrain().Contains(theta(e + 2), theta(e + 3)))
    return LimitIndicators::kNaN;
  return SmallestEigenvalue(RelativeCurvature(model, theta, wheel));
}

double SecondContactClearance(const KinematicModel& model,
                              const Configuration& theta, int wheel) {
  const int e = ConfigIndex::Eta(wheel);
  const RobotGeometry& g = model.geometry();
  const Terrain& terrain = model.terrain();
  const double xg = theta(e + 2), yg = theta(e + 3);
  // Wheel pose from the contact coordinates (model.md §1.6), as
  // KinematicModel::EvaluateChain computes it.
  const SurfaceForms w =
      TorusForms(g.major_radius, g.tube_radius, theta(e), theta(e + 1));
  const SurfaceForms t =
      TerrainForms(terrain.EvaluateSecondOrder(xg, yg), xg, yg);
  const Mat3 R_GW =
      t.frame * ContactRotation(theta(e + 4)) * w.frame.transpose();
  const Vec3 p_W = t.point - R_GW * w.point;
  double worst = std::numeric_limits<double>::infinity();
  for (int a = 0; a < kGridU; ++a) {
    const double u = 2 * M_PI * a / kGridU;
    for (int b = 0; b < kGridV; ++b) {
      const double v = -M_PI + 2 * M_PI * b / kGridV;
      const double rr = g.major_radius + g.tube_radius * std::cos(v);
      const Vec3 pt = p_W + R_GW * Vec3(rr * std::cos(u), rr * std::sin(u),
                                        g.tube_radius * std::sin(v));
      if (!terrain.Contains(pt.x(), pt.y())) continue;
      worst = std::fmin(worst, pt.z() - terrain.Height(pt.x(), pt.y()));
    }
  }
  return kSecondContactTolerance + worst;
}

bool RelativeCurvatureCertain(const KinematicModel& model,
                              const Configuration& theta, int wheel) {
  const double bound = model.terrain().HessianNormBound();
  if (!(bound < std::numeric_limits<double>::infinity())) return false;
  const RobotGeometry& g = model.geometry();
  const Vec2 k_w =
      TorusCurvatures(g.major_radius, g.tube_radius,
                      std::cos(theta(ConfigIndex::Eta(wheel) + 1)));
  return k_w.minCoeff() > bound * (1.0 + 1e-9);
}

void EvaluateLimitIndicators(const KinematicModel& model,
                             const Configuration& theta, bool second_contact,
                             LimitIndicators* out, IndicatorDetail detail) {
  out->violated = "";
  out->wheel = -1;
  auto flag = [out](const char* limit, int wheel) {
    if (out->ok()) {
      out->violated = limit;
      out->wheel = wheel;
    }
  };
  for (int i = 0; i < 3; ++i) {
    const int e = ConfigIndex::Eta(i);
    out->tread_angle[i] = M_PI / 2 - kTreadMargin - std::abs(theta(e + 1));
    out->second_contact[i] = LimitIndicators::kNaN;
    if (!model.terrain().Contains(theta(e + 2), theta(e + 3))) {
      out->relative_curvature[i] = LimitIndicators::kNaN;
      flag("outside_terrain", i);
      continue;
    }
    // The tests of CheckValidity (core/initial_configuration.cc), so that a
    // located state fails the quasi-static solve's validity check too.
    bool curvature_ok = true;  // certain, or K_w + r K_g r is positive definite
    out->relative_curvature[i] = LimitIndicators::kNaN;
    if (detail == IndicatorDetail::kValues ||
        !RelativeCurvatureCertain(model, theta, i)) {
      const Mat2 k = RelativeCurvature(model, theta, i);
      out->relative_curvature[i] = SmallestEigenvalue(k);
      curvature_ok = k(0, 0) > 0 && k.determinant() > 0;
    }
    if (!(out->tread_angle[i] > 0)) {
      flag("tread_angle", i);
    } else if (!curvature_ok) {
      flag("relative_curvature", i);
    }
    if (second_contact) {
      out->second_contact[i] = SecondContactClearance(model, theta, i);
      if (out->second_contact[i] < 0) flag("second_contact", i);
    }
  }
}

Configuration HermiteState(const Configuration& theta0, const Configuration& f0,
                           const Configuration& theta1, const Configuration& f1,
                           double h, double s) {
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s,
               h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  return h00 * theta0 + (h10 * h) * f0 + h01 * theta1 + (h11 * h) * f1;
}

}  // namespace quasiroll
