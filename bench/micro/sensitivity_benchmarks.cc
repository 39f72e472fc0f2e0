// Google Benchmark: sensitivities of the quasi-static solution
// (core/sensitivity.h, docs/performance.md):
//   BM_Sensitivity/<nlp>/<mode>  one SensitivityAnalyzer::Compute() (all 29
//       parameters: Theta, mu, eps, the six rates) at the solution the
//       backend returned at the paper scene's initial configuration; the
//       solve itself is outside the timed loop.
//   BM_Sensitivity/<nlp>/<mode>/primal  the same without the multipliers'
//       derivatives (SensitivityOptions::multipliers = false), what an
//       integrator's Jacobian needs.
//   BM_StepSensitivity/<dae>/<coupling>  one StepSensitivity::Compute()
//       (core/step_sensitivity.h): one paper-scene interval (dt 0.05, one
//       RK4 step, newton) from the initial configuration and its 21 x 29
//       derivative, solves included (zoh: 1, coupled: 4 plus their
//       sensitivities).
#include <benchmark/benchmark.h>

#include <string>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/sensitivity.h"
#include "quasiroll/core/step_sensitivity.h"

namespace quasiroll {
namespace {

void BM_Sensitivity(benchmark::State& state, std::string nlp,
                    ActuationMode mode, bool multipliers) {
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.mode = mode;
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  QuasiStaticSolver solver(model, QuasiStaticParameters::FromScene(scene),
                           NlpSolverRegistry::Create(nlp));
  QuasiStaticSolution sol;
  if (solver.Solve(theta, &sol) != QuasiStaticStatus::kOk) {
    state.SkipWithError(("solve failed: " + sol.message).c_str());
    return;
  }
  SensitivityOptions options;
  options.multipliers = multipliers;
  SensitivityAnalyzer analyzer(options);
  QuasiStaticSensitivities sens;
  for (auto _ : state) {
    analyzer.Compute(solver.problem(), sol.z, &sens);
    benchmark::DoNotOptimize(sens.twist.data());
  }
  if (sens.status != SensitivityStatus::kOk)
    state.SkipWithError(ToString(sens.status));
}

void BM_StepSensitivity(benchmark::State& state, std::string dae,
                        Coupling coupling) {
  const Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  StepSensitivityOptions options;
  options.nlp = "newton";
  options.dae = dae;
  options.coupling = coupling;
  options.dt = scene.dt;
  StepSensitivity step(model, QuasiStaticParameters::FromScene(scene), options);
  StepSensitivityResult result;
  for (auto _ : state) {
    step.Compute(theta, &result);
    benchmark::DoNotOptimize(result.jacobian.data());
  }
  if (result.status != StepSensitivityStatus::kOk)
    state.SkipWithError(ToString(result.status));
}

int RegisterAll() {
  for (const char* dae : {"rk-projection", "rk-baumgarte"}) {
    for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
      const std::string name =
          std::string("BM_StepSensitivity/") + dae + "/" + ToString(coupling);
      benchmark::RegisterBenchmark(name.c_str(), BM_StepSensitivity, dae,
                                   coupling)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  RegisterBuiltinNlpSolvers();
  for (const std::string& nlp : NlpSolverRegistry::Names()) {
    for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
      for (bool multipliers : {true, false}) {
        const std::string name = "BM_Sensitivity/" + nlp + "/" +
                                 ToString(mode) +
                                 (multipliers ? "" : "/primal");
        benchmark::RegisterBenchmark(name.c_str(), BM_Sensitivity, nlp, mode,
                                     multipliers)
            ->Unit(benchmark::kMicrosecond);
      }
    }
  }
  return 0;
}

const int kRegistered = RegisterAll();

}  // namespace
}  // namespace quasiroll
