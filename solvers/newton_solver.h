// Backend "newton": damped Newton on a square equality system.
//
// Solves  g_eq(x) = g_lb_eq  (exactly num_variables() equality rows) with
//   J dx = -r,  r = g_eq(x) - g_lb_eq,  J = d g_eq / dx  (dense partial-pivot
//   LU), x <- x + alpha dx,  alpha = 1, 1/2, ... until either the natural
//   monotonicity test (Deuflhard) |J(x)^{-1} r(x + alpha dx)| <=
//   (1 - alpha/4) |dx|  or the Armijo condition
//   |r(x + alpha dx)|^2 <= (1 - 2e-4 alpha) |r(x)|^2  holds. The first is
//   affine invariant and keeps full steps on ill-conditioned systems, where
//   the residual can rise on the way to the root.
// Converged when max_i |r_i| <= options.feasibility_tolerance. The objective
// is ignored (the root is isolated); bounds and inequality rows are checked at
// the root: if the root violates them the status is kInfeasible (the root of
// a nonsingular square system is locally unique; ClassifySquareSystemRoot,
// core/nlp_polish.h).
// When no damped step is acceptable (J nearly singular away from the root),
// one Levenberg-Marquardt step (J^T J + lambda diag(J^T J)) dx = -J^T r with
// increasing lambda is taken instead, and Newton resumes from there.
// A (numerically) rank-deficient Jacobian, a failed LM step or a
// non-finite residual give kNumericalFailure. Multipliers are left at zero.
// After the first call with given sizes DoSolve() does not allocate.
// Backend options (option_table()): armijo, min_damping, rank_pivot_ratio,
// lm_lambda_init, polish_floor (the constants above; defaults as stated).
#pragma once

#include <memory>
#include <string>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

class NewtonSolver final : public NlpSolver {
 public:
  NewtonSolver();
  ~NewtonSolver() override;
  std::string name() const override { return "newton"; }
  bool RequiresSquareSystem() const override { return true; }
  bool SupportsConcurrentInstances() const override { return true; }
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override;

  struct Workspace;
  // Newton iterations until the equality residual meets its target (the
  // polish_floor tightening included); false when a failure status was set.
  // *iter = steps.
  bool Iterate(const NlpProblem& problem, const NlpOptions& options, int* iter,
               NlpResult* result);
  // LU of the equality Jacobian at result->x into the workspace; false if it
  // is non-finite or rank deficient (a failure status is set unless
  // `polishing`, which then just stops).
  bool FactorJacobian(const NlpProblem& problem, bool polishing, int iter,
                      NlpResult* result);
  // Backtracking along the workspace's dx; true with x_trial, g_trial,
  // r_trial holding the accepted point.
  bool DampedStep(const NlpProblem& problem, double phi, double target,
                  NlpResult* result);
  bool LevenbergMarquardtStep(const NlpProblem& problem, Workspace* w,
                              double phi, NlpResult* result);

  std::unique_ptr<Workspace> ws_;
  double lm_lambda_ = 1e-3;  // Levenberg-Marquardt damping, reset per solve
  struct Settings {
    double armijo = 2e-4;
    double min_damping = 1e-10;
    double rank_pivot_ratio = 1e-13;
    double lm_lambda_init = 1e-3;
    double polish_floor = 1e-14;
  } settings_;
};

}  // namespace quasiroll
