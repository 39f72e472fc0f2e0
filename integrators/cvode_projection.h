// cvode-projection: SUNDIALS CVODE (variable-order, variable-step linear
// multistep methods) on y' = F(t, y), keeping H(y) = 0 by projection, with
// the correction
//   y <- y - D J^T (J D J^T)^{-1} H(y)   (Newton, repeated until
//                                         ||H||_inf <= projection_tolerance)
// and D = diag(CorrectionWeights()). Two methods (backend option lmm):
//  * adams (default): Adams-Moulton, orders 1..max_order. CVODE projects only
//    with BDF, so the state is projected at the end of each call (and at
//    its start, where it must already be consistent): in zoh one projection
//    per hold interval, as rk-projection with one RK4 step per interval.
//  * bdf: BDF (orders 1..5) with CVODE's projection interface
//    (CVodeSetProjFn): after every accepted step CVODE calls back for the
//    correction, and the local error estimate e is projected onto the
//    tangent space of the manifold,
//      e <- e - D J^T (J D J^T)^{-1} J e,
//    so that the step-size control does not react to the drift the
//    projection removes (docs/model.md §8.7; CVODE guide, "projection"). A
//    projection that does not converge (or a singular J D J^T) is a
//    recoverable failure: CVODE retries with a smaller step, up to
//    max_proj_fails times per step.
// Corrector (option nonlinear_solver): each step solves y = a + gamma F(t, y)
// (a from the history, gamma = h beta_0). fixedpoint (default) iterates
// y <- a + gamma F(t, y) without a matrix (SUNNonlinSol_FixedPoint); it
// contracts while gamma ||dF/dy|| < 1, i.e. for non-stiff F (the robot's
// dF/dy: |lambda| < 0.05 s^-1, docs/model.md §8.7). newton solves with the
// dense iteration matrix I - gamma dF/dy.
//
// Written only against the public plugin interface (core/dae.h,
// core/options.h) and SUNDIALS: no quasiroll internals. Registered as one
// line in integrators/registry.cc.
//
// IntegratorOptions: rtol / atol -> CVodeSStolerances, step -> CVodeSetInitStep
// (0 = CVODE's estimate; with restart_step=carry the carried step when
// smaller), min_step -> CVodeSetMinStep, max_steps -> CVodeSetMaxNumSteps
// (per call), t1 -> CVodeSetStopTime (the last step ends on t1),
// ode.Roots -> CVodeRootInit (events). The initial state is projected
// before the first step and the returned state again (with bdf a no-op
// unless CVODE interpolated). Every call re-initialises CVODE (order 1).
// dF/dy (backend option jacobian, Newton only): ift (default) the ODE's
// RhsJacobian() when it has one, and forward differences of Rhs for an
// evaluation where it returns false; fd, or an ODE without one, CVODE's
// difference quotients.
// Backend options (option_table()): projection_tolerance,
// max_projection_iterations, max_order (CVodeSetMaxOrd; at most 5 with bdf),
// max_nonlin_iters (CVodeSetMaxNonlinIters), max_conv_fails
// (CVodeSetMaxConvFails), max_err_test_fails (CVodeSetMaxErrTestFails),
// proj_err_est (CVodeSetProjErrEst), proj_frequency (CVodeSetProjFrequency),
// max_proj_fails (CVodeSetMaxNumProjFails), proj_fail_eta
// (CVodeSetProjFailEta), whose defaults are CVODE's own; jacobian (ift | fd),
// jacobian_reuse; lmm (adams | bdf), nonlinear_solver (fixedpoint | newton),
// restart_step (carry | given | estimate), eta_max_early
// (CVodeSetEtaMaxEarlyStep, default 3). The proj_* options act with bdf
// only, jacobian and jacobian_reuse with newton only.
//
// Status mapping: CV_TOO_MUCH_WORK / CV_TOO_MUCH_ACC / CV_ERR_FAILURE ->
// kStepSizeTooSmall; CV_CONV_FAILURE / linear solver failures ->
// kConvergenceFailure; repeated projection failures (CV_PROJ_FAIL /
// CV_PROJFUNC_FAIL) and a failing final projection -> kConstraintFailure; a
// failing Rhs (returned false; recoverable for CVODE, which retries with a
// smaller step) that ends the integration -> kRhsFailure. Counters: steps =
// CVodeGetNumSteps, rejected_steps = CVodeGetNumErrTestFails,
// rhs_evaluations = Rhs calls (including difference quotients),
// jacobian_evaluations = J = dH/dy evaluations plus CVODE's dF/dy
// evaluations, projection_iterations = Newton corrections. The CVODE
// memory, vectors, matrix, solvers and SUNContext live as long as this
// object and are reused (CVodeReInit) while state_size(), lmm and
// nonlinear_solver are unchanged. SUNDIALS headers are confined to the .cc.
#pragma once

#include <memory>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The "cvode-projection" integrator (registered by integrators/registry.cc).
std::unique_ptr<Integrator> MakeCvodeProjectionIntegrator();

}  // namespace quasiroll
