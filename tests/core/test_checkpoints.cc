// Checkpoints (core/checkpoints.h): the time set, the method's state there
// from the dense output (exact for a linear motion, order 4 with RK4 on a
// curved one), forces held in zoh and solved in coupled mode, and the
// method's stepping untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "quasiroll/core/checkpoints.h"
#include "quasiroll/core/simulator.h"
#include "simulation_support.h"

namespace quasiroll {
namespace {

Scene LoadWithEnd(const std::string& name, double t_end) {
  Scene scene = LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/" +
                          name + ".yaml");
  scene.t_end = t_end;
  return scene;
}

SimulationResult Simulate(const Scene& scene, const std::string& dae,
                          Coupling coupling, double dt,
                          const std::vector<double>& checkpoints) {
  SimulationOptions options = BuiltinOptions(dae, coupling, dt);
  options.checkpoints = checkpoints;
  return Simulator(scene, options).Run();
}

// Every 0.3125 s up to t_end (none of them a multiple of 0.4 or 0.2).
std::vector<double> Grid(double t_end, double interval = 0.3125) {
  std::vector<double> t;
  for (int k = 1; k * interval <= t_end + 1e-12; ++k) t.push_back(k * interval);
  return t;
}

TEST(CheckpointTimes, EveryMthReferenceSamplePlusTheLastTime) {
  // A reference on a 0.0125 s grid that stopped at 1.0037 s (a located
  // limit): every 25th sample (0.3125 s) and the stop.
  std::vector<double> ref;
  for (int k = 0; k * 0.0125 <= 1.0; ++k) ref.push_back(k * 0.0125);
  ref.push_back(1.0037);
  const std::vector<double> t = CheckpointTimes(ref, 0.3125);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_EQ(t[0], ref[25]);
  EXPECT_EQ(t[1], ref[50]);
  EXPECT_EQ(t[2], ref[75]);
  EXPECT_EQ(t[3], 1.0037);
  // An interval that is no multiple of the reference's is rounded to one
  // (0.3 s -> 24 intervals); extra times (switches) join the set, a
  // duplicate within 1e-9 s and times outside (0, t_last] do not.
  const std::vector<double> u =
      CheckpointTimes(ref, 0.3, {0.5, 0.3 + 1e-12, 2.0, 0.0});
  ASSERT_EQ(u.size(), 5u);
  EXPECT_EQ(u[0], ref[24]);
  EXPECT_EQ(u[1], 0.5);
  EXPECT_EQ(u[2], ref[48]);
  EXPECT_EQ(u[3], ref[72]);
  EXPECT_EQ(u[4], 1.0037);
  EXPECT_TRUE(CheckpointTimes({}, 0.3).empty());
  EXPECT_THROW(CheckpointTimes(ref, 0.0), std::invalid_argument);
  EXPECT_THROW(CheckpointTimes(ref, NAN), std::invalid_argument);
}

TEST(Checkpoints, OptionsMustBeAscending) {
  SimulationOptions options;
  options.checkpoints = {0.5, 0.25};
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("checkpoints"), std::string::npos);
  options.checkpoints = {0.25, NAN};
  EXPECT_FALSE(options.IsValid(&why));
  options.checkpoints = {0.25, 0.5};
  EXPECT_TRUE(options.IsValid(&why)) << why;
}

// Oracle O1 (flat straight drive, test_simulator.cc): every coordinate is
// linear in t, which the cubic Hermite interpolant reproduces exactly. The
// checkpoints of a dt = 0.4 s run (between its samples) must equal the
// linear interpolation of its samples and the exact motion x = 0.06 t to
// round-off (1e-12 m over 2 s of 1e-2 m/s-scale motion).
TEST(Checkpoints, LinearMotionRecordedExactly) {
  const Scene scene = LoadWithEnd("flat", 2.0);
  for (Coupling c : {Coupling::kZoh, Coupling::kCoupled}) {
    const SimulationResult r =
        Simulate(scene, "rk-projection", c, 0.4, Grid(2.0));
    ASSERT_TRUE(r.success()) << r.stop_reason;
    ASSERT_EQ(r.checkpoints.size(), 6u);
    for (const TrajectorySample& cp : r.checkpoints) {
      const int k = static_cast<int>(cp.t / 0.4);
      const TrajectorySample &a = r.samples[k], &b = r.samples[k + 1];
      const double w = (cp.t - a.t) / (b.t - a.t);
      const Configuration lin = (1 - w) * a.theta + w * b.theta;
      EXPECT_LE((cp.theta - lin).lpNorm<Eigen::Infinity>(), 1e-12)
          << ToString(c) << " t=" << cp.t;
      EXPECT_NEAR(cp.position.x(), 0.06 * cp.t, 1e-12);
      EXPECT_NEAR(cp.position.y(), 0.0, 1e-12);
      EXPECT_NEAR(cp.velocity.x(), 0.06, 1e-9);
    }
  }
}

// Oracle O2 (constant-steer circle, test_simulator.cc): the COM turns about
// the fixed centre (-b, L/tan phi1) at yaw rate v tan(phi1)/L. With RK4 at
// one step per interval, the checkpoint error (end values O(h^4) plus the
// Hermite interpolant's h^4/384 |p''''|) falls by 2^4 when dt halves: a
// slope >= 3.5 from dt = 1.6 to 0.8 s (a linear interpolant's chord error
// R (omega h)^2 / 8 would give 2). The errors, ~1e-7 m, are far above
// round-off.
TEST(Checkpoints, CurvedMotionAtTheMethodsOrder) {
  const double L = 0.5, b = 0.25, phi = 0.5, t_end = 20.0;
  const Vec2 centre(-b, L / std::tan(phi));
  const double yaw_rate = 0.06 * std::tan(phi) / L;
  const Scene scene = LoadWithEnd("circle", t_end);
  for (Coupling c : {Coupling::kZoh, Coupling::kCoupled}) {
    double err[2] = {0, 0};
    for (int j = 0; j < 2; ++j) {
      const double dt = j == 0 ? 1.6 : 0.8;
      const SimulationResult r =
          Simulate(scene, "rk-projection", c, dt, Grid(t_end));
      ASSERT_TRUE(r.success()) << r.stop_reason;
      ASSERT_EQ(r.checkpoints.size(), 64u);
      const Vec2 p0 = r.samples.front().position.head<2>() - centre;
      for (const TrajectorySample& cp : r.checkpoints) {
        const double a = yaw_rate * cp.t;
        const Vec2 exact =
            centre + Vec2(std::cos(a) * p0.x() - std::sin(a) * p0.y(),
                          std::sin(a) * p0.x() + std::cos(a) * p0.y());
        err[j] = std::max(err[j], (cp.position.head<2>() - exact).norm());
      }
    }
    EXPECT_GT(err[1], 1e-10) << ToString(c);  // above round-off
    std::printf("%s: checkpoint errors %.3g (dt 1.6), %.3g (dt 0.8)\n",
                ToString(c), err[0], err[1]);
    EXPECT_GE(std::log2(err[0] / err[1]), 3.5)
        << ToString(c) << ": errors " << err[0] << ", " << err[1];
  }
}

// The stepping is untouched (the samples, trajectory.csv, are bit-identical
// with and without checkpoints, and so are the method's solve counts); zoh
// checkpoints carry the forces held from the interval's start, coupled ones
// the forces solved at the checkpoint, by solves counted apart.
TEST(Checkpoints, SteppingUnchangedAndForcesAsApplied) {
  const Scene scene = LoadWithEnd("paper", 3.0);
  for (Coupling c : {Coupling::kZoh, Coupling::kCoupled}) {
    const SimulationResult plain = Simulate(scene, "rk-projection", c, 0.2, {});
    const SimulationResult r =
        Simulate(scene, "rk-projection", c, 0.2, Grid(3.0));
    ASSERT_TRUE(r.success()) << r.stop_reason;
    EXPECT_TRUE(plain.checkpoints.empty());
    ASSERT_EQ(r.samples.size(), plain.samples.size());
    for (std::size_t k = 0; k < r.samples.size(); ++k) {
      EXPECT_EQ(r.samples[k].theta, plain.samples[k].theta) << k;
      for (int i = 0; i < 3; ++i)
        EXPECT_EQ(r.samples[k].contacts[i].normal_force,
                  plain.samples[k].contacts[i].normal_force);
    }
    EXPECT_EQ(r.nlp_solves, plain.nlp_solves);
    EXPECT_EQ(r.nlp_iterations, plain.nlp_iterations);
    EXPECT_EQ(r.steps, plain.steps);
    EXPECT_EQ(r.rhs_evaluations, plain.rhs_evaluations);
    ASSERT_EQ(r.checkpoints.size(), 9u);
    bool differs = false;
    for (const TrajectorySample& cp : r.checkpoints) {
      const TrajectorySample& held =
          r.samples[static_cast<std::size_t>(cp.t / 0.2)];
      ASSERT_LT(held.t, cp.t);
      ASSERT_EQ(cp.nlp_status, "OK");
      for (int i = 0; i < 3; ++i) {
        if (c == Coupling::kZoh) {
          EXPECT_EQ(cp.contacts[i].normal_force, held.contacts[i].normal_force);
          EXPECT_EQ(cp.contacts[i].slip, held.contacts[i].slip);
        } else {
          differs = differs || cp.contacts[i].normal_force !=
                                   held.contacts[i].normal_force;
        }
      }
    }
    if (c == Coupling::kZoh) {
      EXPECT_EQ(r.checkpoint_solves, 0);
    } else {
      EXPECT_TRUE(differs);
      // Per interval holding a checkpoint: one solve at its end, one at the
      // checkpoint (t_end is a sample: none).
      EXPECT_GE(r.checkpoint_solves, 2 * 8);
    }
  }
}

// A run that stops early (pvc at mu = 0.3, INFEASIBLE_FRICTION located
// inside its last interval) records every checkpoint up to its stop and none
// past it (those read from the last interval's dense output beyond the
// located stop are dropped).
TEST(Checkpoints, NoneBeyondTheStop) {
  Scene scene = LoadWithEnd("paper", 20.0);
  scene.mode = ActuationMode::kPvc;
  scene.mu = 0.3;
  const std::vector<double> grid = Grid(20.0, 0.05);
  const SimulationResult r =
      Simulate(scene, "rk-projection", Coupling::kZoh, 0.2, grid);
  ASSERT_EQ(r.status, "INFEASIBLE_FRICTION");
  ASSERT_TRUE(r.event.located);
  std::size_t reached = 0;
  while (reached < grid.size() && grid[reached] <= r.t_reached + 1e-9)
    ++reached;
  ASSERT_GT(reached, 0u);
  EXPECT_LT(r.t_reached, grid[reached] - 1e-9);
  ASSERT_EQ(r.checkpoints.size(), reached);
  EXPECT_LE(r.checkpoints.back().t, r.t_reached + 1e-9);
}

}  // namespace
}  // namespace quasiroll
