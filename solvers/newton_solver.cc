#include "quasiroll/solvers/newton_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "quasiroll/core/nlp_polish.h"
#include "quasiroll/core/square_lu.h"

namespace quasiroll {
namespace {

struct Workspace {
  NlpBounds bounds;  // loaded per solve
  Eigen::VectorXd g, g_trial, r, r_trial, dx, dx_bar, x_trial;
  Eigen::MatrixXd jac, jac_eq, jtj, jtj_damped;
  Eigen::VectorXd jtr, jtj_diag;
  SquareLu lu;  // bit-identical to Eigen::PartialPivLU, ~1.6x faster (15 x 15)
  Eigen::LLT<Eigen::MatrixXd> llt;
  std::vector<int> eq_rows;

  void Resize(int n, int m) {
    g.resize(m);
    g_trial.resize(m);
    r.resize(n);
    r_trial.resize(n);
    dx.resize(n);
    dx_bar.resize(n);
    x_trial.resize(n);
    jac.resize(m, n);
    jac_eq.resize(n, n);
    jtj.resize(n, n);
    jtj_damped.resize(n, n);
    jtr.resize(n);
    jtj_diag.resize(n);
    // Factor an identity once to allocate the factor's storage: assigning a
    // size-constructed LLT would copy its uninitialised info() (UBSan).
    if (llt.rows() != n) llt.compute(Eigen::MatrixXd::Identity(n, n));
    eq_rows.reserve(static_cast<size_t>(n));
  }
};

class NewtonSolver final : public NlpSolver {
 public:
  std::string name() const override { return "newton"; }
  bool RequiresSquareSystem() const override { return true; }
  bool SupportsConcurrentInstances() const override { return true; }
  OptionTable option_table() const override {
    return {
        OptionSpec::Double(
            "armijo", 2e-4,
            "sufficient decrease: |r(x + a dx)|^2 <= (1 - armijo "
            "a) |r(x)|^2")
            .GreaterThan(0)
            .LessThan(1),
        OptionSpec::Double("min_damping", 1e-10,
                           "smallest step fraction a before the "
                           "Levenberg-Marquardt fallback")
            .GreaterThan(0)
            .LessThan(1),
        OptionSpec::Double("rank_pivot_ratio", 1e-13,
                           "LU pivot ratio min/max below which the Jacobian "
                           "counts as rank deficient")
            .GreaterThan(0)
            .LessThan(1),
        OptionSpec::Double("lm_lambda_init", 1e-3,
                           "initial Levenberg-Marquardt damping of the "
                           "fallback step (per solve)")
            .GreaterThan(0),
        OptionSpec::Double("polish_floor", 1e-14,
                           "tightest residual target of the polish before "
                           "bounds are judged")
            .GreaterThan(0),
    };
  }

 private:
  void ApplyBackendOptions(const OptionValues& values) override {
    settings_.armijo = values.GetDouble("armijo");
    settings_.min_damping = values.GetDouble("min_damping");
    settings_.rank_pivot_ratio = values.GetDouble("rank_pivot_ratio");
    settings_.lm_lambda_init = values.GetDouble("lm_lambda_init");
    settings_.polish_floor = values.GetDouble("polish_floor");
  }
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override;

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

  Workspace ws_;
  double lm_lambda_ = 1e-3;  // Levenberg-Marquardt damping, reset per solve
  struct Settings {
    double armijo = 2e-4;
    double min_damping = 1e-10;
    double rank_pivot_ratio = 1e-13;
    double lm_lambda_init = 1e-3;
    double polish_floor = 1e-14;
  } settings_;
};

// Levenberg-Marquardt fallback (Marquardt's scaling D = diag(J^T J)):
//   (J^T J + lambda D) dx = -J^T r,  lambda = lambda_k, 10 lambda_k, ...
// taking the first dx with |r(x + dx)|^2 < |r(x)|^2 (for large lambda dx is
// a short step along the steepest-descent direction -J^T r, so one exists
// unless x is stationary for |r|^2). Used when no damped Newton step is
// acceptable: far from the root J can be nearly singular (a slip component
// passing zero makes dC/df_t = sigma ~ eps in the creep law; cond 1.7e12
// seen on the paper scene at t = 2.907 s, against 4e6 at the root), and the
// Newton direction is then huge and useless. lambda_k is kept between calls
// and divided by 10 after each success. On success x, g, r hold the new
// point.
bool NewtonSolver::LevenbergMarquardtStep(const NlpProblem& problem,
                                          Workspace* w, double phi,
                                          NlpResult* result) {
  w->jtj.noalias() = w->jac_eq.transpose() * w->jac_eq;
  w->jtr.noalias() = w->jac_eq.transpose() * w->r;
  w->jtj_diag = w->jtj.diagonal().cwiseMax(1e-300);
  const int n = static_cast<int>(w->r.size());
  for (lm_lambda_ = std::clamp(lm_lambda_, 1e-12, 1.0); lm_lambda_ <= 1e12;
       lm_lambda_ *= 10.0) {
    w->jtj_damped = w->jtj;
    for (int i = 0; i < n; ++i)
      w->jtj_damped(i, i) += lm_lambda_ * w->jtj_diag(i);
    w->llt.compute(w->jtj_damped);
    if (w->llt.info() != Eigen::Success) continue;
    w->dx = w->llt.solve(w->jtr);
    w->x_trial = result->x - w->dx;
    problem.Constraints(w->x_trial, w->g_trial);
    ++result->constraint_evaluations;
    if (EqualityResidual(w->g_trial, w->bounds.g_lb, w->eq_rows, &w->r_trial) &&
        w->r_trial.squaredNorm() < phi) {
      lm_lambda_ *= 0.1;
      return true;
    }
  }
  return false;
}

void NewtonSolver::DoSolve(const NlpProblem& problem,
                           const Eigen::Ref<const Eigen::VectorXd>& x0,
                           const NlpOptions& options, NlpResult* result) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  Workspace& w = ws_;
  w.Resize(n, m);
  w.bounds.Load(problem);
  EqualityRows(w.bounds, &w.eq_rows);  // n rows (validated)

  lm_lambda_ = settings_.lm_lambda_init;
  if (!StartSquareSystem(problem, x0, w.bounds, w.eq_rows, &w.g, &w.r, result))
    return;
  const Eigen::VectorXd& x = result->x;
  int iter = 0;
  if (!Iterate(problem, options, &iter, result)) return;
  result->iterations = iter;
  // The equalities hold; the root is unique nearby, so bounds or inequality
  // rows violated there mean the problem is (locally) infeasible.
  ClassifySquareSystemRoot(w.bounds, x, w.g, w.r.lpNorm<Eigen::Infinity>(),
                           options.feasibility_tolerance, iter, result);
}

bool NewtonSolver::Iterate(const NlpProblem& problem, const NlpOptions& options,
                           int* iter_out, NlpResult* result) {
  Workspace& w = ws_;
  const double tol = options.feasibility_tolerance;
  char msg[160];
  Eigen::VectorXd& x = result->x;
  // An approximate root (|r| <= a loose tol) can violate an inequality row
  // that the root itself satisfies (the friction cone is active to O(eps) on
  // the root of a sliding contact). Before calling such a point infeasible,
  // polish: tighten the residual target and keep iterating, and judge the
  // bounds at the polished point. A polish that stalls keeps the last point.
  const double polish_floor = settings_.polish_floor;
  double target = tol;
  bool polishing = false;
  int& iter = *iter_out;
  // Stall watch (NlpOptions::stall_iterations): the residual of the last
  // halving and the iteration it happened at.
  double r_halved = std::numeric_limits<double>::infinity();
  int iter_halved = 0;
  for (;; ++iter) {
    const double r_max = w.r.lpNorm<Eigen::Infinity>();
    if (r_max <= target) {
      if (target <= polish_floor) break;
      if (MaxConstraintViolation(x, w.g, w.bounds) <= tol) break;
      polishing = true;
      target = std::max(polish_floor, 1e-4 * r_max);
      if (r_max <= target) break;
    }
    if (polishing && iter >= options.max_iterations) break;
    if (r_max <= 0.5 * r_halved) {
      r_halved = r_max;
      iter_halved = iter;
    } else if (!polishing && options.stall_iterations > 0 &&
               iter - iter_halved >= options.stall_iterations) {
      result->status = NlpStatus::kIterationLimit;
      result->stalled = true;
      std::snprintf(msg, sizeof msg,
                    "stalled: |r|_inf = %.3e not halved in %d iterations",
                    r_max, iter - iter_halved);
      result->backend_status = msg;
      result->iterations = iter;
      return false;
    }
    if (iter >= options.max_iterations) {
      result->status = NlpStatus::kIterationLimit;
      std::snprintf(msg, sizeof msg, "max_iterations reached, |r|_inf = %.3e",
                    r_max);
      result->backend_status = msg;
      result->iterations = iter;
      return false;
    }
    if (!FactorJacobian(problem, polishing, iter, result)) {
      if (polishing) break;
      return false;
    }
    w.lu.Solve(w.r, w.dx);
    w.dx = -w.dx;
    const double phi = w.r.squaredNorm();
    bool accepted = DampedStep(problem, phi, target, result);
    if (!accepted && polishing) break;  // |r| <= tol already holds
    if (!accepted) accepted = LevenbergMarquardtStep(problem, &w, phi, result);
    if (!accepted) {
      result->status = NlpStatus::kNumericalFailure;
      std::snprintf(
          msg, sizeof msg,
          "line search and LM step failed at iteration %d, |r|_inf = %.3e",
          iter, r_max);
      result->backend_status = msg;
      result->iterations = iter;
      return false;
    }
    x.swap(w.x_trial);
    w.g.swap(w.g_trial);
    w.r.swap(w.r_trial);
  }
  return true;
}

bool NewtonSolver::FactorJacobian(const NlpProblem& problem, bool polishing,
                                  int iter, NlpResult* result) {
  Workspace& w = ws_;
  const int n = static_cast<int>(w.eq_rows.size());
  problem.ConstraintJacobian(result->x, w.jac);
  ++result->jacobian_evaluations;
  for (int k = 0; k < n; ++k) w.jac_eq.row(k) = w.jac.row(w.eq_rows[k]);
  if (!w.jac_eq.allFinite()) {
    if (polishing) return false;
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status = "non-finite Jacobian";
    result->iterations = iter;
    return false;
  }
  w.lu.Compute(w.jac_eq);
  // Rank test on the pivots of U: partial pivoting puts the largest
  // available entry on the diagonal, so a pivot at round-off level relative
  // to the largest one means a (numerically) rank-deficient Jacobian.
  const double pivot_max = w.lu.MaxAbsPivot(), pivot_min = w.lu.MinAbsPivot();
  if (!(pivot_min > settings_.rank_pivot_ratio * pivot_max)) {
    if (polishing) return false;
    result->status = NlpStatus::kNumericalFailure;
    char msg[160];
    std::snprintf(msg, sizeof msg,
                  "rank-deficient Jacobian (pivot ratio %.3e) at iteration %d",
                  pivot_max > 0 ? pivot_min / pivot_max : 0.0, iter);
    result->backend_status = msg;
    result->iterations = iter;
    return false;
  }
  return true;
}

// Damping: accept x + alpha dx when either
//  (a) natural monotonicity (Deuflhard, affine invariant): the simplified
//      correction dxbar = -J(x)^{-1} r(x + alpha dx), reusing this LU,
//      satisfies |dxbar| <= (1 - alpha/4) |dx|, or
//  (b) Armijo on phi = |r|^2: phi(x + alpha dx) <= (1 - 2e-4 alpha) phi(x).
// (a) matters for ill-conditioned systems (the creeping friction law has
// condition numbers ~1e7-1e8): there a full step can raise |r| while
// moving much closer to the root, and a residual-only test stalls.
bool NewtonSolver::DampedStep(const NlpProblem& problem, double phi,
                              double target, NlpResult* result) {
  Workspace& w = ws_;
  const double dx_norm = w.dx.norm();
  double alpha = 1.0;
  while (alpha >= settings_.min_damping) {
    w.x_trial = result->x + alpha * w.dx;
    problem.Constraints(w.x_trial, w.g_trial);
    ++result->constraint_evaluations;
    if (EqualityResidual(w.g_trial, w.bounds.g_lb, w.eq_rows, &w.r_trial)) {
      const double phi_trial = w.r_trial.squaredNorm();
      if (phi_trial <= (1.0 - settings_.armijo * alpha) * phi ||
          w.r_trial.lpNorm<Eigen::Infinity>() <= target) {
        return true;
      }
      w.lu.Solve(w.r_trial, w.dx_bar);
      if (w.dx_bar.norm() <= (1.0 - 0.25 * alpha) * dx_norm) return true;
    }
    alpha *= 0.5;
  }
  return false;
}

}  // namespace

std::unique_ptr<NlpSolver> MakeNewtonSolver() {
  return std::make_unique<NewtonSolver>();
}

}  // namespace quasiroll
