// Sensitivities of the quasi-static solution (model.md §7.8, core/
// sensitivity.h) against the independent reference: central differences of
// whole re-solves (perturb one parameter, re-solve tightly, difference the
// outputs), on the paper scene, a pvc scene and a bumpy terrain, for every
// registered NLP backend; and the one-sided flag at an active-set change.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <string>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/sensitivity.h"
#include "simulation_support.h"
#include "tests/heap_counter.h"
#include "tests/test_names.h"

namespace quasiroll {
namespace {

// Outputs the sensitivities cover, from a solution: twist, joint rates,
// world forces (21), and the equality multipliers of J_E^T l = -grad f
// computed here from the problem's Jacobian (independent of sensitivity.cc).
struct Point {
  Eigen::Matrix<double, 21, 1> y;
  Eigen::VectorXd lambda;
};

Point Observe(const QuasiStaticProblem& p, QuasiStaticSolution sol) {
  sol.z = Polish(p, sol.z);
  Point pt;
  const Vec12 w = p.JointSpaceVelocity(sol.z);
  pt.y.head<12>() = w;
  for (int i = 0; i < 3; ++i) {
    const Vec3 f = p.F0() * sol.z.segment<3>(p.num_motion() + 3 * i);
    pt.y.segment<3>(12 + 3 * i) =
        p.chains()[i].R_GCW * Vec3(f(0), f(1), -f(2));  // model.md §7.1
  }
  const int n = p.num_variables(), ne = p.num_equalities();
  Eigen::MatrixXd jac(p.num_constraints(), n);
  p.ConstraintJacobian(sol.z, jac);
  Eigen::VectorXd grad(n);
  p.ObjectiveGradient(sol.z, grad);
  pt.lambda = -jac.topRows(ne).transpose().fullPivLu().solve(grad);
  return pt;
}

class Sensitivity : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() { RegisterBuiltinNlpSolvers(); }
};

struct Reference {
  Eigen::Matrix<double, 21, SensitivityParameter::kCount> dy;
  Eigen::MatrixXd dlambda;
  bool ok = true;
  std::string why;
};

// Sets parameter k of the solver's problem to nominal + delta; returns the
// configuration to solve at.
Configuration Perturb(QuasiStaticSolver* solver,
                      const QuasiStaticParameters& nominal,
                      const Configuration& theta, int k, double delta) {
  Configuration t = theta;
  PerturbParameter(nominal, k, delta, &solver->problem(), &t);
  return t;
}

double RefStep(const QuasiStaticParameters& nominal, int k, double rel) {
  if (k == SensitivityParameter::kMu) return rel * nominal.mu;
  if (k == SensitivityParameter::kEpsilon) return rel * nominal.epsilon;
  return rel;
}

// Central differences of whole re-solves with step h = rel * scale, warm
// started from the previous (nearby) solution.
Reference ReSolveReference(QuasiStaticSolver* solver,
                           const QuasiStaticParameters& nominal,
                           const Configuration& theta, double rel) {
  Reference ref;
  ref.dlambda.resize(solver->problem().num_equalities(),
                     SensitivityParameter::kCount);
  QuasiStaticSolution sol;
  for (int k = 0; k < SensitivityParameter::kCount && ref.ok; ++k) {
    const double h = RefStep(nominal, k, rel);
    Point pts[2];
    for (int s = 0; s < 2 && ref.ok; ++s) {
      const Configuration t =
          Perturb(solver, nominal, theta, k, s == 0 ? h : -h);
      if (solver->Solve(t, &sol) != QuasiStaticStatus::kOk) {
        ref.ok = false;
        ref.why = "re-solve failed for parameter " + std::to_string(k) + ": " +
                  sol.message;
      }
      pts[s] = Observe(solver->problem(), sol);
    }
    ref.dy.col(k) = (pts[0].y - pts[1].y) / (2 * h);
    ref.dlambda.col(k) = (pts[0].lambda - pts[1].lambda) / (2 * h);
  }
  Perturb(solver, nominal, theta, 0, 0.0);
  return ref;
}

struct Case {
  std::string name;
  Scene scene;
};

std::vector<Case> Cases() {
  std::vector<Case> cases;
  cases.push_back({"paper", SceneFile("paper")});
  cases.push_back({"circle_pvc", SceneFile("circle_pvc")});
  cases.push_back({"incline10_pvc", SceneFile("incline10")});
  cases.push_back({"bumpy", BumpyScene()});
  return cases;
}

// Natural scales of the 21 outputs (twist linear v0, angular v0/L0, joint
// rates v0/rho, forces m g) and of the parameters (1 for Theta, mu, eps,
// max(1, |rate|)): derivatives are compared after normalising by them.
Eigen::Matrix<double, 21, 1> OutputScales(const QuasiStaticProblem& p) {
  Eigen::Matrix<double, 21, 1> s;
  s.head<3>().setConstant(p.v0());
  s.segment<3>(3).setConstant(p.v0() / p.L0());
  s.segment<6>(6).setConstant(p.v0() / p.rho());
  s.tail<9>().setConstant(p.F0());
  return s;
}

double ParameterScale(const QuasiStaticParameters& nominal, int k) {
  if (k == SensitivityParameter::kMu) return nominal.mu;
  if (k == SensitivityParameter::kEpsilon) return nominal.epsilon;
  if (k >= SensitivityParameter::kRates)
    return std::max(
        1.0, std::abs(nominal.joint_rates[k - SensitivityParameter::kRates]));
  return 1.0;
}

// Largest column-wise difference of the normalised derivatives,
// max_k |a_k - b_k|_inf / max(|b_k|_inf, 1): relative where a column is
// of natural size or larger, relative to the natural scale below.
template <typename A, typename B>
double ColumnError(const A& a, const B& b, const Eigen::VectorXd& row_scale,
                   const QuasiStaticParameters& nominal, int* worst) {
  double e = 0.0;
  for (int k = 0; k < a.cols(); ++k) {
    const double ps = ParameterScale(nominal, k);
    const Eigen::VectorXd an = a.col(k).cwiseQuotient(row_scale) * ps;
    const Eigen::VectorXd bn = b.col(k).cwiseQuotient(row_scale) * ps;
    const double d = (an - bn).template lpNorm<Eigen::Infinity>() /
                     std::max(bn.template lpNorm<Eigen::Infinity>(), 1.0);
    if (d > e) {
      e = d;
      *worst = k;
    }
  }
  return e;
}

// Reference step: h = 5e-6 x the parameter's scale, Richardson-extrapolated
// from h and h/2 (truncation O(h^4)). The solutions are polished to
// round-off, which enters as ~cond(J_E) eps_mach / h (cond ~3e4 in paper
// mode): the measured floor of the differences is ~1e-7 for the outputs.
// Tolerances: outputs 1e-6 relative on every scene (the target; the
// sensitivities' own error is ~eps_mach^(2/3) ~ 4e-11, header). Multipliers:
// 1e-6 in pvc mode; in paper mode the multipliers of the friction rows
// scale like 1/sigma and are computed from J_E^T (cond ~3e4), so both the
// reference and the tangent difference carry ~cond eps_mach / h ~ 1e-5
// (measured 1e-6 .. 3e-5 over h = 1e-7 .. 1e-5): 5e-5 there.
constexpr double kReferenceStep = 5e-6;
constexpr double kOutputTolerance = 1e-6;
constexpr double kPvcMultiplierTolerance = 1e-6;
constexpr double kPaperMultiplierTolerance = 5e-5;

TEST_P(Sensitivity, AgreesWithReSolveCentralDifferences) {
  for (const Case& c : Cases()) {
    const KinematicModel model(c.scene.geometry, c.scene.terrain);
    const Configuration theta = SolveInitialConfiguration(model, c.scene);
    const QuasiStaticParameters params =
        QuasiStaticParameters::FromScene(c.scene);
    QuasiStaticOptions options;
    options.residual_tolerance = 1e-14;
    QuasiStaticSolver solver(model, params,
                             NlpSolverRegistry::Create(GetParam()), options);
    QuasiStaticSolution sol;
    ASSERT_EQ(solver.Solve(theta, &sol), QuasiStaticStatus::kOk)
        << c.name << ": " << sol.message;
    SensitivityAnalyzer analyzer;
    QuasiStaticSensitivities sens;
    ASSERT_EQ(analyzer.Compute(solver.problem(), sol.z, &sens),
              SensitivityStatus::kOk)
        << c.name;
    EXPECT_FALSE(sens.one_sided) << c.name;
    Reference ref = ReSolveReference(&solver, params, theta, kReferenceStep);
    const Reference half =
        ReSolveReference(&solver, params, theta, kReferenceStep / 2);
    ASSERT_TRUE(ref.ok && half.ok) << c.name << ": " << ref.why << half.why;
    ref.dy = (4 * half.dy - ref.dy) / 3;
    ref.dlambda = (4 * half.dlambda - ref.dlambda) / 3;
    Eigen::Matrix<double, 21, SensitivityParameter::kCount> dy;
    dy << sens.twist, sens.joint_rates, sens.forces;
    int wk = -1, wl = -1;
    const int ne = solver.problem().num_equalities();
    const double ey =
        ColumnError(dy, ref.dy, OutputScales(solver.problem()), params, &wk);
    const Eigen::VectorXd lscale = Eigen::VectorXd::Constant(
        ne, std::max(1.0, sens.multiplier_values.lpNorm<Eigen::Infinity>()));
    const double el = ColumnError(sens.multipliers.topRows(ne), ref.dlambda,
                                  lscale, params, &wl);
    EXPECT_LE(ey, kOutputTolerance) << c.name << ": worst parameter " << wk;
    EXPECT_LE(el, params.mode == ActuationMode::kPvc
                      ? kPvcMultiplierTolerance
                      : kPaperMultiplierTolerance)
        << c.name << ": worst parameter " << wl;
    std::printf("%s %s: outputs %.2e multipliers %.2e\n", GetParam().c_str(),
                c.name.c_str(), ey, el);
  }
}

// At an active-set change the derivative is one-sided and flagged. pvc on
// the 10 degree incline is statically determinate (model.md §7.5): as mu
// falls to mu_min the critical wheel's cone slack mu^2 f_n^2 - |f_t|^2 =
// f_n^2 (mu^2 - mu_min^2) goes to 0, where I2 becomes active. At mu =
// mu_min (1 + 1e-9) the scaled slack is ~1e-11 < activity_tolerance 1e-10;
// at mu_min (1 + 1e-2) it is ~1e-4 and the derivative is two-sided.
TEST_P(Sensitivity, OneSidedAtFrictionConeLimit) {
  InclineAtFrictionLimit incline;
  const KinematicModel& model = incline.model;
  const Configuration& theta = incline.theta;
  QuasiStaticParameters& params = incline.params;
  const int critical = incline.critical;
  const double mu_min = incline.mu_min;
  ASSERT_GT(mu_min, 0.3);  // 0.318914 or 0.394378 (model.md §7.7)
  for (double margin : {1e-9, 1e-2}) {
    params.mu = mu_min * (1 + margin);
    QuasiStaticSolver solver(model, params,
                             NlpSolverRegistry::Create(GetParam()));
    QuasiStaticSolution sol;
    ASSERT_EQ(solver.Solve(theta, &sol), QuasiStaticStatus::kOk)
        << "margin " << margin << ": " << sol.message;
    SensitivityAnalyzer analyzer;
    QuasiStaticSensitivities sens;
    ASSERT_EQ(analyzer.Compute(solver.problem(), sol.z, &sens),
              SensitivityStatus::kOk);
    if (margin > 1e-3) {
      EXPECT_FALSE(sens.one_sided) << "slack " << sens.min_inequality_slack;
      continue;
    }
    ASSERT_TRUE(sens.one_sided) << "slack " << sens.min_inequality_slack;
    // Every item named is a friction cone, one of them the critical wheel's
    // (both rear wheels on the incline may share it by symmetry).
    const int m = solver.problem().num_constraints();
    bool has_critical = false;
    for (int a = 0; a < sens.num_one_sided; ++a) {
      const int item = sens.one_sided_items[a];
      EXPECT_GE(item, m - 3);
      EXPECT_LT(item, m);
      has_critical |= item == m - 3 + critical;
      EXPECT_EQ(OneSidedName(sens, item).rfind("I2 wheel ", 0), 0u)
          << OneSidedName(sens, item);
    }
    EXPECT_TRUE(has_critical) << "critical wheel " << critical + 1;
  }
}

// Misuse throws; a singular J_E is a status. At z = 0 every force is zero,
// so the friction rows lose their motion columns (dC/ds = f_t s^T / sigma +
// mu f_n I = 0) and only the 3 E1 rows constrain the 6 motion unknowns.
TEST_P(Sensitivity, MisuseThrowsAndSingularIsAStatus) {
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  QuasiStaticProblem problem(model, QuasiStaticParameters::FromScene(scene));
  problem.SetConfiguration(SolveInitialConfiguration(model, scene));
  SensitivityAnalyzer analyzer;
  QuasiStaticSensitivities sens;
  EXPECT_THROW(analyzer.Compute(problem, Eigen::VectorXd::Zero(3), &sens),
               std::invalid_argument);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(problem.num_variables());
  z(0) = std::nan("");
  EXPECT_THROW(analyzer.Compute(problem, z, &sens), std::invalid_argument);
  z.setZero();
  EXPECT_EQ(analyzer.Compute(problem, z, &sens), SensitivityStatus::kSingular)
      << "rcond " << sens.rcond;
  SensitivityOptions bad;
  bad.activity_tolerance = -1;
  EXPECT_THROW(SensitivityAnalyzer{bad}, std::invalid_argument);
}

// After a first call, Compute() neither allocates nor depends on the
// previous call (the same bits twice).
TEST(SensitivityWorkspace, NoAllocationAfterWarmUpAndRepeatable) {
  RegisterBuiltinNlpSolvers();
  const Scene scene = SceneFile("paper");
  const KinematicModel model(scene.geometry, scene.terrain);
  QuasiStaticSolver solver(model, QuasiStaticParameters::FromScene(scene),
                           NlpSolverRegistry::Create("newton"));
  QuasiStaticSolution sol;
  ASSERT_EQ(solver.Solve(SolveInitialConfiguration(model, scene), &sol),
            QuasiStaticStatus::kOk);
  SensitivityAnalyzer analyzer;
  QuasiStaticSensitivities first, second;
  ASSERT_EQ(analyzer.Compute(solver.problem(), sol.z, &first),
            SensitivityStatus::kOk);
  const long long before = testing_util::g_heap_allocations.load();
  analyzer.Compute(solver.problem(), sol.z, &second);
  EXPECT_EQ(testing_util::g_heap_allocations.load() - before, 0);
  EXPECT_EQ(first.twist, second.twist);
  EXPECT_EQ(first.forces, second.forces);
  EXPECT_EQ(first.multipliers, second.multipliers);
  // Without the multipliers' derivatives: the same outputs, NaN multipliers.
  SensitivityOptions primal_only;
  primal_only.multipliers = false;
  QuasiStaticSensitivities primal;
  SensitivityAnalyzer(primal_only).Compute(solver.problem(), sol.z, &primal);
  EXPECT_EQ(primal.twist, first.twist);
  EXPECT_EQ(primal.forces, first.forces);
  EXPECT_TRUE(primal.multipliers.array().isNaN().all());
}

INSTANTIATE_TEST_SUITE_P(AllBackends, Sensitivity,
                         ::testing::ValuesIn(BuiltinNlpBackendNames()),
                         testing_util::ParamName());

}  // namespace
}  // namespace quasiroll
