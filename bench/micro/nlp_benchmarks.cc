// Google Benchmark: every registered NLP backend on HS71 (cold start from the
// published x0, warm start from the solution with its multipliers) and on the
// client-sized square system ContactLikeSystem(18) (warm start from a nearby
// root, as in the quasi-static loop).
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "quasiroll/conformance/nlp_reference_problems.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll {
namespace {

void SolveLoop(benchmark::State& state, const std::string& backend,
               const ReferenceProblem& problem, bool warm, double tol) {
  auto solver = NlpSolverRegistry::Create(backend);
  NlpOptions options;
  options.feasibility_tolerance = tol;
  options.max_iterations = 500;
  NlpResult result;
  Eigen::VectorXd x0 = problem.starting_point();
  if (warm) {
    if (solver->Solve(problem, x0, options, &result) != NlpStatus::kConverged) {
      state.SkipWithError(
          ("cold solve failed: " + result.backend_status).c_str());
      return;
    }
    x0 = result.x;
    options.warm_start_multipliers = true;
  }
  const Eigen::VectorXd multipliers = result.multipliers;
  int iterations = 0, failures = 0;
  for (auto _ : state) {
    result.multipliers = multipliers;
    const NlpStatus status = solver->Solve(problem, x0, options, &result);
    benchmark::DoNotOptimize(result.x.data());
    iterations += result.iterations;
    failures += status != NlpStatus::kConverged;
  }
  state.counters["iterations"] =
      benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  state.counters["failures"] = failures;
}

int RegisterAll() {
  RegisterBuiltinNlpSolvers();
  static const Hs071Problem hs071;
  static const ContactLikeSystem contact(18);
  for (const std::string& name : NlpSolverRegistry::Names()) {
    if (!NlpSolverRegistry::Create(name)->RequiresSquareSystem()) {
      benchmark::RegisterBenchmark(("BM_Nlp_HS71_Cold/" + name).c_str(),
                                   [name](benchmark::State& s) {
                                     SolveLoop(s, name, hs071, false, 1e-10);
                                   })
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("BM_Nlp_HS71_Warm/" + name).c_str(),
                                   [name](benchmark::State& s) {
                                     SolveLoop(s, name, hs071, true, 1e-10);
                                   })
          ->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark(("BM_Nlp_Contact18_Cold/" + name).c_str(),
                                 [name](benchmark::State& s) {
                                   SolveLoop(s, name, contact, false, 1e-12);
                                 })
        ->Unit(benchmark::kMicrosecond);
  }
  return 0;
}

const int kRegistered = RegisterAll();

}  // namespace
}  // namespace quasiroll
