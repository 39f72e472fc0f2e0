// Helpers shared by the core/ tests that simulate whole scenes.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <string>
#include <vector>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {

// Default options with the integrator, the coupling and the output interval
// set; the built-in backends are registered (idempotent).
inline SimulationOptions BuiltinOptions(const std::string& dae,
                                        Coupling coupling, double dt) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  SimulationOptions options;
  options.dae = dae;
  options.coupling = coupling;
  options.dt = dt;
  return options;
}

// The names of the built-in NLP backends (registered first), for tests
// instantiated on every backend.
inline std::vector<std::string> BuiltinNlpBackendNames() {
  RegisterBuiltinNlpSolvers();
  return NlpSolverRegistry::Names();
}

// bench/scenes/<name>.yaml.
inline Scene SceneFile(const std::string& name) {
  return LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/" + name +
                   ".yaml");
}

// bench/scenes/paper.yaml.
inline Scene PaperScene() { return SceneFile("paper"); }

// The default suite's `bumpy` problem (bench/suites/default.yaml): flat.yaml
// with mu 1 on a random Gaussian terrain (seed 1).
inline Scene BumpyScene() {
  return LoadSceneFromString(R"(name: bumpy
mode: paper
mass: 5.0
gravity: 9.8
mu: 1.0
epsilon: 1.0e-8
joint_rates: [0, 0.6, 0, 0.6, 0, 0.6]
robot: {a: 0.25, b: 0.25, track: 0.4, z_h: 0.05, major_radius: 0.08, tube_radius: 0.02, camber_offset: 0.0}
initial: {x: 0, y: 0, yaw: 0, joint_angles: [0, 0, 0, 0, 0, 0]}
terrain:
  type: gaussians
  random: {seed: 1, count: 80, amplitude: [-0.01, 0.01], sigma: [0.06, 0.12],
           x: [-0.5, 2.0], y: [-0.8, 0.8]}
)");
}

// The pvc robot on the 10 degree incline (bench/scenes/incline10.yaml) at
// its initial configuration, and mu_min there: the friction at which the
// `critical` wheel's cone becomes active (statically determinate, model.md
// §7.5, §7.7). `params` holds the scene's parameters.
struct InclineAtFrictionLimit {
  Scene scene = SceneFile("incline10");
  KinematicModel model{scene.geometry, scene.terrain};
  Configuration theta = SolveInitialConfiguration(model, scene);
  QuasiStaticParameters params = QuasiStaticParameters::FromScene(scene);
  int critical = -1;
  double mu_min = MinimumFriction();

 private:
  double MinimumFriction() {
    QuasiStaticProblem probe(model, params);
    probe.SetConfiguration(theta);
    return probe.MinimumFriction(&critical, nullptr);
  }
};

// A few Newton steps on the square equality system E (model.md §7.3) take a
// re-solve from the solver's residual tolerance to round-off, so that the
// solve error does not dominate finite differences (it enters divided by
// the step).
inline Eigen::VectorXd Polish(const QuasiStaticProblem& p, Eigen::VectorXd z) {
  const int ne = p.num_equalities();
  Eigen::VectorXd g(p.num_constraints());
  Eigen::MatrixXd jac(p.num_constraints(), p.num_variables());
  p.Constraints(z, g);
  double best = g.head(ne).lpNorm<Eigen::Infinity>();
  for (int it = 0; it < 3; ++it) {
    p.ConstraintJacobian(z, jac);
    const Eigen::VectorXd trial =
        z - jac.topRows(ne).fullPivLu().solve(g.head(ne));
    p.Constraints(trial, g);
    const double r = g.head(ne).lpNorm<Eigen::Infinity>();
    if (!(r < best)) break;
    best = r;
    z = trial;
  }
  return z;
}

}  // namespace quasiroll
