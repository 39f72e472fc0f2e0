// Feasibility helpers for NLP backends: the active-set polish and the
// infeasibility tests the built-in backends use, public so that a plugin
// wrapping another optimiser (examples/external_plugin/lm_solver.cc) reaches
// the same 1e-12 feasibility and the same statuses without rewriting them.
//
// Notation: the problem of core/nlp.h, its bounds b = (x_lb, x_ub, g_lb, g_ub),
// J = dg/dx, and the max-norm violation
//   viol(x) = MaxConstraintViolation(x, g(x), b)   (>= 0, inf if g non-finite).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

struct PolishStats {
  int iterations = 0;      // Gauss-Newton steps computed (both passes)
  int accepted_steps = 0;  // of those, steps that moved the returned x
  int constraint_evaluations = 0;
  int jacobian_evaluations = 0;
  double max_violation = 0.0;  // viol at the returned x
  bool success = false;        // max_violation <= feasibility_tolerance
};

// Active-set polish: a few Gauss-Newton (minimum-norm) steps on the active
// constraints of an approximately optimal point *x, which bring feasibility
// from ~1e-8 (typical SQP / augmented-Lagrangian answers) to round-off. With
// tol = feasibility_tolerance and a = active_tol, one pass is:
//   box:    x_j <= x_lb_j + a  ->  x_j = x_lb_j,  x_j >= x_ub_j - a  ->
//           x_j = x_ub_j  (fixed); every other variable is free (set F);
//   rows A: the equalities, plus every inequality side with
//             g_i < g_lb_i + band  (target t_i = g_lb_i)  or
//             g_i > g_ub_i - band  (target t_i = g_ub_i),
//           band = -tol in the first pass (only rows violated beyond tol:
//           a merely near-active row, e.g. a friction cone at
//           (1 - 1e-7) mu f_n while sliding, would be pulled onto its bound
//           and fight the equalities), band = a in the second;
//   step:   dx = pinv(J[A, F]) (g_A - t_A)  (complete orthogonal
//           decomposition: dependent rows are harmless),
//           x_F <- clamp(x_F - alpha dx, box),  alpha = 1, 1/2, ... >= 1e-10,
//           the first alpha with
//             viol(x_trial) < viol(x)   or   (viol(x_trial) finite and
//             |pinv(J[A, F]) (g_A(x_trial) - t_A)|_2 <= (1 - alpha/4) |dx|_2)
//           (natural monotonicity: on ill-conditioned systems a step may
//           raise the violation while moving much closer to the root);
//   stop:   viol <= tol, max_iterations steps, no alpha accepted, no free
//           variable, no row in A, or non-finite J[A, F].
// A pass returns the point of least viol it saw (never worse than its
// box-projected start). The second pass (band = a) runs from the original *x
// only if the first fails; the answer is the second's unless it failed with a
// larger viol than the first's. x moves by O(viol), so the objective changes
// only at second order. Allocates (it runs once per solve, after the
// backend's own iterations).
PolishStats PolishActiveConstraints(const NlpProblem& problem,
                                    const NlpBounds& bounds, double active_tol,
                                    double feasibility_tolerance,
                                    int max_iterations, Eigen::VectorXd* x);

// Thresholds of LooksLocallyInfeasible().
constexpr double kInfeasibleViolation = 1e-6;
constexpr double kInfeasibleStationarity = 1e-6;

// Evidence of (local) infeasibility: x is a stationary point of the squared
// row violation 1/2 |v(x)|^2, bounds by projection, at which the violation is
// clearly positive. With
//   v_i = g_i - g_lb_i if g_i < g_lb_i,  g_i - g_ub_i if g_i > g_ub_i,  else 0
//   d   = J^T v,  projected: d_j = 0 where x_j <= x_lb_j and d_j > 0, or
//         x_j >= x_ub_j and d_j < 0  (a bound blocks that direction)
// it returns true iff g and J are finite and
//   viol(x) >= kInfeasibleViolation   and
//   |d|_inf <= kInfeasibleStationarity * max(1, max_ij |J_ij|) * |v|_inf.
bool LooksLocallyInfeasible(const NlpProblem& problem, const NlpBounds& bounds,
                            const Eigen::Ref<const Eigen::VectorXd>& x);

// Status of a root x of a square equality system (as many equality rows as
// variables, nonsingular Jacobian, equality residual |r|_inf <= tol): the root
// is locally unique, so a bound or inequality row violated there means no
// feasible point nearby:
//   kInfeasible  if viol(x) > tol   (g = g(x) given),
//   kConverged   otherwise.
// Sets result->status and result->backend_status ("converged in <iterations>
// iterations, |r|_inf = <residual_inf>" or "root found in <iterations>
// iterations violates bounds/inequalities by <viol>"); returns the status.
// Newton-type backends on a square equality system (newton, the example
// plugin's lm) work on the equality rows E = {i : g_lb_i == g_ub_i} and
// their residual r = g_E - g_lb_E:
//   EqualityRows:      *rows = E, in row order (allocation-free once
//                      reserved);
//   EqualityResidual:  *r = g_E - g_lb_E (r sized |E|); false if non-finite;
//   StartSquareSystem: result->x = x0, *g = g(x0) (counted in
//                      result->constraint_evaluations), *r its residual;
//                      false, with kNumericalFailure set, when r is
//                      non-finite.
void EqualityRows(const NlpBounds& bounds, std::vector<int>* rows);
// Every row of g by kind, in row order: the equalities into *eq_rows, each
// finite side of the others into *side_rows with *side_sign -1 for
// g_lb_i <= g_i (listed first) and +1 for g_i <= g_ub_i.
void ClassifyRows(const NlpBounds& bounds, std::vector<int>* eq_rows,
                  std::vector<int>* side_rows, std::vector<double>* side_sign);
bool EqualityResidual(const Eigen::VectorXd& g, const Eigen::VectorXd& g_lb,
                      const std::vector<int>& rows, Eigen::VectorXd* r);
bool StartSquareSystem(const NlpProblem& problem,
                       const Eigen::Ref<const Eigen::VectorXd>& x0,
                       const NlpBounds& bounds, const std::vector<int>& rows,
                       Eigen::VectorXd* g, Eigen::VectorXd* r,
                       NlpResult* result);

NlpStatus ClassifySquareSystemRoot(const NlpBounds& bounds,
                                   const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& g,
                                   double residual_inf, double tol,
                                   int iterations, NlpResult* result);

}  // namespace quasiroll
