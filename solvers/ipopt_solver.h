// Backends "ipopt" and "ipopt-mumps": Ipopt's primal-dual interior-point
// method, differing only in the linear solver of the KKT systems:
//   ipopt        dense Bunch-Kaufman LDL^T (LAPACK dsytrf), plugged in through
//                Ipopt's MA27 interface (HSLLoader.h: LSL_setMA27; see
//                ipopt_dense_ma27.cc). For quasiroll's NLPs (n + m <= ~60)
//                it is 3-4x faster than MUMPS, whose per-call overhead
//                dominated (docs/performance.md), and it keeps no global state,
//                so solver objects may run in parallel threads (Ipopt >= 3.11
//                keeps its tags thread-local).
//   ipopt-mumps  Debian's sequential MUMPS, Ipopt's stock solver. MUMPS with
//                its dummy MPI is not thread-safe: never run two ipopt-mumps
//                solvers at once (the harness serialises them).
//
// One Ipopt::IpoptApplication per solver object (created and initialised in
// the constructor without reading an ipopt.opt file) and one persistent TNLP
// adapter that only delegates to the NlpProblem (dense Jacobian pattern,
// exact Hessian if problem.HasLagrangianHessian(), else L-BFGS). When a solve
// has the same structure as the previous one (sizes, Hessian mode, which
// bounds are finite / fixed, which rows are equalities) ReOptimizeTNLP() reuses
// Ipopt's algorithm objects; otherwise OptimizeTNLP() rebuilds them.
//
// Warm start (options.warm_start_multipliers and result->multipliers of size
// m): Ipopt's warm_start_init_point with the given constraint multipliers;
// bound multipliers are estimated from the reduced gradient
//   z_L - z_U = grad f(x0) + J(x0)^T lambda.
//
// Status: Solve_Succeeded, Solved_To_Acceptable_Level (only reachable when
// feasible to options.feasibility_tolerance, see acceptable_constr_viol_tol)
// and Feasible_Point_Found (square problems) -> kConverged;
// Infeasible_Problem_Detected -> kInfeasible; Maximum_Iterations_Exceeded ->
// kIterationLimit; every other code -> kNumericalFailure. Multipliers are
// Ipopt's lambda.
//
// Options that differ from Ipopt's defaults, and why (ipopt_solver.cc):
// mu_strategy monotone (Ipopt switches to the adaptive strategy with L-BFGS;
// its quality-function oracle cost ~40 % of a warm solve in extra
// backsolves), bound_relax_factor 0, tol / constr_viol_tol from NlpOptions.
// Backend options (option_table(), docs/plugins.md): mu_strategy, mu_init,
// warm_start_mu_init, warm_start_push, bound_relax_factor,
// hessian_approximation (auto = exact when the problem has a Hessian),
// limited_memory_max_history, nlp_scaling_method, acceptable_tol,
// acceptable_iter; ipopt-mumps also mumps_pivtol, mumps_mem_percent. The
// defaults are the values above and otherwise Ipopt's own.
#pragma once

#include <memory>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

enum class IpoptLinearSolver {
  kDenseLdlt,  // "ipopt"
  kMumps,      // "ipopt-mumps"
};

// The "ipopt" (dense LDL^T) and "ipopt-mumps" backends (registered by
// solvers/registry.cc).
std::unique_ptr<NlpSolver> MakeIpoptSolver(
    IpoptLinearSolver linear_solver = IpoptLinearSolver::kDenseLdlt);

}  // namespace quasiroll
