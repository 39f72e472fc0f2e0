// Internal helpers shared by the "slsqp" and "ceres" backends (not part of the
// public API; includes only core/nlp.h and Eigen).
//
// ActiveSetPolisher: a few Gauss-Newton (minimum-norm) steps on the active
// constraints of an approximately optimal point x:
//   active rows  A = equality rows + inequality rows within active_tol of a
//                    bound (or violating it), each targeting that bound;
//   fixed vars     = variables within active_tol of a bound (set to it);
//   step           dx_free = -pinv(J_A[:, free]) r_A   (complete orthogonal
//                  decomposition, so dependent rows are harmless).
// Moves x by O(current violation), i.e. changes the objective only at second
// order, and brings feasibility from ~1e-8 (typical SQP/AL answers) to
// round-off. Never returns a point whose violation exceeds that of its
// (box-projected) start. Allocates (it runs once per solve, after the backend
// finished).
//
// LooksLocallyInfeasible: true if x is a stationary point of the squared
// constraint violation 0.5 |v(x)|^2 (bounds by projection) at which the
// violation is clearly positive: evidence of (local) infeasibility.
#pragma once

#include <Eigen/Core>

#include "quasiroll/core/nlp.h"

namespace quasiroll::internal {

struct NlpBounds {
  Eigen::VectorXd x_lb, x_ub, g_lb, g_ub;
  void Load(const NlpProblem& problem);
};

struct PolishStats {
  int iterations = 0;      // Gauss-Newton steps computed (both passes)
  int accepted_steps = 0;  // of those, steps that moved the returned x
  int constraint_evaluations = 0;
  int jacobian_evaluations = 0;
  double max_violation = 0.0;  // at the returned x
  bool success = false;        // max_violation <= feasibility tolerance
};

PolishStats PolishActiveConstraints(const NlpProblem& problem,
                                    const NlpBounds& bounds, double active_tol,
                                    double feasibility_tolerance,
                                    int max_iterations, Eigen::VectorXd* x);

bool LooksLocallyInfeasible(const NlpProblem& problem, const NlpBounds& bounds,
                            const Eigen::VectorXd& x);

}  // namespace quasiroll::internal
