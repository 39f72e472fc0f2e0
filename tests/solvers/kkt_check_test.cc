// NlpSolver::Solve()'s independent first-order (KKT) check (core/nlp.h): a
// backend that claims convergence at a point that is not a KKT point is
// downgraded to kNotOptimal, whatever multipliers it reports; a true optimum
// keeps kConverged with least-squares multipliers when the backend gives
// none. Fake backends return prescribed points, so every claim is known.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <string>

#include "quasiroll/conformance/nlp_reference_problems.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// min 50 ((x1 - 3)^2 + (x2 - 3)^2)  s.t.  row: x1 + x2 in [row_lb, row_ub],
// 0 <= x <= 10. With row_ub = 4 (row_lb = -inf) the optimum is x* = (2, 2),
// f* = 100, on the row's upper side with multiplier lambda* = +100 (Ipopt's
// sign: >= 0 against g_ub); grad f(x*) = (-100, -100), |grad f| ~ 1e2.
class Bowl final : public NlpProblem {
 public:
  Bowl(double row_lb, double row_ub, double var_lb = 0.0)
      : row_lb_(row_lb), row_ub_(row_ub), var_lb_(var_lb) {}
  int num_variables() const override { return 2; }
  int num_constraints() const override { return 1; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu,
                 Eigen::Ref<Eigen::VectorXd> gl,
                 Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl.setConstant(var_lb_);
    xu.setConstant(10.0);
    gl(0) = row_lb_;
    gu(0) = row_ub_;
  }
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return 50.0 * (x.array() - 3.0).square().sum();
  }
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override {
    grad = 100.0 * (x.array() - 3.0).matrix();
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override {
    g(0) = x(0) + x(1);
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    jac << 1.0, 1.0;
  }

 private:
  double row_lb_, row_ub_, var_lb_;
};

// Claims kConverged at a prescribed point, optionally with multipliers.
class ClaimingBackend final : public NlpSolver {
 public:
  ClaimingBackend(Eigen::VectorXd x, Eigen::VectorXd multipliers = {})
      : x_(std::move(x)), multipliers_(std::move(multipliers)) {}
  std::string name() const override { return "claiming"; }

 private:
  void DoSolve(const NlpProblem&, const Eigen::Ref<const Eigen::VectorXd>&,
               const NlpOptions&, NlpResult* result) override {
    result->x = x_;
    if (multipliers_.size() > 0) {
      result->multipliers = multipliers_;
      result->has_multipliers = true;
    }
    result->iterations = 1;
    result->backend_status = "FTOL_REACHED";
    result->status = NlpStatus::kConverged;
  }
  Eigen::VectorXd x_, multipliers_;
};

NlpStatus SolveWith(ClaimingBackend* backend, const NlpProblem& p,
                    NlpResult* r) {
  return backend->Solve(p, Eigen::Vector2d(1.0, 1.0), NlpOptions(), r);
}

// A backend's claim of x = (2, 2) on `p`, with the multiplier 100 or none.
NlpStatus SolveClaimingTwoTwo(const NlpProblem& p, bool with_multipliers,
                              NlpResult* r) {
  ClaimingBackend backend(
      Eigen::Vector2d(2.0, 2.0),
      with_multipliers ? Eigen::VectorXd::Constant(1, 100) : Eigen::VectorXd());
  return SolveWith(&backend, p, r);
}

// The case: an interior point (the row has slack 0.02), |grad f| ~
// 1e2, zero multipliers, objective 2 % above the optimum. Relative residual:
// r = grad f = (-101, -101) pushes against x_ub = 10 at slack 8.01:
// w = 101 * 8.01 / 9.01 = 89.8, / s_d = 101 -> 0.889.
TEST(KktCheckTest, InteriorNonStationaryPointIsDowngraded) {
  const Bowl p(-kInf, 4.0);
  const Eigen::Vector2d x(1.99, 1.99);
  ASSERT_NEAR(p.Objective(x), 102.01, 1e-9);  // f* = 100
  for (bool with_zero_multipliers : {false, true}) {
    ClaimingBackend backend(x, with_zero_multipliers ? Eigen::VectorXd::Zero(1)
                                                     : Eigen::VectorXd());
    NlpResult r;
    EXPECT_EQ(SolveWith(&backend, p, &r), NlpStatus::kNotOptimal)
        << r.backend_status;
    EXPECT_NEAR(r.kkt_residual, 101.0 * 8.01 / 9.01 / 101.0, 1e-12);
    EXPECT_NE(r.backend_status.find("claimed convergence rejected: KKT"),
              std::string::npos)
        << r.backend_status;
    EXPECT_EQ(r.max_constraint_violation, 0.0);  // feasible: only KKT fails
  }
}

// At the true optimum the check finds lambda = 100 by least squares when the
// backend reports no multipliers, and also accepts the backend's own.
TEST(KktCheckTest, TrueOptimumKeepsConvergedWithLeastSquaresMultipliers) {
  const Bowl p(-kInf, 4.0);
  for (bool with_multipliers : {false, true}) {
    NlpResult r;
    EXPECT_EQ(SolveClaimingTwoTwo(p, with_multipliers, &r),
              NlpStatus::kConverged)
        << r.backend_status;
    // Exact arithmetic gives 0; round-off in r = grad f + J^T lambda is
    // a few ulps of s_d = 100.
    EXPECT_LE(r.kkt_residual, 1e-14);
  }
}

// Every kConverged result carries multipliers of size m that certify the
// reported residual (core/nlp.h, NlpResult::multipliers_estimated): the
// backend's own when they pass, else the least-squares lambda = 100 that
// certified the point (backend gave none, or gave lambda = 0, which leaves
// grad f = (-100, -100) unbalanced).
TEST(KktCheckTest, ConvergedResultCarriesTheCertifyingMultipliers) {
  const Bowl p(-kInf, 4.0);
  struct Case {
    Eigen::VectorXd given;
    bool estimated;
  };
  for (const Case& c : {Case{Eigen::VectorXd(), true},
                        Case{Eigen::VectorXd::Constant(1, 100), false},
                        Case{Eigen::VectorXd::Zero(1), true}}) {
    ClaimingBackend backend(Eigen::Vector2d(2.0, 2.0), c.given);
    NlpResult r;
    ASSERT_EQ(SolveWith(&backend, p, &r), NlpStatus::kConverged)
        << r.backend_status;
    ASSERT_EQ(r.multipliers.size(), 1);
    EXPECT_EQ(r.multipliers_estimated, c.estimated) << c.given.size();
    EXPECT_EQ(r.has_multipliers, !c.estimated);
    // lambda* = 100 exactly; the least squares is one 2x1 solve (round-off
    // a few ulps of 100).
    EXPECT_NEAR(r.multipliers(0), 100.0, 1e-12);
    KktVerifier kkt;
    EXPECT_EQ(kkt.ResidualWith(p, r.x, r.multipliers), r.kkt_residual);
    // A backend that sets no native count gets its comparable one.
    EXPECT_EQ(r.native_iterations, r.iterations);
  }
}

// The same point (2, 2) when the row is x1 + x2 >= 4: the row is active on
// its lower side, where the multiplier must be <= 0, but stationarity needs
// lambda = +100: x is not a minimum (f falls towards (3, 3)). Caught with
// least-squares multipliers (the wrong-sign side is released: lambda = 0,
// residual |grad f| / s_d) and with the backend's wrong-sign +100.
TEST(KktCheckTest, WrongSignInequalityMultiplierIsCaught) {
  const Bowl p(4.0, kInf);
  for (bool with_multipliers : {false, true}) {
    NlpResult r;
    EXPECT_EQ(SolveClaimingTwoTwo(p, with_multipliers, &r),
              NlpStatus::kNotOptimal)
        << r.backend_status;
    // grad f = (-100, -100) against x_ub = 10 at slack 8: 100 * 8/9 / 100.
    EXPECT_NEAR(r.kkt_residual, 8.0 / 9.0, 1e-12) << with_multipliers;
  }
  // A correct multiplier of the right sign on the same side passes: the
  // optimum of min 50 |x - 3|^2 s.t. x1 + x2 >= 8 is (4, 4), lambda = -100.
  const Bowl far(8.0, kInf);
  ClaimingBackend backend(Eigen::Vector2d(4.0, 4.0));
  NlpResult r;
  EXPECT_EQ(SolveWith(&backend, far, &r), NlpStatus::kConverged)
      << r.backend_status;
  EXPECT_LE(r.kkt_residual, 1e-14);
}

// A variable bound with the wrong-sign multiplier: x >= 2 componentwise and
// the claim x = (2, 2) (the row x1 + x2 <= 100 inactive); f decreases towards
// (3, 3), so z_L = r_j = -100 < 0.
TEST(KktCheckTest, WrongSignBoundMultiplierIsCaught) {
  const Bowl p(-kInf, 100.0, /*var_lb=*/2.0);
  ClaimingBackend backend(Eigen::Vector2d(2.0, 2.0));
  NlpResult r;
  EXPECT_EQ(SolveWith(&backend, p, &r), NlpStatus::kNotOptimal)
      << r.backend_status;
  EXPECT_NEAR(r.kkt_residual, 8.0 / 9.0, 1e-12);
  // With the bound at 4 instead, (4, 4) is the optimum (z_L = +100).
  const Bowl q(-kInf, 100.0, /*var_lb=*/4.0);
  ClaimingBackend at_bound(Eigen::Vector2d(4.0, 4.0));
  EXPECT_EQ(SolveWith(&at_bound, q, &r), NlpStatus::kConverged)
      << r.backend_status;
  EXPECT_LE(r.kkt_residual, 1e-14);
}

// A claim off by 1e-3 from the optimum along the row is first-order
// non-optimal by ~ |H| 1e-3 / s_d = 1e-3 > sqrt(1e-10): downgraded; with a
// custom kkt_tolerance of 1e-2 it is accepted (the tolerance is what decides).
TEST(KktCheckTest, ToleranceIsTheDocumentedOne) {
  const Bowl p(-kInf, 4.0);
  ClaimingBackend backend(Eigen::Vector2d(2.001, 1.999));
  NlpOptions options;
  EXPECT_DOUBLE_EQ(options.EffectiveKktTolerance(), 1e-5);  // sqrt(1e-10)
  NlpResult r;
  EXPECT_EQ(backend.Solve(p, Eigen::Vector2d(1, 1), options, &r),
            NlpStatus::kNotOptimal);
  // lambda_LS = 100 (mean), r = (+0.1, -0.1); the larger side error is
  // r_2 = -0.1 against x_ub at slack 8.001; s_d = |grad f|_inf = 100.1.
  EXPECT_NEAR(r.kkt_residual, 0.1 * 8.001 / 9.001 / 100.1, 1e-12);
  options.kkt_tolerance = 1e-2;
  EXPECT_EQ(backend.Solve(p, Eigen::Vector2d(1, 1), options, &r),
            NlpStatus::kConverged);
  options.kkt_tolerance = -1.0;
  EXPECT_THROW(backend.Solve(p, Eigen::Vector2d(1, 1), options, &r),
               std::invalid_argument);
}

// ResidualWith evaluates the formula for given multipliers. HS71 at its
// published optimum: x1 = 1 is on its bound, so the multipliers follow from
// the stationarity rows 2..4 (3 equations, 2 unknowns, consistent at x*),
// solved here by a plain QR independent of the verifier; they reproduce
// Ipopt's published ones (hs071 example: lambda = (-0.552294, 0.161469)).
TEST(KktCheckTest, ResidualWithMultipliersOnHs071) {
  Hs071Problem p;
  const Eigen::VectorXd& x = p.known_solution();
  Eigen::VectorXd grad(4);
  Eigen::MatrixXd jac(2, 4);
  p.ObjectiveGradient(x, grad);
  p.ConstraintJacobian(x, jac);
  const Eigen::Vector2d lambda =
      jac.rightCols(3).transpose().householderQr().solve(-grad.tail(3));
  EXPECT_NEAR(lambda(0), -0.552294, 1e-6);
  EXPECT_NEAR(lambda(1), 0.161469, 1e-6);
  KktVerifier verifier;
  // x* has 9 digits: the residual is first order in that error.
  EXPECT_LE(verifier.ResidualWith(p, x, lambda), 1e-7);
  // Flipped signs: the inequality multiplier points at the missing upper
  // side and stationarity fails: O(1).
  EXPECT_GE(verifier.ResidualWith(p, x, -lambda), 0.1);
}

}  // namespace
}  // namespace quasiroll
