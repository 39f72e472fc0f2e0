// No heap allocation inside a warmed-up simulation step (issue: performance
// requirement). Counts calls to the global operator new while Simulator::
// Advance() runs; this binary replaces operator new, so it is kept separate.
#include <gtest/gtest.h>

#include "quasiroll/core/simulator.h"
#include "tests/heap_counter.h"
#include "tests/test_names.h"

namespace quasiroll {
namespace {

class WarmStep : public ::testing::TestWithParam<std::string> {
 protected:
  // The paper scene with newton and the parameter's integrator.
  static SimulationOptions PaperOptions() {
    RegisterBuiltinNlpSolvers();
    RegisterBuiltinIntegrators();
    SimulationOptions options;
    options.nlp = "newton";
    options.dae = GetParam();
    return options;
  }
  // Heap allocations during 50 steps after 5 warm-up steps.
  static long long AllocationsInWarmSteps(const SimulationOptions& options,
                                          SimulationResult* result,
                                          std::size_t* warm_checkpoints) {
    const Scene scene = LoadScene(std::string(QUASIROLL_SOURCE_DIR) +
                                  "/bench/scenes/paper.yaml");
    Simulator sim(scene, options);
    sim.Begin(sim.initial_configuration(), result);
    for (int k = 0; k < 5; ++k)
      EXPECT_TRUE(sim.Advance(result)) << result->stop_reason;
    *warm_checkpoints = result->checkpoints.size();
    const long long before = testing_util::g_heap_allocations.load();
    for (int k = 0; k < 50; ++k)
      EXPECT_TRUE(sim.Advance(result)) << result->stop_reason;
    return testing_util::g_heap_allocations.load() - before;
  }
};

TEST_P(WarmStep, AdvanceDoesNotAllocate) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer owns operator new";
#endif
  SimulationResult result;
  std::size_t warm = 0;
  EXPECT_EQ(AllocationsInWarmSteps(PaperOptions(), &result, &warm), 0)
      << "allocations in 50 warmed-up steps";
}

// Recording checkpoints (core/checkpoints.h) from the dense output, here
// every 0.0375 s (most of the 0.05 s intervals hold one), allocates nothing
// either once the output vector is reserved by Begin().
TEST_P(WarmStep, AdvanceWithCheckpointsDoesNotAllocate) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer owns operator new";
#endif
  SimulationOptions options = PaperOptions();
  for (int k = 1; k * 0.0375 < 3.0; ++k)
    options.checkpoints.push_back(k * 0.0375);
  SimulationResult result;
  std::size_t warm = 0;
  EXPECT_EQ(AllocationsInWarmSteps(options, &result, &warm), 0)
      << "allocations in 50 warmed-up steps";
  EXPECT_GE(result.checkpoints.size(), warm + 60);  // 2.5 s / 0.0375 s
}

INSTANTIATE_TEST_SUITE_P(RkBackends, WarmStep,
                         ::testing::Values("rk-projection", "rk-baumgarte"),
                         testing_util::ParamName());

}  // namespace
}  // namespace quasiroll
