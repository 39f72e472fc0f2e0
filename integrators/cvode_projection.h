// cvode-projection: SUNDIALS CVODE (variable-order, variable-step BDF with
// Newton iterations and a dense direct linear solver) on y' = F(t, y), with
// CVODE's projection interface (CVodeSetProjFn) keeping H(y) = 0: after every
// accepted step CVODE calls back for the correction
//   y <- y - D J^T (J D J^T)^{-1} H(y)   (Newton, repeated until
//                                         ||H||_inf <= projection_tolerance)
// with D = diag(CorrectionWeights()), and the local error estimate e is
// projected onto the tangent space of the manifold,
//   e <- e - D J^T (J D J^T)^{-1} J e,
// so that the step-size control does not react to the drift the projection
// removes (docs/model.md §8.7; CVODE guide, "projection"). A projection that
// does not converge (or a singular J D J^T) is a recoverable failure: CVODE
// retries with a smaller step, up to max_proj_fails times per step.
//
// Written only against the public plugin interface (core/dae.h,
// core/options.h) and SUNDIALS: no quasiroll internals. Registered as one
// line in integrators/registry.cc.
//
// IntegratorOptions: rtol / atol -> CVodeSStolerances, step -> CVodeSetInitStep
// (0 = CVODE's estimate), min_step -> CVodeSetMinStep, max_steps ->
// CVodeSetMaxNumSteps (per call), t1 -> CVodeSetStopTime (the last step ends
// on t1, whose state is the projected step state), ode.Roots -> CVodeRootInit
// (events). The initial state is projected before the first step and the
// returned state again (a no-op unless CVODE interpolated). dF/dy (backend
// option jacobian): ift (default) the ODE's RhsJacobian() when it has one,
// and forward differences of Rhs for an evaluation where it returns false;
// fd, or an ODE without one, CVODE's difference quotients.
// Backend options (option_table()): projection_tolerance,
// max_projection_iterations, max_order (CVodeSetMaxOrd), max_nonlin_iters
// (CVodeSetMaxNonlinIters), max_conv_fails (CVodeSetMaxConvFails),
// max_err_test_fails (CVodeSetMaxErrTestFails), proj_err_est
// (CVodeSetProjErrEst), proj_frequency (CVodeSetProjFrequency),
// max_proj_fails (CVodeSetMaxNumProjFails), proj_fail_eta
// (CVodeSetProjFailEta); defaults are CVODE's own; jacobian (ift | fd).
//
// Status mapping: CV_TOO_MUCH_WORK / CV_TOO_MUCH_ACC / CV_ERR_FAILURE ->
// kStepSizeTooSmall; CV_CONV_FAILURE / linear solver failures ->
// kConvergenceFailure; repeated projection failures (CV_PROJ_FAIL /
// CV_PROJFUNC_FAIL) -> kConstraintFailure; a failing Rhs (returned false;
// recoverable for CVODE, which retries with a smaller step) that ends the
// integration -> kRhsFailure. Counters: steps = CVodeGetNumSteps,
// rejected_steps = CVodeGetNumErrTestFails, rhs_evaluations = Rhs calls
// (including difference quotients), jacobian_evaluations = J = dH/dy
// evaluations plus CVODE's dF/dy evaluations, projection_iterations = Newton
// corrections. The CVODE memory, vectors, matrix, linear solver and
// SUNContext live as long as this object and are reused (CVodeReInit) while
// state_size() is unchanged. SUNDIALS headers are confined to the .cc.
#pragma once

#include <memory>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The "cvode-projection" integrator (registered by integrators/registry.cc).
std::unique_ptr<Integrator> MakeCvodeProjectionIntegrator();

}  // namespace quasiroll
