// rk-projection: explicit Runge-Kutta step of y' = F, then the Newton
// projection y <- y - D J^T (J D J^T)^{-1} H(y), repeated until
// ||H||_inf <= projection_tolerance (at most max_projection_iterations, else
// kConstraintFailure) (model.md §8.4). The initial state is projected too.
// With an FSAL pair the first stage is re-evaluated whenever the projection
// moved y. Methods, step control and events: integrators/runge_kutta.h.
// Options (option_table()): projection_tolerance, max_projection_iterations
// and the RK driver's (rk_method, safety, max_growth, max_shrink,
// stage_failure_shrink).
//
// Accuracy note: the method has the order of the RK scheme only when F is
// tangent to the constraint manifold (J F = 0 on H = 0, as for a velocity
// that already satisfies the loop closures), i.e. when the projection only
// removes numerical drift. If J F != 0 it is a splitting ("flow of F, then
// project") of order 1 towards x' = F - D J^T (J D J^T)^{-1} J F; use
// rk-baumgarte or ida there (observed on a 21-state test field with
// J F != 0: error 7e-3 at h = 0.05, decreasing only linearly with h).
#pragma once

#include <memory>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The "rk-projection" integrator (registered by integrators/registry.cc).
std::unique_ptr<Integrator> MakeRkProjectionIntegrator();

}  // namespace quasiroll
