// Backend "ipopt": Ipopt's primal-dual interior-point method.
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
// Ipopt's lambda. Not thread-safe across objects if Ipopt's linear solver
// (sequential MUMPS in Debian) is not.
#pragma once

#include <memory>
#include <string>

#include "core/nlp.h"

namespace quasiroll {

class IpoptSolver final : public NlpSolver {
 public:
  IpoptSolver();
  ~IpoptSolver() override;
  std::string name() const override { return "ipopt"; }

 private:
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace quasiroll
