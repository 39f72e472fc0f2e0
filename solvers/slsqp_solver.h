// Backend "slsqp": NLopt's LD_SLSQP (Kraft's sequential least-squares QP).
//
//   equality rows      -> one add_equality_mconstraint   (g - g_lb = 0)
//   inequality rows    -> one add_inequality_mconstraint with a row per finite
//                         side (g_lb - g <= 0, g - g_ub <= 0)
//   variable bounds    -> set_lower_bounds / set_upper_bounds (x0 is clamped
//                         into the box first)
//   ftol_rel = xtol_rel = options.optimality_tolerance,
//   constraint tolerance = options.feasibility_tolerance,
//   maxeval = 3 * options.max_iterations (SLSQP does ~1-3 evaluations per
//   major iteration). NLopt does not expose the major iteration count:
//   `native_iterations` reports objective-gradient evaluations plus polish
//   steps computed, and `iterations` (accepted iterates, core/nlp.h) is
//   recovered from NLopt's calls (which points come with a gradient request,
//   slsqp_solver.cc, TrackPoint) plus the polish steps that moved x.
//
// NLopt may report success (SUCCESS/FTOL/XTOL/STOPVAL, also ROUNDOFF_LIMITED
// which "typically returns a useful result") with constraints violated beyond
// our tolerance. Such answers are re-checked; if violated, a cheap Newton
// polish on the active constraints (core/nlp_polish.h: minimum-norm
// Gauss-Newton steps, moving x by O(violation), so the objective changes only
// at second order) is applied, and only a point that then meets
// feasibility_tolerance is kConverged. Otherwise: kInfeasible if x is a
// stationary point of the constraint violation with clearly positive
// violation (LooksLocallyInfeasible), else kNumericalFailure. NLopt exceptions
// (roundoff_limited, forced_stop, bad_alloc, invalid_argument, runtime_error)
// map to statuses; non-finite function values force a stop ->
// kNumericalFailure.
//
// Backend options (option_table()): ftol_rel, xtol_rel (0 = NlpOptions'
// optimality_tolerance), ftol_abs (0 = off), maxeval_per_iteration (the 3
// above), polish_active_tol, polish_max_iterations (the polish below).
//
// The nlopt::opt object and all callback workspaces persist across solves with
// the same structure; NLopt's SLSQP itself allocates its work arrays on each
// optimize() call (library limitation).
#pragma once

#include <memory>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

// The "slsqp" backend (registered by solvers/registry.cc).
std::unique_ptr<NlpSolver> MakeSlsqpSolver();

}  // namespace quasiroll
