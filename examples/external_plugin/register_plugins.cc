#include "register_plugins.h"

#include <memory>

#include <quasiroll/core/backend_info.h>
#include <quasiroll/core/dae.h>
#include <quasiroll/core/nlp.h>

#include "lm_solver.h"
#include "midpoint_projection.h"

namespace example {

void RegisterExamplePlugins() {
  quasiroll::BackendInfo lm;
  lm.description =
      "example plugin: Levenberg-Marquardt (QR, More scaling) on square "
      "equality systems";
  lm.family = "least squares";
  lm.thread_safe = true;  // as LevenbergMarquardtSolver says
  quasiroll::NlpSolverRegistry::Register(kNlpName, std::move(lm), [] {
    return std::make_unique<LevenbergMarquardtSolver>();
  });
  quasiroll::BackendInfo midpoint;
  midpoint.description =
      "example plugin: explicit midpoint (RK2, fixed step) + Newton "
      "projection onto H = 0";
  midpoint.family = "explicit Runge-Kutta";
  midpoint.thread_safe = true;
  quasiroll::IntegratorRegistry::Register(kDaeName, std::move(midpoint), [] {
    return std::make_unique<MidpointProjectionIntegrator>();
  });
}

}  // namespace example
