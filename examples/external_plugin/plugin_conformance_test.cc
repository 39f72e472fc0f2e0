// The example plugins through quasiroll's conformance kit (docs/plugins.md,
// "Conformance kit"): the checks the built-in backends pass, one line per
// backend. Links quasiroll::conformance and GTest::gtest_main.
#include <quasiroll/conformance/integrator_conformance.h>
#include <quasiroll/conformance/nlp_conformance.h>

#include "register_plugins.h"

namespace {

// Before main() runs the tests: the suites create backends by name.
[[maybe_unused]] const bool kRegistered = [] {
  example::RegisterExamplePlugins();
  return true;
}();

}  // namespace

// Each instance has its own workspace (lm_solver.h) and no global state.
QUASIROLL_NLP_CONFORMANCE(levenberg_marquardt, example::kNlpName,
                          /*thread_safe=*/true);
// Explicit midpoint (order 2, fixed step): 100 midpoint steps per step make the
// pendulum's step 1e-4; Andrews' mechanism (|v'| ~ 1e4) needs steps of 1e-6,
// i.e. step 1e-4 with those.
QUASIROLL_INTEGRATOR_CONFORMANCE(midpoint_projection, example::kDaeName,
                                 .backend_options = {{"midpoint_steps", "100"}},
                                 .andrews_step = 1e-4);
