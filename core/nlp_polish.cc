#include "quasiroll/core/nlp_polish.h"

#include <Eigen/QR>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

namespace quasiroll {

namespace {

// One polish pass. Rows targeted: equalities, violated inequality rows and,
// with `near_active`, inequality rows within active_tol of a bound.
PolishStats PolishPass(const NlpProblem& problem, const NlpBounds& b,
                       double active_tol, double feasibility_tolerance,
                       int max_iterations, bool near_active,
                       Eigen::VectorXd* x_io) {
  PolishStats stats;
  Eigen::VectorXd& x = *x_io;
  const int n = problem.num_variables(), m = problem.num_constraints();
  Eigen::VectorXd g(m), g_trial(m), x_trial(n), r, dx;
  Eigen::MatrixXd jac(m, n), ja;
  std::vector<int> free_vars, rows;
  std::vector<double> targets;

  // Project onto the box and freeze near-active variables at their bound.
  for (int j = 0; j < n; ++j) {
    if (x(j) <= b.x_lb(j) + active_tol) {
      x(j) = b.x_lb(j);
    } else if (x(j) >= b.x_ub(j) - active_tol) {
      x(j) = b.x_ub(j);
    } else {
      free_vars.push_back(j);
    }
  }
  problem.Constraints(x, g);
  ++stats.constraint_evaluations;
  stats.max_violation = MaxConstraintViolation(x, g, b);
  double best_violation = stats.max_violation;
  Eigen::VectorXd x_best = x;
  int accepted_at_best = 0;

  while (stats.max_violation > feasibility_tolerance &&
         stats.iterations < max_iterations && !free_vars.empty() &&
         std::isfinite(stats.max_violation)) {
    rows.clear();
    targets.clear();
    // Without near_active, only rows violated beyond the tolerance: a row at
    // -1e-20 is feasible and must not be pulled onto its bound.
    const double band = near_active ? active_tol : -feasibility_tolerance;
    for (int i = 0; i < m; ++i) {
      if (b.g_lb(i) == b.g_ub(i) || g(i) < b.g_lb(i) + band) {
        rows.push_back(i);
        targets.push_back(b.g_lb(i));
      } else if (g(i) > b.g_ub(i) - band) {
        rows.push_back(i);
        targets.push_back(b.g_ub(i));
      }
    }
    if (rows.empty()) break;  // only bounds violated: projection did it
    problem.ConstraintJacobian(x, jac);
    ++stats.jacobian_evaluations;
    const int k = static_cast<int>(rows.size()),
              f = static_cast<int>(free_vars.size());
    ja.resize(k, f);
    r.resize(k);
    for (int a = 0; a < k; ++a) {
      r(a) = g(rows[a]) - targets[a];
      for (int c = 0; c < f; ++c) ja(a, c) = jac(rows[a], free_vars[c]);
    }
    if (!ja.allFinite()) break;
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(ja);
    dx = cod.solve(r);
    // Halve the step until the violation decreases, or until the simplified
    // correction pinv(J_A) r_A(x_trial) shrinks (natural monotonicity: on
    // ill-conditioned systems a step can raise the violation while moving
    // much closer to the solution, see newton_solver.h).
    bool improved = false;
    const double dx_norm = dx.norm();
    for (double alpha = 1.0; alpha >= 1e-10; alpha *= 0.5) {
      x_trial = x;
      for (int c = 0; c < f; ++c) {
        const int j = free_vars[c];
        x_trial(j) = std::clamp(x(j) - alpha * dx(c), b.x_lb(j), b.x_ub(j));
      }
      problem.Constraints(x_trial, g_trial);
      ++stats.constraint_evaluations;
      const double v = MaxConstraintViolation(x_trial, g_trial, b);
      bool natural = false;
      if (std::isfinite(v) && v >= stats.max_violation) {
        for (int a = 0; a < k; ++a) r(a) = g_trial(rows[a]) - targets[a];
        natural = cod.solve(r).norm() <= (1.0 - 0.25 * alpha) * dx_norm;
      }
      if (v < stats.max_violation || natural) {
        x.swap(x_trial);
        g.swap(g_trial);
        stats.max_violation = v;
        improved = true;
        ++stats.accepted_steps;
        break;
      }
    }
    ++stats.iterations;
    if (stats.max_violation < best_violation) {
      best_violation = stats.max_violation;
      x_best = x;
      accepted_at_best = stats.accepted_steps;
    }
    if (!improved) break;
  }
  // Natural-monotonicity steps may raise the violation on the way to a root
  // they never reach (seen: 1.2e-12 -> 1.4e-11 near a singular root of the
  // paper scene): never return a point worse than the best one seen.
  if (stats.max_violation > best_violation) {
    x = x_best;
    stats.max_violation = best_violation;
    stats.accepted_steps = accepted_at_best;
  }
  stats.success = stats.max_violation <= feasibility_tolerance;
  return stats;
}

}  // namespace

PolishStats PolishActiveConstraints(const NlpProblem& problem,
                                    const NlpBounds& b, double active_tol,
                                    double feasibility_tolerance,
                                    int max_iterations, Eigen::VectorXd* x_io) {
  // Targeting an inequality that is merely close to its bound (e.g. a
  // friction cone at |f_t| = (1 - 1e-7) mu f_n while sliding) would pull the
  // point onto the bound and fight the equalities; so first polish without
  // near-active rows, and include them only if that pass fails.
  const Eigen::VectorXd x0 = *x_io;
  PolishStats first = PolishPass(problem, b, active_tol, feasibility_tolerance,
                                 max_iterations, false, x_io);
  if (first.success) return first;
  Eigen::VectorXd x_first = *x_io;
  *x_io = x0;
  PolishStats second = PolishPass(problem, b, active_tol, feasibility_tolerance,
                                  max_iterations, true, x_io);
  second.iterations += first.iterations;
  second.constraint_evaluations += first.constraint_evaluations;
  second.jacobian_evaluations += first.jacobian_evaluations;
  if (!second.success && first.max_violation < second.max_violation) {
    *x_io = x_first;
    first.iterations = second.iterations;
    first.constraint_evaluations = second.constraint_evaluations;
    first.jacobian_evaluations = second.jacobian_evaluations;
    return first;
  }
  return second;
}

bool LooksLocallyInfeasible(const NlpProblem& problem, const NlpBounds& b,
                            const Eigen::Ref<const Eigen::VectorXd>& x) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  Eigen::VectorXd g(m), v(m), grad(n);
  Eigen::MatrixXd jac(m, n);
  problem.Constraints(x, g);
  problem.ConstraintJacobian(x, jac);
  if (!g.allFinite() || !jac.allFinite()) return false;
  const double viol = MaxConstraintViolation(x, g, b);
  if (viol < kInfeasibleViolation) return false;  // not clearly infeasible
  for (int i = 0; i < m; ++i)
    v(i) = g(i) < b.g_lb(i) ? g(i) - b.g_lb(i)
                            : (g(i) > b.g_ub(i) ? g(i) - b.g_ub(i) : 0.0);
  grad.noalias() = jac.transpose() * v;
  // Projected gradient: at a bound, a component pushing outwards is blocked.
  for (int j = 0; j < n; ++j) {
    if (x(j) <= b.x_lb(j) && grad(j) > 0) grad(j) = 0;
    if (x(j) >= b.x_ub(j) && grad(j) < 0) grad(j) = 0;
  }
  const double scale =
      std::max(1.0, jac.cwiseAbs().maxCoeff()) * v.lpNorm<Eigen::Infinity>();
  return grad.lpNorm<Eigen::Infinity>() <= kInfeasibleStationarity * scale;
}

void EqualityRows(const NlpBounds& bounds, std::vector<int>* rows) {
  rows->clear();
  for (int i = 0; i < bounds.g_lb.size(); ++i)
    if (bounds.g_lb(i) == bounds.g_ub(i)) rows->push_back(i);
}

void ClassifyRows(const NlpBounds& bounds, std::vector<int>* eq_rows,
                  std::vector<int>* side_rows, std::vector<double>* side_sign) {
  eq_rows->clear();
  side_rows->clear();
  side_sign->clear();
  for (int i = 0; i < bounds.g_lb.size(); ++i) {
    if (bounds.g_lb(i) == bounds.g_ub(i)) {
      eq_rows->push_back(i);
      continue;
    }
    if (std::isfinite(bounds.g_lb(i))) {
      side_rows->push_back(i);
      side_sign->push_back(-1.0);
    }
    if (std::isfinite(bounds.g_ub(i))) {
      side_rows->push_back(i);
      side_sign->push_back(+1.0);
    }
  }
}

bool EqualityResidual(const Eigen::VectorXd& g, const Eigen::VectorXd& g_lb,
                      const std::vector<int>& rows, Eigen::VectorXd* r) {
  for (std::size_t k = 0; k < rows.size(); ++k)
    (*r)(static_cast<Eigen::Index>(k)) = g(rows[k]) - g_lb(rows[k]);
  return r->allFinite();
}

bool StartSquareSystem(const NlpProblem& problem,
                       const Eigen::Ref<const Eigen::VectorXd>& x0,
                       const NlpBounds& bounds, const std::vector<int>& rows,
                       Eigen::VectorXd* g, Eigen::VectorXd* r,
                       NlpResult* result) {
  result->x = x0;
  problem.Constraints(result->x, *g);
  ++result->constraint_evaluations;
  if (EqualityResidual(*g, bounds.g_lb, rows, r)) return true;
  result->status = NlpStatus::kNumericalFailure;
  result->backend_status = "non-finite residual at the starting point";
  return false;
}

namespace {

void AppendInt(int value, std::string* out) {
  char buf[16];
  const std::to_chars_result res = std::to_chars(buf, buf + sizeof buf, value);
  out->append(buf, res.ptr);
}

void AppendScientific3(double value, std::string* out) {
  char buf[32];
  const std::to_chars_result res = std::to_chars(
      buf, buf + sizeof buf, value, std::chars_format::scientific, 3);
  out->append(buf, res.ptr);
}

}  // namespace

NlpStatus ClassifySquareSystemRoot(const NlpBounds& b,
                                   const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& g,
                                   double residual_inf, double tol,
                                   int iterations, NlpResult* result) {
  // Called once per solve: the message is assembled with std::to_chars
  // (printf's "%d" and "%.3e", byte for byte), which is several times
  // cheaper than snprintf's floating-point formatting.
  const double viol = MaxConstraintViolation(x, g, b);
  std::string& msg = result->backend_status;
  if (viol > tol) {
    result->status = NlpStatus::kInfeasible;
    msg = "root found in ";
    AppendInt(iterations, &msg);
    msg += " iterations violates bounds/inequalities by ";
    AppendScientific3(viol, &msg);
  } else {
    result->status = NlpStatus::kConverged;
    msg = "converged in ";
    AppendInt(iterations, &msg);
    msg += " iterations, |r|_inf = ";
    AppendScientific3(residual_inf, &msg);
  }
  return result->status;
}

}  // namespace quasiroll
