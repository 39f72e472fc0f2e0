// The quasi-static problem (model.md §7) against the analytic oracles of
// model.md §9.1 (O1, O3, O3-num, O4, O6), on every registered NLP backend.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <thread>
#include <vector>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/terrains.h"
#include "tests/core/simulation_support.h"
#include "tests/test_names.h"

namespace quasiroll {
namespace {

constexpr double kMg = 49.0;  // m g, default scene

struct Scenario {
  std::unique_ptr<KinematicModel> model;
  Configuration theta;
  QuasiStaticParameters params;
};

Scenario MakeSetup(std::shared_ptr<const Terrain> terrain, ActuationMode mode,
                   double yaw, std::array<double, 6> joints,
                   std::array<double, 6> rates, double mu = 0.5) {
  Scenario s;
  s.model = std::make_unique<KinematicModel>(RobotGeometry{}, terrain);
  s.theta = SolveInitialConfiguration(*s.model, 0, 0, yaw, joints);
  s.params.mode = mode;
  s.params.mu = mu;
  s.params.joint_rates = rates;
  return s;
}

// Paper mode on one Gaussian bump, steered 0.2 rad, yawed 0.1 rad.
Scenario OneBumpPaperScenario() {
  std::vector<GaussianBump> bumps = {{0.0231, 0.2323, -0.1855, 0.3764}};
  return MakeSetup(std::make_shared<GaussianTerrain>(bumps),
                   ActuationMode::kPaper, 0.1, {0.2, 0, 0, 0, 0, 0},
                   {0, 0.6, 0, 0.6, 0, 0.6});
}

class QuasiStaticBackends : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() { RegisterBuiltinNlpSolvers(); }
  QuasiStaticSolution Solve(const Scenario& s,
                            QuasiStaticOptions options = {}) {
    QuasiStaticSolver solver(*s.model, s.params,
                             NlpSolverRegistry::Create(GetParam()), options);
    QuasiStaticSolution sol;
    solver.Solve(s.theta, &sol);
    return sol;
  }
};

// Force tolerance: relative force error <= condition number x residual
// tolerance (model.md §7.3). Creeping paper-mode states have cond ~1.2e7 at
// eps = 1e-8, so 1.2e7 * 1e-12 * 49 N ~ 6e-4 N; pvc mode cond <= 140 gives
// ~1e-8 N. We use those bounds.
double ForceTolerance(ActuationMode mode) {
  return mode == ActuationMode::kPaper ? 6e-4 : 1e-8;
}

// O1: flat straight drive, both modes.
TEST_P(QuasiStaticBackends, O1FlatStraightDrive) {
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    const Scenario s = MakeSetup(std::make_shared<PlaneTerrain>(0.0), mode, 0.0,
                                 {0, 0, 0, 0, 0, 0}, {0, 0.6, 0, 0.6, 0, 0.6});
    const QuasiStaticSolution sol = Solve(s);
    ASSERT_EQ(sol.status, QuasiStaticStatus::kOk)
        << ToString(mode) << ": " << sol.message;
    const double tol = ForceTolerance(mode);
    EXPECT_NEAR(sol.twist(0), 0.06, 1e-9);  // rho alphadot
    EXPECT_NEAR(sol.twist.segment<5>(1).norm(), 0.0, 1e-9);
    EXPECT_NEAR(sol.contacts[0].normal_force, 24.5, tol);
    EXPECT_NEAR(sol.contacts[1].normal_force, 12.25, tol);
    EXPECT_NEAR(sol.contacts[2].normal_force, 12.25, tol);
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(sol.contacts[i].slip.norm(), 1e-8);  // creep <= eps
      EXPECT_NEAR(sol.contacts[i].traction.norm(), 0.0, tol);
    }
    if (mode == ActuationMode::kPvc) {
      EXPECT_NEAR(sol.joint_rates[1], 0.6, 1e-9);  // free front wheel rolls
      EXPECT_NEAR(sol.joint_rates[2], 0.0, 1e-9);
      EXPECT_NEAR(sol.joint_rates[4], 0.0, 1e-9);
    }
  }
}

// O3 / O3-num: 10 degree incline, straight up and down, both modes.
TEST_P(QuasiStaticBackends, O3InclineUpAndDown) {
  const double beta = 10.0 * M_PI / 180;
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    for (int dir : {+1, -1}) {
      const double yaw = dir > 0 ? 0.0 : M_PI;
      const Scenario s =
          MakeSetup(std::make_shared<InclineTerrain>(beta, 0.0), mode, yaw,
                    {0, 0, 0, 0, 0, 0}, {0, 0.6, 0, 0.6, 0, 0.6});
      const QuasiStaticSolution sol = Solve(s);
      ASSERT_EQ(sol.status, QuasiStaticStatus::kOk)
          << ToString(mode) << " dir " << dir << ": " << sol.message;
      const double tol = ForceTolerance(mode);
      double sum_n = 0, sum_t = 0;
      for (const auto& c : sol.contacts) {
        sum_n += c.normal_force;
        sum_t += c.traction(0);
      }
      EXPECT_NEAR(sum_n, 48.2556, 1e-4);  // O3-num, 6 digits given
      EXPECT_NEAR(sum_n, kMg * std::cos(beta), 3 * tol);
      EXPECT_NEAR(sum_t, dir * kMg * std::sin(beta), 3 * tol);
      const double n1 =
          kMg * (0.25 * std::cos(beta) - dir * 0.15 * std::sin(beta)) / 0.5;
      EXPECT_NEAR(sol.contacts[0].normal_force, n1, tol);
      EXPECT_NEAR(sol.contacts[0].normal_force, dir > 0 ? 21.5752 : 26.6804,
                  1e-4);
      if (mode == ActuationMode::kPaper) {
        for (const auto& c : sol.contacts)  // traction proportional to load
          EXPECT_NEAR(c.traction.norm() / c.normal_force, std::tan(beta),
                      tol / 10);
      } else {
        EXPECT_NEAR(sol.contacts[0].traction(0), 0.0, tol);
        EXPECT_NEAR(sol.contacts[1].traction(0), dir * kMg * std::sin(beta) / 2,
                    tol);
        EXPECT_NEAR(sol.contacts[2].traction(0), dir * kMg * std::sin(beta) / 2,
                    tol);
      }
    }
  }
}

// Threshold behaviour (O3-paper / O3-pvc): just above mu_req solves, just
// below returns INFEASIBLE_FRICTION with mu_min within 1e-6 of the analytic
// threshold.
TEST_P(QuasiStaticBackends, InclineFrictionThreshold) {
  const double beta = 10.0 * M_PI / 180;
  struct Case {
    ActuationMode mode;
    int dir;
    double threshold;
  };
  const double tb = std::tan(beta), sb = std::sin(beta), cb = std::cos(beta);
  const Case cases[] = {
      {ActuationMode::kPaper, +1, tb},
      {ActuationMode::kPvc, +1, 0.5 * sb / (0.25 * cb + 0.15 * sb)},
      {ActuationMode::kPvc, -1, 0.5 * sb / (0.25 * cb - 0.15 * sb)}};
  EXPECT_NEAR(cases[0].threshold, 0.176327, 1e-6);
  EXPECT_NEAR(cases[1].threshold, 0.318914, 1e-6);
  EXPECT_NEAR(cases[2].threshold, 0.394378, 1e-6);
  for (const Case& c : cases) {
    for (double factor : {1.01, 0.99}) {
      const Scenario s =
          MakeSetup(std::make_shared<InclineTerrain>(beta, 0.0), c.mode,
                    c.dir > 0 ? 0.0 : M_PI, {0, 0, 0, 0, 0, 0},
                    {0, 0.6, 0, 0.6, 0, 0.6}, factor * c.threshold);
      const QuasiStaticSolution sol = Solve(s);
      if (factor > 1) {
        EXPECT_EQ(sol.status, QuasiStaticStatus::kOk)
            << ToString(c.mode) << " dir " << c.dir << ": " << sol.message;
      } else {
        EXPECT_EQ(sol.status, QuasiStaticStatus::kInfeasibleFriction)
            << ToString(c.mode) << " dir " << c.dir << ": " << sol.message;
        EXPECT_NEAR(sol.mu_min, c.threshold, 1e-6);
      }
    }
  }
}

// O4: paper mode with real slip (steered front wheel, equal rates): every
// sliding contact is on the cone boundary opposing its slip; G ~ 0.
TEST_P(QuasiStaticBackends, O4SlidingContactsOpposeSlip) {
  const Scenario s =
      MakeSetup(std::make_shared<PlaneTerrain>(0.0), ActuationMode::kPaper, 0.0,
                {0.3, 0, 0, 0, 0, 0}, {0, 0.6, 0, 0.6, 0, 0.6});
  const QuasiStaticSolution sol = Solve(s);
  ASSERT_EQ(sol.status, QuasiStaticStatus::kOk) << sol.message;
  double sum_fn = 0;
  int sliding = 0;
  for (int i = 0; i < 3; ++i) {
    const ContactOutput& c = sol.contacts[i];
    sum_fn += c.normal_force;
    if (c.slip.norm() < 1e-5) continue;  // >= 1000 eps: sliding
    ++sliding;
    // Traction in {C_W} tangent basis from the world force.
    const ChainState& cs = [&]() -> const ChainState& {
      static ChainState st;
      s.model->EvaluateChain(s.theta, i, &st);
      return st;
    }();
    const Vec3 f_cw = cs.R_GCW.transpose() * c.force_world;
    const Vec2 ft = f_cw.head<2>();
    EXPECT_NEAR(ft.dot(c.slip) / (ft.norm() * c.slip.norm()), -1.0, 1e-9);
    // |f_t| = mu f_n |s| / sqrt(|s|^2 + eps^2): relative deficit eps^2/2|s|^2.
    EXPECT_NEAR(ft.norm(), 0.5 * c.normal_force, 1e-6);
  }
  EXPECT_GE(sliding, 1);
  EXPECT_GE(sol.gap, -1e-12);
  EXPECT_LE(sol.gap, 0.5 * 1e-8 * sum_fn * 1.0001);  // G <= mu eps sum f_n
}

// O6: pvc mode on rough terrain equals the explicit statically determinate
// solution of model.md §7.5.
TEST_P(QuasiStaticBackends, O6PvcMatchesExplicitSolution) {
  std::vector<GaussianBump> bumps = {{0.0231, 0.2323, -0.1855, 0.3764},
                                     {0.0369, 0.0122, 0.7951, 0.3896},
                                     {0.0376, 0.9101, -0.4398, 0.3412}};
  const Scenario s =
      MakeSetup(std::make_shared<GaussianTerrain>(bumps), ActuationMode::kPvc,
                0.2, {0.1, 0, 0.05, 0, -0.03, 0}, {0.05, 0, 0, 0.6, 0, 0.7});
  QuasiStaticOptions options;
  options.diagnostics = true;
  const QuasiStaticSolution sol = Solve(s, options);
  ASSERT_EQ(sol.status, QuasiStaticStatus::kOk) << sol.message;
  // Explicit: S f = -s_b.
  QuasiStaticProblem problem(*s.model, s.params);
  problem.SetConfiguration(s.theta);
  Eigen::VectorXd z(problem.num_variables());
  z.setZero();
  Eigen::VectorXd g(problem.num_constraints());
  Eigen::MatrixXd jac(problem.num_constraints(), problem.num_variables());
  problem.Constraints(z, g);
  problem.ConstraintJacobian(z, jac);
  const Eigen::MatrixXd statics = jac.block(3, problem.num_motion(), 9, 9);
  const Eigen::VectorXd f = statics.fullPivLu().solve(-g.segment(3, 9));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sol.contacts[i].normal_force, kMg * f(3 * i + 2), 1e-8);
    EXPECT_LE(sol.contacts[i].slip.norm(), 1e-7);  // creep only: O(eps)
  }
  EXPECT_LT(sol.condition_number, 1e3);
  EXPECT_LT(sol.mu_min, 0.5);
}

// The Jacobian of the NLP constraints against central differences.
TEST(QuasiStaticProblem, ConstraintJacobianMatchesFiniteDifferences) {
  std::vector<GaussianBump> bumps = {{0.0231, 0.2323, -0.1855, 0.3764},
                                     {0.03, 0.3, 0.25, 0.25}};
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    Scenario s =
        MakeSetup(std::make_shared<GaussianTerrain>(bumps), mode, 0.3,
                  {0.2, 0, 0.05, 0, -0.05, 0}, {0.1, 0.6, 0.2, 0.5, 0.1, 0.7});
    s.params.epsilon = 1e-3;  // keep the creep law smooth on the FD scale
    QuasiStaticProblem problem(*s.model, s.params);
    problem.SetConfiguration(s.theta);
    const int n = problem.num_variables(), m = problem.num_constraints();
    Eigen::VectorXd z(n);
    for (int i = 0; i < n; ++i) z(i) = 0.3 * std::sin(1.7 * i + 0.4);
    Eigen::MatrixXd jac(m, n);
    problem.ConstraintJacobian(z, jac);
    for (int c = 0; c < n; ++c) {
      Eigen::VectorXd zp = z, zm = z, gp(m), gm(m);
      zp(c) += 1e-6;
      zm(c) -= 1e-6;
      problem.Constraints(zp, gp);
      problem.Constraints(zm, gm);
      // Central differences: error ~ h^2 |g'''| + eps|g|/h ~ 1e-9 here.
      EXPECT_LT(((gp - gm) / 2e-6 - jac.col(c)).lpNorm<Eigen::Infinity>(), 1e-7)
          << ToString(mode) << " column " << c;
    }
  }
}

// Virtual power (O7): sum_i F_i . v_ci = -(P_grav + P_act).
TEST(QuasiStaticProblem, VirtualPowerBalance) {
  RegisterBuiltinNlpSolvers();
  const Scenario s = OneBumpPaperScenario();
  QuasiStaticSolver solver(*s.model, s.params,
                           NlpSolverRegistry::Create("newton"));
  QuasiStaticSolution sol;
  ASSERT_EQ(solver.Solve(s.theta, &sol), QuasiStaticStatus::kOk) << sol.message;
  Mat3 R;
  Vec3 p;
  s.model->PlatformPose(s.theta, &R, &p);
  double contact_power = 0;
  for (int i = 0; i < 3; ++i) {
    ChainState cs;
    s.model->EvaluateChain(s.theta, i, &cs);
    const Vec3 v =
        cs.R_GCW * Vec3(sol.contacts[i].slip(0), sol.contacts[i].slip(1),
                        sol.contacts[i].normal_velocity);
    contact_power += sol.contacts[i].force_world.dot(v);
  }
  const double p_grav = Vec3(0, 0, -kMg).dot(R * sol.twist.head<3>());
  double p_act = 0;
  for (int j = 0; j < 6; ++j)
    p_act += sol.actuator_torques[j] * sol.joint_rates[j];
  EXPECT_NEAR(contact_power, -(p_grav + p_act), 1e-9);
}

// Cross-backend agreement: 50 configurations along drives on the rough
// terrain R1 (paper scene), both modes. Every backend that reports OK must
// agree with `newton` on the scaled unknowns (twist, passive rates, forces):
// to 1e-9 where the scaled equality Jacobian's condition number is below 1e3
// (pvc, real slip), otherwise to condition number x residual tolerance (1e-12)
// (creeping paper-mode states are ill-conditioned by design, model.md §7).
TEST_P(QuasiStaticBackends, AgreesWithNewtonAlongRoughDrive) {
  RegisterBuiltinIntegrators();
  const Scene paper =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  int compared = 0;
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    Scene scene = paper;
    scene.mode = mode;
    scene.t_end = 12.25;  // 246 samples: every 10th gives 25 configurations
    Simulator sim(scene, SimulationOptions{});
    const SimulationResult drive = sim.Run();
    ASSERT_TRUE(drive.success()) << drive.stop_reason;
    const QuasiStaticParameters params =
        QuasiStaticParameters::FromScene(scene);
    QuasiStaticOptions options;
    options.diagnostics = true;
    QuasiStaticSolver reference(sim.model(), params,
                                NlpSolverRegistry::Create("newton"), options);
    QuasiStaticSolver candidate(sim.model(), params,
                                NlpSolverRegistry::Create(GetParam()), options);
    for (size_t k = 0; k < drive.samples.size() && k < 250; k += 10) {
      const Configuration& theta = drive.samples[k].theta;
      QuasiStaticSolution ref, got;
      ASSERT_EQ(reference.Solve(theta, &ref), QuasiStaticStatus::kOk)
          << ref.message;
      if (candidate.Solve(theta, &got) != QuasiStaticStatus::kOk) continue;
      const double cond = ref.condition_number;
      const double tol = cond < 1e3 ? 1e-9 : std::min(1e-5, cond * 1e-12);
      const double diff = (got.z - ref.z).lpNorm<Eigen::Infinity>();
      EXPECT_LE(diff, tol) << GetParam() << " " << ToString(mode) << " sample "
                           << k << " cond " << cond;
      ++compared;
    }
  }
  EXPECT_GE(compared, 45) << "too few converged solves to compare";
}

// Backends that declare SupportsConcurrentInstances() (the harness then runs
// them in parallel threads): two solver objects solving at the same time in
// two threads give bit-identical answers to one object solving alone. Shared
// unsynchronised state in a backend or its library would show here as a
// difference or a crash (CI also runs this under ASan/UBSan).
TEST_P(QuasiStaticBackends, ConcurrentInstancesMatchSequentialSolves) {
  if (!NlpSolverRegistry::Create(GetParam())->SupportsConcurrentInstances())
    GTEST_SKIP() << GetParam() << " is serialised by the harness";
  RegisterBuiltinIntegrators();
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.t_end = 5.0;
  std::vector<Configuration> states;
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    scene.mode = mode;
    Simulator sim(scene, SimulationOptions{});
    const SimulationResult drive = sim.Run();
    ASSERT_TRUE(drive.success()) << drive.stop_reason;
    for (size_t k = 0; k < drive.samples.size(); k += 5)
      states.push_back(drive.samples[k].theta);
  }
  scene.mode = ActuationMode::kPvc;  // mixed states: warm and cold paths
  struct Answers {
    std::vector<QuasiStaticStatus> status;
    std::vector<Eigen::VectorXd> z;
  };
  // Each call builds its own model (KinematicModel caches per instance).
  auto solve_all = [&](Answers* out) {
    Simulator sim(scene, SimulationOptions{});
    QuasiStaticSolver solver(sim.model(),
                             QuasiStaticParameters::FromScene(scene),
                             NlpSolverRegistry::Create(GetParam()));
    QuasiStaticSolution sol;
    for (const Configuration& theta : states) {
      out->status.push_back(solver.Solve(theta, &sol));
      out->z.push_back(sol.z);
    }
  };
  Answers alone, first, second;
  solve_all(&alone);
  std::thread t1(solve_all, &first), t2(solve_all, &second);
  t1.join();
  t2.join();
  int ok = 0;
  for (size_t k = 0; k < states.size(); ++k) {
    ok += alone.status[k] == QuasiStaticStatus::kOk;
    for (const Answers* a : {&first, &second}) {
      EXPECT_EQ(a->status[k], alone.status[k]) << "state " << k;
      EXPECT_TRUE(a->z[k].size() == alone.z[k].size() &&
                  (a->z[k].array() == alone.z[k].array()).all())
          << "state " << k << " differs from the sequential solve";
    }
  }
  EXPECT_GE(ok, static_cast<int>(states.size()) / 2) << "too few solves";
}

// Every accepted solve carries the KKT residual NlpSolver::Solve() recomputed
// (core/nlp.h). The equality system is square and regular at the roots, so
// least-squares equality multipliers make grad f + J^T lambda vanish: the
// residual is round-off whatever the backend (no backend returns non-KKT
// points here; the check bites on problems with degrees of freedom).
TEST_P(QuasiStaticBackends, AcceptedSolvesCarryTheirKktResidual) {
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    const Scenario s =
        MakeSetup(std::make_shared<PlaneTerrain>(0.0), mode, 0.0,
                  {0.2, 0, 0, 0, 0, 0}, {0, 0.6, 0, 0.6, 0, 0.6});
    const QuasiStaticSolution sol = Solve(s);
    ASSERT_EQ(sol.status, QuasiStaticStatus::kOk) << sol.message;
    // Round-off of r = grad f + J^T lambda relative to s_d (O(1) terms,
    // n <= 18): far below 1e-12.
    EXPECT_LE(sol.kkt_residual, 1e-12) << GetParam() << " " << ToString(mode);
  }
}

// What a client sees when Solve() downgrades a claimed convergence
// (kNotOptimal): never OK; with mu > mu_min the solve is an honest
// SOLVER_FAILURE naming the NLP status.
class NotOptimalBackend final : public NlpSolver {
 public:
  std::string name() const override { return "not-optimal"; }

 private:
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override {
    newton_->Solve(problem, x0, options, result);
    result->backend = name();
    result->status = NlpStatus::kNotOptimal;
    result->backend_status += " [claimed convergence rejected: KKT residual]";
  }
  std::unique_ptr<NlpSolver> newton_ = NlpSolverRegistry::Create("newton");
};

TEST(QuasiStaticSolver, DowngradedSolveIsSolverFailure) {
  RegisterBuiltinNlpSolvers();
  const Scenario s =
      MakeSetup(std::make_shared<PlaneTerrain>(0.0), ActuationMode::kPaper, 0.0,
                {0, 0, 0, 0, 0, 0}, {0, 0.6, 0, 0.6, 0, 0.6});
  QuasiStaticSolver solver(*s.model, s.params,
                           std::make_unique<NotOptimalBackend>());
  QuasiStaticSolution sol;
  EXPECT_EQ(solver.Solve(s.theta, &sol), QuasiStaticStatus::kSolverFailure)
      << sol.message;
  EXPECT_EQ(sol.nlp_status, NlpStatus::kNotOptimal);
  EXPECT_NE(sol.message.find("not_optimal"), std::string::npos) << sol.message;
  EXPECT_TRUE(std::isnan(sol.kkt_residual));
  // Flat ground, mu = 0.5 > mu_min = 0: not a friction limit.
  EXPECT_LT(sol.mu_min, s.params.mu);
}

// Refine (the switch-location probes, model.md §7.3): from an accepted
// root to a tighter residual. Every backend either reaches it (then the
// residual meets it and the solution stays within the first solve's
// tolerance, scaled by the condition number; newton must reach it) or
// leaves the solution as it was; a looser tolerance or a failed solve is
// not attempted.
TEST_P(QuasiStaticBackends, RefineTightensTheResidualOrLeavesTheSolution) {
  const Scenario s = OneBumpPaperScenario();
  QuasiStaticSolver solver(*s.model, s.params,
                           NlpSolverRegistry::Create(GetParam()));
  QuasiStaticSolution sol;
  if (solver.Solve(s.theta, &sol) != QuasiStaticStatus::kOk)
    GTEST_SKIP() << GetParam() << ": " << sol.message;
  const QuasiStaticSolution first = sol;
  EXPECT_FALSE(solver.Refine(1e-12, &sol));  // not tighter
  EXPECT_EQ((sol.z - first.z).norm(), 0.0);
  const bool refined = solver.Refine(1e-14, &sol);
  // Newton's quadratic convergence reaches it in one or two iterations.
  if (GetParam() == "newton") {
    EXPECT_TRUE(refined);
  }
  if (refined) {
    EXPECT_LE(sol.residual, 1e-14);
    EXPECT_EQ(sol.status, QuasiStaticStatus::kOk);
    // Condition number (~1.2e7 for creeping paper-mode states) x 1e-12.
    EXPECT_LT((sol.z - first.z).lpNorm<Eigen::Infinity>(), 1.2e7 * 1e-12);
  } else {
    EXPECT_EQ((sol.z - first.z).norm(), 0.0);
    EXPECT_EQ(sol.residual, first.residual);
  }
  EXPECT_GT(sol.nlp_solves, first.nlp_solves);
  QuasiStaticSolution failed = first;
  failed.status = QuasiStaticStatus::kSolverFailure;
  EXPECT_FALSE(solver.Refine(1e-14, &failed));
}

INSTANTIATE_TEST_SUITE_P(AllBackends, QuasiStaticBackends,
                         ::testing::ValuesIn(BuiltinNlpBackendNames()),
                         testing_util::ParamName());

}  // namespace
}  // namespace quasiroll
