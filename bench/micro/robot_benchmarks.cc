// Google Benchmark micro-benchmarks of the robot kernels (docs/performance.md):
//   BM_QuasiStaticSolve/<nlp>/<mode>/<warm|cold>  one quasi-static solve on the
//       paper scene; "warm" alternates between two consecutive ZOH states
//       (each solve starts from the other's solution, as in a run), "cold"
//       resets the warm start every time.
//   BM_Step/<dae>/<coupling>   one warmed-up hold interval (dt = 0.05 s) of
//       the paper scene: the quasi-static solve, the recorded sample and the
//       integration (Simulator::Advance).
//   BM_PaperScene/<nlp>/<dae>  the whole paper scene (20 s, 400 intervals).
//   BM_KktCheck/<mode>  NlpSolver::Solve()'s KKT check alone at a root.
// Run: build/bench/quasiroll_benchmarks --benchmark_out=bench.json
//      --benchmark_out_format=json   (scripts/run-benchmarks.sh does this)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>
#include <string>

#include "quasiroll/bench/micro/benchmark_support.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {
namespace {

Scene PaperScene(ActuationMode mode) {
  Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  scene.mode = mode;
  return scene;
}

void BM_QuasiStaticSolve(benchmark::State& state, std::string nlp,
                         ActuationMode mode, bool warm) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  const Scene scene = PaperScene(mode);
  // Two consecutive states of a short run.
  Scene short_scene = scene;
  short_scene.t_end = 0.1;
  Simulator sim(short_scene, SimulationOptions{});
  const SimulationResult run = sim.Run();
  if (run.samples.size() < 2) {
    state.SkipWithError("paper scene run failed");
    return;
  }
  const Configuration a = run.samples[0].theta, b = run.samples[1].theta;
  QuasiStaticSolver solver(sim.model(), QuasiStaticParameters::FromScene(scene),
                           NlpSolverRegistry::Create(nlp));
  QuasiStaticSolution sol;
  solver.Solve(a, &sol);
  bool use_b = true;
  long long iterations = 0, solves = 0;
  for (auto _ : state) {
    if (!warm) solver.Reset();
    solver.Solve(use_b ? b : a, &sol);
    use_b = !use_b;
    iterations += sol.nlp_iterations;
    ++solves;
    if (sol.status != QuasiStaticStatus::kOk) {
      state.SkipWithError(("solve failed: " + sol.message).c_str());
      break;
    }
  }
  state.counters["nlp_iters"] = benchmark::Counter(
      static_cast<double>(iterations) / std::max(1LL, solves));
}

// The independent first-order check NlpSolver::Solve() runs after every
// claimed convergence (core/nlp.h), alone: at a newton root of the paper
// scene, without backend multipliers (newton gives none), as in a warm solve.
void BM_KktCheck(benchmark::State& state, ActuationMode mode) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Scene scene = PaperScene(mode);
  scene.t_end = 0.1;
  Simulator sim(scene, SimulationOptions{});
  const SimulationResult run = sim.Run();
  QuasiStaticSolver solver(sim.model(), QuasiStaticParameters::FromScene(scene),
                           NlpSolverRegistry::Create("newton"));
  QuasiStaticSolution sol;
  if (run.samples.size() < 2 ||
      solver.Solve(run.samples[1].theta, &sol) != QuasiStaticStatus::kOk) {
    state.SkipWithError("paper scene solve failed");
    return;
  }
  const QuasiStaticProblem& p = solver.problem();
  NlpBounds bounds;
  bounds.Load(p);
  Eigen::VectorXd g(p.num_constraints());
  p.Constraints(sol.z, g);
  const NlpOptions options;
  const double tol = options.EffectiveKktTolerance();
  KktVerifier verifier;
  double residual = 0;
  for (auto _ : state) {
    residual =
        verifier.Verify(p, sol.z, g, bounds, nullptr,
                        std::max(options.feasibility_tolerance, tol), tol);
    benchmark::DoNotOptimize(residual);
  }
  state.counters["kkt_residual"] = residual;
}

void BM_Step(benchmark::State& state, std::string dae, Coupling coupling) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  const Scene scene = PaperScene(ActuationMode::kPaper);
  SimulationOptions options;
  options.dae = dae;
  options.coupling = coupling;
  Simulator sim(scene, options);
  SimulationResult result;
  sim.Begin(sim.initial_configuration(), &result);
  sim.Advance(&result);  // warm up: the first solve is cold
  long long steps = 0;
  for (auto _ : state) {
    if (AdvanceOrRestart(state, sim, &result) == AdvanceOutcome::kFailed) break;
    ++steps;
  }
  state.SetLabel("solve + record + one 0.05 s interval");
}

void BM_PaperScene(benchmark::State& state, std::string nlp, std::string dae) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  SimulationOptions options;
  options.nlp = nlp;
  options.dae = dae;
  Simulator sim(PaperScene(ActuationMode::kPaper), options);
  for (auto _ : state) {
    SimulationResult r = sim.Run();
    if (!r.success()) {
      state.SkipWithError(r.stop_reason.c_str());
      break;
    }
    benchmark::DoNotOptimize(r.samples.back().position);
  }
}

int RegisterAll() {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  for (const std::string& nlp : NlpSolverRegistry::Names()) {
    for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
      for (bool warm : {true, false}) {
        const std::string name = "BM_QuasiStaticSolve/" + nlp + "/" +
                                 ToString(mode) + (warm ? "/warm" : "/cold");
        benchmark::RegisterBenchmark(name.c_str(), BM_QuasiStaticSolve, nlp,
                                     mode, warm)
            ->Unit(benchmark::kMicrosecond);
      }
    }
  }
  for (ActuationMode mode : {ActuationMode::kPaper, ActuationMode::kPvc}) {
    const std::string name = std::string("BM_KktCheck/") + ToString(mode);
    benchmark::RegisterBenchmark(name.c_str(), BM_KktCheck, mode)
        ->Unit(benchmark::kMicrosecond);
  }
  for (const std::string& dae : IntegratorRegistry::Names()) {
    for (Coupling c : {Coupling::kZoh, Coupling::kCoupled}) {
      const std::string name = "BM_Step/" + dae + "/" + ToString(c);
      benchmark::RegisterBenchmark(name.c_str(), BM_Step, dae, c)
          ->Unit(benchmark::kMicrosecond);
    }
  }
  for (const std::string& nlp : NlpSolverRegistry::Names()) {
    for (const std::string& dae : IntegratorRegistry::Names()) {
      const std::string name = "BM_PaperScene/" + nlp + "/" + dae;
      benchmark::RegisterBenchmark(name.c_str(), BM_PaperScene, nlp, dae)
          ->Unit(benchmark::kMillisecond);
    }
  }
  return 0;
}

const int registered = RegisterAll();

}  // namespace
}  // namespace quasiroll
