// The harness's verdict columns (docs/harness.md): timing statistics over
// repeats, the quasi-static validity ratio on a trajectory with a known
// acceleration, and the failure-cause classification on hand-made evidence.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>

#include "quasiroll/bench/harness/failure_causes.h"
#include "quasiroll/bench/harness/metrics.h"
#include "quasiroll/bench/harness/reference.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll::bench {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::string kScenes =
    std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/";

TEST(TimingStats, MinMedianMaxOverRepeats) {
  TimingStats t = ComputeTimingStats({0.3, 0.1, 0.2});
  EXPECT_EQ(t.min, 0.1);
  EXPECT_EQ(t.median, 0.2);
  EXPECT_EQ(t.max, 0.3);
  t = ComputeTimingStats({0.4, 0.1, 0.2, 0.3});  // even count: middle mean
  EXPECT_DOUBLE_EQ(t.median, 0.25);
  EXPECT_TRUE(std::isnan(ComputeTimingStats({}).median));
}

// Quartiles by type-7 interpolation, values checked against
// numpy.percentile([...], [25, 75]) (linear method, its default).
TEST(TimingStats, QuartilesInterpolateBetweenOrderStatistics) {
  // n = 5: positions 1 and 3 fall on order statistics: 0.2 and 0.4.
  TimingStats t = ComputeTimingStats({0.5, 0.1, 0.4, 0.2, 0.3});
  EXPECT_DOUBLE_EQ(t.q1, 0.2);
  EXPECT_DOUBLE_EQ(t.q3, 0.4);
  // n = 4: positions 0.75 and 2.25: 1 + 0.75 * (2 - 1) = 1.75, 3 + 0.25 * 7.
  t = ComputeTimingStats({10.0, 1.0, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(t.q1, 1.75);
  EXPECT_DOUBLE_EQ(t.q3, 4.75);
  // One repeat: no spread.
  t = ComputeTimingStats({0.7});
  EXPECT_EQ(t.q1, 0.7);
  EXPECT_EQ(t.q3, 0.7);
  EXPECT_TRUE(std::isnan(ComputeTimingStats({}).q3));
}

// Oracle O2 (the constant-steer circle, paper mode): the COM moves on a
// circle at constant speed v with yaw rate Omega, contact forces are the
// static load (sum |F_i| = m g, no traction). The only inertial load is the
// centripetal m v Omega; the rotation is about the principal z axis at
// constant rate (I alpha = 0, omega x I omega = 0). The one-sided difference
// at the first sample gives |v(h) - v(0)| / h = v Omega sinc(Omega h / 2),
// the largest estimate along the path (central ones give sinc(Omega h)).
TEST(QuasiStaticValidity, CircleRatioIsCentripetalOverWeight) {
  Scene scene = LoadScene(kScenes + "circle.yaml");
  const YAML::Node root = yaml::LoadYamlFile(kScenes + "circle.yaml");
  const TerrainSpec spec =
      yaml::ReadTerrainSpec(root["terrain"], "terrain", kScenes);
  ASSERT_EQ(DetectAnalyticCase(scene, spec), AnalyticCase::kCircle);
  const AnalyticSolution circle(scene, spec, AnalyticCase::kCircle);
  const double h = 0.05;
  std::vector<TrajectorySample> run;
  for (int k = 0; k <= 200; ++k) run.push_back(circle.Sample(k * h));
  const double v = run[0].velocity.norm();
  const double omega = run[0].angular_velocity.z();
  ASSERT_GT(v, 0.06);  // 0.0622 m/s: Omega R_com, R_com = 0.9488 m
  const double x = omega * h / 2;
  const double expected =
      scene.mass * v * omega * (std::sin(x) / x) / (scene.mass * 9.8);
  // Round-off of differences of O(0.06) velocities over h: ~1e-15 / 0.05.
  EXPECT_NEAR(QuasiStaticInertiaRatio(run, scene), expected, 1e-12);
  EXPECT_NEAR(expected, 4.16e-4, 1e-6);  // v Omega / g
}

// A pure roll acceleration alpha about the platform's x axis (principal, so
// omega x I omega = 0): the ratio is I_xx alpha / L0 / load, with I_xx of
// the documented box estimate m/12 (track^2 + (z_h + rho)^2).
TEST(QuasiStaticValidity, RotationalInertiaEntersThroughTheMomentScale) {
  const Scene scene = LoadScene(kScenes + "flat.yaml");
  const double alpha = 0.2, h = 0.05, load = 49.0;
  std::vector<TrajectorySample> run;
  for (int k = 0; k <= 10; ++k) {
    TrajectorySample s;
    s.t = k * h;
    s.angular_velocity = Vec3(alpha * s.t, 0, 0);
    for (ContactSample& c : s.contacts) c.normal_force = load / 3;
    run.push_back(s);
  }
  const RobotGeometry& g = scene.geometry;
  const double height = g.z_h + g.rho();
  const double ixx = scene.mass / 12 * (g.track * g.track + height * height);
  EXPECT_DOUBLE_EQ(EstimatedInertia(scene).x(), ixx);
  EXPECT_NEAR(QuasiStaticInertiaRatio(run, scene),
              ixx * alpha / g.wheelbase() / load, 1e-15);
  // A failed last sample (NaN velocities) is skipped, not propagated.
  run.back().velocity = Vec3::Constant(kNaN);
  EXPECT_NEAR(QuasiStaticInertiaRatio(run, scene),
              ixx * alpha / g.wheelbase() / load, 1e-15);
  run.resize(1);
  EXPECT_TRUE(std::isnan(QuasiStaticInertiaRatio(run, scene)));
}

// What the integrator's BackendInfo knows a priori about a fixed-step RK4
// run of `dae` with Baumgarte gain `sigma` (where it has one) at `step`.
std::string KnownInstability(const std::string& dae, double sigma,
                             double step) {
  RegisterBuiltinIntegrators();
  std::unique_ptr<Integrator> integrator = IntegratorRegistry::Create(dae);
  GivenOptions given;
  const OptionTable table = integrator->option_table();
  if (FindOption(table, "baumgarte_sigma"))
    given["baumgarte_sigma"] = std::to_string(sigma);
  if (FindOption(table, "rk_method")) given["rk_method"] = "rk4";
  integrator->SetBackendOptions(given);
  return IntegratorRegistry::Info(dae).KnownInstability(
      integrator->backend_options(), step);
}

// Evidence of a paper-scene run (dt 0.05, RK4) against a reference on the
// dt/4 grid that reached `ref_t` with `ref_status`.
FailureEvidence Evidence(const std::string& status, double t_reached,
                         const std::string& ref_status, double ref_t) {
  FailureEvidence e;
  e.status = ParseRunStatus(status).value();
  e.t_reached = t_reached;
  e.dt = 0.05;
  e.known_instability = KnownInstability("rk-projection", 5, 0.05);
  e.drift_max = 1e-12;
  e.gap_max = 1e-13;
  e.drift_bound = e.gap_bound = 1e-3;
  e.has_reference = true;
  e.ref_status = ParseRunStatus(ref_status);
  e.ref_t_reached = ref_t;
  e.ref_dt = 0.0125;
  return e;
}

TEST(FailureCauses, SuccessHasNoCause) {
  const FailureCause c =
      ClassifyFailure(Evidence("success", 20, "success", 20));
  EXPECT_EQ(c.cause, "");
  EXPECT_EQ(c.detail, "");
}

// A friction stop where the reference stops too (pvc at mu 0.3 on R1: the
// run at 14.30 s, the reference at 14.2625 s) is physical.
TEST(FailureCauses, FrictionStopShared) {
  FailureCause c = ClassifyFailure(
      Evidence("INFEASIBLE_FRICTION", 14.30, "INFEASIBLE_FRICTION", 14.2625));
  EXPECT_EQ(c.cause, "physical");
  EXPECT_EQ(c.detail, "friction_limit");
  c = ClassifyFailure(Evidence("LIFT_OFF", 3.0, "LIFT_OFF", 3.0));
  EXPECT_EQ(c.detail, "lift_off");
  // The sampled second-contact check (every 5 samples) detects 0.25 s late
  // at worst: still the same place.
  FailureEvidence sampled =
      Evidence("DEGENERATE_CONTACT", 17.35, "DEGENERATE_CONTACT", 17.146875);
  EXPECT_EQ(ClassifyFailure(sampled).cause, "numerical");
  sampled.contact_check = 5;
  EXPECT_EQ(ClassifyFailure(sampled).cause, "physical");
  // Same status, but 0.5 s (10 intervals) before the reference's stop: the
  // run left the path; the cause is the method's.
  c = ClassifyFailure(
      Evidence("INFEASIBLE_FRICTION", 13.75, "INFEASIBLE_FRICTION", 14.2625));
  EXPECT_EQ(c.cause, "numerical");
}

// A run that goes past its reference's physical stop stepped over the
// limit (docs/model.md §8.6): the dip of tests/core/test_limit_events.cc,
// where zoh at dt 0.05 used to reach t_end although the reference stops
// on the relative-curvature limit at 3.39 s. Never a success, whatever it
// stops on later; within the same-place tolerance the stop is shared.
TEST(FailureCauses, PassingThePhysicalStopIsAMissedEvent) {
  struct Case {
    const char* status;
    double t_reached;
    const char* ref_status;
    const char* cause;
    const char* detail;
  };
  // Reference stop at 3.3906 s, same-place tolerance 0.1 s here.
  for (const Case& k : std::initializer_list<Case>{
           // Reaching t_end past it, or stopping 0.17 s (more than two
           // intervals) after it: missed.
           {"success", 4.0, "DEGENERATE_CONTACT", "numerical", "missed_event"},
           {"DEGENERATE_CONTACT", 3.5586, "DEGENERATE_CONTACT", "numerical",
            "missed_event"},
           {"rhs_failure", 3.5586, "INFEASIBLE_FRICTION", "numerical",
            "missed_event"},
           // Within the tolerance: the same stop, physical.
           {"DEGENERATE_CONTACT", 3.45, "DEGENERATE_CONTACT", "physical",
            "degenerate_contact"},
           // Stopping before it is not a missed event; nor is passing a
           // reference that stopped for a numerical reason (reference_stop
           // reference_failure: SOLVER_FAILURE, SINGULAR or an integrator
           // status left after the retry ladder, bench/harness/
           // reference_retry.h).
           {"DEGENERATE_CONTACT", 2.0, "DEGENERATE_CONTACT", "numerical",
            "step_too_large"},
           {"success", 4.0, "SOLVER_FAILURE", "", ""},
           {"success", 4.0, "SINGULAR", "", ""},
           {"success", 4.0, "rhs_failure", "", ""},
           {"LIFT_OFF", 3.9, "step_size_too_small", "numerical",
            "step_too_large"}}) {
    const FailureCause c =
        ClassifyFailure(Evidence(k.status, k.t_reached, k.ref_status, 3.3906));
    EXPECT_EQ(c.cause, k.cause) << k.status << " at " << k.t_reached;
    EXPECT_EQ(c.detail, k.detail) << k.status << " at " << k.t_reached;
  }
  // A blow-up keeps its root cause.
  FailureEvidence e = Evidence("drift_exceeded", 4.0, "LIFT_OFF", 3.0);
  e.drift_max = 0.5;
  EXPECT_EQ(ClassifyFailure(e).detail, "drift_blowup");
}

// The default suite's stability_dt blow-up: rk-baumgarte, zoh, dt 3.2 s,
// sigma 5 (sigma h = 16 > 2.785) stops at 3.2 s with INFEASIBLE_FRICTION and
// mu_min 4.1 while the reference drives on: never a friction limit.
TEST(FailureCauses, BlowUpIsNeverAFrictionLimit) {
  FailureEvidence e = Evidence("INFEASIBLE_FRICTION", 3.2, "success", 20.0);
  e.dt = 3.2;
  e.known_instability = KnownInstability("rk-baumgarte", 5, 3.2);
  e.drift_max = 0.74;
  e.gap_max = 0.37;
  FailureCause c = ClassifyFailure(e);
  EXPECT_EQ(c.cause, "numerical");
  EXPECT_EQ(c.detail, "baumgarte_instability");
  // Within RK4's bound the drift is the evidence ...
  e.known_instability = KnownInstability("rk-baumgarte", 0.5, 3.2);  // 1.6
  EXPECT_EQ(ClassifyFailure(e).detail, "drift_blowup");
  e.drift_max = 1e-6;
  EXPECT_EQ(ClassifyFailure(e).detail, "gap_blowup");
  // ... and without any, the hold interval that left the path.
  e.gap_max = 1e-6;
  EXPECT_EQ(ClassifyFailure(e).detail, "step_too_large");
  // Projection has no Baumgarte term: sigma does not matter there.
  e.known_instability = KnownInstability("rk-projection", 200, 3.2);
  EXPECT_EQ(ClassifyFailure(e).detail, "step_too_large");
  // No reference: the solver's verdict stands unless the method's own
  // evidence contradicts it.
  e.has_reference = false;
  EXPECT_EQ(ClassifyFailure(e).cause, "physical");
  e.drift_max = 0.74;
  EXPECT_EQ(ClassifyFailure(e).cause, "numerical");
}

// stability.yaml on R1 at roughness 12: every method and the reference stop
// on the friction limit at 2.55 s after a motion whose inertia ratio reaches
// 0.15, fifteen times the 0.01 bound; the stop is the model's, not the
// method's or a physical limit the model can vouch for.
TEST(FailureCauses, StopBeyondQuasiStaticValidityIsTheModels) {
  FailureEvidence e =
      Evidence("INFEASIBLE_FRICTION", 2.55, "INFEASIBLE_FRICTION", 2.55);
  e.qs_inertia_bound = 0.01;
  EXPECT_EQ(ClassifyFailure(e).cause, "physical");  // NaN: unknown
  e.qs_inertia_ratio = 0.009;
  EXPECT_EQ(ClassifyFailure(e).cause, "physical");
  e.qs_inertia_ratio = 0.15;
  FailureCause c = ClassifyFailure(e);
  EXPECT_EQ(c.cause, "model");
  EXPECT_EQ(c.detail, "quasi_static_invalid");
  // Whatever the status: a solver that gives up in that motion too.
  e.status = RunStatus::kSolverFailure;
  EXPECT_EQ(ClassifyFailure(e).detail, "quasi_static_invalid");
  // A run that blew up made its own violent motion: the other rules judge
  // it, as if the validity were unknown.
  auto without_validity = [](FailureEvidence x) {
    x.qs_inertia_ratio = kNaN;
    return ClassifyFailure(x);
  };
  e.status = RunStatus::kInfeasibleFriction;
  e.ref_status = RunStatus::kSuccess;
  e.ref_t_reached = 20;
  e.drift_max = 0.5;
  c = ClassifyFailure(e);
  EXPECT_EQ(c.cause, "numerical");
  EXPECT_EQ(c.detail, without_validity(e).detail);
  EXPECT_EQ(c.detail, "drift_blowup");
  e.drift_max = 1e-12;
  e.known_instability = "baumgarte_instability";
  EXPECT_EQ(ClassifyFailure(e).detail, "baumgarte_instability");
  // Successes and errors keep theirs.
  e.known_instability.clear();
  e.status = RunStatus::kSuccess;
  EXPECT_EQ(ClassifyFailure(e).cause, "");
  e.status = RunStatus::kError;
  EXPECT_EQ(ClassifyFailure(e).detail, "error");
}

// A stop where the reference stopped at a breakaway (reference_stop
// model:breakaway: its twist diverges there, model.md §8.8) is the model's
// even when the run's own samples and retry show no fast motion (a solve
// that gave up without a converged retry, or a friction limit the held
// twist reached); elsewhere, or after a blow-up, the other rules judge.
TEST(FailureCauses, StopAtTheReferencesBreakawayIsTheModels) {
  FailureEvidence e =
      Evidence("SOLVER_FAILURE", 5.8456, "SOLVER_FAILURE", 5.845638);
  e.qs_inertia_bound = 0.01;
  e.qs_inertia_ratio = 0.0024;
  EXPECT_EQ(ClassifyFailure(e).detail, "shared_solver_failure");
  e.ref_breakaway = true;
  FailureCause c = ClassifyFailure(e);
  EXPECT_EQ(c.cause, "model");
  EXPECT_EQ(c.detail, "quasi_static_invalid");
  e.status = RunStatus::kInfeasibleFriction;
  e.t_reached = 5.856;
  EXPECT_EQ(ClassifyFailure(e).detail, "quasi_static_invalid");
  e.t_reached = 5.2;  // two output intervals (0.1 s) before: not there
  EXPECT_EQ(ClassifyFailure(e).cause, "numerical");
  e.t_reached = 5.856;
  e.drift_max = 0.5;
  EXPECT_NE(ClassifyFailure(e).cause, "model");
}

TEST(FailureCauses, SolverIntegratorBoundsAndErrors) {
  EXPECT_EQ(
      ClassifyFailure(Evidence("SOLVER_FAILURE", 2.6, "success", 20)).detail,
      "solver_failure");
  // A solver failure stays numerical even where the reference's solver
  // fails too (a solution exists: mu > mu_min; in the default suite ceres
  // passes where newton and the newton reference fail) ...
  const FailureCause shared = ClassifyFailure(
      Evidence("SOLVER_FAILURE", 13.2, "SOLVER_FAILURE", 13.2125));
  EXPECT_EQ(shared.cause, "numerical");
  // ... named apart, so that a chart says the reference failed there too
  // (stability.yaml, R1 at roughness 12: every backend and the reference
  // stop at 2.55 s with mu = 0.5 against mu_min = 0.4965); also when an
  // implicit integrator's residual failed because the NLP did.
  EXPECT_EQ(shared.detail, "shared_solver_failure");
  EXPECT_EQ(
      ClassifyFailure(Evidence("rhs_failure", 2.549, "SOLVER_FAILURE", 2.549))
          .detail,
      "shared_solver_failure");
  EXPECT_EQ(
      ClassifyFailure(Evidence("rhs_failure", 1.0, "SOLVER_FAILURE", 2.549))
          .detail,
      "integrator_failure");
  // ... unless the reference meets a physical limit there.
  EXPECT_EQ(ClassifyFailure(Evidence("SOLVER_FAILURE", 11.5,
                                     "INFEASIBLE_FRICTION", 11.5125))
                .detail,
            "friction_limit");
  // Rank-deficient statics on the reference's path at the same place.
  const FailureCause c =
      ClassifyFailure(Evidence("SINGULAR", 2.6, "SINGULAR", 2.6125));
  EXPECT_EQ(c.cause, "physical");
  EXPECT_EQ(c.detail, "singular_point");
  EXPECT_EQ(
      ClassifyFailure(Evidence("step_size_too_small", 1, "success", 20)).detail,
      "integrator_failure");
  EXPECT_EQ(
      ClassifyFailure(Evidence("drift_exceeded", 20, "success", 20)).detail,
      "drift_blowup");
  EXPECT_EQ(ClassifyFailure(Evidence("gap_exceeded", 20, "success", 20)).detail,
            "gap_blowup");
  // A run that reaches t_end past the drift bound with sigma h = 3 > 2.785
  // (stability.yaml, rk-baumgarte at dt 0.2 s, sigma 15): the root cause.
  FailureEvidence unstable = Evidence("drift_exceeded", 4, "success", 4);
  unstable.dt = 0.2;
  unstable.known_instability = KnownInstability("rk-baumgarte", 15, 0.2);
  unstable.drift_max = 2e-3;
  EXPECT_EQ(ClassifyFailure(unstable).detail, "baumgarte_instability");
  // sigma h = 2.5: stable, the symptom is the cause
  unstable.known_instability = KnownInstability("rk-baumgarte", 12.5, 0.2);
  EXPECT_EQ(ClassifyFailure(unstable).detail, "drift_blowup");
  const FailureCause err =
      ClassifyFailure(Evidence("error", kNaN, "success", 20));
  EXPECT_EQ(err.cause, "numerical");
  EXPECT_EQ(err.detail, "error");
}

}  // namespace
}  // namespace quasiroll::bench
