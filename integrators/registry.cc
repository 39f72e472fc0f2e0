#include <memory>
#include <mutex>

#include "quasiroll/core/dae.h"
#include "quasiroll/integrators/rk_baumgarte.h"
#include "quasiroll/integrators/rk_projection.h"
#ifdef QUASIROLL_HAVE_SUNDIALS
#include "quasiroll/integrators/cvode_projection.h"
#include "quasiroll/integrators/ida_integrator.h"
#endif

namespace quasiroll {

void RegisterBuiltinIntegrators() {
  static std::once_flag once;
  std::call_once(once, [] {
    IntegratorRegistry::Register(
        "rk-baumgarte",
        "explicit Runge-Kutta on the Baumgarte-corrected field (model.md §8.3)",
        [] { return std::make_unique<RkBaumgarteIntegrator>(); });
    IntegratorRegistry::Register(
        "rk-projection",
        "explicit Runge-Kutta step + Newton projection onto H = 0 (model.md "
        "§8.4)",
        [] { return std::make_unique<RkProjectionIntegrator>(); });
#ifdef QUASIROLL_HAVE_SUNDIALS
    IntegratorRegistry::Register(
        "ida",
        "SUNDIALS IDA on the index-2 GGL / index-1 Baumgarte DAE (model.md "
        "§8.5)",
        [] { return std::make_unique<IdaIntegrator>(); });
    IntegratorRegistry::Register(
        "cvode-projection",
        "SUNDIALS CVODE BDF with its projection onto H = 0 (CVodeSetProjFn)",
        [] { return std::make_unique<CvodeProjectionIntegrator>(); });
#endif
  });
}

}  // namespace quasiroll
