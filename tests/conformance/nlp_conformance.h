// NLP backend conformance suites (docs/plugins.md, "Conformance kit").
//
// One line in a test file linking quasiroll::conformance and
// GTest::gtest_main runs every check on a registered backend:
//
//   QUASIROLL_NLP_CONFORMANCE(my_backend, "my-backend", /*thread_safe=*/true);
//
// (the arguments after the name initialise NlpConformanceTraits, so
// `.thread_safe = true, .detects_infeasibility = false` works too)
// (the backend must be registered before main() runs the tests, e.g. by a
// registration function called from a static initialiser or a gtest
// Environment). The checks are also callable directly (Expect* below), so a
// test can assert that a broken backend fails them.
#pragma once

#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include "quasiroll/conformance/nlp_reference_problems.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/options.h"

namespace quasiroll {
// GTest prints statuses by name.
inline void PrintTo(NlpStatus status, std::ostream* os) {
  *os << ToString(status);
}
}  // namespace quasiroll

namespace quasiroll::conformance {

// What a registration claims about its backend.
struct NlpConformanceTraits {
  // Separate instances may solve in different threads at the same time:
  // checked by ConcurrentSolvesMatchSequential (skipped when false).
  bool thread_safe = false;
  // The backend reports kInfeasible on the infeasible reference problems.
  // false: it must still not claim convergence there (and may report
  // kNumericalFailure or kIterationLimit, e.g. an SQP method whose
  // linearisations become inconsistent).
  bool detects_infeasibility = true;
};

struct NlpConformanceParam {
  std::string backend;  // NlpSolverRegistry name
  NlpConformanceTraits traits;
};
// GTest prints the backend name instead of the struct's bytes.
void PrintTo(const NlpConformanceParam& param, std::ostream* os);

// Tolerances of ExpectReferenceOptimum (origins in nlp_conformance.cc).
inline constexpr double kNlpSolutionTolerance = 1e-6;
inline constexpr double kNlpObjectiveTolerance = 1e-8;

// The options every solve of the kit uses: the NlpOptions defaults
// (feasibility and optimality tolerance 1e-10) with max_iterations = 500.
NlpOptions ConformanceNlpOptions();

// `problem` (feasible, with a known optimum) solved from its starting point:
// either kConverged at the known optimum (max |x - x*| <=
// kNlpSolutionTolerance, 1e-5 for hs032; |f - f*| <= kNlpObjectiveTolerance *
// max(1, |f*|); violation <= feasibility tolerance; Solve()'s independent KKT
// residual <= kNlpSolutionTolerance), or an honest failure: a status other
// than kConverged that is not a convergence claim Solve() rejected
// (kNotOptimal, or "claimed convergence rejected" in backend_status).
// A square-system-only backend must reject a non-square problem with
// std::invalid_argument.
void ExpectReferenceOptimumOrHonestFailure(NlpSolver& solver,
                                           const ReferenceProblem& problem);
// `problem` (infeasible) solved from its starting point: not kConverged, not
// a rejected claim (as above); kInfeasible if `detects_infeasibility`.
void ExpectInfeasibilityDetected(NlpSolver& solver,
                                 const ReferenceProblem& problem,
                                 bool detects_infeasibility = true);
// Every OptionSpec's default is accepted by its own range, names are unique
// and of [a-z0-9_], docs are non-empty; backend_options() has every option;
// SetBackendOptions() accepts every default as text and rejects an unknown
// name with std::invalid_argument.
void ExpectOptionTableValid(NlpSolver& solver);
// Fresh instances of `backend` solving the feasible reference problems in
// four threads at once give the statuses, iteration counts and x (bitwise)
// that fresh instances give one after another.
void ExpectConcurrentSolvesMatchSequential(const std::string& backend);

// Names of the feasible reference problems (the HS set and the square
// systems) and of the infeasible ones.
std::vector<std::string> FeasibleReferenceProblemNames();
std::vector<std::string> InfeasibleReferenceProblemNames();

// Backend-level checks: option table, infeasibility, thread safety.
class NlpConformanceTest
    : public ::testing::TestWithParam<NlpConformanceParam> {};
// One test per (backend, feasible reference problem).
class NlpReferenceOptimumTest
    : public ::testing::TestWithParam<
          std::tuple<NlpConformanceParam, std::string>> {};

// Used by QUASIROLL_NLP_CONFORMANCE. Defined next to the suites' TEST_Ps, so
// that a registration links them in from the static library.
NlpConformanceParam MakeNlpConformanceParam(const std::string& backend,
                                            NlpConformanceTraits traits);
std::string NlpConformanceName(
    const ::testing::TestParamInfo<NlpConformanceParam>& info);
std::string NlpReferenceOptimumName(
    const ::testing::TestParamInfo<
        std::tuple<NlpConformanceParam, std::string>>& info);

}  // namespace quasiroll::conformance

// The suites' names (gtest needs them unqualified where they are
// instantiated).
using QuasirollNlpConformance = ::quasiroll::conformance::NlpConformanceTest;
using QuasirollNlpReferenceOptimum =
    ::quasiroll::conformance::NlpReferenceOptimumTest;

// Runs the NLP conformance suites on the registered backend `backend_name`;
// `id` is a C++ identifier naming the instantiation.
#define QUASIROLL_NLP_CONFORMANCE(id, backend_name, ...)                       \
  INSTANTIATE_TEST_SUITE_P(                                                    \
      id, QuasirollNlpConformance,                                             \
      ::testing::Values(::quasiroll::conformance::MakeNlpConformanceParam(     \
          backend_name,                                                        \
          ::quasiroll::conformance::NlpConformanceTraits{__VA_ARGS__})),       \
      ::quasiroll::conformance::NlpConformanceName);                           \
  INSTANTIATE_TEST_SUITE_P(                                                    \
      id, QuasirollNlpReferenceOptimum,                                        \
      ::testing::Combine(                                                      \
          ::testing::Values(::quasiroll::conformance::MakeNlpConformanceParam( \
              backend_name,                                                    \
              ::quasiroll::conformance::NlpConformanceTraits{__VA_ARGS__})),   \
          ::testing::ValuesIn(                                                 \
              ::quasiroll::conformance::FeasibleReferenceProblemNames())),     \
      ::quasiroll::conformance::NlpReferenceOptimumName)
