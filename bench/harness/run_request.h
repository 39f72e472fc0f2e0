// What to run (docs/architecture.md, "A new setting of a run"): the one type
// the CLI (`quasiroll run`), the Python module (`quasiroll.run`) and the
// harness fill, and the one place that checks it and turns it into a scene
// and SimulationOptions: scene overrides, defaults from the scene and the
// registry, the shorthand keys of integrator options, and the conflict
// rules. A front end only names the keys in its messages (KeyNamer).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/options.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll::bench {

struct RunRequest {
  // Scene overrides; unset = the scene's value.
  std::optional<double> mu, eps;
  std::optional<ActuationMode> mode;
  // Backends; "" = the registry's default (BackendRole::kDefault).
  std::string nlp, dae;
  Coupling coupling = Coupling::kZoh;
  // Unset = the scene's (dt, t_end) or the library's default.
  std::optional<double> dt, t_end;
  std::optional<double> tol, atol;   // integrator rtol, atol
  std::optional<double> nlp_tol;     // quasi-static residual tolerance
  std::optional<int> nlp_max_iter;   // quasi-static solver iteration limit
  std::optional<int> substeps;       // integrator steps per dt
  std::optional<int> contact_check;  // second-contact check every N samples,
                                     // 0 = never
  // Located stops (SimulationOptions::locate_events, event_points,
  // event_tolerance): on/off, indicator points per hold interval, bisection
  // tolerance [s].
  std::optional<bool> locate_events;
  std::optional<int> event_points;
  std::optional<double> event_tolerance;
  // Switches located and coupled intervals restarted there
  // (SimulationOptions::locate_switches).
  std::optional<bool> locate_switches;
  // Shorthands of integrator options (IntegratorShorthands()): applied when
  // the run's integrator has the option.
  std::optional<std::string> rk_method;
  std::optional<double> sigma;
  std::optional<int> dae_index;
  // The backends' own options (--nlp-opt / --dae-opt, nlp_options /
  // dae_options).
  GivenOptions nlp_options, dae_options;
};

// A run-level key ("dt", "rk_method", "dae_options", ...) as a front end
// writes it in messages ("--dt" on the command line, "dt" in Python).
using KeyNamer = std::function<std::string(const std::string& key)>;

// A shorthand key of the request and the integrator option it stands for.
struct IntegratorShorthand {
  const char* key;
  const char* option;
};
// rk_method -> rk_method, sigma -> baumgarte_sigma, dae_index -> dae_index.
const std::vector<IntegratorShorthand>& IntegratorShorthands();

// The value of shorthand `key` in `request` as option text (the number
// formatter's text for sigma), unset when the request does not give it.
std::optional<std::string> ShorthandText(const RunRequest& request,
                                         const std::string& key);

// The run settings' keys are RunSettingNames() (core/options.h): a backend
// option may not have one of these names (it would act next to the run's
// own setting, e.g. a plugin's `substeps` multiplying the run's).
// ResolveRunRequest and suites refuse such a backend (ShadowedRunSetting),
// and the conformance kit checks option tables for it.

struct ResolvedRun {
  Scene scene;                     // the base scene with the overrides
  SimulationOptions options;       // everything the Simulator needs
  std::vector<std::string> notes;  // e.g. a shorthand that does not apply
};

// Checks `request` and resolves it against `base` and the registries.
// Throws std::invalid_argument with one line "<name>: <problem>, got
// <value>" (name from `namer`) for: a value out of range, an unknown
// backend, dt > t_end, a shorthand also given as the backend option it
// stands for, and a backend that declares an option named like a run
// setting. A shorthand for an integrator without the option is a note.
ResolvedRun ResolveRunRequest(const Scene& base, const RunRequest& request,
                              const KeyNamer& namer);

// A quasi-static solve (`quasiroll solve`, quasiroll.solve()): the part of
// a run the solve has, resolved by the same rules.
struct ResolvedSolve {
  Scene scene;  // the base scene with the overrides
  std::string nlp;
  GivenOptions nlp_options;
  QuasiStaticOptions quasi_static;  // nlp_tol, nlp_max_iter applied
};

// ResolveRunRequest for a solve: `request` may set the scene overrides
// (mu, eps, mode), nlp, nlp_options, nlp_tol and nlp_max_iter; the same
// errors as a run's.
ResolvedSolve ResolveSolveRequest(const Scene& base, const RunRequest& request,
                                  const KeyNamer& namer);

}  // namespace quasiroll::bench
