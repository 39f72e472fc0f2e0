// Benchmark suites (docs/harness.md): loading and validating a suite YAML file
// and expanding it into the ordered list of runs (grid points).
//
// A suite names scenes (scene files + partial overrides) and named groups;
// each group is a Cartesian grid over method parameters (NLP backend, DAE
// backend, coupling, RK scheme, dt, tolerances, Baumgarte sigma, epsilon, IDA
// index, substeps) and scene sweeps (mu, terrain seed, roughness). Everything
// is checked before anything runs: every problem is a SceneError whose
// message is one line "<entry.path>: <problem>, got <value>".
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "quasiroll/bench/harness/run_request.h"
#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/terrains.h"

namespace quasiroll::bench {

// ------------------------------------------------------------- schema ----

// One entry of the suite's `scenes:` list.
struct SuiteScene {
  std::string name;        // label used in run ids and runs.csv (`scene`)
  std::string file;        // scene file as resolved (relative to the suite)
  std::string entry_path;  // "scenes[2]", for messages
  Scene scene;             // file + overrides applied
  TerrainSpec terrain;     // effective terrain spec (file, then overrides)
  std::string heightmap_digest;  // FNV of the heightmap CSV ("" otherwise)
  bool random_terrain() const {
    return terrain.type == TerrainSpec::Type::kGaussians &&
           terrain.random.has_value();
  }
  bool gaussian_terrain() const {
    return terrain.type == TerrainSpec::Type::kGaussians;
  }
};

// How reference trajectories are computed (suite key `reference`).
struct ReferenceSettings {
  // Use the closed-form trajectory when the scene admits one.
  bool analytic = true;
  // Output interval of the numerical reference = scene dt / dt_divisor.
  int dt_divisor = 4;
  // RK4 steps per output interval (step = scene dt / (dt_divisor * substeps)).
  int substeps = 4;
  // NLP backend; "" = the registry's BackendRole::kReference one.
  std::string nlp;
  double residual_tolerance = 1e-12;
  // `nlp`, or the registered reference NLP when it is empty.
  std::string Nlp() const;
  // The fixed-step integrator of references (BackendRole::kReference).
  static std::string Integrator();
  // Canonical text (part of every reference key).
  std::string Canonical() const;
};

// A run's verdict bounds (suite/group key `bounds`): a run that reaches
// t_end with drift_max > drift or gap_max > gap is drift_exceeded /
// gap_exceeded instead of success. Defaults (docs/harness.md): the largest
// values of any successful default-suite run were drift 1.57e-4 and gap
// 4.7e-5 m (Baumgarte RK4 at dt 0.4 s), the smallest of a run that blew up
// 2.4e-2 and 1.3e-2 m; 1e-3 lies between, a decade from each.
//
// qs_inertia: a run that stops early after a motion whose quasi-static
// inertia ratio (docs/model.md §8.8, core/quasi_static_validity.h) exceeds
// it has met the model's limit, not the method's: cause `model`, detail
// `quasi_static_invalid`. Default 1e-2: inertial loads at 1 % of the contact
// loads, the level at which the dropped terms reach the forces' own
// solver-independent accuracy in the default suite's rough scenes.
struct RunBounds {
  double drift = 1e-3;  // max ||H||_inf over the samples
  double gap = 1e-3;    // max geometric gap over the samples [m]
  double qs_inertia = kQuasiStaticInertiaThreshold;  // max ratio of the motion
  bool operator==(const RunBounds& o) const {
    return drift == o.drift && gap == o.gap && qs_inertia == o.qs_inertia;
  }
};

// Spacing of the accuracy checkpoints (suite/group key
// `checkpoint_interval`, core/checkpoints.h, docs/harness.md "Errors at
// checkpoints") [s]: rounded to a whole number of the reference's output
// intervals. 0.3125 s = 25 reference intervals of the paper scene (dt 0.05 s,
// dt_divisor 4) and a multiple of none of the default suite's dt values
// (0.025 .. 6.4 s), so that the checkpoints fall between the samples of
// every rung: no method's grid is favoured.
constexpr double kDefaultCheckpointInterval = 0.3125;

// One grid point: everything needed to run it, in physical units.
struct RunSpec {
  int index = 0;  // position in grid order
  std::string group;
  int scene_index = 0;  // into Suite::scenes
  std::string scene;    // SuiteScene::name
  // Method.
  std::string nlp, dae;
  Coupling coupling = Coupling::kZoh;
  std::string rk_method = "rk4";  // shorthand of dae option rk_method
  double dt = 0;                  // hold / output interval [s]
  double tol = 0;                 // integrator rtol (adaptive RK, IDA)
  double atol = 0;                // integrator atol = tol * atol_ratio
  double nlp_tol = 0;             // quasi-static residual tolerance
  double sigma = 0;   // Baumgarte gain [1/s] (dae option baumgarte_sigma)
  double eps = 0;     // regularisation velocity epsilon [m/s]
  int dae_index = 2;  // IDA formulation (dae option dae_index)
  int substeps = 1;   // integrator steps per dt (step = dt / substeps)
  // Sampled second-contact (single-point contact) check every N samples,
  // 0 = never (SimulationOptions::second_contact_check_every).
  int contact_check = 0;
  // Iteration limit of each quasi-static solve (QuasiStaticOptions).
  int nlp_max_iter = 100;
  // Located stops (SimulationOptions defaults).
  bool locate_events = true;
  int event_points = 3;
  double event_tolerance = 1e-9;  // [s]
  bool locate_switches = true;    // SimulationOptions::locate_switches
  // Scene sweeps.
  double mu = 0;
  std::optional<std::uint64_t> seed;  // only for random gaussian terrains
  double roughness = 1.0;             // gaussian amplitude scale factor
  double t_end = 0;
  int repeats = 1;
  // Timed alone (group key `exclusive`): the run starts only when no other
  // run of the process is running, and none starts until it has finished
  // (all its repeats), whatever --jobs is.
  bool exclusive = false;
  RunBounds bounds;  // group's, else suite's, else the defaults
  // Accuracy checkpoint spacing [s]: group's, else suite's, else the default.
  double checkpoint_interval = kDefaultCheckpointInterval;
  // Generic axes: swept scene fields (suite key `scene_fields`), dotted path
  // -> the value as YAML flow text, in file order; applied to the scene with
  // the scene loader's rules.
  std::vector<std::pair<std::string, std::string>> scene_fields;
  // Backend options handed to the run's backends: the group's nlp_options /
  // dae_options plus the shorthand keys rk_method, sigma, dae_index for the
  // integrator options of the same meaning (rk_method, baumgarte_sigma,
  // dae_index) that the run's integrator has.
  GivenOptions nlp_options, dae_options;
  // The group's explicit backend options only (part of the key).
  GivenOptions nlp_options_explicit, dae_options_explicit;

  std::string key;     // canonical text of every parameter above
  std::string run_id;  // <group>-<scene>-<nlp>-<dae>-<coupling>-<8 hex>

  // The run as a RunRequest (docs/architecture.md, "A new setting of a
  // run"): its backends, times, tolerances and checks, mu and epsilon, the
  // explicit backend options, and the shorthands rk_method / sigma /
  // dae_index except where the explicit integrator options already hold
  // them. ResolveRun turns it into what the Simulator runs.
  RunRequest Request() const;
};

struct Suite {
  std::string path;  // as given ("" when loaded from a string)
  std::string name;
  std::string description;
  std::uint64_t text_hash = 0;  // FNV-1a of the suite file's text
  ReferenceSettings reference;
  RunBounds bounds;  // suite-level `bounds` (groups may override)
  // Suite-level `checkpoint_interval` (groups may override) [s].
  double checkpoint_interval = kDefaultCheckpointInterval;
  std::vector<SuiteScene> scenes;
  std::vector<std::string> groups;  // in file order
  std::vector<RunSpec> runs;        // grid order
};

// Loads, validates and expands a suite. Registers the built-in NLP solvers and
// integrators (backend names are checked against the registries). Throws
// SceneError naming the entry path and value on any problem.
Suite LoadSuite(const std::string& path);
// Same from text; relative scene files resolve against `base_dir`.
Suite LoadSuiteFromString(const std::string& text, const std::string& origin,
                          const std::string& base_dir);

// ------------------------------------------------- effective scenes ----

// The terrain spec of `scene` with the run's sweeps applied: a seed replaces
// the random generator's seed; a roughness != 1 turns the bumps (generated or
// explicit) into an explicit list with every amplitude scaled. Throws
// SceneError if a sweep does not apply to the terrain.
TerrainSpec SweptTerrain(const SuiteScene& scene,
                         std::optional<std::uint64_t> seed, double roughness);

// The scene a run's reference is computed on: scene + mu, seed, roughness and
// t_end of the run (not the method parameters: epsilon stays the scene's).
Scene ReferenceScene(const Suite& suite, const RunSpec& run);
// The scene the run itself simulates: ReferenceScene + the run's epsilon.
Scene RunScene(const Suite& suite, const RunSpec& run);

// The scene and SimulationOptions `run` simulates: ResolveRunRequest of
// run.Request() on ReferenceScene(suite, run), the same step the CLI and
// the Python module take. Throws SceneError naming the run for a request
// that does not resolve (suites are checked when expanded, so only a
// RunSpec edited by hand can).
ResolvedRun ResolveRun(const Suite& suite, const RunSpec& run);

// Canonical text of every parameter of a scene that affects its motion
// (geometry, mass, gravity, mu, mode, rates, initial pose, time span,
// epsilon and the terrain with all its parameters). `terrain` must be the
// spec the scene's terrain was built from.
std::string SceneCanonicalText(const Scene& scene, const TerrainSpec& terrain,
                               const std::string& heightmap_digest);

// Filename-safe id of a run's terrain ("<scene>", or
// "<scene>_s<seed>_r<roughness>" when swept).
std::string TerrainId(const RunSpec& run, const SuiteScene& scene);

}  // namespace quasiroll::bench
