// quasiroll._quasiroll: the pybind11 extension behind `import quasiroll`
// (bench/python/quasiroll/__init__.py adds the pandas / numpy layer;
// docs/python.md). Outputs are the documents the CLI writes — pose and solve
// JSON, trajectory.csv and run.json text (docs/formats.md) — so the Python
// results have exactly the CLI's keys, columns and digits.
//
// The GIL is released while C++ computes; a run gives it back every 0.1 s
// of wall time to let Ctrl-C (KeyboardInterrupt) through.
#include <dlfcn.h>
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include "quasiroll/bench/harness/run_request.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/command_json.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/plugin_loader.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/sensitivity.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/step_sensitivity.h"

namespace py = pybind11;

namespace quasiroll {
namespace {

// Keyword-argument checks with the CLI's wording (docs/cli.md), naming the
// keyword as the caller wrote it.
void RequirePositive(const char* name, const std::optional<double>& v) {
  if (v && !(std::isfinite(*v) && *v > 0))
    throw std::invalid_argument(std::string(name) +
                                ": must be a finite number > 0, got " +
                                bench::Num(*v));
}
ActuationMode ModeFromString(const std::string& mode) {
  if (mode == "paper") return ActuationMode::kPaper;
  if (mode == "pvc") return ActuationMode::kPvc;
  throw std::invalid_argument("mode: must be one of paper, pvc, got '" + mode +
                              "'");
}

Scene WithOverrides(Scene scene, const std::optional<double>& mu,
                    const std::optional<double>& eps,
                    const std::optional<std::string>& mode) {
  RequirePositive("mu", mu);
  RequirePositive("eps", eps);
  if (mu) scene.mu = *mu;
  if (eps) scene.epsilon = *eps;
  if (mode) scene.mode = ModeFromString(*mode);
  return scene;
}

std::string PoseText(const Scene& scene) {
  std::string json;
  {
    py::gil_scoped_release release;
    const KinematicModel model(scene.geometry, scene.terrain);
    InitialConfigurationReport report;
    const Configuration theta =
        SolveInitialConfiguration(model, scene, &report);
    json = PoseJson(scene, model, theta, report);
  }
  return json;
}

// The request keys a solve and a run share: the scene overrides and the
// NLP backend with its tolerance, iteration limit and options.
bench::RunRequest SolveRequest(const std::string& nlp, std::optional<double> mu,
                               std::optional<double> eps,
                               std::optional<std::string> mode,
                               std::optional<double> nlp_tol,
                               std::optional<int> nlp_max_iter,
                               const GivenOptions& nlp_options) {
  bench::RunRequest request;
  request.mu = mu;
  request.eps = eps;
  if (mode) request.mode = ModeFromString(*mode);
  request.nlp = nlp;  // "" (Python None): the registry's default
  request.nlp_tol = nlp_tol;
  request.nlp_max_iter = nlp_max_iter;
  request.nlp_options = nlp_options;
  return request;
}

std::string SolveText(const Scene& scene_in, const std::string& nlp,
                      std::optional<double> mu, std::optional<double> eps,
                      std::optional<std::string> mode,
                      std::optional<double> nlp_tol,
                      std::optional<int> nlp_max_iter,
                      const GivenOptions& nlp_options, bool sensitivities) {
  const bench::RunRequest request =
      SolveRequest(nlp, mu, eps, mode, nlp_tol, nlp_max_iter, nlp_options);
  const bench::ResolvedSolve resolved = bench::ResolveSolveRequest(
      scene_in, request, [](const std::string& key) { return key; });
  const Scene& scene = resolved.scene;
  std::string json;
  {
    py::gil_scoped_release release;
    const KinematicModel model(scene.geometry, scene.terrain);
    const Configuration theta = SolveInitialConfiguration(model, scene);
    QuasiStaticOptions options = resolved.quasi_static;
    options.diagnostics = true;
    std::unique_ptr<NlpSolver> solver_nlp =
        NlpSolverRegistry::Create(resolved.nlp);
    solver_nlp->SetBackendOptions(resolved.nlp_options);
    QuasiStaticSolver solver(model, QuasiStaticParameters::FromScene(scene),
                             std::move(solver_nlp), options);
    QuasiStaticSolution sol;
    const QuasiStaticStatus status = solver.Solve(theta, &sol);
    QuasiStaticSensitivities sens;
    if (status == QuasiStaticStatus::kOk && sensitivities)
      SensitivityAnalyzer().Compute(solver.problem(), sol.z, &sens);
    json = SolveJson(scene, resolved.nlp, status, sol,
                     sensitivities ? &sens : nullptr);
  }
  return json;
}

// One interval and its derivative (core/step_sensitivity.h; docs/python.md
// `step`), as a dict of numpy arrays with the keys of the CLI's
// `step_sensitivities` object (docs/formats.md); derivatives None when
// they were not computed or do not exist (status SINGULAR or a failure).
py::dict StepDict(const Scene& scene_in,
                  const std::optional<std::vector<double>>& state,
                  std::optional<double> dt, const std::string& coupling,
                  const std::string& dae, int substeps, const std::string& nlp,
                  std::optional<double> mu, std::optional<double> eps,
                  std::optional<std::string> mode,
                  std::optional<double> nlp_tol,
                  std::optional<int> nlp_max_iter,
                  const GivenOptions& nlp_options, bool derivatives) {
  RequirePositive("dt", dt);
  if (state && state->size() != static_cast<std::size_t>(kConfigSize))
    throw std::invalid_argument(
        "state: must have 21 entries (state_names), "
        "got " +
        std::to_string(state->size()));
  const bench::RunRequest request =
      SolveRequest(nlp, mu, eps, mode, nlp_tol, nlp_max_iter, nlp_options);
  const bench::ResolvedSolve resolved = bench::ResolveSolveRequest(
      scene_in, request, [](const std::string& key) { return key; });
  const Scene& scene = resolved.scene;
  StepSensitivityOptions o;
  o.nlp = resolved.nlp;
  o.nlp_options = resolved.nlp_options;
  o.quasi_static = resolved.quasi_static;
  o.dt = dt ? *dt : scene.dt;
  o.coupling = CouplingFromString(coupling);
  if (!dae.empty()) o.dae = dae;
  o.substeps = substeps;
  o.derivatives = derivatives;
  RegisterBuiltinNlpSolvers();
  Configuration theta;
  StepSensitivityResult r;
  {
    py::gil_scoped_release release;
    const KinematicModel model(scene.geometry, scene.terrain);
    theta = state
                ? Configuration(Eigen::Map<const Configuration>(state->data()))
                : SolveInitialConfiguration(model, scene);
    StepSensitivity step(model, QuasiStaticParameters::FromScene(scene), o);
    step.Compute(theta, &r);
  }
  py::dict d;
  d["status"] = ToString(r.status);
  d["message"] = r.message;
  d["method"] = StepSensitivityResult::kMethod;
  d["dae"] = o.dae;
  d["coupling"] = ToString(o.coupling);
  d["dt"] = o.dt;
  d["substeps"] = o.substeps;
  d["one_sided"] = !r.one_sided.empty();
  d["one_sided_constraints"] = r.one_sided;
  std::vector<std::string> names(StateNames().begin(), StateNames().end());
  std::vector<std::string> rates(JointNames().begin(), JointNames().end());
  d["state_names"] = names;
  d["rate_names"] = rates;
  d["state"] = Eigen::VectorXd(theta);
  d["state_next"] = r.theta_next.allFinite()
                        ? py::object(py::cast(Eigen::VectorXd(r.theta_next)))
                        : py::object(py::none());
  d["drift"] = r.drift;
  const bool have = derivatives && r.jacobian.allFinite();
  for (const SensitivityEntry& e : StepSensitivityEntries(r)) {
    if (!have) {
      d[e.name.c_str()] = py::none();
    } else if (e.vector) {
      d[e.name.c_str()] = Eigen::VectorXd(e.value.col(0));
    } else {
      d[e.name.c_str()] = Eigen::MatrixXd(e.value);
    }
  }
  return d;
}

// (trajectory.csv text, run.json text) of one simulation.
std::pair<std::string, std::string> RunText(
    const Scene& scene_in, const std::string& nlp, const std::string& dae,
    const std::string& coupling, std::optional<double> dt,
    std::optional<double> t_end, std::optional<double> mu,
    std::optional<double> eps, std::optional<std::string> mode,
    std::optional<std::string> rk_method, std::optional<double> sigma,
    std::optional<double> tol, std::optional<double> atol,
    std::optional<double> nlp_tol, std::optional<int> dae_index,
    std::optional<int> substeps, std::optional<int> contact_check,
    std::optional<int> nlp_max_iter, const GivenOptions& nlp_options,
    const GivenOptions& dae_options, std::optional<bool> locate_events,
    std::optional<int> event_points, std::optional<double> event_tolerance,
    std::optional<bool> locate_switches) {
  bench::RunRequest request =
      SolveRequest(nlp, mu, eps, mode, nlp_tol, nlp_max_iter, nlp_options);
  request.dae = dae;
  request.coupling = CouplingFromString(coupling);
  request.dt = dt;
  request.t_end = t_end;
  request.tol = tol;
  request.atol = atol;
  request.substeps = substeps;
  request.contact_check = contact_check;
  request.locate_events = locate_events;
  request.event_points = event_points;
  request.event_tolerance = event_tolerance;
  request.locate_switches = locate_switches;
  request.rk_method = rk_method;
  request.sigma = sigma;
  request.dae_index = dae_index;
  request.dae_options = dae_options;
  // Keywords are named as written in Python: dt, t_end, dae_options.
  const bench::ResolvedRun resolved = bench::ResolveRunRequest(
      scene_in, request, [](const std::string& key) { return key; });
  const Scene& scene = resolved.scene;
  const SimulationOptions& options = resolved.options;

  std::optional<Simulator> sim;
  SimulationResult result;
  {
    py::gil_scoped_release release;
    sim.emplace(scene, options);
    sim->Begin(sim->initial_configuration(), &result);
  }
  bool more = true;
  while (more) {
    {
      py::gil_scoped_release release;
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      do {
        more = sim->Advance(&result);
      } while (more && std::chrono::steady_clock::now() < until);
    }
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }
  std::pair<std::string, std::string> out;
  {
    py::gil_scoped_release release;
    out.first = TrajectoryCsv(result);
    out.second = RunJson(scene, options, sim->dt(), sim->t_end(), result);
  }
  return out;
}

// A plugin resolves quasiroll's symbols to this module's (it holds the
// whole core library): the module, loaded RTLD_LOCAL by Python, is made
// global first so that the plugin's dlopen can see them.
py::dict LoadPluginForPython(const std::string& path) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Dl_info self;
  if (::dladdr(reinterpret_cast<void*>(&LoadPluginForPython), &self) &&
      self.dli_fname)
    ::dlopen(self.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
  LoadedPlugin plugin;
  try {
    plugin = LoadPlugin(path);
  } catch (const std::runtime_error& e) {
    throw py::value_error(e.what());
  }
  py::dict d;
  d["file"] = plugin.file;
  d["path"] = plugin.path;
  d["sha256"] = plugin.sha256;
  d["version"] = plugin.version;
  d["nlp"] = plugin.nlp_backends;
  d["dae"] = plugin.integrators;
  return d;
}

}  // namespace
}  // namespace quasiroll

PYBIND11_MODULE(_quasiroll, m) {
  using namespace quasiroll;
  m.doc() = "quasiroll C++ core (use the `quasiroll` package)";

  static py::exception<SceneError> scene_error(m, "SceneError",
                                               PyExc_ValueError);
  static py::exception<GeometryError> geometry_error(m, "GeometryError",
                                                     PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SceneError& e) {
      scene_error(e.what());
    } catch (const GeometryError& e) {
      geometry_error(e.what());
    }
  });

  py::class_<Scene>(m, "Scene",
                    "A scene (docs/scenes.md). Copy with copy.copy() before "
                    "changing attributes you want to keep.")
      .def_readonly("name", &Scene::name)
      .def_readonly("source_path", &Scene::source_path)
      .def_property(
          "mu", [](const Scene& s) { return s.mu; },
          [](Scene& s, double v) { s = WithOverrides(s, v, {}, {}); })
      .def_property(
          "epsilon", [](const Scene& s) { return s.epsilon; },
          [](Scene& s, double v) { s = WithOverrides(s, {}, v, {}); })
      .def_property(
          "mode", [](const Scene& s) { return std::string(ToString(s.mode)); },
          [](Scene& s, const std::string& v) { s.mode = ModeFromString(v); })
      .def_readonly("dt", &Scene::dt)
      .def_readonly("t_end", &Scene::t_end)
      .def_property_readonly("terrain",
                             [](const Scene& s) {
                               return s.terrain ? s.terrain->Describe()
                                                : std::string();
                             })
      .def("__copy__", [](const Scene& s) { return Scene(s); })
      .def("__deepcopy__", [](const Scene& s, py::dict) { return Scene(s); })
      .def("__repr__", [](const Scene& s) {
        return "<quasiroll.Scene '" + s.name + "' mode=" + ToString(s.mode) +
               " mu=" + std::to_string(s.mu) + " from '" + s.source_path + "'>";
      });

  m.def(
      "load_scene", [](const std::string& path) { return LoadScene(path); },
      py::arg("path"), "Load and validate a scene YAML file");
  m.def("_pose_json", &PoseText, py::arg("scene"));
  m.def("_solve_json", &SolveText, py::arg("scene"), py::arg("nlp"),
        py::arg("mu"), py::arg("eps"), py::arg("mode"), py::arg("nlp_tol"),
        py::arg("nlp_max_iter"), py::arg("nlp_options"),
        py::arg("sensitivities") = false);
  m.def("_step", &StepDict, py::arg("scene"), py::arg("state"), py::arg("dt"),
        py::arg("coupling"), py::arg("dae"), py::arg("substeps"),
        py::arg("nlp"), py::arg("mu"), py::arg("eps"), py::arg("mode"),
        py::arg("nlp_tol"), py::arg("nlp_max_iter"), py::arg("nlp_options"),
        py::arg("derivatives"));
  m.def("_run_text", &RunText, py::arg("scene"), py::arg("nlp"), py::arg("dae"),
        py::arg("coupling"), py::arg("dt"), py::arg("t_end"), py::arg("mu"),
        py::arg("eps"), py::arg("mode"), py::arg("rk_method"), py::arg("sigma"),
        py::arg("tol"), py::arg("atol"), py::arg("nlp_tol"),
        py::arg("dae_index"), py::arg("substeps"), py::arg("contact_check"),
        py::arg("nlp_max_iter"), py::arg("nlp_options"), py::arg("dae_options"),
        py::arg("locate_events"), py::arg("event_points"),
        py::arg("event_tolerance"), py::arg("locate_switches"));
  m.def("backends", [] {
    RegisterBuiltinNlpSolvers();
    RegisterBuiltinIntegrators();
    py::dict d;
    d["nlp"] = NlpSolverRegistry::Names();
    d["dae"] = IntegratorRegistry::Names();
    return d;
  });
  m.def("load_plugin", &LoadPluginForPython, py::arg("path"),
        "Load backends from a plugin library (docs/plugins.md)");
  m.attr("commit") = GitCommit();
}
