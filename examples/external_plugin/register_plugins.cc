#include "register_plugins.h"

#include <memory>

#include <quasiroll/core/dae.h>
#include <quasiroll/core/nlp.h>

#include "lm_solver.h"
#include "midpoint_projection.h"

namespace example {

void RegisterExamplePlugins() {
  quasiroll::NlpSolverRegistry::Register(
      kNlpName,
      "example plugin: Levenberg-Marquardt (QR, More scaling) on square "
      "equality systems",
      [] { return std::make_unique<LevenbergMarquardtSolver>(); });
  quasiroll::IntegratorRegistry::Register(
      kDaeName,
      "example plugin: explicit midpoint (RK2, fixed step) + Newton projection "
      "onto H = 0",
      [] { return std::make_unique<MidpointProjectionIntegrator>(); });
}

}  // namespace example
