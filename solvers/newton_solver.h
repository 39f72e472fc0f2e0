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
// non-finite residual give kNumericalFailure; max_i |r_i| not halved over
// options.stall_iterations iterations (if > 0; not while polishing) gives
// kIterationLimit early. Multipliers are left at zero.
// After the first call with given sizes DoSolve() does not allocate.
// Backend options (option_table()): armijo, min_damping, rank_pivot_ratio,
// lm_lambda_init, polish_floor (the constants above; defaults as stated).
#pragma once

#include <memory>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

// The "newton" backend (registered by solvers/registry.cc).
std::unique_ptr<NlpSolver> MakeNewtonSolver();

}  // namespace quasiroll
