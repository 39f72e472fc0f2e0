// Helpers shared by the core/ tests that simulate whole scenes.
#pragma once

#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {

// Default options with the integrator, the coupling and the output interval
// set; the built-in backends are registered (idempotent).
inline SimulationOptions BuiltinOptions(const std::string& dae,
                                        Coupling coupling, double dt) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  SimulationOptions options;
  options.dae = dae;
  options.coupling = coupling;
  options.dt = dt;
  return options;
}

// bench/scenes/paper.yaml.
inline Scene PaperScene() {
  return LoadScene(std::string(QUASIROLL_SOURCE_DIR) +
                   "/bench/scenes/paper.yaml");
}

}  // namespace quasiroll
