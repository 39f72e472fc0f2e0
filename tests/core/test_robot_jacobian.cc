// The robot ODE's Jacobian dF/dTheta (model.md §8.9; Simulator::ProbeOde)
// against central differences of its right-hand side, in both couplings,
// on the paper, incline10 and bumpy scenes; and the implicit integrators
// with jacobian=ift against jacobian=fd on the paper scene (coupled).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/reference.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/simulator.h"
#include "tests/core/simulation_support.h"
#include "tests/heap_counter.h"

namespace quasiroll {
namespace {

using Matrix21 = Eigen::Matrix<double, kConfigSize, kConfigSize>;

// An independent evaluation of F: the twist held (zoh) or re-solved tightly
// and polished at Theta (coupled), then the kinematics.
class ReferenceRhs {
 public:
  ReferenceRhs(const Scene& scene, const KinematicModel& model)
      : model_(model),
        solver_(model, QuasiStaticParameters::FromScene(scene),
                NlpSolverRegistry::Create("newton"), [] {
                  QuasiStaticOptions o;
                  o.residual_tolerance = 1e-14;
                  return o;
                }()) {}

  bool Twist(const Configuration& theta, Vec12* w) {
    QuasiStaticSolution sol;
    if (solver_.Solve(theta, &sol) != QuasiStaticStatus::kOk) return false;
    *w = solver_.problem().JointSpaceVelocity(Polish(solver_.problem(), sol.z));
    return true;
  }
  // coupled: w re-solved at theta; zoh: `held`.
  bool F(const Configuration& theta, const Vec12* held, Configuration* f) {
    Vec12 w;
    if (held) {
      w = *held;
    } else if (!Twist(theta, &w)) {
      return false;
    }
    return model_.Rhs(theta, w, f);
  }

 private:
  const KinematicModel& model_;
  QuasiStaticSolver solver_;
};

// Central differences with h_k = rel max(1, |theta_k|) at rel and rel / 2,
// Richardson-extrapolated (truncation O(h^4)).
bool DifferenceJacobian(ReferenceRhs* ref, const Configuration& theta,
                        const Vec12* held, double rel, Matrix21* out) {
  Matrix21 d[2];
  for (int r = 0; r < 2; ++r) {
    for (int k = 0; k < kConfigSize; ++k) {
      const double h =
          (r == 0 ? rel : rel / 2) * std::max(1.0, std::abs(theta(k)));
      Configuration tp = theta, tm = theta, fp, fm;
      tp(k) += h;
      tm(k) -= h;
      if (!ref->F(tp, held, &fp) || !ref->F(tm, held, &fm)) return false;
      d[r].col(k) = (fp - fm) / (tp(k) - tm(k));
    }
  }
  *out = (4 * d[1] - d[0]) / 3;
  return true;
}

// Norm of the comparison: the largest entry error relative to the largest
// entry, max_ij |J - R| / max_ij |R|.
double RelativeMaxError(const Matrix21& j, const Matrix21& r) {
  return (j - r).cwiseAbs().maxCoeff() / r.cwiseAbs().maxCoeff();
}

// Tolerance 1e-6 (the target). Origin: the reference's step 5e-6
// with Richardson extrapolation leaves truncation ~h^4 (negligible); its
// round-off is the solves' error divided by h, ~cond(J_E) eps_mach / h
// ~1e-7 after polishing (coupled; tests/core/test_sensitivity.cc measures
// that floor for dw/dTheta), ~eps_mach / h ~ 4e-11 for the kinematics alone
// (zoh). The Jacobian's own error is ~eps_mach^(2/3) ~ 4e-11 (central
// differences of the kinematics at h = cbrt(eps_mach), IFT sensitivities,
// core/sensitivity.h) plus the IFT's error from the run's solve tolerance.
constexpr double kReferenceStep = 5e-6;
constexpr double kJacobianTolerance = 1e-6;

struct Case {
  std::string name;
  Scene scene;
};

std::vector<Case> Cases() {
  return {{"paper", SceneFile("paper")},
          {"incline10", SceneFile("incline10")},
          {"bumpy", BumpyScene()}};
}

TEST(RobotJacobian, AgreesWithCentralDifferencesOfRhs) {
  for (const Case& c : Cases()) {
    for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
      SimulationOptions options =
          BuiltinOptions("rk-projection", coupling, 0.05);
      Simulator sim(c.scene, options);
      // The initial state and one 0.5 s into the run.
      SimulationResult run;
      sim.Begin(sim.initial_configuration(), &run);
      for (int k = 0; k < 10 && sim.Advance(&run); ++k) {
      }
      ASSERT_GE(run.samples.size(), 10u) << c.name << ": " << run.stop_reason;
      const std::vector<Configuration> states = {sim.initial_configuration(),
                                                 run.samples.back().theta};
      const KinematicModel& model = sim.model();
      ReferenceRhs ref(c.scene, model);
      for (std::size_t s = 0; s < states.size(); ++s) {
        const Configuration& theta = states[s];
        const std::string where =
            c.name + " " + ToString(coupling) + " state " + std::to_string(s);
        const RobotOdeProbe probe = sim.ProbeOde(theta, theta);
        ASSERT_TRUE(probe.rhs_ok) << where;
        ASSERT_TRUE(probe.jacobian_ok) << where;
        Vec12 held;
        const bool zoh = coupling == Coupling::kZoh;
        ASSERT_TRUE(ref.Twist(theta, &held)) << where;
        // The probe evaluates the same F as the reference.
        Configuration f;
        ASSERT_TRUE(ref.F(theta, zoh ? &held : nullptr, &f)) << where;
        EXPECT_LE((probe.rhs - f).lpNorm<Eigen::Infinity>(),
                  1e-8 * f.lpNorm<Eigen::Infinity>())
            << where;
        Matrix21 reference;
        ASSERT_TRUE(DifferenceJacobian(&ref, theta, zoh ? &held : nullptr,
                                       kReferenceStep, &reference))
            << where;
        const double error = RelativeMaxError(probe.jacobian, reference);
        EXPECT_LE(error, kJacobianTolerance) << where;
        // coupled: the Jacobian reuses the Rhs's solve (one solve, however
        // many NLP attempts it took, for both).
        if (!zoh) {
          EXPECT_LE(probe.nlp_solves, 2) << where;
        }
        std::printf("%s: relative max error %.2e (|J|max %.3g)\n",
                    where.c_str(), error, reference.cwiseAbs().maxCoeff());
      }
    }
  }
}

// Once warmed up, evaluating the Jacobian allocates nothing (RobotOde's
// workspaces are preallocated, the analyzer's after its first call): a
// probe at a new state (coupled: a new solve, then the Jacobian reusing it).
TEST(RobotJacobian, NoAllocationAfterWarmUp) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer owns operator new";
#endif
  for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
    Simulator sim(PaperScene(),
                  BuiltinOptions("rk-projection", coupling, 0.05));
    const Configuration theta = sim.initial_configuration();
    ASSERT_TRUE(sim.ProbeOde(theta, theta).jacobian_ok);
    Configuration moved = theta;
    moved(ConfigIndex::kTheta + 1) += 1e-3;  // alpha1: wheel 1 rolled on
    const long long before = testing_util::g_heap_allocations.load();
    const RobotOdeProbe probe = sim.ProbeOde(moved, moved);
    const long long allocations =
        testing_util::g_heap_allocations.load() - before;
    EXPECT_TRUE(probe.jacobian_ok) << ToString(coupling);
    EXPECT_EQ(allocations, 0) << ToString(coupling);
  }
}

// At an inequality about to become active the derivative is one-sided
// (core/sensitivity.h): RhsJacobian returns false and counts the fallback.
// pvc on the 10 degree incline at mu = mu_min (1 + 1e-9): the critical
// wheel's friction cone slack is ~1e-11 (tests/core/test_sensitivity.cc).
TEST(RobotJacobian, OneSidedPointFallsBack) {
  Scene scene = SceneFile("incline10");
  Simulator probe_sim(
      scene, BuiltinOptions("rk-projection", Coupling::kCoupled, 0.05));
  const Configuration theta = probe_sim.initial_configuration();
  QuasiStaticProblem problem(probe_sim.model(),
                             QuasiStaticParameters::FromScene(scene));
  problem.SetConfiguration(theta);
  int critical = -1;
  const double mu_min = problem.MinimumFriction(&critical, nullptr);
  ASSERT_GT(mu_min, 0.3);
  for (double margin : {1e-2, 1e-9}) {
    scene.mu = mu_min * (1 + margin);
    Simulator sim(scene,
                  BuiltinOptions("rk-projection", Coupling::kCoupled, 0.05));
    const RobotOdeProbe probe = sim.ProbeOde(theta, theta);
    ASSERT_TRUE(probe.rhs_ok) << margin;
    EXPECT_EQ(probe.jacobian_ok, margin > 1e-3) << margin;
    EXPECT_EQ(probe.jacobian_fallbacks, margin > 1e-3 ? 0 : 1) << margin;
  }
}

// y' = -diag(1, 2, 3, 4) y whose RhsJacobian succeeds on odd calls only:
// the integrators difference Rhs for the other evaluations (per call) and
// still converge; with jacobian=fd they never ask.
class FlakyJacobianOde final : public ConstrainedOde {
 public:
  int state_size() const override { return 4; }
  int num_constraints() const override { return 0; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    ydot = -Rates().cwiseProduct(y);
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd>) const override {}
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd>) const override {}
  bool RhsJacobian(double, const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::MatrixXd> dfdy) override {
    if (++calls % 2 == 0) return false;
    dfdy = -Rates().asDiagonal().toDenseMatrix();
    return true;
  }
  static Eigen::Vector4d Rates() { return Eigen::Vector4d(1, 2, 3, 4); }
  int calls = 0;
};

TEST(RobotJacobian, IntegratorsFallBackPerEvaluation) {
  RegisterBuiltinIntegrators();
  for (const std::string name : {"ida", "cvode-projection"}) {
    if (!IntegratorRegistry::Has(name)) GTEST_SKIP() << "no SUNDIALS";
    for (const char* mode : {"ift", "fd"}) {
      std::unique_ptr<Integrator> integrator = IntegratorRegistry::Create(name);
      GivenOptions given = {{"jacobian", mode}};
      // cvode-projection uses dF/dy with Newton only (its default is the
      // fixed-point iteration).
      if (name == "cvode-projection") given["nonlinear_solver"] = "newton";
      integrator->SetBackendOptions(given);
      FlakyJacobianOde ode;
      Eigen::VectorXd y = Eigen::VectorXd::Ones(4);
      IntegratorOptions options;
      IntegratorResult result;
      ASSERT_EQ(integrator->Integrate(ode, 0.0, 2.0, y, options, &result),
                IntegratorStatus::kSuccess)
          << name << " " << mode << ": " << result.message;
      const Eigen::Vector4d exact =
          (-2.0 * FlakyJacobianOde::Rates()).array().exp();
      EXPECT_LT((y - exact).lpNorm<Eigen::Infinity>(), 1e-6)
          << name << " " << mode;
      if (std::string(mode) == "fd") {
        EXPECT_EQ(ode.calls, 0) << name;
      } else {
        EXPECT_GE(ode.calls, 4) << name;  // both branches taken
      }
    }
  }
}

// Invalid values of the backend option are std::invalid_argument naming the
// option and the value.
TEST(RobotJacobian, InvalidJacobianOptionThrows) {
  RegisterBuiltinIntegrators();
  for (const std::string name : {"ida", "cvode-projection"}) {
    if (!IntegratorRegistry::Has(name)) GTEST_SKIP() << "no SUNDIALS";
    std::unique_ptr<Integrator> integrator = IntegratorRegistry::Create(name);
    try {
      integrator->SetBackendOptions({{"jacobian", "foo"}});
      ADD_FAILURE() << name << ": no exception";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("jacobian"), std::string::npos) << what;
      EXPECT_NE(what.find("foo"), std::string::npos) << what;
    }
    integrator->SetBackendOptions({{"jacobian", "fd"}});
    EXPECT_EQ(integrator->backend_options().GetString("jacobian"), "fd");
    integrator->SetBackendOptions({});
    EXPECT_EQ(integrator->backend_options().GetString("jacobian"), "ift");
  }
}

// Max over t = 0.4 k of |COM position a - b| [m] (as
// tests/core/test_switch_events.cc).
double PathError(const SimulationResult& a, const SimulationResult& b) {
  double worst = 0;
  for (const TrajectorySample& x : a.samples) {
    const double k = x.t / 0.4;
    if (std::abs(k - std::round(k)) > 1e-9) continue;
    for (const TrajectorySample& y : b.samples)
      if (std::abs(y.t - x.t) < 1e-9)
        worst = std::max(worst, (x.position - y.position).norm());
  }
  return worst;
}

// ida and cvode-projection on the whole 20 s paper scene, coupled, rtol
// 1e-8, dt 0.05: with the exact Jacobian (ift) the run is as accurate
// against the reference as with differences (fd), and costs far fewer
// right-hand sides (each one an NLP solve): fd spends 21 + 1 per Jacobian.
// The reference is the one the harness computes for this scene
// (bench::ComputeNumericalReference: coupled RK4 at 0.003125 s, newton at
// residual 1e-12, with the retry ladder). A dp54 run at rtol 1e-12 was used
// before: its error control asks for less than the NLP's residual floor at
// the first switch (2.907 s, ~1.5e-11), and a round-off-level change of the
// contact velocities made it stop there.
TEST(RobotJacobian, ImplicitIntegratorsWithIftMatchFdWithFewerRhs) {
  RegisterBuiltinIntegrators();
  if (!IntegratorRegistry::Has("ida")) GTEST_SKIP() << "no SUNDIALS";
  const Scene scene = PaperScene();
  const SimulationResult ref =
      bench::ComputeNumericalReference(scene, bench::ReferenceSettings{});
  ASSERT_TRUE(ref.success()) << ref.stop_reason;
  for (const std::string name : {"ida", "cvode-projection"}) {
    SimulationResult r[2];
    const char* modes[2] = {"ift", "fd"};
    for (int m = 0; m < 2; ++m) {
      SimulationOptions o = BuiltinOptions(name, Coupling::kCoupled, 0.05);
      o.dae_options["jacobian"] = modes[m];
      // Per evaluation: the reuse across matrix updates (default 0.01)
      // spares most evaluations of either kind.
      o.dae_options["jacobian_reuse"] = "0";
      // cvode-projection: its Newton configuration (dF/dy is used with
      // Newton only; the measured values below are BDF's).
      if (name == "cvode-projection") {
        o.dae_options["lmm"] = "bdf";
        o.dae_options["nonlinear_solver"] = "newton";
        o.dae_options["restart_step"] = "given";
        o.dae_options["eta_max_early"] = "10";
      }
      r[m] = Simulator(scene, o).Run();
      ASSERT_TRUE(r[m].success())
          << name << " " << modes[m] << ": " << r[m].stop_reason;
      ASSERT_EQ(r[m].dae_options.GetString("jacobian"), modes[m]);
    }
    const double e_ift = PathError(r[0], ref), e_fd = PathError(r[1], ref);
    const double apart = PathError(r[0], r[1]);
    std::printf(
        "%s: error ift %.3e fd %.3e m, ift-fd %.3e m; rhs %lld vs %lld, "
        "jacobians %lld vs %lld, steps %d vs %d\n",
        name.c_str(), e_ift, e_fd, apart, r[0].rhs_evaluations,
        r[1].rhs_evaluations, r[0].jacobian_evaluations,
        r[1].jacobian_evaluations, r[0].steps, r[1].steps);
    // Error no worse than with differences (up to the rtol-level scatter
    // of two step sequences), the two trajectories apart by far less than
    // their error against the reference (measured 2026-11-27: ida 1.277e-8
    // vs 1.283e-8 m, 8.3e-10 apart; cvode-projection 1.440e-6 m both,
    // 1.6e-10 apart), and within each method's rtol 1e-8 level.
    EXPECT_LE(e_ift, 1.5 * e_fd + 1e-9) << name;
    EXPECT_LT(apart, 0.25 * e_fd) << name;
    EXPECT_LT(e_ift, name == "ida" ? 3e-8 : 3e-6) << name;
    // Far fewer right-hand sides (measured 4.1x and 3.6x fewer).
    EXPECT_LT(3 * r[0].rhs_evaluations, r[1].rhs_evaluations) << name;
  }
}

}  // namespace
}  // namespace quasiroll
