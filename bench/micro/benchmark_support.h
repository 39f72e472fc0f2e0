// Shared loop step of the simulator micro-benchmarks (bench/micro/*.cc).
#pragma once

#include <benchmark/benchmark.h>

#include <functional>

#include "quasiroll/core/simulator.h"

namespace quasiroll {

enum class AdvanceOutcome { kInterval, kRestarted, kFailed };

// One output interval of `sim` inside a benchmark loop. At the end of the
// run the run starts again from the initial configuration, warmed by one
// interval, with the timer paused: `before_restart` and `after_restart`
// (if set) bank and reset the caller's counters around it. A failed run
// skips the benchmark with its stop reason (kFailed: leave the loop).
inline AdvanceOutcome AdvanceOrRestart(
    benchmark::State& state, Simulator& sim, SimulationResult* result,
    const std::function<void()>& before_restart = {},
    const std::function<void()>& after_restart = {}) {
  if (sim.Advance(result)) return AdvanceOutcome::kInterval;
  if (!result->success()) {
    state.SkipWithError(result->stop_reason.c_str());
    return AdvanceOutcome::kFailed;
  }
  state.PauseTiming();
  if (before_restart) before_restart();
  sim.Begin(sim.initial_configuration(), result);
  sim.Advance(result);
  if (after_restart) after_restart();
  state.ResumeTiming();
  return AdvanceOutcome::kRestarted;
}

}  // namespace quasiroll
