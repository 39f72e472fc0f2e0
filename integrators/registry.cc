// Registers every integrator compiled into quasiroll::integrators, each with
// the BackendInfo it carries (core/backend_info.h). Seconds per hold interval
// with newton: the calibration of docs/cluster.md ("Cost model", default
// suite); cvode-projection's from its paper-scene timings in
// docs/performance.md scaled by rk-projection's ratio of the two, then
// divided by the speed-ups measured when Adams became its default (zoh 2.4,
// coupled 1.73; docs/performance.md "cvode-projection in zoh: Adams").
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

namespace {
// RK4's stability interval on the negative real axis is (-2.785, 0): a
// Baumgarte term -sigma H integrated by fixed-step RK4 grows for
// sigma h > 2.785.
constexpr double kRk4RealStabilityBound = 2.785;

BackendInfo Info(const char* description, const char* family,
                 const char* library, const char* version, double zoh,
                 double coupled) {
  BackendInfo info =
      ThreadSafeBackendInfo(description, family, library, version);
  info.seconds_per_hold_zoh = zoh;
  info.seconds_per_hold_coupled = coupled;
  return info;
}

// The explicit RK backends: error-controlled unless the scheme is RK4.
bool AdaptiveRk(const OptionValues& options) {
  return options.GetString("rk_method") != "rk4";
}
}  // namespace

void RegisterBuiltinIntegrators() {
  static std::once_flag once;
  std::call_once(once, [] {
    BackendInfo baumgarte = Info(
        "explicit Runge-Kutta on the Baumgarte-corrected field (model.md "
        "§8.3)",
        "explicit Runge-Kutta", "", "", 0.000107, 0.000387);
    baumgarte.adaptive = AdaptiveRk;
    baumgarte.known_instability = [](const OptionValues& options,
                                     double step) -> std::string {
      return options.GetString("rk_method") == "rk4" &&
                     options.GetDouble("baumgarte_sigma") * step >
                         kRk4RealStabilityBound
                 ? "baumgarte_instability"
                 : "";
    };
    IntegratorRegistry::Register("rk-baumgarte", std::move(baumgarte),
                                 [] { return MakeRkBaumgarteIntegrator(); });
    BackendInfo projection = Info(
        "explicit Runge-Kutta step + Newton projection onto H = 0 (model.md "
        "§8.4)",
        "explicit Runge-Kutta", "", "", 0.000111, 0.000204);
    projection.adaptive = AdaptiveRk;
    projection.roles = {BackendRole::kDefault, BackendRole::kReference};
    IntegratorRegistry::Register("rk-projection", std::move(projection),
                                 [] { return MakeRkProjectionIntegrator(); });
#ifdef QUASIROLL_HAVE_SUNDIALS
    BackendInfo ida = Info(
        "SUNDIALS IDA on the index-2 GGL / index-1 Baumgarte DAE (model.md "
        "§8.5)",
        "BDF (DAE)", "SUNDIALS IDA", QUASIROLL_SUNDIALS_VERSION, 0.00216,
        0.00559);
    ida.adaptive = [](const OptionValues&) { return true; };
    ida.roles = {BackendRole::kReferenceCheck};
    IntegratorRegistry::Register("ida", std::move(ida),
                                 [] { return MakeIdaIntegrator(); });
    BackendInfo cvode = Info(
        "SUNDIALS CVODE Adams (default; projected at each call's end) or BDF "
        "with its projection onto H = 0 after every step (CVodeSetProjFn)",
        "Adams / BDF (ODE + projection)", "SUNDIALS CVODE",
        QUASIROLL_SUNDIALS_VERSION, 0.00037, 0.00132);
    cvode.adaptive = [](const OptionValues&) { return true; };
    IntegratorRegistry::Register("cvode-projection", std::move(cvode), [] {
      return MakeCvodeProjectionIntegrator();
    });
#endif
  });
}

}  // namespace quasiroll
