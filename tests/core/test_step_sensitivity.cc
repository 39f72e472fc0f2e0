// The derivative of one whole interval (core/step_sensitivity.h, model.md
// §7.9) against its independent reference: central differences of
// re-simulated intervals (one-interval Simulator runs from perturbed
// states and parameters), on the paper scene and the incline10 scene, zoh
// and coupled, rk-projection and rk-baumgarte; the value against the
// Simulator's own interval; the projector P against differences of the
// Newton projection; statuses for a one-sided derivative and a failed
// solve; misuse.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/loop_closure_ode.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/step_sensitivity.h"
#include "quasiroll/core/weighted_projection.h"
#include "simulation_support.h"
#include "tests/heap_counter.h"
#include "tests/test_names.h"

namespace quasiroll {
namespace {

using P = SensitivityParameter;

struct Case {
  std::string scene;
  Coupling coupling;
  std::string dae;
  int substeps = 1;  // RK4 steps per interval
};

std::string CaseName(const Case& c) {
  return testing_util::GtestName(
      c.scene + "_" + ToString(c.coupling) + "_" + c.dae +
      (c.substeps > 1 ? "_substeps" + std::to_string(c.substeps) : ""));
}

// gtest's name for a parameter in failure messages and test listings.
void PrintTo(const Case& c, std::ostream* os) { *os << CaseName(c); }

StepSensitivityOptions StepOptions(const Case& c, double dt) {
  StepSensitivityOptions o;
  o.coupling = c.coupling;
  o.dae = c.dae;
  o.dt = dt;
  o.substeps = c.substeps;
  return o;
}

// The simulator's interval: a run of one interval from theta0, located
// events and switches off (the plain integrator interval).
bool Resimulate(const Scene& scene, const Case& c, double dt, int substeps,
                const Configuration& theta0, Configuration* theta1) {
  SimulationOptions o;
  o.nlp = "newton";
  o.dae = c.dae;
  o.coupling = c.coupling;
  o.dt = dt;
  o.t_end = dt;
  o.integrator.step = dt / substeps;
  o.locate_events = false;
  o.locate_switches = false;
  Simulator sim(scene, o);
  const SimulationResult r = sim.Run(theta0);
  if (!r.success() || r.samples.size() != 2) return false;
  *theta1 = r.samples[1].theta;
  return true;
}

// Perturbation k of the 29 parameters, or along a state direction.
Scene Perturbed(Scene scene, int k, double delta) {
  if (k == P::kMu) scene.mu += delta;
  if (k == P::kEpsilon) scene.epsilon += delta;
  if (k >= P::kRates) scene.joint_rates[k - P::kRates] += delta;
  return scene;
}

double Scale(const Scene& scene, int k) {
  if (k == P::kMu) return scene.mu;
  if (k == P::kEpsilon) return scene.epsilon;
  if (k >= P::kRates)
    return std::max(1.0, std::abs(scene.joint_rates[k - P::kRates]));
  return 1.0;
}

class StepSensitivityTest : public ::testing::TestWithParam<Case> {
 protected:
  static void SetUpTestSuite() {
    RegisterBuiltinNlpSolvers();
    RegisterBuiltinIntegrators();
  }
};

constexpr double kDt = 0.05;  // the scenes' hold interval

// The value is the simulator's interval: round-off in zoh (the same
// operations), the quasi-static tolerance in coupled mode (the simulator's
// stage solves are warm-started from the sample's, ours cold at Theta_k).
TEST_P(StepSensitivityTest, ValueIsTheSimulatorsInterval) {
  const Case& c = GetParam();
  const Scene scene = SceneFile(c.scene);
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  for (int substeps : {1, 3}) {
    StepSensitivityOptions o = StepOptions(c, kDt);
    o.substeps = substeps;
    o.derivatives = false;
    StepSensitivity step(model, QuasiStaticParameters::FromScene(scene), o);
    StepSensitivityResult r;
    ASSERT_EQ(step.Compute(theta, &r), StepSensitivityStatus::kOk) << r.message;
    Configuration ref;
    ASSERT_TRUE(Resimulate(scene, c, kDt, substeps, theta, &ref));
    const double diff = (r.theta_next - ref).lpNorm<Eigen::Infinity>();
    EXPECT_LE(diff, c.coupling == Coupling::kZoh ? 1e-15 : 1e-13)
        << "substeps " << substeps;
    EXPECT_TRUE(r.jacobian.array().isNaN().all());
    std::printf("%s substeps %d: |value - simulator| = %.2e\n",
                CaseName(c).c_str(), substeps, diff);
  }
}

// Reference: central differences of re-simulated intervals, step 3e-6 x
// the parameter's scale, Richardson-extrapolated from h and h/2. State
// perturbations go along an orthonormal basis of the tangent space (null
// space of J(Theta_k)), the ones a planner makes, and along the 21
// coordinates (off H = 0 the integrator's initial projection / Baumgarte
// term act, header). Tolerance 1e-6 relative (the target), columns
// normalised by the parameter's scale and compared relative to
// max(|reference|_inf, dt) (dt: a unit change of the rates for one
// interval). Its origin: the reference's error, truncation + noise. Noise:
// the re-solves' error (Newton to a scaled residual <= 1e-12, in practice
// ~1e-15 after the last quadratic step) over 2h; truncation: in paper mode
// a creeping wheel's slip curves on the scale eps = 1e-8 m/s, which a step
// in the rates moves by ~rho h (model.md §7.8), so the differences leave
// the asymptotic range early. Measured worst (paper, rates): h = 1e-4:
// 1.8e-5, 3e-5: 1.3e-7, 1e-5: 5.7e-7, 3e-6: 1.5e-8, 1e-6: 2.6e-8 (noise);
// incline10 (pvc) 3e-9 at every h <= 1e-5. The derivative's own error is
// ~eps_mach^(2/3) ~ 4e-11 (differences of the field) plus the quasi-static
// sensitivities' (model.md §7.8).
constexpr double kReferenceStep = 3e-6;
constexpr double kTolerance = 1e-6;

TEST_P(StepSensitivityTest, AgreesWithResimulatedCentralDifferences) {
  const Case& c = GetParam();
  const Scene scene = SceneFile(c.scene);
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  StepSensitivity step(model, QuasiStaticParameters::FromScene(scene),
                       StepOptions(c, kDt));
  StepSensitivityResult r;
  ASSERT_EQ(step.Compute(theta, &r), StepSensitivityStatus::kOk) << r.message;
  // Tangent basis: the last 9 right singular vectors of J (rank 12).
  LoopClosureJacobian jac;
  model.ConstraintJacobian(theta, &jac);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jac, Eigen::ComputeFullV);
  const Eigen::MatrixXd tangent = svd.matrixV().rightCols(9);
  // Directions: 9 tangent, the 21 coordinates (off H = 0 too: the
  // projection's P(Theta_k), the Baumgarte field off the manifold), then
  // mu, eps, the 6 rates.
  Eigen::Matrix<double, 21, 30> dirs;
  dirs << tangent, Eigen::Matrix<double, 21, 21>::Identity();
  const int nd = 30 + 8;
  double worst = 0.0;
  int worst_d = -1;
  for (int d = 0; d < nd; ++d) {
    const int k = d < 30 ? -1 : P::kMu + (d - 30);
    const double scale = k < 0 ? 1.0 : Scale(scene, k);
    auto central = [&](double h, Configuration* out) {
      Configuration plus, minus;
      Configuration t_plus = theta, t_minus = theta;
      if (k < 0) {
        t_plus += h * dirs.col(d);
        t_minus -= h * dirs.col(d);
      }
      const Scene s_plus = k < 0 ? scene : Perturbed(scene, k, h);
      const Scene s_minus = k < 0 ? scene : Perturbed(scene, k, -h);
      if (!Resimulate(s_plus, c, kDt, c.substeps, t_plus, &plus) ||
          !Resimulate(s_minus, c, kDt, c.substeps, t_minus, &minus))
        return false;
      *out = (plus - minus) / (2 * h);
      return true;
    };
    Configuration d1, d2;
    const double h = kReferenceStep * scale;
    ASSERT_TRUE(central(h, &d1) && central(h / 2, &d2)) << "direction " << d;
    const Configuration ref = (4 * d2 - d1) / 3;
    const Configuration got = k < 0 ? Configuration(r.dstate() * dirs.col(d))
                                    : Configuration(r.jacobian.col(k));
    const double err = (got - ref).lpNorm<Eigen::Infinity>() * scale /
                       std::max(ref.lpNorm<Eigen::Infinity>() * scale, kDt);
    if (err > worst) {
      worst = err;
      worst_d = d;
    }
    EXPECT_LE(err, kTolerance) << "direction " << d << " (0-8 tangent, 9-29 "
                               << "coordinates, 30 mu, 31 eps, 32-37 rates)";
  }
  std::printf("%s: worst relative error %.2e (direction %d)\n",
              CaseName(c).c_str(), worst, worst_d);
}

INSTANTIATE_TEST_SUITE_P(Scenes, StepSensitivityTest,
                         ::testing::ValuesIn(std::vector<Case>{
                             {"paper", Coupling::kZoh, "rk-projection"},
                             {"paper", Coupling::kZoh, "rk-baumgarte"},
                             {"paper", Coupling::kCoupled, "rk-projection"},
                             {"paper", Coupling::kCoupled, "rk-baumgarte"},
                             {"incline10", Coupling::kZoh, "rk-projection"},
                             {"incline10", Coupling::kZoh, "rk-baumgarte"},
                             {"incline10", Coupling::kCoupled, "rk-projection"},
                             {"incline10", Coupling::kCoupled, "rk-baumgarte"},
                             {"paper", Coupling::kZoh, "rk-projection", 2},
                             {"incline10", Coupling::kCoupled, "rk-baumgarte",
                              2}}),
                         [](const auto& info) { return CaseName(info.param); });

// The header's projector: at a point y* on H = 0, the derivative of the
// converged Newton projection is P = I - D J^T (J D J^T)^{-1} J. Checked
// against central differences of WeightedProjection::Project (tolerance
// 1e-14) along random directions; P is the D-oblique projector (J P = 0,
// P^2 = P).
TEST(StepSensitivityProjection, ProjectorIsTheProjectionsDerivative) {
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  LoopClosureOde ode(model);  // H, J, D as the simulator's
  WeightedProjection proj;
  proj.Begin(ode);
  IntegratorResult counters;
  LoopClosureJacobian jac;
  model.ConstraintJacobian(theta, &jac);
  const Configuration d = model.CorrectionWeights();
  const Eigen::Matrix<double, 12, 12> a =
      jac * d.asDiagonal() * jac.transpose();
  const Eigen::Matrix<double, 21, 21> p =
      Eigen::Matrix<double, 21, 21>::Identity() -
      d.asDiagonal() * jac.transpose() * a.ldlt().solve(jac);
  EXPECT_LE((jac * p).norm(), 1e-12);
  EXPECT_LE((p * p - p).norm(), 1e-12);
  std::srand(7);
  const double h = 1e-5;
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    const Configuration v = Configuration::Random().normalized();
    Eigen::VectorXd plus = theta + h * v, minus = theta - h * v;
    bool moved = false;
    ASSERT_EQ(proj.Project(ode, plus, 1e-14, 20, &counters, &moved),
              IntegratorStatus::kSuccess);
    ASSERT_EQ(proj.Project(ode, minus, 1e-14, 20, &counters, &moved),
              IntegratorStatus::kSuccess);
    const Configuration fd = (plus - minus) / (2 * h);
    worst = std::max(worst, (fd - p * v).lpNorm<Eigen::Infinity>() /
                                (p * v).lpNorm<Eigen::Infinity>());
  }
  // Truncation ~h |d2 Pi| and Newton's tolerance 1e-14 / h; measured 4.9e-11.
  EXPECT_LE(worst, 1e-7);
  std::printf("projector vs differences of the projection: %.2e\n", worst);
}

// F(Y, w) = KinematicModel::Rhs is linear in w (the header's exact g_w).
TEST(StepSensitivityField, RhsIsLinearInTheTwist) {
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  std::srand(3);
  const Vec12 w1 = Vec12::Random(), w2 = Vec12::Random();
  Configuration f1, f2, f12;
  ASSERT_TRUE(model.Rhs(theta, w1, &f1));
  ASSERT_TRUE(model.Rhs(theta, w2, &f2));
  ASSERT_TRUE(model.Rhs(theta, 2.0 * w1 - 3.0 * w2, &f12));
  EXPECT_LE((f12 - (2.0 * f1 - 3.0 * f2)).lpNorm<Eigen::Infinity>(),
            1e-13 * f12.lpNorm<Eigen::Infinity>());
}

// incline10 (pvc) at mu = mu_min (1 + 1e-9): the critical wheel's friction
// cone is about to become active (core/sensitivity.h): the step reports
// ONE_SIDED and names it with the stage, value and derivative finite.
TEST(StepSensitivityStatusTest, OneSidedAtTheFrictionConeIsReported) {
  RegisterBuiltinNlpSolvers();
  InclineAtFrictionLimit incline;
  const KinematicModel& model = incline.model;
  const Configuration& theta = incline.theta;
  QuasiStaticParameters& params = incline.params;
  params.mu = incline.mu_min * (1 + 1e-9);
  for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
    StepSensitivityOptions o;
    o.coupling = coupling;
    StepSensitivity step(model, params, o);
    StepSensitivityResult r;
    EXPECT_EQ(step.Compute(theta, &r), StepSensitivityStatus::kOneSided)
        << ToString(r.status) << ": " << r.message;
    ASSERT_FALSE(r.one_sided.empty());
    EXPECT_NE(r.one_sided.front().find("I2 wheel"), std::string::npos)
        << r.one_sided.front();
    EXPECT_NE(r.message.find("one-sided"), std::string::npos) << r.message;
    EXPECT_TRUE(r.theta_next.allFinite());
    EXPECT_TRUE(r.jacobian.allFinite());
  }
}

// A singular quasi-static Jacobian is a status with the value and no
// derivative. Forced here by counting every J_E as singular
// (singular_rcond = 1: rcond <= 1 always; a J_E singular to working
// precision is what the default 1e-14 catches, core/sensitivity.h).
TEST(StepSensitivityStatusTest, SingularIsAStatusWithValueAndNoDerivative) {
  RegisterBuiltinNlpSolvers();
  const Scene scene = SceneFile("paper");
  for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
    StepSensitivityOptions o;
    o.coupling = coupling;
    o.sensitivity.singular_rcond = 1.0;
    const StepSensitivityResult r = ComputeStepSensitivity(scene, o);
    o.derivatives = false;
    const StepSensitivityResult value = ComputeStepSensitivity(scene, o);
    EXPECT_EQ(r.status, StepSensitivityStatus::kSingular) << r.message;
    EXPECT_NE(
        r.message.find(coupling == Coupling::kZoh ? "Theta_k" : "stage 1"),
        std::string::npos)
        << r.message;
    EXPECT_NE(r.message.find("SINGULAR"), std::string::npos) << r.message;
    EXPECT_EQ(r.theta_next, value.theta_next);
    EXPECT_TRUE(r.jacobian.array().isNaN().all());
  }
}

// After a first call Compute() does not allocate (zoh and coupled: the
// solver's warm-started solves and the analyzer reuse their workspaces) and
// gives the same bits again (the solver restarts cold every call).
TEST(StepSensitivityWorkspace, NoAllocationAfterWarmUpAndRepeatable) {
  RegisterBuiltinNlpSolvers();
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
    for (const char* dae : {"rk-projection", "rk-baumgarte"}) {
      StepSensitivityOptions o;
      o.coupling = coupling;
      o.dae = dae;
      StepSensitivity step(model, QuasiStaticParameters::FromScene(scene), o);
      StepSensitivityResult first, second;
      ASSERT_EQ(step.Compute(theta, &first), StepSensitivityStatus::kOk);
      const long long before = testing_util::g_heap_allocations.load();
      step.Compute(theta, &second);
      EXPECT_EQ(testing_util::g_heap_allocations.load() - before, 0)
          << dae << " " << ToString(coupling);
      EXPECT_EQ(first.theta_next, second.theta_next);
      EXPECT_EQ(first.jacobian, second.jacobian);
    }
  }
}

// A failed quasi-static solve (mu far below mu_min) is a status with the
// solve's reason, and no value.
TEST(StepSensitivityStatusTest, FailedSolveIsAStatusWithoutValue) {
  RegisterBuiltinNlpSolvers();
  Scene scene = SceneFile("incline10");
  scene.mu = 0.05;
  const StepSensitivityResult r = ComputeStepSensitivity(scene, {});
  EXPECT_EQ(r.status, StepSensitivityStatus::kQuasiStaticFailure);
  EXPECT_NE(r.message.find("Theta_k"), std::string::npos) << r.message;
  EXPECT_TRUE(r.theta_next.array().isNaN().all());
}

TEST(StepSensitivityStatusTest, MisuseThrowsNamingTheField) {
  RegisterBuiltinNlpSolvers();
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  const QuasiStaticParameters params = QuasiStaticParameters::FromScene(scene);
  auto message = [&](StepSensitivityOptions o) -> std::string {
    try {
      StepSensitivity step(model, params, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  StepSensitivityOptions o;
  o.dt = 0;
  EXPECT_NE(message(o).find("dt: must be finite and > 0, got 0"),
            std::string::npos);
  o = {};
  o.substeps = 0;
  EXPECT_NE(message(o).find("substeps"), std::string::npos);
  o = {};
  o.dae = "ida";
  EXPECT_NE(message(o).find("dae: must be rk-projection or rk-baumgarte"),
            std::string::npos)
      << message(o);
  EXPECT_NE(message(o).find("'ida'"), std::string::npos);
  o = {};
  o.rk_method = "dp54";
  EXPECT_NE(message(o).find("rk_method"), std::string::npos);
  EXPECT_NE(message(o).find("'dp54'"), std::string::npos);
  o = {};
  o.nlp = "no-such-solver";
  EXPECT_THROW(StepSensitivity(model, params, o), std::invalid_argument);
  StepSensitivity step(model, params, {});
  StepSensitivityResult r;
  Configuration bad = SolveInitialConfiguration(model, scene);
  bad(3) = std::nan("");
  EXPECT_THROW(step.Compute(bad, &r), std::invalid_argument);
}

}  // namespace
}  // namespace quasiroll
