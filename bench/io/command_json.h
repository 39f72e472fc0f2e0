// The JSON documents of `quasiroll pose --json` and `quasiroll solve --json`
// (docs/formats.md), shared by the CLI and the Python module (bench/python).
#pragma once

#include <array>
#include <string>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/sensitivity.h"

namespace quasiroll {

// What `quasiroll pose` prints of a configuration, as text or JSON.
struct PoseView {
  Mat3 R;
  Vec3 p;
  Vec3 rpy;
  std::array<ChainState, 3> chains;
};
PoseView EvaluatePose(const KinematicModel& model, const Configuration& theta);

// `pose --json`: the initial configuration `theta` of `scene` (solved with
// `report`).
std::string PoseJson(const Scene& scene, const KinematicModel& model,
                     const Configuration& theta,
                     const InitialConfigurationReport& report);

// `solve --json`: one quasi-static solve by backend `nlp`. A value the solve
// did not produce (everything but the diagnostics when the status is not
// OK) is null, arrays keeping their length; critical_wheel is 1-based or
// null (docs/cli.md, "Conventions").
// With `sensitivities` (solve --sensitivities) the object also has the key
// "sensitivities": null when the solve failed, else status, method,
// one_sided, one_sided_constraints, state_names, rate_names,
// multiplier_values and the entries
// d<output>_d<input> of SensitivityEntries() (vectors, or arrays of rows).
std::string SolveJson(const Scene& scene, const std::string& nlp,
                      QuasiStaticStatus status, const QuasiStaticSolution& sol,
                      const QuasiStaticSensitivities* sensitivities = nullptr);

}  // namespace quasiroll
