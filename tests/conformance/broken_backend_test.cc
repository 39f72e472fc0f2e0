// The kit must fail a backend that claims convergence at a wrong point. The
// kit's checks run directly on deliberately broken backends, with their
// failures captured (gtest-spi.h) and asserted.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "quasiroll/conformance/nlp_conformance.h"

namespace quasiroll::conformance {
namespace {

// Claims convergence at a fixed point with zero multipliers, whatever the
// problem; or, with an empty point, at the starting point.
class FixedAnswerSolver final : public NlpSolver {
 public:
  explicit FixedAnswerSolver(Eigen::VectorXd answer)
      : answer_(std::move(answer)) {}
  std::string name() const override { return "fixed-answer"; }

 private:
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& /*options*/, NlpResult* result) override {
    result->x = answer_.size() > 0 ? answer_ : Eigen::VectorXd(x0);
    result->multipliers.setZero(problem.num_constraints());
    result->has_multipliers = true;
    result->iterations = 1;
    result->status = NlpStatus::kConverged;
    result->backend_status = "converged (fixed answer)";
  }
  Eigen::VectorXd answer_;
};

// Reports an iteration limit without claiming anything: honest.
class GivesUpSolver final : public NlpSolver {
 public:
  std::string name() const override { return "gives-up"; }

 private:
  void DoSolve(const NlpProblem&, const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions&, NlpResult* result) override {
    result->x = x0;
    result->iterations = 1;
    result->status = NlpStatus::kIterationLimit;
    result->backend_status = "gave up";
  }
};

// Failures the kit's check reported, with their messages joined.
struct Captured {
  int failures = 0;
  std::string messages;
};

template <typename Check>
Captured Capture(Check&& check) {
  ::testing::TestPartResultArray results;
  {
    ::testing::ScopedFakeTestPartResultReporter reporter(
        ::testing::ScopedFakeTestPartResultReporter::
            INTERCEPT_ONLY_CURRENT_THREAD,
        &results);
    check();
  }
  Captured captured;
  for (int i = 0; i < results.size(); ++i) {
    if (results.GetTestPartResult(i).failed()) {
      ++captured.failures;
      captured.messages += results.GetTestPartResult(i).message();
      captured.messages += "\n";
    }
  }
  return captured;
}

// HS40's feasible set is x1^3 = 1 - x2^2, x2 = x4^2, x3 = x1^2 x4, where
// f = -x1^3 x2^2 = u^2 - u with u = x2^2: besides the minimum (u = 1/2,
// f* = -1/4) it has the stationary point u = 0, x = (1, 0, 0, 0), f = 0, a
// local maximum along the set. grad f = 0 there, so it is feasible and its
// KKT residual with zero multipliers is 0: NlpSolver::Solve()'s independent
// check accepts the claim. Only the kit's comparison with the known optimum
// catches this false convergence.
TEST(BrokenBackendTest, StationaryPointThatIsNotTheOptimumFailsTheKit) {
  FixedAnswerSolver solver(Eigen::Vector4d(1.0, 0.0, 0.0, 0.0));
  Hs040Problem problem;
  NlpResult r;
  ASSERT_EQ(solver.Solve(problem, problem.starting_point(),
                         ConformanceNlpOptions(), &r),
            NlpStatus::kConverged)
      << "Solve() no longer accepts the stationary point: " << r.backend_status;
  const Captured captured =
      Capture([&] { ExpectReferenceOptimumOrHonestFailure(solver, problem); });
  EXPECT_EQ(captured.failures, 2) << captured.messages;  // x and f
  EXPECT_NE(captured.messages.find("converged away from the known optimum"),
            std::string::npos)
      << captured.messages;
  EXPECT_NE(captured.messages.find("known optimum -0.25"), std::string::npos)
      << captured.messages;
}

// The kit's optimum check on `solver` fails once, with `message`.
void ExpectOneFalseClaimFound(NlpSolver& solver,
                              const ReferenceProblem& problem,
                              const std::string& message) {
  const Captured captured =
      Capture([&] { ExpectReferenceOptimumOrHonestFailure(solver, problem); });
  EXPECT_EQ(captured.failures, 1) << captured.messages;
  EXPECT_NE(captured.messages.find(message), std::string::npos)
      << captured.messages;
}

// Claims that Solve() itself rejects are false claims to the kit, not honest
// failures: at an infeasible point (demoted to kNumericalFailure, "claimed
// convergence rejected") and at a feasible non-KKT point (kNotOptimal).
TEST(BrokenBackendTest, ClaimsThatSolveRejectsFailTheKit) {
  {
    // HS71's x0 = (1, 5, 5, 1) has sum x^2 = 52 != 40.
    FixedAnswerSolver solver{Eigen::VectorXd()};  // claims x0
    Hs071Problem problem;
    ExpectOneFalseClaimFound(solver, problem, "false convergence claim");
  }
  {
    // HS32 at x = (0, 0.25, 0.75): x1 + x2 + x3 = 1, 6 x2 + 4 x3 - x1^3 =
    // 4.5 >= 3, x >= 0, so feasible; grad f = (2s + 8(x1 - x2), 6s - 8(x1 -
    // x2), 2s) with s = x1 + 3 x2 + x3 = 1.5 is not in the span of the
    // active rows: Solve() says kNotOptimal.
    FixedAnswerSolver solver(Eigen::Vector3d(0.0, 0.25, 0.75));
    Hs032Problem problem;
    NlpResult r;
    ASSERT_EQ(solver.Solve(problem, problem.starting_point(),
                           ConformanceNlpOptions(), &r),
              NlpStatus::kNotOptimal)
        << r.backend_status;
    ExpectOneFalseClaimFound(solver, problem,
                             "false convergence claim: not_optimal");
  }
}

// A convergence claim on a problem without feasible points (demoted by
// Solve() to kNumericalFailure) is not infeasibility detection.
TEST(BrokenBackendTest, ConvergenceOnAnInfeasibleProblemFailsTheKit) {
  FixedAnswerSolver solver{Eigen::VectorXd()};
  InfeasibleDiskProblem problem;
  const Captured captured =
      Capture([&] { ExpectInfeasibilityDetected(solver, problem); });
  EXPECT_GE(captured.failures, 1) << captured.messages;
  EXPECT_NE(captured.messages.find("kInfeasible"), std::string::npos)
      << captured.messages;
}

// The control: an honest failure status passes the optimum check (and the
// captured list is empty), so the failures above are the claims' doing.
TEST(BrokenBackendTest, AnHonestFailurePassesTheOptimumCheck) {
  GivesUpSolver solver;
  Hs071Problem problem;
  const Captured captured =
      Capture([&] { ExpectReferenceOptimumOrHonestFailure(solver, problem); });
  EXPECT_EQ(captured.failures, 0) << captured.messages;
}

}  // namespace
}  // namespace quasiroll::conformance
