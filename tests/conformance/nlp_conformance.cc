#include "quasiroll/conformance/nlp_conformance.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <set>
#include <stdexcept>
#include <thread>

#include "quasiroll/conformance/option_table_conformance.h"

namespace quasiroll::conformance {
namespace {

std::string GtestName(std::string name) {
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

// Solve() rejected a convergence claim: a false claim by the backend.
bool IsRejectedClaim(const NlpResult& r) {
  return r.status == NlpStatus::kNotOptimal ||
         r.backend_status.find("claimed convergence rejected") !=
             std::string::npos;
}

}  // namespace

void PrintTo(const NlpConformanceParam& param, std::ostream* os) {
  *os << param.backend << (param.traits.thread_safe ? " (thread-safe)" : "")
      << (param.traits.detects_infeasibility ? ""
                                             : " (no infeasibility detection)");
}

NlpOptions ConformanceNlpOptions() {
  NlpOptions options;
  options.max_iterations = 500;
  return options;
}

std::vector<std::string> FeasibleReferenceProblemNames() {
  std::vector<std::string> names;
  for (const auto& p : MakeReferenceProblems())
    if (p->is_feasible()) names.push_back(p->name());
  return names;
}

std::vector<std::string> InfeasibleReferenceProblemNames() {
  std::vector<std::string> names;
  for (const auto& p : MakeReferenceProblems())
    if (!p->is_feasible()) names.push_back(p->name());
  return names;
}

void ExpectReferenceOptimumOrHonestFailure(NlpSolver& solver,
                                           const ReferenceProblem& problem) {
  SCOPED_TRACE(solver.name() + " on " + problem.name());
  const NlpOptions options = ConformanceNlpOptions();
  NlpResult r;
  if (solver.RequiresSquareSystem() && !problem.IsSquareSystem()) {
    EXPECT_THROW(solver.Solve(problem, problem.starting_point(), options, &r),
                 std::invalid_argument)
        << "a square-system-only backend must reject a problem with "
        << problem.num_variables() << " unknowns and "
        << problem.CountEqualities() << " equalities as misuse";
    return;
  }
  const NlpStatus status =
      solver.Solve(problem, problem.starting_point(), options, &r);
  EXPECT_EQ(status, r.status);
  if (status != NlpStatus::kConverged) {
    // An honest failure: a status, not a convergence claim that Solve()'s
    // independent check had to reject.
    EXPECT_FALSE(IsRejectedClaim(r))
        << "false convergence claim: " << ToString(status) << ", "
        << r.backend_status;
    EXPECT_NE(status, NlpStatus::kNotRun) << r.backend_status;
    EXPECT_NE(status, NlpStatus::kInvalidInput) << r.backend_status;
    return;
  }
  // Converged: at the known optimum. Tolerances: the loosest accuracy the
  // in-tree backend tests (tests/solvers/nlp_solvers_test.cc, AccuracyOf)
  // ask of a built-in backend at these options (slsqp, ceres: x to 1e-6,
  // f to 1e-8 relative). HS32's bound x1 >= 0 is weakly active and f grows
  // only like 4 x1^2, so f to eps pins x1 to sqrt(eps / 4) only: 1e-5 there
  // (same test). The KKT residual is bounded like the x error (same test).
  const double x_tol = problem.name() == "hs032" ? 1e-5 : kNlpSolutionTolerance;
  const double x_error =
      (r.x - problem.known_solution()).lpNorm<Eigen::Infinity>();
  EXPECT_LE(x_error, x_tol)
      << "converged away from the known optimum (" << problem.solution_source()
      << "): x = " << r.x.transpose();
  EXPECT_LE(std::abs(r.objective - problem.known_objective()),
            kNlpObjectiveTolerance *
                std::max(1.0, std::abs(problem.known_objective())))
      << "objective " << r.objective << ", known optimum "
      << problem.known_objective();
  EXPECT_LE(r.max_constraint_violation, options.feasibility_tolerance);
  EXPECT_LE(r.kkt_residual, kNlpSolutionTolerance) << r.backend_status;
}

void ExpectInfeasibilityDetected(NlpSolver& solver,
                                 const ReferenceProblem& problem,
                                 bool detects_infeasibility) {
  SCOPED_TRACE(solver.name() + " on " + problem.name());
  NlpResult r;
  const NlpOptions options = ConformanceNlpOptions();
  if (solver.RequiresSquareSystem() && !problem.IsSquareSystem()) {
    EXPECT_THROW(solver.Solve(problem, problem.starting_point(), options, &r),
                 std::invalid_argument);
    return;
  }
  const NlpStatus status =
      solver.Solve(problem, problem.starting_point(), options, &r);
  EXPECT_NE(status, NlpStatus::kConverged)
      << "converged on a problem without feasible points: x = "
      << r.x.transpose();
  EXPECT_FALSE(IsRejectedClaim(r))
      << "false convergence claim: " << ToString(status) << ", "
      << r.backend_status;
  if (detects_infeasibility) {
    EXPECT_EQ(status, NlpStatus::kInfeasible) << r.backend_status;
  } else {
    EXPECT_TRUE(status == NlpStatus::kInfeasible ||
                status == NlpStatus::kNumericalFailure ||
                status == NlpStatus::kIterationLimit)
        << ToString(status) << ": " << r.backend_status;
  }
}

void ExpectOptionTableValid(NlpSolver& solver) {
  ExpectBackendOptionTableValid(solver);
}

void ExpectConcurrentSolvesMatchSequential(const std::string& backend) {
  SCOPED_TRACE(backend);
  auto probe = NlpSolverRegistry::Create(backend);
  std::vector<std::unique_ptr<ReferenceProblem>> problems;
  for (const std::string& name : FeasibleReferenceProblemNames()) {
    auto p = MakeReferenceProblem(name);
    if (!probe->RequiresSquareSystem() || p->IsSquareSystem())
      problems.push_back(std::move(p));
  }
  const NlpOptions options = ConformanceNlpOptions();
  // Each run: a fresh instance per problem, as the harness creates them.
  auto run_all = [&](std::vector<NlpResult>* results) {
    results->resize(problems.size());
    for (size_t i = 0; i < problems.size(); ++i) {
      auto solver = NlpSolverRegistry::Create(backend);
      solver->Solve(*problems[i], problems[i]->starting_point(), options,
                    &(*results)[i]);
    }
  };
  std::vector<NlpResult> sequential;
  run_all(&sequential);
  constexpr int kThreads = 4;
  std::vector<std::vector<NlpResult>> concurrent(kThreads);
  {
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back(run_all, &concurrent[t]);
    for (std::thread& thread : threads) thread.join();
  }
  for (int t = 0; t < kThreads; ++t) {
    for (size_t i = 0; i < problems.size(); ++i) {
      const NlpResult& a = sequential[i];
      const NlpResult& b = concurrent[t][i];
      SCOPED_TRACE(problems[i]->name() + ", thread " + std::to_string(t));
      EXPECT_EQ(a.status, b.status) << b.backend_status;
      EXPECT_EQ(a.iterations, b.iterations);
      // Bitwise: the same arithmetic in the same order.
      EXPECT_TRUE(a.x == b.x) << "sequential " << a.x.transpose()
                              << "\nconcurrent " << b.x.transpose();
    }
  }
}

NlpConformanceParam MakeNlpConformanceParam(const std::string& backend,
                                            NlpConformanceTraits traits) {
  return NlpConformanceParam{backend, traits};
}

std::string NlpConformanceName(
    const ::testing::TestParamInfo<NlpConformanceParam>& info) {
  return GtestName(info.param.backend);
}

std::string NlpReferenceOptimumName(
    const ::testing::TestParamInfo<
        std::tuple<NlpConformanceParam, std::string>>& info) {
  return GtestName(std::get<0>(info.param).backend + "_" +
                   std::get<1>(info.param));
}

}  // namespace quasiroll::conformance

// ------------------------------------------------------------- suites ---

namespace quasiroll::conformance {
namespace {

// A binary may link the kit for its reference problems or for one kind of
// backend only.
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(QuasirollNlpConformance);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(QuasirollNlpReferenceOptimum);

TEST_P(QuasirollNlpReferenceOptimum, KnownOptimumOrHonestFailure) {
  const auto& [param, problem_name] = GetParam();
  auto solver = NlpSolverRegistry::Create(param.backend);
  auto problem = MakeReferenceProblem(problem_name);
  ASSERT_NE(problem, nullptr) << problem_name;
  ExpectReferenceOptimumOrHonestFailure(*solver, *problem);
}

TEST_P(QuasirollNlpConformance, InfeasibilityIsDetected) {
  for (const std::string& name : InfeasibleReferenceProblemNames()) {
    auto solver = NlpSolverRegistry::Create(GetParam().backend);
    ExpectInfeasibilityDetected(*solver, *MakeReferenceProblem(name),
                                GetParam().traits.detects_infeasibility);
  }
}

TEST_P(QuasirollNlpConformance, OptionTableIsValid) {
  auto solver = NlpSolverRegistry::Create(GetParam().backend);
  ExpectOptionTableValid(*solver);
}

// The registration, the registry's BackendInfo and the object say the same
// about thread safety (the harness schedules by the object's answer).
TEST_P(QuasirollNlpConformance, ThreadSafetyClaimsAgree) {
  const std::string& name = GetParam().backend;
  EXPECT_EQ(NlpSolverRegistry::Create(name)->SupportsConcurrentInstances(),
            GetParam().traits.thread_safe)
      << name;
  EXPECT_EQ(NlpSolverRegistry::Info(name).thread_safe,
            GetParam().traits.thread_safe)
      << name;
}

TEST_P(QuasirollNlpConformance, ConcurrentSolvesMatchSequential) {
  if (!GetParam().traits.thread_safe)
    GTEST_SKIP() << GetParam().backend << " is not registered as thread-safe";
  ExpectConcurrentSolvesMatchSequential(GetParam().backend);
}

}  // namespace
}  // namespace quasiroll::conformance
