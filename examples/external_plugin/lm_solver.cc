#include "lm_solver.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace example {

using quasiroll::NlpStatus;

struct LevenbergMarquardtSolver::Workspace {
  Eigen::VectorXd x_lb, x_ub, g_lb, g_ub, g, g_trial;
  Eigen::VectorXd r, r_trial, dx, x_trial, scale, rhs, jdx;
  Eigen::MatrixXd jac, jac_eq, aug;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  std::vector<int> eq_rows;

  void Resize(int n, int m) {
    for (Eigen::VectorXd* v :
         {&x_lb, &x_ub, &r, &r_trial, &dx, &x_trial, &scale, &jdx})
      v->resize(n);
    for (Eigen::VectorXd* v : {&g_lb, &g_ub, &g, &g_trial}) v->resize(m);
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

namespace {
// r = g(rows) - g_lb(rows); false if non-finite.
bool Residual(const Eigen::VectorXd& g, const Eigen::VectorXd& g_lb,
              const std::vector<int>& rows, Eigen::VectorXd* r) {
  for (size_t k = 0; k < rows.size(); ++k)
    (*r)(static_cast<Eigen::Index>(k)) = g(rows[k]) - g_lb(rows[k]);
  return r->allFinite();
}
}  // namespace

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
  problem.GetBounds(w.x_lb, w.x_ub, w.g_lb, w.g_ub);
  w.eq_rows.clear();
  for (int i = 0; i < m; ++i)
    if (w.g_lb(i) == w.g_ub(i))
      w.eq_rows.push_back(i);  // n rows (Solve checked)

  const double tol = options.feasibility_tolerance;
  char msg[200];
  // `iter` counts every LM step computed (the native count), `accepted` the
  // steps that moved x: the comparable count of core/nlp.h.
  int accepted = 0;
  auto fail = [&](NlpStatus status, const char* what, int iter) {
    result->status = status;
    std::snprintf(msg, sizeof msg, "%s at iteration %d, |r|_inf = %.3e", what,
                  iter, w.r.lpNorm<Eigen::Infinity>());
    result->backend_status = msg;
    result->iterations = accepted;
    result->native_iterations = iter;
  };

  Eigen::VectorXd& x = result->x;
  x = x0;
  problem.Constraints(x, w.g);
  ++result->constraint_evaluations;
  if (!Residual(w.g, w.g_lb, w.eq_rows, &w.r)) {
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status = "non-finite residual at the starting point";
    return;
  }
  double phi = 0.5 * w.r.squaredNorm();
  double lambda = -1.0, nu = 2.0;
  bool need_jacobian = true;
  w.scale.setZero();

  int iter = 0;
  while (w.r.lpNorm<Eigen::Infinity>() > tol) {
    if (iter >= options.max_iterations)
      return fail(NlpStatus::kIterationLimit, "max_iterations reached", iter);
    ++iter;
    if (need_jacobian) {
      problem.ConstraintJacobian(x, w.jac);
      ++result->jacobian_evaluations;
      for (int k = 0; k < n; ++k) w.jac_eq.row(k) = w.jac.row(w.eq_rows[k]);
      if (!w.jac_eq.allFinite())
        return fail(NlpStatus::kNumericalFailure, "non-finite Jacobian", iter);
      // Moré scaling: D_jj = max over iterations of |column j of J|.
      for (int j = 0; j < n; ++j)
        w.scale(j) = std::max(w.scale(j), w.jac_eq.col(j).norm());
      const double smax = w.scale.maxCoeff();
      if (!(smax > 0))
        return fail(NlpStatus::kNumericalFailure, "zero Jacobian", iter);
      w.scale = w.scale.cwiseMax(1e-10 * smax);
      if (lambda < 0) lambda = lambda_init_scale_ * smax * smax;
      need_jacobian = false;
    }

    // dx = argmin |J dx + r|^2 + lambda |D dx|^2.
    w.aug.topRows(n) = w.jac_eq;
    w.aug.bottomRows(n).setZero();
    w.aug.bottomRows(n).diagonal() = std::sqrt(lambda) * w.scale;
    w.rhs.head(n) = -w.r;
    w.rhs.tail(n).setZero();
    w.qr.compute(w.aug);
    w.dx = w.qr.solve(w.rhs);
    if (!w.dx.allFinite())
      return fail(NlpStatus::kNumericalFailure, "non-finite step", iter);
    w.jdx.noalias() = w.jac_eq * w.dx;
    const double predicted = -(w.r.dot(w.jdx) + 0.5 * w.jdx.squaredNorm());

    w.x_trial = x + w.dx;
    problem.Constraints(w.x_trial, w.g_trial);
    ++result->constraint_evaluations;
    bool accept = false;
    double phi_trial = phi;
    if (Residual(w.g_trial, w.g_lb, w.eq_rows, &w.r_trial)) {
      phi_trial = 0.5 * w.r_trial.squaredNorm();
      accept = w.r_trial.lpNorm<Eigen::Infinity>() <= tol ||
               (phi_trial < phi && predicted > 0);
    }
    if (accept) {
      const double rho = predicted > 0 ? (phi - phi_trial) / predicted : 1.0;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      nu = 2.0;
      x.swap(w.x_trial);
      w.g.swap(w.g_trial);
      w.r.swap(w.r_trial);
      phi = phi_trial;
      need_jacobian = true;
      ++accepted;
    } else {
      // Reject: shorter, more gradient-like step. A step below round-off
      // relative to x means no further progress is possible.
      const double step =
          (w.scale.asDiagonal() * w.dx).lpNorm<Eigen::Infinity>();
      const double size = (w.scale.asDiagonal() * x).lpNorm<Eigen::Infinity>();
      if (!(step > 1e-15 * std::max(size, 1e-300)) || !(lambda < 1e300))
        return fail(NlpStatus::kNumericalFailure, "stagnated", iter);
      lambda *= nu;
      nu *= 2.0;
    }
  }
  result->iterations = accepted;
  result->native_iterations = iter;

  const double viol =
      quasiroll::MaxConstraintViolation(x, w.g, w.x_lb, w.x_ub, w.g_lb, w.g_ub);
  if (viol > tol) {
    result->status = NlpStatus::kInfeasible;
    std::snprintf(msg, sizeof msg,
                  "root found in %d iterations violates bounds/inequalities by "
                  "%.3e",
                  iter, viol);
  } else {
    result->status = NlpStatus::kConverged;
    std::snprintf(msg, sizeof msg, "converged in %d iterations, |r|_inf = %.3e",
                  iter, w.r.lpNorm<Eigen::Infinity>());
  }
  result->backend_status = msg;
}

}  // namespace example
