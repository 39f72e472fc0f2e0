// ida: SUNDIALS IDA (variable-order BDF) on the DAE in y = (x, nu)
// (model.md §8.5):
//
//   dae_index = 2 (GGL type):    x' - F(t, x) - D J(x)^T nu = 0,  H(x) = 0
//   dae_index = 1 (Baumgarte):   x' - F(t, x) - D J(x)^T nu = 0,
//                                J(x) x' + sigma H(x)       = 0
//
// nu (num_constraints rows) is algebraic (IDASetId 0) and excluded from the
// local error test (IDASetSuppressAlg). Consistent initial values are computed
// here, not by IDACalcIC: for index 2, x is first projected onto H = 0 (Newton
// projection as rk-projection), then nu0 = -(J D J^T)^{-1} (J F [+ sigma H]),
// x'0 = F + D J^T nu0. For index 2 the final x is projected again, so H holds
// to projection_tolerance and not only to the Newton tolerance of IDA.
//
// Backend options (option_table()): dae_index, baumgarte_sigma,
// projection_tolerance / max_projection_iterations (initial and final
// projection), multiplier_atol, and IDA's max_order (IDASetMaxOrd),
// max_nonlin_iters (IDASetMaxNonlinIters), max_conv_fails
// (IDASetMaxConvFails), max_err_test_fails (IDASetMaxErrTestFails),
// suppress_alg (IDASetSuppressAlg); defaults are IDA's own; jacobian (ift:
// dF/dx from ode.RhsJacobian where it returns true, else differences for
// that evaluation; fd: always differences).
// Options: rtol / atol -> IDASVtolerances on x (nu gets a loose atol of 1e3:
// it only has to converge through D J^T nu, see ida_integrator.cc), step ->
// IDASetInitStep (0 = IDA's estimate), min_step -> IDASetMinStep, max_steps
// -> IDASetMaxNumSteps (per call), t1 -> IDASetStopTime, ode.Roots ->
// IDARootInit. Iteration matrix: analytic except the second-derivative terms
// d(D J^T nu)/dx and d(J x')/dx (see Jacobian in the .cc); dF/dx from
// ode.RhsJacobian (jacobian=ift) or forward differences.
// Status mapping: IDA_TOO_MUCH_WORK / IDA_TOO_MUCH_ACC / IDA_ERR_FAIL ->
// kStepSizeTooSmall; corrector / linear solver / residual failures ->
// kConvergenceFailure, or kRhsFailure when the last Rhs call returned false;
// setup errors -> kInvalidInput. Rhs returning false is IDA's recoverable
// residual error (+1): IDA cuts the step and retries, so a failure at a trial
// point (corrector iterate, finite-difference perturbation, a step across a
// stick/slip transition) costs a retry, and only a path that really leaves
// the domain of F stops, with IDA_REP_RES_ERR just short of where it leaves.
// Counters: steps = IDAGetNumSteps, rejected_steps = IDAGetNumErrTestFails,
// rhs_evaluations = Rhs calls (including finite differences),
// jacobian_evaluations = J evaluations plus IDA Jacobian evaluations.
//
// The IDA memory, vectors, dense matrix / linear solver and the SUNContext
// live as long as this object and are reused via IDAReInit while
// (state_size, num_constraints) are unchanged. A call that continues the
// last one (same problem, t0 = its end, y = the state it returned, and no
// jump of the residual there; ContinuesLastCall in the .cc) skips the
// re-initialisation and keeps IDA's order and step (model.md §8.6). SUNDIALS
// headers are confined to ida_integrator.cc.
#pragma once

#include <memory>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The "ida" integrator (registered by integrators/registry.cc).
std::unique_ptr<Integrator> MakeIdaIntegrator();

}  // namespace quasiroll
