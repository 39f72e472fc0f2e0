// The built-in backends through the conformance kit: one line each, as a
// plugin registers its own (docs/plugins.md, "Conformance kit").
#include "quasiroll/conformance/integrator_conformance.h"
#include "quasiroll/conformance/nlp_conformance.h"

namespace {

// Before main() runs the tests: the suites create backends by name.
[[maybe_unused]] const bool kRegistered = [] {
  quasiroll::RegisterBuiltinNlpSolvers();
  quasiroll::RegisterBuiltinIntegrators();
  return true;
}();

}  // namespace

// Thread safety as the backends report it (SupportsConcurrentInstances()):
// ipopt-mumps is not, MUMPS keeps global state.
QUASIROLL_NLP_CONFORMANCE(newton, "newton", /*thread_safe=*/true);
#ifdef QUASIROLL_HAVE_IPOPT
QUASIROLL_NLP_CONFORMANCE(ipopt, "ipopt", /*thread_safe=*/true);
QUASIROLL_NLP_CONFORMANCE(ipopt_mumps, "ipopt-mumps", /*thread_safe=*/false);
#endif
#ifdef QUASIROLL_HAVE_NLOPT
// SLSQP ends an infeasible problem with violated constraints
// (kNumericalFailure), without an infeasibility test of its own.
QUASIROLL_NLP_CONFORMANCE(slsqp, "slsqp", /*thread_safe=*/true,
                          /*detects_infeasibility=*/false);
#endif
#ifdef QUASIROLL_HAVE_CERES
QUASIROLL_NLP_CONFORMANCE(ceres, "ceres", /*thread_safe=*/true);
#endif

// The RK backends' default scheme is fixed-step RK4; the Andrews check needs
// the method's own step control (as tests/integrators/robustness_test.cc).
QUASIROLL_INTEGRATOR_CONFORMANCE(rk_baumgarte, "rk-baumgarte",
                                 .backend_options = {{"rk_method", "dp54"}});
QUASIROLL_INTEGRATOR_CONFORMANCE(rk_projection, "rk-projection",
                                 .backend_options = {{"rk_method", "dp54"}});
#ifdef QUASIROLL_HAVE_SUNDIALS
QUASIROLL_INTEGRATOR_CONFORMANCE(ida, "ida");
QUASIROLL_INTEGRATOR_CONFORMANCE(cvode_projection, "cvode-projection");
#endif
