// Backend "ceres": Ceres Solver used in penalty / least-squares form.
//
// Notation: x in R^n, rows g(x) with bounds [g_lb, g_ub], E = equality rows,
// I = finite sides of inequality rows written as h_i(x) <= 0
// (g_lb - g <= 0 or g - g_ub <= 0), box lb <= x <= ub.
//
// Phase 1 (always, when there are constraint rows or fixed variables):
// feasibility least squares with Ceres' trust region (Levenberg-Marquardt,
// DENSE_QR), analytic dense Jacobian (one ceres::CostFunction block):
//   min_x 1/2 sum_E (g_e - g_lb,e)^2 + 1/2 sum_I max(0, h_i)^2
//   s.t. lb <= x <= ub     (Ceres parameter bounds; lb == ub -> residual
//                           x_j - lb_j instead, as Ceres needs lb < ub).
// The hinge residual max(0, h) makes the cost C^1. An iteration callback stops
// as soon as |r|_2 <= feasibility_tolerance/2 (so every residual is below the
// tolerance); function/gradient/parameter tolerances are 1e-16 so round-off,
// not Ceres, is the limit. Outcome: all residuals <= tolerance -> feasible
// (for a square system, num equalities == n, that is the answer:
// kConverged); Ceres CONVERGENCE at violation >= 1e-6 (a minimum of the
// violation with positive cost) -> kInfeasible; NO_CONVERGENCE ->
// kIterationLimit; FAILURE or a stall just above the tolerance ->
// kNumericalFailure.
//
// Phase 2 (problems with degrees of freedom, i.e. a real objective): a least-
// squares penalty cannot locate a constrained optimum of a general f, so an
// augmented Lagrangian (Powell-Hestenes-Rockafellar) outer loop is run:
//   Phi(x) = f(x) + sum_E [lam_e c_e + rho/2 c_e^2]
//                 + sum_{I and box} 1/(2 rho) [max(0, mu_i + rho h_i)^2 -
//                 mu_i^2]
// (box bounds are AL inequalities lb - x <= 0, x - ub <= 0; fixed variables
// AL equalities). Phi is C^1; each inner problem min_x Phi is solved with
// ceres::GradientProblemSolver (BFGS directions, Wolfe line search, gradient
// tolerance = optimality_tolerance). Updates: lam <- lam + rho c,
// mu <- max(0, mu + rho h); rho <- 10 rho when the feasibility/complementarity
// measure V = max(|c|, |min(-h, mu/rho)|) did not drop by 4x (rho <= 1e8).
// Converged when max violation and V <= feasibility_tolerance and the inner
// solve is stationary. Because BFGS with a function-value line search stalls
// at |grad Phi| ~ sqrt(eps |f| rho), pushing V to 1e-10 by raising rho only
// amplifies round-off; instead, once V <= max(feasibility_tolerance, 1e-7)
// (active set settled; AL theory gives |x - x*| <= C |lambda - lambda*|/rho
// ~ C V), the point is finished by an active-set Newton polish
// (core/nlp_polish.h: minimum-norm Gauss-Newton steps on the active rows,
// moving x by O(V)). The answer is only kConverged if every constraint
// residual is <= feasibility_tolerance.
//
// iterations (the comparable count, core/nlp.h) = successful LM steps + all
// inner BFGS iterations + accepted polish steps; native_iterations = all LM
// steps (successful and unsuccessful) + BFGS iterations + polish steps
// computed. max_iterations caps the LM iterations, the number of AL outer
// iterations and each inner solve.
// Warm start (warm_start_multipliers and a multiplier vector of size m, in
// Ipopt's convention lambda = mu_upper - mu_lower): seeds lam / mu; box
// multipliers from the reduced gradient grad f + J^T lambda.
//
// Backend options (option_table()): the penalty schedule rho_init,
// rho_growth, rho_max, rho_grow_unless (rho grows unless V fell below this
// fraction of the previous V), polish_threshold (the 1e-7 above),
// infeasible_threshold (1e-6: violation of a Ceres CONVERGENCE that counts as
// infeasible), polish_max_iterations, and Ceres' trust_region_strategy,
// linear_solver, line_search_direction. Defaults: the values above.
//
// Inputs are validated and x0 clamped into the box before Ceres is called,
// so Ceres never reaches a CHECK failure (which would abort the process).
#pragma once

#include <memory>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

// The "ceres" backend (registered by solvers/registry.cc).
std::unique_ptr<NlpSolver> MakeCeresNlpSolver();

}  // namespace quasiroll
