// Registers every NLP backend compiled into quasiroll::solvers, each with
// the BackendInfo it carries (core/backend_info.h). Cost ratios: seconds per
// hold interval with rk-projection in zoh mode relative to newton's, from
// the calibration of docs/cluster.md ("Cost model", default suite).
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

namespace {
BackendInfo Info(const char* description, const char* family,
                 const char* library, const char* version, double cost_ratio) {
  BackendInfo info =
      ThreadSafeBackendInfo(description, family, library, version);
  info.cost_ratio = cost_ratio;
  return info;
}
}  // namespace

void RegisterBuiltinNlpSolvers() {
  static std::once_flag once;
  std::call_once(once, [] {
    BackendInfo newton =
        Info("damped Newton with dense LU on square equality systems", "Newton",
             "", "", 1.0);
    newton.roles = {BackendRole::kDefault, BackendRole::kReference,
                    BackendRole::kContinuation};
    NlpSolverRegistry::Register("newton", std::move(newton),
                                [] { return MakeNewtonSolver(); });
#ifdef QUASIROLL_HAVE_IPOPT
    NlpSolverRegistry::Register(
        "ipopt",
        Info("Ipopt interior point (exact or L-BFGS Hessian), dense LDL^T KKT "
             "solves",
             "interior point", "Ipopt", QUASIROLL_IPOPT_VERSION, 12.25),
        [] { return MakeIpoptSolver(); });
    BackendInfo mumps =
        Info("Ipopt interior point with its stock MUMPS linear solver (serial)",
             "interior point", "Ipopt", QUASIROLL_IPOPT_VERSION, 88.1);
    mumps.thread_safe = false;  // sequential MUMPS keeps global state
    NlpSolverRegistry::Register("ipopt-mumps", std::move(mumps), [] {
      return MakeIpoptSolver(IpoptLinearSolver::kMumps);
    });
#endif
#ifdef QUASIROLL_HAVE_NLOPT
    NlpSolverRegistry::Register(
        "slsqp",
        Info("NLopt SLSQP with an active-set Newton feasibility polish", "SQP",
             "NLopt", QUASIROLL_NLOPT_VERSION, 2.13),
        [] { return MakeSlsqpSolver(); });
#endif
#ifdef QUASIROLL_HAVE_CERES
    NlpSolverRegistry::Register(
        "ceres",
        Info("Ceres: least-squares feasibility + augmented Lagrangian",
             "least squares", "Ceres", QUASIROLL_CERES_VERSION, 3.63),
        [] { return MakeCeresNlpSolver(); });
#endif
  });
}

}  // namespace quasiroll
