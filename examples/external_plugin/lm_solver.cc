#include "lm_solver.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <quasiroll/core/nlp_polish.h>

namespace example {

using quasiroll::NlpStatus;

struct LevenbergMarquardtSolver::Workspace {
  quasiroll::NlpBounds bounds;  // loaded per solve
  Eigen::VectorXd g, g_trial;
  Eigen::VectorXd r, r_trial, dx, x_trial, scale, rhs, jdx;
  Eigen::MatrixXd jac, jac_eq, aug;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  std::vector<int> eq_rows;
  // Iteration state: phi = |r|^2 / 2, damping lambda (< 0: not yet set) and
  // its growth factor nu, accepted steps.
  double phi = 0.0, lambda = -1.0, nu = 2.0;
  int accepted = 0;

  void Resize(int n, int m) {
    for (Eigen::VectorXd* v : {&r, &r_trial, &dx, &x_trial, &scale, &jdx})
      v->resize(n);
    for (Eigen::VectorXd* v : {&g, &g_trial}) v->resize(m);
    rhs.resize(2 * n);
    jac.resize(m, n);
    jac_eq.resize(n, n);
    aug.resize(2 * n, n);
    eq_rows.reserve(static_cast<size_t>(n));
  }
};

LevenbergMarquardtSolver::LevenbergMarquardtSolver()
    : ws_(std::make_unique<Workspace>()) {}
LevenbergMarquardtSolver::~LevenbergMarquardtSolver() = default;

quasiroll::OptionTable LevenbergMarquardtSolver::option_table() const {
  return {quasiroll::OptionSpec::Double(
              "lambda_init_scale", 1e-6,
              "initial damping lambda_0 = scale * max_j |J e_j|^2")
              .GreaterThan(0)};
}

void LevenbergMarquardtSolver::ApplyBackendOptions(
    const quasiroll::OptionValues& values) {
  lambda_init_scale_ = values.GetDouble("lambda_init_scale");
}

void LevenbergMarquardtSolver::DoSolve(
    const quasiroll::NlpProblem& problem,
    const Eigen::Ref<const Eigen::VectorXd>& x0,
    const quasiroll::NlpOptions& options, quasiroll::NlpResult* result) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  Workspace& w = *ws_;
  w.Resize(n, m);
  w.bounds.Load(problem);
  quasiroll::EqualityRows(w.bounds, &w.eq_rows);  // n rows (Solve checked)
  if (!quasiroll::StartSquareSystem(problem, x0, w.bounds, w.eq_rows, &w.g,
                                    &w.r, result))
    return;
  const Eigen::VectorXd& x = result->x;
  int iter = 0;
  if (!Iterate(problem, options, &iter, result)) return;
  // The library's test for a square system's root: bounds or inequality
  // rows violated at the (locally unique) root mean kInfeasible.
  quasiroll::ClassifySquareSystemRoot(
      w.bounds, x, w.g, w.r.lpNorm<Eigen::Infinity>(),
      options.feasibility_tolerance, iter, result);
}

bool LevenbergMarquardtSolver::Iterate(const quasiroll::NlpProblem& problem,
                                       const quasiroll::NlpOptions& options,
                                       int* iter_out,
                                       quasiroll::NlpResult* result) {
  Workspace& w = *ws_;
  const double tol = options.feasibility_tolerance;
  w.phi = 0.5 * w.r.squaredNorm();
  w.lambda = -1.0;
  w.nu = 2.0;
  w.accepted = 0;
  bool need_jacobian = true;
  w.scale.setZero();

  // `iter` counts every LM step computed (the native count), w.accepted the
  // steps that moved x: the comparable count of core/nlp.h.
  int& iter = *iter_out;
  while (w.r.lpNorm<Eigen::Infinity>() > tol) {
    if (iter >= options.max_iterations)
      return Fail(NlpStatus::kIterationLimit, "max_iterations reached", iter,
                  result);
    ++iter;
    if (need_jacobian) {
      if (const char* why = UpdateJacobian(problem, result))
        return Fail(NlpStatus::kNumericalFailure, why, iter, result);
      need_jacobian = false;
    }
    double predicted = 0.0;
    if (!ComputeStep(&predicted))
      return Fail(NlpStatus::kNumericalFailure, "non-finite step", iter,
                  result);
    if (TryStep(problem, predicted, tol, result)) {
      need_jacobian = true;
      continue;
    }
    // Rejected: shorter, more gradient-like step. A step below round-off
    // relative to x means no further progress is possible.
    const double step = (w.scale.asDiagonal() * w.dx).lpNorm<Eigen::Infinity>();
    const double size =
        (w.scale.asDiagonal() * result->x).lpNorm<Eigen::Infinity>();
    if (!(step > 1e-15 * std::max(size, 1e-300)) || !(w.lambda < 1e300))
      return Fail(NlpStatus::kNumericalFailure, "stagnated", iter, result);
    w.lambda *= w.nu;
    w.nu *= 2.0;
  }
  result->iterations = w.accepted;
  result->native_iterations = iter;
  return true;
}

bool LevenbergMarquardtSolver::Fail(NlpStatus status, const char* what,
                                    int iter,
                                    quasiroll::NlpResult* result) const {
  const Workspace& w = *ws_;
  char msg[200];
  result->status = status;
  std::snprintf(msg, sizeof msg, "%s at iteration %d, |r|_inf = %.3e", what,
                iter, w.r.lpNorm<Eigen::Infinity>());
  result->backend_status = msg;
  result->iterations = w.accepted;
  result->native_iterations = iter;
  return false;
}

const char* LevenbergMarquardtSolver::UpdateJacobian(
    const quasiroll::NlpProblem& problem, quasiroll::NlpResult* result) {
  Workspace& w = *ws_;
  const int n = static_cast<int>(w.eq_rows.size());
  problem.ConstraintJacobian(result->x, w.jac);
  ++result->jacobian_evaluations;
  for (int k = 0; k < n; ++k) w.jac_eq.row(k) = w.jac.row(w.eq_rows[k]);
  if (!w.jac_eq.allFinite()) return "non-finite Jacobian";
  // Moré scaling: D_jj = max over iterations of |column j of J|.
  for (int j = 0; j < n; ++j)
    w.scale(j) = std::max(w.scale(j), w.jac_eq.col(j).norm());
  const double smax = w.scale.maxCoeff();
  if (!(smax > 0)) return "zero Jacobian";
  w.scale = w.scale.cwiseMax(1e-10 * smax);
  if (w.lambda < 0) w.lambda = lambda_init_scale_ * smax * smax;
  return nullptr;
}

bool LevenbergMarquardtSolver::ComputeStep(double* predicted) {
  Workspace& w = *ws_;
  const int n = static_cast<int>(w.eq_rows.size());
  // dx = argmin |J dx + r|^2 + lambda |D dx|^2.
  w.aug.topRows(n) = w.jac_eq;
  w.aug.bottomRows(n).setZero();
  w.aug.bottomRows(n).diagonal() = std::sqrt(w.lambda) * w.scale;
  w.rhs.head(n) = -w.r;
  w.rhs.tail(n).setZero();
  w.qr.compute(w.aug);
  w.dx = w.qr.solve(w.rhs);
  if (!w.dx.allFinite()) return false;
  w.jdx.noalias() = w.jac_eq * w.dx;
  *predicted = -(w.r.dot(w.jdx) + 0.5 * w.jdx.squaredNorm());
  return true;
}

bool LevenbergMarquardtSolver::TryStep(const quasiroll::NlpProblem& problem,
                                       double predicted, double tol,
                                       quasiroll::NlpResult* result) {
  Workspace& w = *ws_;
  Eigen::VectorXd& x = result->x;
  w.x_trial = x + w.dx;
  problem.Constraints(w.x_trial, w.g_trial);
  ++result->constraint_evaluations;
  bool accept = false;
  double phi_trial = w.phi;
  if (quasiroll::EqualityResidual(w.g_trial, w.bounds.g_lb, w.eq_rows,
                                  &w.r_trial)) {
    phi_trial = 0.5 * w.r_trial.squaredNorm();
    accept = w.r_trial.lpNorm<Eigen::Infinity>() <= tol ||
             (phi_trial < w.phi && predicted > 0);
  }
  if (!accept) return false;
  const double rho = predicted > 0 ? (w.phi - phi_trial) / predicted : 1.0;
  w.lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
  w.nu = 2.0;
  x.swap(w.x_trial);
  w.g.swap(w.g_trial);
  w.r.swap(w.r_trial);
  w.phi = phi_trial;
  ++w.accepted;
  return true;
}

}  // namespace example
