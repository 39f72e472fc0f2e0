// Located stops (model.md §8.6, core/limit_events.h): the indicators against
// CheckValidity, the Hermite dense output, and limits between two samples
// located against independent values.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/limit_events.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/terrains.h"
#include "simulation_support.h"

namespace quasiroll {
namespace {

// Flat ground with one narrow Gaussian dip (amplitude -4 mm, sigma 15 mm)
// centred on the front wheel's path, 0.2 m ahead of it. Its curvature
// 0.004/0.015^2 = 17.8 1/m at the centre exceeds the wheel's 10 1/m, so
// K_w + r K_g r is indefinite only over the middle ~17 mm of the dip: the
// front wheel reaches the edge of that stretch at ~3.3906 s (driving at
// 0.06 m/s) while a coarse zoh run used to step over it and carry on.
Scene DipScene() {
  const std::string yaml =
      "name: dip\nmode: paper\nmass: 5.0\ngravity: 9.8\nmu: 1.0\n"
      "epsilon: 1.0e-8\njoint_rates: [0, 0.6, 0, 0.6, 0, 0.6]\n"
      "robot: {a: 0.25, b: 0.25, track: 0.4, z_h: 0.05, major_radius: 0.08, "
      "tube_radius: 0.02, camber_offset: 0.0}\n"
      "initial: {x: 0, y: 0, yaw: 0, joint_angles: [0, 0, 0, 0, 0, 0]}\n"
      "time: {t_end: 4, dt: 0.05}\n"
      "terrain: {type: gaussians, bumps: [{amplitude: -0.004, x: 0.45, y: 0, "
      "sigma: 0.015}]}\n";
  return LoadSceneFromString(yaml, "dip");
}

SimulationResult Simulate(const Scene& scene, double dt, bool locate,
                          const std::string& dae = "rk-projection",
                          Coupling coupling = Coupling::kZoh) {
  SimulationOptions o = BuiltinOptions(dae, coupling, dt);
  o.locate_events = locate;
  return Simulator(scene, o).Run();
}

// Distance of t from the nearest output time k dt.
double OffGrid(double t, double dt) {
  return std::abs(t - dt * std::round(t / dt));
}

TEST(LimitEvents, HermiteIsExactForCubics) {
  Configuration a, b, c, d;
  for (int i = 0; i < kConfigSize; ++i) {
    a(i) = 0.1 * i;
    b(i) = -0.3 + 0.01 * i;
    c(i) = 0.7 - 0.02 * i;
    d(i) = 0.05 * i * i;
  }
  const double t0 = 0.3, h = 0.2;
  auto x = [&](double t) -> Configuration {
    const double u = t - t0;
    return a + u * b + u * u * c + u * u * u * d;
  };
  auto xd = [&](double t) -> Configuration {
    const double u = t - t0;
    return b + 2 * u * c + 3 * u * u * d;
  };
  for (double s : {0.0, 0.125, 0.5, 0.9, 1.0}) {
    const Configuration y =
        HermiteState(x(t0), xd(t0), x(t0 + h), xd(t0 + h), h, s);
    EXPECT_LE((y - x(t0 + s * h)).lpNorm<Eigen::Infinity>(), 1e-14) << s;
  }
}

// The indicators flag exactly the states CheckValidity refuses, and the
// curvature margin is the smallest eigenvalue of K_w + r K_g r.
TEST(LimitEvents, IndicatorsAgreeWithCheckValidity) {
  const Scene scene = DipScene();
  const SimulationResult r = Simulate(scene, 0.01, true);
  ASSERT_EQ(r.status, "DEGENERATE_CONTACT") << r.stop_reason;
  KinematicModel model(scene.geometry, scene.terrain);
  int checked = 0;
  for (const TrajectorySample& ts : r.samples) {
    LimitIndicators ind;
    EvaluateLimitIndicators(model, ts.theta, true, &ind);
    const ValidityReport v = CheckValidity(model, ts.theta, true);
    EXPECT_EQ(ind.ok(), v.ok()) << ts.t;
    for (int i = 0; i < 3; ++i) {
      ChainState cs;
      model.EvaluateChain(ts.theta, i, &cs);
      const Mat2 k = cs.wheel.K + cs.r_psi * cs.ground.K * cs.r_psi;
      Eigen::SelfAdjointEigenSolver<Mat2> eig(0.5 * (k + k.transpose()));
      EXPECT_NEAR(ind.relative_curvature[i], eig.eigenvalues()(0), 1e-9);
      EXPECT_NEAR(ind.tread_angle[i],
                  M_PI / 2 - 0.1 - std::abs(ts.theta(ConfigIndex::V(i))),
                  1e-15);
      // (The wheel bridges the dip before the curvature limit: the
      // second-contact clearance turns negative first, with CheckValidity.)
      if (v.contact[i] == ContactValidity::kValid ||
          v.contact[i] == ContactValidity::kSecondContact) {
        EXPECT_EQ(ind.second_contact[i] < 0,
                  v.contact[i] == ContactValidity::kSecondContact)
            << ts.t;
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 300);
}

// Terrain::HessianNormBound bounds ||hess h||_2 everywhere (checked on a
// grid against the eigenvalues of the evaluated Hessian), and is attained
// by a single bump at its centre. Where RelativeCurvatureCertain clears a
// wheel, the evaluated lambda_min of K_w + r K_g r is at least
// lambda_min(K_w) - B > 0 (Weyl, model.md §3.2), and the verdict-only
// indicators name the same violation as the full ones. States: random
// contact coordinates (seeded), tread angles up to the tread limit.
TEST(LimitEvents, CurvatureBoundClearsOnlyWheelsThatPass) {
  auto hessian_norm = [](const Terrain& t, double x, double y) {
    const TerrainJet j = t.EvaluateSecondOrder(x, y);
    Mat2 h;
    h << j.hxx, j.hxy, j.hxy, j.hyy;
    return Eigen::SelfAdjointEigenSolver<Mat2>(h)
        .eigenvalues()
        .cwiseAbs()
        .maxCoeff();
  };
  const GaussianTerrain one({{0.004, 0.3, -0.2, 0.015}});
  EXPECT_DOUBLE_EQ(one.HessianNormBound(), 0.004 / (0.015 * 0.015));
  EXPECT_NEAR(hessian_norm(one, 0.3, -0.2), one.HessianNormBound(), 1e-12);
  const Scene paper = PaperScene(), dip = DipScene(), bumpy = BumpyScene();
  const SinusoidTerrain waves(
      {{0.01, 0.5, 0.8, 0.3, 1.1},
       {0.004, 0.3, std::numeric_limits<double>::infinity(), 0, 0}});
  EXPECT_EQ(PlaneTerrain().HessianNormBound(), 0.0);
  EXPECT_EQ(InclineTerrain(0.2, 0.3).HessianNormBound(), 0.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int certain = 0, evaluated = 0;
  for (const Terrain* t :
       {static_cast<const Terrain*>(&one), paper.terrain.get(),
        dip.terrain.get(), bumpy.terrain.get(),
        static_cast<const Terrain*>(&waves)}) {
    const double bound = t->HessianNormBound();
    for (int k = 0; k < 2000; ++k) {
      const double x = -0.8 + 3.3 * unit(rng), y = -1.3 + 2.6 * unit(rng);
      EXPECT_LE(hessian_norm(*t, x, y), bound * (1 + 1e-12)) << x << " " << y;
    }
  }
  for (const Scene* scene : {&paper, &dip, &bumpy}) {
    const KinematicModel model(scene->geometry, scene->terrain);
    const double bound = scene->terrain->HessianNormBound();
    const RobotGeometry& g = scene->geometry;
    for (int k = 0; k < 3000; ++k) {
      Configuration theta = Configuration::Zero();
      for (int i = 0; i < 3; ++i) {
        const int e = ConfigIndex::Eta(i);
        theta(e) = 2 * M_PI * unit(rng);
        theta(e + 1) = (M_PI / 2 - 0.05) * (2 * unit(rng) - 1);
        theta(e + 2) = 0.2 + 1.0 * unit(rng);
        theta(e + 3) = -0.4 + 0.8 * unit(rng);
        theta(e + 4) = 2 * M_PI * unit(rng);
      }
      LimitIndicators full, verdict;
      EvaluateLimitIndicators(model, theta, false, &full);
      EvaluateLimitIndicators(model, theta, false, &verdict,
                              IndicatorDetail::kVerdict);
      EXPECT_STREQ(full.violated, verdict.violated);
      EXPECT_EQ(full.wheel, verdict.wheel);
      for (int i = 0; i < 3; ++i) {
        const double cv = std::cos(theta(ConfigIndex::Eta(i) + 1));
        const double wheel_min = std::fmin(
            cv / (g.major_radius + g.tube_radius * cv), 1.0 / g.tube_radius);
        if (RelativeCurvatureCertain(model, theta, i)) {
          ++certain;
          EXPECT_TRUE(std::isnan(verdict.relative_curvature[i]));
          EXPECT_GE(full.relative_curvature[i], wheel_min - bound - 1e-12);
          EXPECT_GT(full.relative_curvature[i], 0.0);
        } else {
          ++evaluated;
          EXPECT_EQ(verdict.relative_curvature[i], full.relative_curvature[i]);
        }
      }
    }
  }
  // Both branches are exercised (the dip's 17.8 1/m exceeds every wheel
  // curvature but the tube's; R1's 5.27 1/m clears upright wheels).
  EXPECT_GT(certain, 1000);
  EXPECT_GT(evaluated, 1000);
}

// The indicators take an end state's curvature from the chain cache
// (KinematicModel::CachedChain) and compute it from the surfaces' forms
// otherwise: the same values bit for bit, and a lookup that neither
// evaluates nor evicts.
TEST(LimitEvents, CachedAndComputedCurvatureAgreeBitForBit) {
  const Scene scene = DipScene();
  const SimulationResult r = Simulate(scene, 0.05, true);
  ASSERT_GT(r.samples.size(), 10u);
  for (const TrajectorySample& ts : r.samples) {
    KinematicModel model(scene.geometry, scene.terrain);
    ChainState cs;
    for (int i = 0; i < 3; ++i)
      EXPECT_FALSE(model.CachedChain(ts.theta, i, &cs));
    LimitIndicators computed, cached;
    EvaluateLimitIndicators(model, ts.theta, false, &computed);
    for (int i = 0; i < 3; ++i) {
      EXPECT_FALSE(model.CachedChain(ts.theta, i, &cs)) << "no side effect";
      model.EvaluateChain(ts.theta, i, &cs);
      ChainState again;
      ASSERT_TRUE(model.CachedChain(ts.theta, i, &again));
      EXPECT_EQ(std::memcmp(&again.ground.K, &cs.ground.K, sizeof(Mat2)), 0);
    }
    EvaluateLimitIndicators(model, ts.theta, false, &cached);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(std::memcmp(&computed.relative_curvature[i],
                            &cached.relative_curvature[i], sizeof(double)),
                0)
          << ts.t << " wheel " << i;
    }
  }
}

// The curvature limit lies between two samples: the run stops at the
// located time, to event_tolerance, with the limit's name and wheel. The
// independent value: the adaptive ida run (coupled, rtol 1e-8), whose steps
// shrink to 1e-12 s at the singularity of the contact rates (K^-1) where
// K_w + r K_g r loses definiteness, and a located coupled run at dt 1 ms.
TEST(LimitEvents, CurvatureLimitBetweenSamplesIsLocated) {
  const Scene scene = DipScene();
  const SimulationResult ida =
      Simulate(scene, 0.5, false, "ida", Coupling::kCoupled);
  ASSERT_FALSE(ida.success());
  const double t_ida = ida.t_reached;
  EXPECT_NEAR(t_ida, 3.3906, 1e-3);
  const SimulationResult fine =
      Simulate(scene, 0.001, true, "rk-projection", Coupling::kCoupled);
  const double dt = 0.002;
  const SimulationResult r = Simulate(scene, dt, true);
  for (const SimulationResult* x : {&r, &fine}) {
    ASSERT_EQ(x->status, "DEGENERATE_CONTACT") << x->stop_reason;
    const StopEvent& e = x->event;
    EXPECT_EQ(e.limit, "relative_curvature");
    EXPECT_EQ(e.wheel, 1);
    EXPECT_TRUE(e.located);
    EXPECT_EQ(e.tolerance, 1e-9);
    EXPECT_LE(e.t_upper - e.t_lower, 1e-9);
    EXPECT_GT(e.t_upper, e.t_lower);
    EXPECT_EQ(e.t, x->t_reached);
    EXPECT_EQ(x->samples.back().t, x->t_reached);
    EXPECT_EQ(x->samples.back().nlp_status, "DEGENERATE_CONTACT");
    EXPECT_NEAR(x->t_reached, t_ida, 5e-4);
  }
  EXPECT_GT(OffGrid(r.t_reached, dt), 1e-6);  // strictly between samples
  EXPECT_NEAR(fine.t_reached, t_ida, 1e-4);
  // Every sample before the stop is valid.
  for (size_t k = 0; k + 1 < r.samples.size(); ++k)
    EXPECT_EQ(r.samples[k].nlp_status, "OK");
}

// At the paper's dt = 0.05 zoh steps over the ~17 mm stretch (the contact
// jumps 32 mm in one interval) and, checked at the samples only, drives on
// to t_end; the dense output sees the crossing and the run stops there.
TEST(LimitEvents, CoarseZohNoLongerCarriesOn) {
  const Scene scene = DipScene();
  const SimulationResult sampled = Simulate(scene, 0.05, false);
  EXPECT_TRUE(sampled.success()) << sampled.stop_reason;
  const SimulationResult r = Simulate(scene, 0.05, true);
  ASSERT_EQ(r.status, "DEGENERATE_CONTACT") << r.stop_reason;
  EXPECT_EQ(r.event.limit, "relative_curvature");
  EXPECT_TRUE(r.event.located);
  EXPECT_LE(r.event.t_upper - r.event.t_lower, 1e-9);
  EXPECT_LT(r.t_reached, 3.7);
  EXPECT_GT(OffGrid(r.t_reached, 0.05), 1e-6);
}

// A quasi-static limit between samples: pvc on R1 at mu = 0.3 meets the
// friction limit (wheel 2) at ~14.257 s. Checked at the samples the run
// stops at 14.30 s; located, at the last feasible time to event_tolerance,
// within the integration error of a located run at dt/10 (1.2e-3 s apart).
TEST(LimitEvents, FrictionLimitBetweenSamplesIsLocated) {
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.mode = ActuationMode::kPvc;
  scene.mu = 0.3;
  const SimulationResult sampled = Simulate(scene, 0.05, false);
  ASSERT_EQ(sampled.status, "INFEASIBLE_FRICTION");
  EXPECT_NEAR(sampled.t_reached, 14.30, 1e-9);
  EXPECT_FALSE(sampled.event.located);
  EXPECT_EQ(sampled.event.limit, "friction_limit");
  const SimulationResult fine = Simulate(scene, 0.005, true);
  const SimulationResult r = Simulate(scene, 0.05, true);
  for (const SimulationResult* x : {&r, &fine}) {
    ASSERT_EQ(x->status, "INFEASIBLE_FRICTION") << x->stop_reason;
    EXPECT_EQ(x->event.limit, "friction_limit");
    EXPECT_EQ(x->event.wheel, 2);
    EXPECT_TRUE(x->event.located);
    EXPECT_LE(x->event.t_upper - x->event.t_lower, 1e-9);
    EXPECT_EQ(x->t_reached, x->event.t_upper);
    EXPECT_EQ(x->samples.back().t, x->t_reached);
    EXPECT_EQ(x->samples.back().nlp_status, "INFEASIBLE_FRICTION");
    EXPECT_NEAR(x->event.mu_min, 0.3, 1e-6);  // at the crossing
  }
  EXPECT_GT(OffGrid(r.t_reached, 0.05), 1e-6);
  EXPECT_LT(r.t_reached, sampled.t_reached);
  EXPECT_GT(r.t_reached, sampled.t_reached - 0.05);
  EXPECT_NEAR(r.t_reached, fine.t_reached, 2e-3);
}

}  // namespace
}  // namespace quasiroll
