// The fast path of issue #22 (docs/performance.md, "The fast path"): newton +
// rk-projection (RK4) on the paper scene in zoh mode.
//   BM_ZohInterval/<variant>  one warmed-up Simulator::Advance() (the
//       quasi-static solve, the recorded sample, one 0.05 s hold interval
//       with its event checks), cycling through the scene's 400 intervals
//       (a new run starts, untimed, after the last one), so the time per
//       iteration is the run's mean time per step as in run.json
//       (wall_s / counters.steps). Variants, for the profile breakdown:
//         full       the defaults (the run `quasiroll run` makes)
//         no-switch  locate_switches = false: no switch location / slip
//                    integrals (their probe solves)
//         plain      locate_switches = locate_events = false: solve, sample
//                    and integration only
//       Counters: nlp solves and iterations per step.
//   BM_TrajectoryCsv  formatting the scene's 401-sample trajectory.csv
//       (TrajectoryCsv), to compare with the loop's time (target: <= 1/5).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/bench/micro/benchmark_support.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {
namespace {

Scene FastPathScene() {
  return LoadScene(std::string(QUASIROLL_SOURCE_DIR) +
                   "/bench/scenes/paper.yaml");
}

SimulationOptions FastPathOptions(bool switches, bool events) {
  SimulationOptions options;
  options.nlp = "newton";
  options.dae = "rk-projection";  // RK4 by default
  options.coupling = Coupling::kZoh;
  options.locate_switches = switches;
  options.locate_events = events;
  return options;
}

void BM_ZohInterval(benchmark::State& state, bool switches, bool events) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Simulator sim(FastPathScene(), FastPathOptions(switches, events));
  SimulationResult result;
  sim.Begin(sim.initial_configuration(), &result);
  sim.Advance(&result);  // warm up: the first solve is cold
  long long steps = 0, solves = 0, iterations = 0;
  long long solves_seen = result.nlp_solves,
            iterations_seen = result.nlp_iterations;
  const auto bank = [&] {
    solves += result.nlp_solves - solves_seen;
    iterations += result.nlp_iterations - iterations_seen;
  };
  const auto reset = [&] {
    solves_seen = result.nlp_solves;
    iterations_seen = result.nlp_iterations;
  };
  for (auto _ : state) {
    if (AdvanceOrRestart(state, sim, &result, bank, reset) ==
        AdvanceOutcome::kFailed)
      break;
    ++steps;
  }
  solves += result.nlp_solves - solves_seen;
  iterations += result.nlp_iterations - iterations_seen;
  const double per_step = 1.0 / static_cast<double>(std::max(1LL, steps));
  state.counters["nlp_solves"] =
      benchmark::Counter(static_cast<double>(solves) * per_step);
  state.counters["nlp_iters"] =
      benchmark::Counter(static_cast<double>(iterations) * per_step);
  state.SetItemsProcessed(steps);
  state.SetLabel("per step (solve + sample + one 0.05 s interval)");
}

void BM_TrajectoryCsv(benchmark::State& state) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Simulator sim(FastPathScene(), FastPathOptions(true, true));
  const SimulationResult result = sim.Run();
  if (!result.success()) {
    state.SkipWithError(result.stop_reason.c_str());
    return;
  }
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string csv = TrajectoryCsv(result);
    bytes = csv.size();
    benchmark::DoNotOptimize(csv.data());
  }
  state.counters["samples"] = static_cast<double>(result.samples.size());
  state.SetBytesProcessed(static_cast<long long>(bytes) * state.iterations());
}

int RegisterFastPath() {
  benchmark::RegisterBenchmark("BM_ZohInterval/full", BM_ZohInterval, true,
                               true)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_ZohInterval/no-switch", BM_ZohInterval,
                               false, true)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_ZohInterval/plain", BM_ZohInterval, false,
                               false)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_TrajectoryCsv", BM_TrajectoryCsv)
      ->Unit(benchmark::kMicrosecond);
  return 0;
}

const int fast_path_registered = RegisterFastPath();

}  // namespace
}  // namespace quasiroll
