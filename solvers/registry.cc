// Registers every NLP backend compiled into quasiroll::solvers.
#include <memory>
#include <mutex>

#include "quasiroll/core/nlp.h"
#include "quasiroll/solvers/newton_solver.h"
#ifdef QUASIROLL_HAVE_IPOPT
#include "quasiroll/solvers/ipopt_solver.h"
#endif
#ifdef QUASIROLL_HAVE_NLOPT
#include "quasiroll/solvers/slsqp_solver.h"
#endif
#ifdef QUASIROLL_HAVE_CERES
#include "quasiroll/solvers/ceres_solver.h"
#endif

namespace quasiroll {

void RegisterBuiltinNlpSolvers() {
  static std::once_flag once;
  std::call_once(once, [] {
    NlpSolverRegistry::Register(
        "newton", "damped Newton with dense LU on square equality systems",
        [] { return std::make_unique<NewtonSolver>(); });
#ifdef QUASIROLL_HAVE_IPOPT
    NlpSolverRegistry::Register(
        "ipopt",
        "Ipopt interior point (exact or L-BFGS Hessian), dense LDL^T KKT "
        "solves",
        [] { return std::make_unique<IpoptSolver>(); });
    NlpSolverRegistry::Register(
        "ipopt-mumps",
        "Ipopt interior point with its stock MUMPS linear solver (serial)", [] {
          return std::make_unique<IpoptSolver>(IpoptLinearSolver::kMumps);
        });
#endif
#ifdef QUASIROLL_HAVE_NLOPT
    NlpSolverRegistry::Register(
        "slsqp", "NLopt SLSQP with an active-set Newton feasibility polish",
        [] { return std::make_unique<SlsqpSolver>(); });
#endif
#ifdef QUASIROLL_HAVE_CERES
    NlpSolverRegistry::Register(
        "ceres", "Ceres: least-squares feasibility + augmented Lagrangian",
        [] { return std::make_unique<CeresNlpSolver>(); });
#endif
  });
}

}  // namespace quasiroll
