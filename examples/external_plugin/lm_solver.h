// Backend "levenberg-marquardt" (example plugin): Levenberg-Marquardt on the
// equality rows of a square system, built against the installed quasiroll
// package only.
//
// Solves  r(x) = g_eq(x) - g_lb_eq = 0  (num_variables() equality rows) by
//   min_dx |J dx + r|^2 + lambda |D dx|^2,
// solved by a column-pivoting QR of the stacked matrix [J; sqrt(lambda) D]
// (no normal equations, so the accuracy is that of J, not J^T J), with Moré's
// column scaling D and Nielsen's update of lambda from the gain ratio. As
// lambda -> 0 near the root the step becomes the Newton step, which gives the
// 1e-12 scaled residual the quasi-static solver asks for.
//
// Statuses (docs/plugins.md): kConverged when max|r| <= feasibility_tolerance
// and the bounds / inequality rows hold at the root; kInfeasible when the
// root violates them (a root of a nonsingular square system is locally
// unique: quasiroll::ClassifySquareSystemRoot, core/nlp_polish.h);
// kIterationLimit after max_iterations step attempts;
// kNumericalFailure for a non-finite residual or Jacobian, or stagnation.
// Never throws for numerical trouble. The objective is ignored.
// iterations = accepted steps (core/nlp.h), native_iterations = all steps
// computed (rejected ones, after which lambda grows, included); multipliers:
// none of its own (NlpSolver::Solve() estimates them, multipliers_estimated).
// Backend options (option_table(), the plugin's own): lambda_init_scale,
// the initial damping lambda_0 = lambda_init_scale * max_j |J e_j|^2.
#pragma once

#include <memory>
#include <string>

#include <quasiroll/core/nlp.h>

namespace example {

class LevenbergMarquardtSolver final : public quasiroll::NlpSolver {
 public:
  LevenbergMarquardtSolver();
  ~LevenbergMarquardtSolver() override;
  std::string name() const override { return "levenberg-marquardt"; }
  // Solve() then rejects non-square problems with std::invalid_argument.
  bool RequiresSquareSystem() const override { return true; }
  // All state is in members: separate instances may solve concurrently.
  bool SupportsConcurrentInstances() const override { return true; }
  quasiroll::OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const quasiroll::OptionValues& values) override;
  double lambda_init_scale_ = 1e-6;

  void DoSolve(const quasiroll::NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const quasiroll::NlpOptions& options,
               quasiroll::NlpResult* result) override;

  // DoSolve()'s phases.
  // LM steps until |r|_inf <= feasibility_tolerance; false when a failure
  // status was set. *iter = steps computed.
  bool Iterate(const quasiroll::NlpProblem& problem,
               const quasiroll::NlpOptions& options, int* iter,
               quasiroll::NlpResult* result);
  // Sets `status` with "<what> at iteration <iter>, |r|_inf = ..."; false.
  bool Fail(quasiroll::NlpStatus status, const char* what, int iter,
            quasiroll::NlpResult* result) const;
  // J, the scaling D and the first lambda at result->x; the failure
  // message, or nullptr.
  const char* UpdateJacobian(const quasiroll::NlpProblem& problem,
                             quasiroll::NlpResult* result);
  // The damped step dx and the predicted decrease of phi; false if dx is not
  // finite.
  bool ComputeStep(double* predicted);
  // Evaluates x + dx and moves there if accepted (lambda updated).
  bool TryStep(const quasiroll::NlpProblem& problem, double predicted,
               double tol, quasiroll::NlpResult* result);

  struct Workspace;
  std::unique_ptr<Workspace> ws_;  // per instance: one solver per thread
};

}  // namespace example
