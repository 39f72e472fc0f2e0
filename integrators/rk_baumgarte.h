// rk-baumgarte: explicit Runge-Kutta on the Baumgarte-corrected field
// (model.md §8.3)
//
//   y' = F - D J^T (J D J^T)^{-1} (J F + sigma H),
//
// the D^{-1}-weighted minimal-norm change of F with J y' = -sigma H, so that
// ||H(t)|| = ||H(0)|| e^{-sigma t} in exact arithmetic. RK4 is stable for
// sigma * h < 2.785. Methods, step control and events:
// integrators/runge_kutta.h.
// Options (option_table()): baumgarte_sigma and the RK driver's (rk_method,
// safety, max_growth, max_shrink, stage_failure_shrink).
#pragma once

#include <memory>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The "rk-baumgarte" integrator (registered by integrators/registry.cc).
std::unique_ptr<Integrator> MakeRkBaumgarteIntegrator();

}  // namespace quasiroll
