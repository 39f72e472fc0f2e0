// Contact geometry and kinematics against finite differences and analytic
// values (model.md §1–§6, oracle O7).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/terrains.h"

namespace quasiroll {
namespace {

// A rough terrain with h_x h_y != 0 almost everywhere (the R1 bumps near the
// start plus one strong bump), so that non-orthogonality of the graph chart
// matters in every test that uses it.
std::shared_ptr<const Terrain> RoughTerrain() {
  std::vector<GaussianBump> bumps = {{0.0231, 0.2323, -0.1855, 0.3764},
                                     {0.0369, 0.0122, 0.7951, 0.3896},
                                     {-0.0237, -0.1266, 0.7844, 0.4492},
                                     {0.0376, 0.9101, -0.4398, 0.3412},
                                     {0.03, 0.3, 0.25, 0.25}};
  return std::make_shared<GaussianTerrain>(bumps);
}

KinematicModel RoughModel() {
  return KinematicModel(RobotGeometry{}, RoughTerrain());
}

// Central difference of a vector function; truncation error ~ h^2 f'''/6,
// round-off ~ eps |f| / h: with h = 1e-6 both are ~1e-10 for O(1..100)
// derivatives, hence the 1e-7 tolerances below (1000x margin).
template <typename F>
Eigen::VectorXd CentralDiff(F f, double h) {
  return (f(h) - f(-h)) / (2 * h);
}

// The forms f at a chart point against central differences (h = 1e-6) of
// the chart c(du, dv) -> SurfaceForms there: A = e^T dc, K = e^T dn A^{-1}
// (to k_tol), tau = e_2^T dx (dx: derivative of the first frame axis),
// det(frame) = 1. Returns dc for further checks.
template <typename Chart>
Eigen::Matrix<double, 3, 2> ExpectFormsMatchDifferences(const SurfaceForms& f,
                                                        Chart c, double k_tol) {
  const double h = 1e-6;
  Eigen::Matrix<double, 3, 2> dc, dn, dx;
  dc.col(0) = (c(h, 0).point - c(-h, 0).point) / (2 * h);
  dc.col(1) = (c(0, h).point - c(0, -h).point) / (2 * h);
  dn.col(0) = (c(h, 0).frame.col(2) - c(-h, 0).frame.col(2)) / (2 * h);
  dn.col(1) = (c(0, h).frame.col(2) - c(0, -h).frame.col(2)) / (2 * h);
  dx.col(0) = (c(h, 0).frame.col(0) - c(-h, 0).frame.col(0)) / (2 * h);
  dx.col(1) = (c(0, h).frame.col(0) - c(0, -h).frame.col(0)) / (2 * h);
  const Eigen::Matrix<double, 3, 2> e = f.frame.leftCols<2>();
  EXPECT_LT((f.A - e.transpose() * dc).norm(), 1e-8);
  EXPECT_LT((f.K - e.transpose() * dn * f.A.inverse()).norm(), k_tol);
  EXPECT_LT((f.tau - f.frame.col(1).transpose() * dx).norm(), 1e-8);
  EXPECT_NEAR(f.frame.determinant(), 1.0, 1e-14);
  return dc;
}

TEST(SurfaceForms, TorusFormsMatchDefinitions) {
  const double R = 0.08, r = 0.02;
  for (double u : {0.3, 1.7, -2.5}) {
    for (double v : {0.0, 0.4, -0.9}) {
      const SurfaceForms f = TorusForms(R, r, u, v);
      const Eigen::Matrix<double, 3, 2> dc = ExpectFormsMatchDifferences(
          f,
          [&](double du, double dv) {
            return TorusForms(R, r, u + du, v + dv);
          },
          1e-6);
      EXPECT_LT(
          (f.frame.col(2) - dc.col(0).cross(dc.col(1)).normalized()).norm(),
          1e-8);
    }
  }
}

TEST(SurfaceForms, TerrainFormsMatchDefinitionsOnNonOrthogonalChart) {
  auto terrain = RoughTerrain();
  for (const Vec2& pt : {Vec2(0.1, 0.05), Vec2(0.35, 0.3), Vec2(-0.2, 0.6)}) {
    const TerrainJet jet = terrain->Evaluate(pt.x(), pt.y());
    ASSERT_GT(std::abs(jet.hx * jet.hy), 1e-6)
        << "chart must be non-orthogonal here";
    const SurfaceForms f = TerrainForms(jet, pt.x(), pt.y());
    ExpectFormsMatchDifferences(
        f,
        [&](double dx, double dy) {
          return TerrainForms(terrain->Evaluate(pt.x() + dx, pt.y() + dy),
                              pt.x() + dx, pt.y() + dy);
        },
        1e-7);
    EXPECT_LT((f.K - f.K.transpose()).norm(), 1e-14);
    EXPECT_LT(std::abs(f.frame.col(0).dot(f.frame.col(1))), 1e-15);
  }
}

// World velocity p' and angular velocity vee(R' R(0)^T) of a pose path
// t -> (R(t), p(t)) at t = 0 by central differences (h = 1e-6); r0 = R(0).
struct WorldTwist {
  Vec3 v, w;
};
template <typename PosePath>
WorldTwist CentralDiffTwist(PosePath pose, const Mat3& r0) {
  const double h = 1e-6;
  Mat3 Rp, Rm;
  Vec3 pp, pm;
  pose(h, &Rp, &pp);
  pose(-h, &Rm, &pm);
  return {(pp - pm) / (2 * h), Vee((Rp - Rm) / (2 * h) * r0.transpose())};
}

Configuration RoughStart(const KinematicModel& model) {
  return SolveInitialConfiguration(model, 0.05, 0.1, 0.3,
                                   {0.2, 0.4, 0.05, -0.3, -0.08, 1.1});
}

// Chain i's state at theta into *s, and its contact velocity map L_i.
ContactVelocityMap ChainMap(const KinematicModel& model,
                            const Configuration& theta, int i, ChainState* s) {
  model.EvaluateChain(theta, i, s);
  ContactVelocityMap L;
  model.ContactVelocities(*s, i, &L);
  return L;
}

TEST(Kinematics, LoopClosureJacobianMatchesCentralDifferences) {
  const KinematicModel model = RoughModel();
  Configuration theta = RoughStart(model);
  // Also off the manifold H = 0: J is exact everywhere (model.md §6).
  Configuration off = theta;
  for (int i = 0; i < kConfigSize; ++i)
    off(i) += 1e-3 * std::sin(3.0 * i + 1.0);
  for (const Configuration& q : {theta, off}) {
    LoopClosureJacobian jac;
    model.ConstraintJacobian(q, &jac);
    for (int c = 0; c < kConfigSize; ++c) {
      auto h_at = [&](double d) {
        Configuration qq = q;
        qq(c) += d;
        LoopClosure h;
        model.Constraints(qq, &h);
        return Eigen::VectorXd(h);
      };
      const Eigen::VectorXd fd = CentralDiff(h_at, 1e-6);
      EXPECT_LT((jac.col(c) - fd).lpNorm<Eigen::Infinity>(), 1e-7)
          << "column " << c;
    }
  }
}

// Wheel material point and wheel orientation under a platform twist and joint
// motion, by forward kinematics only (independent of L_i).
TEST(Kinematics, ContactVelocityMapMatchesFiniteDifferencedMotion) {
  const KinematicModel model = RoughModel();
  const Configuration theta = RoughStart(model);
  Vec12 w;
  w << 0.05, -0.01, 0.02, 0.03, -0.02, 0.04, 0.1, 0.6, -0.2, 0.5, 0.3, 0.7;
  for (int i = 0; i < 3; ++i) {
    ChainState s;
    const ContactVelocityMap L = ChainMap(model, theta, i, &s);
    const Vec6 twist = L * w;
    // Material point of the wheel at the contact, fixed in {W}.
    Mat3 R_PW0;
    Vec3 p_PW0;
    std::array<Vec3, 2> ax, pt;
    const int j = ConfigIndex::kTheta + 2 * i;
    model.Mount(i, theta(j), theta(j + 1), &R_PW0, &p_PW0, &ax, &pt);
    const Vec3 local =
        R_PW0.transpose() * (s.R.transpose() * (s.p_c - s.p) - p_PW0);
    auto pose = [&](double t, Mat3* R_GW, Vec3* point) {
      const Vec3 wb = w.segment<3>(3) * t;
      const Mat3 R =
          s.R * Eigen::AngleAxisd(
                    wb.norm(), wb.norm() > 0 ? wb.normalized() : Vec3::UnitX())
                    .toRotationMatrix();
      const Vec3 p =
          s.p + s.R * w.head<3>() * t;  // body twist held, first order exact
      Mat3 R_PW;
      Vec3 p_PW;
      model.Mount(i, theta(j) + w(6 + 2 * i) * t,
                  theta(j + 1) + w(7 + 2 * i) * t, &R_PW, &p_PW, &ax, &pt);
      *R_GW = R * R_PW;
      *point = p + R * (p_PW + R_PW * local);
    };
    const WorldTwist fd = CentralDiffTwist(pose, s.R_GW);
    EXPECT_LT((twist.head<3>() - s.R_GCW.transpose() * fd.v).norm(), 1e-8)
        << "wheel " << i;
    EXPECT_LT((twist.tail<3>() - s.R_GCW.transpose() * fd.w).norm(), 1e-8)
        << "wheel " << i;
  }
}

// The right-hand side's kernel ContactTwist equals L_i w to round-off
// (a few ulps of the largest term, |w| ~ 1 here) for every chain, on random
// twists and joint rates.
TEST(Kinematics, ContactTwistEqualsTheMapTimesTheTwist) {
  const KinematicModel model = RoughModel();
  const Configuration theta = RoughStart(model);
  std::srand(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec12 w = Vec12::Random();
    for (int i = 0; i < 3; ++i) {
      ChainState s;
      const ContactVelocityMap L = ChainMap(model, theta, i, &s);
      const Vec6 by_map = L * w;
      EXPECT_LT(
          (model.ContactTwist(s, i, w) - by_map).lpNorm<Eigen::Infinity>(),
          1e-15 * (1 + by_map.lpNorm<Eigen::Infinity>()))
          << "wheel " << i << " trial " << trial;
    }
  }
}

// O7: Montana o L_i equals the inverse chain-twist map, and chain forward
// kinematics differentiated along the Montana rates reproduces the platform
// twist (independent of the inverse map's algebra).
TEST(Kinematics, MontanaIsConsistentWithChainForwardKinematics) {
  const KinematicModel model = RoughModel();
  const Configuration theta = RoughStart(model);
  Vec12 w;
  w << 0.06, 0.01, -0.01, 0.02, 0.03, -0.05, 0.2, 0.6, 0.1, 0.6, -0.1, 0.6;
  for (int i = 0; i < 3; ++i) {
    ChainState s;
    const ContactVelocityMap L = ChainMap(model, theta, i, &s);
    // Make contact persist for this chain: remove the v_z component along the
    // platform z velocity direction of row 2 (least-norm correction).
    Vec12 wi = w;
    const Eigen::Matrix<double, 1, 12> row = L.row(2);
    wi -= row.transpose() * (row * wi) / row.squaredNorm();
    const Vec6 twist = L * wi;
    ASSERT_LT(std::abs(twist(2)), 1e-15);
    EtaRates rates;
    ASSERT_TRUE(model.ContactRates(s, twist, &rates));
    const int j = 2 * i;
    const Vec6 vp = model.PlatformVelocity(s, rates, wi(6 + j), wi(7 + j));
    Vec6 expected;
    expected << s.R * wi.head<3>(), s.R * wi.segment<3>(3);
    EXPECT_LT((vp - expected).norm(), 1e-13) << "wheel " << i;
    // Forward kinematics of chain i along (eta rates, joint rates).
    auto chain_pose = [&](double t, Mat3* R, Vec3* p) {
      Configuration q = theta;
      q.segment<5>(ConfigIndex::Eta(i)) += t * rates;
      q(ConfigIndex::kTheta + j) += t * wi(6 + j);
      q(ConfigIndex::kTheta + j + 1) += t * wi(7 + j);
      ChainState cs;
      model.EvaluateChain(q, i, &cs);
      *R = cs.R;
      *p = cs.p;
    };
    const WorldTwist fd = CentralDiffTwist(chain_pose, s.R);
    EXPECT_LT((fd.v - expected.head<3>()).norm(), 1e-8) << "wheel " << i;
    EXPECT_LT((fd.w - expected.tail<3>()).norm(), 1e-8) << "wheel " << i;
  }
}

// O7, last item: straight drive on a plane whose gradient is oblique to the
// heading. With the general-chart forms the contact points travel exactly
// rho * alphadot * t; Montana's orthogonal-chart metric diag(|c_x|, |c_y|)
// gets the contact-coordinate rates wrong where h_x h_y != 0.
TEST(Kinematics, ObliqueInclineStraightDriveCoversRhoAlphaDotT) {
  const double beta = 12.0 * M_PI / 180, gamma = 35.0 * M_PI / 180;
  const double yaw = 57.0 * M_PI / 180;
  auto terrain = std::make_shared<InclineTerrain>(beta, gamma);
  const KinematicModel model(RobotGeometry{}, terrain);
  const Configuration theta0 =
      SolveInitialConfiguration(model, 0, 0, yaw, {0, 0, 0, 0, 0, 0});
  const double rho = model.geometry().rho(), rate = 0.6,
               t_end = 0.3 / (rho * rate);
  Vec12 w = Vec12::Zero();
  w(0) = rho * rate;
  w(7) = w(9) = w(11) = rate;

  // Orthogonal-chart variant: only the metric differs on a plane (K_g = 0,
  // tau_g = 0), so x_g, y_g rates are A_g^{-1} b versus M^{-1} b.
  auto rhs = [&](const Configuration& q, bool orthogonal, Configuration* qd) {
    ASSERT_TRUE(model.Rhs(q, w, qd));
    if (!orthogonal) return;
    for (int i = 0; i < 3; ++i) {
      ChainState s;
      model.EvaluateChain(q, i, &s);
      const Vec2 b =
          s.r_psi * (s.ground.A * qd->segment<2>(ConfigIndex::Xg(i)));
      const TerrainJet jet =
          terrain->Evaluate(q(ConfigIndex::Xg(i)), q(ConfigIndex::Yg(i)));
      const Vec2 metric(std::hypot(1.0, jet.hx), std::hypot(1.0, jet.hy));
      qd->segment<2>(ConfigIndex::Xg(i)) = (s.r_psi * b).cwiseQuotient(metric);
    }
  };
  for (bool orthogonal : {false, true}) {
    Configuration q = theta0, k1, k2, k3, k4;
    const int n = 100;
    const double h = t_end / n;
    for (int s = 0; s < n; ++s) {
      rhs(q, orthogonal, &k1);
      rhs(q + 0.5 * h * k1, orthogonal, &k2);
      rhs(q + 0.5 * h * k2, orthogonal, &k3);
      rhs(q + h * k3, orthogonal, &k4);
      q += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    for (int i = 0; i < 3; ++i) {
      auto point = [&](const Configuration& c) {
        const double x = c(ConfigIndex::Xg(i)), y = c(ConfigIndex::Yg(i));
        return Vec3(x, y, terrain->Height(x, y));
      };
      const double dist = (point(q) - point(theta0)).norm();
      if (!orthogonal) {
        // Exact motion is a straight line at constant speed: RK4 error is at
        // round-off level; 1e-12 m leaves room for 100 steps of round-off.
        EXPECT_NEAR(dist, 0.3, 1e-12) << "wheel " << i;
      } else {
        // About 1.7 % (5 mm) off for this geometry (model.md §5).
        EXPECT_GT(std::abs(dist - 0.3), 1e-3) << "wheel " << i;
      }
    }
    if (!orthogonal) {
      LoopClosure h_end;
      model.Constraints(q, &h_end);
      EXPECT_LT(h_end.lpNorm<Eigen::Infinity>(), 1e-12);
    }
  }
}

// KinematicModel::RhsStateDerivative differences one chain's rates per
// column: the numbers of central differences of the whole Rhs at the same
// step (its divisor, h_+ + h_-, may differ from (theta_k + h) - (theta_k - h)
// in the last bit), and F is chain-local, so everything outside chain i's
// rows is exactly zero in both. RhsTwistDerivative w is F(theta, w).
TEST(Kinematics, RhsDerivativesAreTheWholeFieldsDifferences) {
  const KinematicModel model = RoughModel();
  const Configuration theta = RoughStart(model);
  Vec12 w;
  w << 0.05, -0.01, 0.02, 0.03, -0.02, 0.04, 0.1, 0.6, -0.2, 0.5, 0.3, 0.7;
  RhsStateJacobian dfdtheta, whole;
  ASSERT_TRUE(model.RhsStateDerivative(theta, w, &dfdtheta));
  const double root = std::cbrt(std::numeric_limits<double>::epsilon());
  for (int k = 0; k < kConfigSize; ++k) {
    Configuration plus = theta, minus = theta, f_plus, f_minus;
    plus(k) += root * std::max(1.0, std::abs(theta(k)));
    minus(k) -= root * std::max(1.0, std::abs(theta(k)));
    ASSERT_TRUE(model.Rhs(plus, w, &f_plus) && model.Rhs(minus, w, &f_minus));
    whole.col(k) = (f_plus - f_minus) / (plus(k) - minus(k));
  }
  EXPECT_LE((dfdtheta - whole).cwiseAbs().maxCoeff(),
            1e-14 * whole.cwiseAbs().maxCoeff());
  for (int k = 0; k < kConfigSize; ++k) {
    const int chain = k < ConfigIndex::kTheta ? k / 5 : (k - 15) / 2;
    for (int r = 0; r < kConfigSize; ++r) {
      if (r >= ConfigIndex::Eta(chain) && r < ConfigIndex::Eta(chain) + 5)
        continue;
      EXPECT_EQ(whole(r, k), 0.0) << r << ", " << k;
      EXPECT_EQ(dfdtheta(r, k), 0.0) << r << ", " << k;
    }
  }
  RhsTwistJacobian dfdw;
  Configuration f;
  ASSERT_TRUE(model.RhsTwistDerivative(theta, &dfdw));
  ASSERT_TRUE(model.Rhs(theta, w, &f));
  EXPECT_LE((dfdw * w - f).lpNorm<Eigen::Infinity>(),
            1e-13 * f.lpNorm<Eigen::Infinity>());
}

TEST(InitialConfiguration, FlatGroundGivesDesignHeight) {
  const KinematicModel model(RobotGeometry{},
                             std::make_shared<PlaneTerrain>(0.0));
  InitialConfigurationReport report;
  const Configuration theta =
      SolveInitialConfiguration(model, 0, 0, 0, {0, 0, 0, 0, 0, 0}, &report);
  Mat3 R;
  Vec3 p;
  model.PlatformPose(theta, &R, &p);
  EXPECT_NEAR(p.z(), 0.15, 1e-12);  // h_c = z_h + rho (model.md §1.5)
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_LT((R - Mat3::Identity()).norm(), 1e-12);
  EXPECT_LE(report.loop_closure, 1e-10);
  const Vec3 expected[3] = {{0.25, 0, 0}, {-0.25, 0.2, 0}, {-0.25, -0.2, 0}};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(theta(ConfigIndex::Xg(i)), expected[i].x(), 1e-12);
    EXPECT_NEAR(theta(ConfigIndex::Yg(i)), expected[i].y(), 1e-12);
    EXPECT_NEAR(theta(ConfigIndex::V(i)), 0.0, 1e-12);  // tread crown
  }
}

// Platform pose (R, p) of the initial configuration at (x0, y0, yaw0) with
// zero joint angles on an incline of slope beta ascending towards `ascent`.
void InclineStart(double beta, double ascent, double x0, double y0, double yaw0,
                  Mat3* R, Vec3* p) {
  const KinematicModel model(RobotGeometry{},
                             std::make_shared<InclineTerrain>(beta, ascent));
  const Configuration theta =
      SolveInitialConfiguration(model, x0, y0, yaw0, {0, 0, 0, 0, 0, 0});
  model.PlatformPose(theta, R, p);
}

TEST(InitialConfiguration, InclineGivesSlopePitchAndRoll) {
  const double beta = 10.0 * M_PI / 180;
  Mat3 R;
  Vec3 p;
  // Straight uphill: nose up by beta (pitch = -beta with R = Rz Ry Rx).
  {
    InclineStart(beta, 0.0, 0, 0, 0, &R, &p);
    const Vec3 rpy = RpyFromRotation(R);
    EXPECT_NEAR(rpy(0), 0.0, 1e-10);
    EXPECT_NEAR(rpy(1), -beta, 1e-10);
    // COM sits h_c above the plane along its normal: z = h_c / cos(beta).
    EXPECT_NEAR(p.z(), 0.15 / std::cos(beta), 1e-10);
  }
  // Across the slope (heading +x, ascent along +y): roll = -beta (left up).
  {
    InclineStart(beta, M_PI / 2, 0, 0, 0, &R, &p);
    const Vec3 rpy = RpyFromRotation(R);
    EXPECT_NEAR(rpy(0), beta, 1e-10);
    EXPECT_NEAR(rpy(1), 0.0, 1e-10);
  }
  // Oblique: the platform z axis is the plane normal.
  {
    InclineStart(beta, 0.7, 0.1, -0.2, 1.9, &R, &p);
    const TerrainJet jet = InclineTerrain(beta, 0.7).Evaluate(0, 0);
    const Vec3 n = Vec3(-jet.hx, -jet.hy, 1).normalized();
    EXPECT_LT((R.col(2) - n).norm(), 1e-10);
  }
}

TEST(InitialConfiguration, RoughStartIsConsistent) {
  const KinematicModel model = RoughModel();
  InitialConfigurationReport report;
  const Configuration theta = SolveInitialConfiguration(
      model, 0.05, 0.1, 0.3, {0.2, 0.4, 0.05, -0.3, -0.08, 1.1}, &report);
  EXPECT_LE(report.contact_residual, 1e-10);
  EXPECT_LE(report.loop_closure, 1e-10);
  EXPECT_TRUE(CheckValidity(model, theta, true).ok());
}

TEST(InitialConfiguration, PaperSceneIsConsistent) {
  const Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  const KinematicModel model(scene.geometry, scene.terrain);
  InitialConfigurationReport report;
  const Configuration theta = SolveInitialConfiguration(model, scene, &report);
  LoopClosure h;
  model.Constraints(theta, &h);
  EXPECT_LE(h.lpNorm<Eigen::Infinity>(), 1e-10);
  EXPECT_TRUE(CheckValidity(model, theta, true).ok());
}

TEST(InitialConfiguration, ImpossibleGeometryIsAClearError) {
  // A pit narrower than the wheel (bottom curvature 500 1/m > 50 1/m): contact
  // search fails or the contact is invalid, reported as GeometryError, never a
  // crash.
  auto terrain = std::make_shared<GaussianTerrain>(
      std::vector<GaussianBump>{{-0.05, 0.25, 0.0, 0.01}});
  const KinematicModel model(RobotGeometry{}, terrain);
  EXPECT_THROW(SolveInitialConfiguration(model, 0, 0, 0, {0, 0, 0, 0, 0, 0}),
               GeometryError);
}

}  // namespace
}  // namespace quasiroll
