#include "quasiroll/bench/cli/commands.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/run_request.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/command_json.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/sensitivity.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/step_sensitivity.h"

namespace quasiroll::cli {

namespace {

const std::vector<std::string> kRkMethods = {"rk4", "dp54", "bs32"};

void AddSceneOverrides(CLI::App* command, SceneOverrides* o) {
  command
      ->add_option("--mu", o->mu,
                   "Friction coefficient (default: the scene's `mu`)")
      ->check(PositiveNumber());
  command
      ->add_option("--eps", o->eps,
                   "Friction regularisation velocity [m/s] (default: the "
                   "scene's `epsilon`)")
      ->check(PositiveNumber());
  command
      ->add_option("--mode", o->mode,
                   "Actuation mode paper | pvc (default: the scene's)")
      ->check(OneOf({"paper", "pvc"}));
}

void AddNlpTol(CLI::App* command, std::optional<double>* nlp_tol) {
  command
      ->add_option("--nlp-tol", *nlp_tol,
                   "Quasi-static residual tolerance, scaled (default: " +
                       bench::Num(QuasiStaticOptions().residual_tolerance) +
                       ")")
      ->check(PositiveNumber());
}

void AddNlpMaxIter(CLI::App* command, std::optional<int>* nlp_max_iter) {
  command
      ->add_option("--nlp-max-iter", *nlp_max_iter,
                   "Iteration limit of each quasi-static solve (default: " +
                       std::to_string(QuasiStaticOptions().max_iterations) +
                       ")")
      ->check(IntegerIn(1, 1000000));
}

}  // namespace

// `quasiroll run`: its flags are the keys of a RunRequest
// (bench/harness/run_request.h).
void Commands::RegisterRun(CLI::App& app, const std::vector<std::string>& nlps,
                           const std::vector<std::string>& daes) {
  const IntegratorOptions integrator_defaults;
  CLI::App* run = app.add_subcommand(
      "run", "Simulate a scene; writes DIR/trajectory.csv and DIR/run.json");
  run->add_option("--scene", run_.scene, "Scene YAML file")->required();
  run->add_option("--nlp", run_.request.nlp,
                  "NLP backend (see 'quasiroll list')")
      ->check(OneOf(nlps))
      ->capture_default_str();
  run->add_option("--dae", run_.request.dae,
                  "Integrator backend (see 'quasiroll list')")
      ->check(OneOf(daes))
      ->capture_default_str();
  run->add_option("--coupling", run_.coupling, "zoh | coupled")
      ->check(OneOf({"zoh", "coupled"}))
      ->capture_default_str();
  run->add_option("--dt", run_.request.dt,
                  "Hold/output interval [s] (default: the scene's time.dt)")
      ->check(PositiveNumber());
  run->add_option("--t-end", run_.request.t_end,
                  "End time [s] (default: the scene's time.t_end)")
      ->check(PositiveNumber());
  AddSceneOverrides(run, &run_.overrides);
  const std::string rk_help =
      "RK scheme of rk-baumgarte / rk-projection: rk4 | dp54 | bs32 "
      "(default: rk4; shorthand of --dae-opt rk_method=...)";
  CLI::Option* rk_method =
      run->add_option("--rk-method", run_.request.rk_method, rk_help);
  rk_method->check(OneOf(kRkMethods));
  deprecated_.push_back({run->add_option("--rk", run_.request.rk_method,
                                         "Deprecated: --rk-method")
                             ->check(OneOf(kRkMethods))
                             ->excludes(rk_method)
                             ->group("Deprecated"),
                         "--rk", "--rk-method"});
  run->add_option("--sigma", run_.request.sigma,
                  "Baumgarte gain [1/s] (rk-baumgarte; ida with --dae-index 1; "
                  "default: 5; shorthand of --dae-opt baumgarte_sigma=...)")
      ->check(NonNegativeNumber());
  CLI::Option* tol =
      run->add_option("--tol", run_.request.tol,
                      "Relative tolerance of adaptive RK and IDA (default: " +
                          bench::Num(integrator_defaults.rtol) + ")");
  tol->check(PositiveNumber());
  deprecated_.push_back(
      {run->add_option("--rtol", run_.request.tol, "Deprecated: --tol")
           ->check(PositiveNumber())
           ->excludes(tol)
           ->group("Deprecated"),
       "--rtol", "--tol"});
  run->add_option("--atol", run_.request.atol,
                  "Absolute tolerance of adaptive RK and IDA (default: " +
                      bench::Num(integrator_defaults.atol) + ")")
      ->check(PositiveNumber());
  AddNlpTol(run, &run_.request.nlp_tol);
  run->add_option("--dae-index", run_.request.dae_index,
                  "IDA formulation: 2 (GGL) or 1 (Baumgarte) (default: 2; "
                  "shorthand of --dae-opt dae_index=...)")
      ->check(IntegerIn(1, 2));
  AddNlpMaxIter(run, &run_.request.nlp_max_iter);
  run->add_option("--substeps", run_.request.substeps,
                  "Integrator steps per dt (RK4 step = dt / substeps; initial "
                  "step of adaptive schemes; default: 1)")
      ->check(IntegerIn(1, 100000));
  run->add_option("--contact-check", run_.request.contact_check,
                  "Sampled second-contact check every N samples, 0 = never "
                  "(default: never)")
      ->check(IntegerIn(0, 1000000000));
  run->add_option("--locate-events", run_.request.locate_events,
                  "Locate physical limits between samples and stop there: "
                  "true | false (default: true)");
  run->add_option("--event-points", run_.request.event_points,
                  "Limit-indicator points inside each hold interval for "
                  "located stops (default: 3)")
      ->check(IntegerIn(0, 1000));
  run->add_option("--event-tolerance", run_.request.event_tolerance,
                  "Bisection tolerance of a located stop [s] (default: 1e-9)")
      ->check(PositiveNumber());
  run->add_option("--locate-switches", run_.request.locate_switches,
                  "Locate slide/stick switches between samples and restart "
                  "coupled integration there: true | false (default: true)");
  run->add_option("--nlp-opt", run_.nlp_opts,
                  "NLP backend option key=value (repeatable; see 'quasiroll "
                  "list --options')");
  run->add_option("--dae-opt", run_.dae_opts,
                  "Integrator option key=value (repeatable; see 'quasiroll "
                  "list --options')");
  run->add_option("--out", run_.out, "Output directory")->capture_default_str();
  run->add_option("--progress", run_.progress,
                  "auto (a line updated in place when stderr is a TTY) | bar "
                  "| none")
      ->check(OneOf({"auto", "bar", "none"}))
      ->capture_default_str();
  run->callback([this] { selected_ = [this] { return RunRun(run_); }; });
}

void Commands::Register(CLI::App& app) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  const std::vector<std::string> nlps = NlpSolverRegistry::Names();
  const std::vector<std::string> daes = IntegratorRegistry::Names();
  // Defaults: the registered backends with the default role.
  solve_.nlp = run_.request.nlp =
      NlpSolverRegistry::WithRole(BackendRole::kDefault);
  run_.request.dae = IntegratorRegistry::WithRole(BackendRole::kDefault);

  CLI::App* pose = app.add_subcommand(
      "pose", "Print the initial consistent configuration of a scene");
  pose->add_option("--scene", pose_.scene, "Scene YAML file")->required();
  pose->add_flag("--json", pose_.json, "Print JSON instead of text");
  pose->callback([this] { selected_ = [this] { return RunPose(pose_); }; });

  CLI::App* solve = app.add_subcommand(
      "solve",
      "Solve the quasi-static problem at a scene's initial configuration");
  solve->add_option("--scene", solve_.scene, "Scene YAML file")->required();
  solve->add_option("--nlp", solve_.nlp, "NLP backend (see 'quasiroll list')")
      ->check(OneOf(nlps))
      ->capture_default_str();
  AddSceneOverrides(solve, &solve_.overrides);
  AddNlpTol(solve, &solve_.nlp_tol);
  AddNlpMaxIter(solve, &solve_.nlp_max_iter);
  solve->add_option("--nlp-opt", solve_.nlp_opts,
                    "NLP backend option key=value (repeatable; see 'quasiroll "
                    "list --options')");
  solve->add_flag("--json", solve_.json, "Print JSON instead of text");
  solve->add_flag("--sensitivities", solve_.sensitivities,
                  "Also compute the derivatives of the solution w.r.t. the "
                  "state, mu, eps and the commanded rates (docs/cli.md)");
  CLI::Option* step = solve->add_flag(
      "--step-derivative", solve_.step_derivative,
      "Also integrate one interval from the initial configuration and "
      "compute its derivative w.r.t. the state, mu, eps and the rates "
      "(docs/cli.md)");
  // The interval's flags mean nothing without --step-derivative.
  solve
      ->add_option("--dt", solve_.dt,
                   "--step-derivative: interval [s] (default: the scene's "
                   "dt)")
      ->check(PositiveNumber())
      ->needs(step);
  solve
      ->add_option("--coupling", solve_.coupling,
                   "--step-derivative: zoh | coupled")
      ->check(OneOf({"zoh", "coupled"}))
      ->capture_default_str()
      ->needs(step);
  solve
      ->add_option("--dae", solve_.dae,
                   "--step-derivative: explicit fixed-step RK4 integrator, "
                   "the projection or the Baumgarte one (default " +
                       StepSensitivityOptions().dae + ")")
      ->needs(step);
  solve
      ->add_option("--substeps", solve_.substeps,
                   "--step-derivative: RK4 steps per interval")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->needs(step);
  solve->callback([this] { selected_ = [this] { return RunSolve(solve_); }; });

  RegisterRun(app, nlps, daes);

  CLI::App* list = app.add_subcommand(
      "list", "List the registered NLP backends and integrators");
  list->add_flag("--options", list_.options,
                 "Also print each backend's options (name, type, default, "
                 "range, doc)");
  list->add_flag("--json", list_.json, "Print JSON instead of text");
  list->callback([this] { selected_ = [this] { return RunList(list_); }; });

  bench_.Register(app, &selected_);
  atlas_.Register(app, &selected_);
  for (CLI::App* command : app.get_subcommands({})) command->allow_extras();
}

void Commands::CheckParsed(const CLI::App& app) const {
  for (const CLI::App* command : app.get_subcommands())
    RejectUnknownArguments(*command, "quasiroll " + command->get_name());
  WarnDeprecatedSpellings(deprecated_);
}

int Commands::Run() { return selected_ ? selected_() : kExitBadInput; }

std::string VersionText() {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  std::string text = "quasiroll " QUASIROLL_VERSION "\ncommit      " +
                     GitCommit() +
                     "\nbuild type  " QUASIROLL_BUILD_TYPE "\nnlp         ";
  for (const std::string& name : NlpSolverRegistry::Names()) text += name + " ";
  text.back() = '\n';
  text += "dae         ";
  for (const std::string& name : IntegratorRegistry::Names())
    text += name + " ";
  text.back() = '\n';
  text += "reports     " + bench::ReportScriptPath();
  return text;
}

int RunPose(const PoseArgs& args) {
  const Scene scene = LoadScene(args.scene);
  const KinematicModel model(scene.geometry, scene.terrain);
  InitialConfigurationReport report;
  const Configuration theta = SolveInitialConfiguration(model, scene, &report);
  if (args.json) {
    std::cout << PoseJson(scene, model, theta, report) << "\n";
    return kExitOk;
  }
  const PoseView pose = EvaluatePose(model, theta);
  const Vec3& p = pose.p;
  const Vec3& rpy = pose.rpy;
  const auto& chains = pose.chains;
  std::printf("scene        %s (%s)\n", scene.name.c_str(),
              scene.terrain->Describe().c_str());
  std::printf("position     x=%.9f y=%.9f z=%.9f m\n", p.x(), p.y(), p.z());
  std::printf("roll/pitch/yaw  %.9f %.9f %.9f rad\n", rpy(0), rpy(1), rpy(2));
  std::printf(
      "joints       phi1=%.6f alpha1=%.6f delta2=%.6f alpha2=%.6f "
      "delta3=%.6f alpha3=%.6f rad\n",
      theta(15), theta(16), theta(17), theta(18), theta(19), theta(20));
  for (int i = 0; i < 3; ++i) {
    const Vec3& c = chains[i].p_c;
    const Vec3 n = chains[i].ground.frame.col(2);
    std::printf(
        "wheel %d      contact (%.9f, %.9f, %.9f) normal (%.6f, %.6f, "
        "%.6f) psi=%.9f u_w=%.6f v_w=%.6f\n",
        i + 1, c.x(), c.y(), c.z(), n.x(), n.y(), n.z(),
        theta(ConfigIndex::Psi(i)), theta(ConfigIndex::U(i)),
        theta(ConfigIndex::V(i)));
  }
  std::printf(
      "||H||_inf    %.3e   (contact residual %.3e, %d Newton "
      "iterations)\n",
      report.loop_closure, report.contact_residual, report.iterations);
  return 0;
}

namespace {

void PrintTable(const OptionTable& table) {
  for (const OptionSpec& o : table)
    std::printf("      %-28s %-6s %-14s %-22s %s\n", o.name.c_str(),
                ToString(o.type), OptionValueText(o.default_value).c_str(),
                o.RangeText().c_str(), o.doc.c_str());
}

// --nlp-opt / --dae-opt values -> name -> text; a key given twice is an
// error.
GivenOptions ParseOptionFlags(const std::vector<std::string>& flags,
                              const std::string& flag) {
  GivenOptions given;
  for (const std::string& f : flags) {
    const auto [key, value] = SplitKeyValue(f, flag);
    if (!given.emplace(key, value).second)
      throw UsageError(flag,
                       "option '" + key + "' given twice, got \"" + f + "\"");
  }
  return given;
}

}  // namespace

namespace {
// The registered backends with their BackendInfo as a JSON array.
template <typename RegistryT>
std::string BackendListJson(bool with_options) {
  std::string out = "[";
  for (const std::string& name : RegistryT::Names()) {
    const BackendInfo info = RegistryT::Info(name);
    std::string roles;
    for (BackendRole role : info.roles) {
      if (!roles.empty()) roles += ",";
      roles += JsonQuote(ToString(role));
    }
    if (out.size() > 1) out += ",";
    out += "{\"name\":";
    out += JsonQuote(name);
    out += ",\"description\":";
    out += JsonQuote(info.description);
    out += ",\"family\":";
    out += JsonQuote(info.family);
    out += ",\"library\":";
    out += JsonQuote(info.library);
    out += ",\"library_version\":";
    out += JsonQuote(info.library_version);
    out +=
        info.thread_safe ? ",\"thread_safe\":true" : ",\"thread_safe\":false";
    out += ",\"roles\":[";
    out += roles;
    out += "]";
    if (with_options) {
      out += ",\"options\":";
      out += OptionTableJson(RegistryT::Create(name)->option_table());
    }
    out += "}";
  }
  return out + "]";
}
}  // namespace

int RunList(const ListArgs& args) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  if (args.json) {
    // {"nlp": [{"name", "description", "family", "library",
    // "library_version", "thread_safe", "roles"[, "options"]}], "dae": [...]}
    std::cout << "{\"nlp\":" << BackendListJson<NlpSolverRegistry>(args.options)
              << ",\"dae\":"
              << BackendListJson<IntegratorRegistry>(args.options) << "}\n";
    return 0;
  }
  std::printf("NLP backends (--nlp):\n");
  for (const std::string& name : NlpSolverRegistry::Names()) {
    std::printf("  %-14s %s\n", name.c_str(),
                NlpSolverRegistry::Description(name).c_str());
    if (args.options)
      PrintTable(NlpSolverRegistry::Create(name)->option_table());
  }
  std::printf("DAE integrators (--dae):\n");
  for (const std::string& name : IntegratorRegistry::Names()) {
    std::printf("  %-14s %s\n", name.c_str(),
                IntegratorRegistry::Description(name).c_str());
    if (args.options)
      PrintTable(IntegratorRegistry::Create(name)->option_table());
  }
  if (args.options)
    std::printf(
        "Options: --nlp-opt / --dae-opt key=value, suite keys nlp_options / "
        "dae_options (columns: name, type, default, range, doc).\n");
  return 0;
}

namespace {

// A RunRequest key as the command line spells it: --dt, --t-end, --dae-opt.
std::string FlagName(const std::string& key) {
  if (key == "nlp_options") return "--nlp-opt";
  if (key == "dae_options") return "--dae-opt";
  std::string flag = "--" + key;
  for (char& c : flag)
    if (c == '_') c = '-';
  return flag;
}

// --mu, --eps, --mode into the request (the flag checked the mode's text).
void SetSceneOverrides(const SceneOverrides& o, bench::RunRequest* request) {
  request->mu = o.mu;
  request->eps = o.eps;
  if (o.mode)
    request->mode =
        *o.mode == "pvc" ? ActuationMode::kPvc : ActuationMode::kPaper;
}

}  // namespace

namespace {

// `solve --sensitivities` text: a short summary (the JSON has them all).
void PrintSensitivities(const QuasiStaticSensitivities& s) {
  std::printf("sensitivities %s (%s), %s\n", ToString(s.status),
              QuasiStaticSensitivities::kMethod,
              s.one_sided ? "ONE-SIDED at:" : "two-sided");
  for (int a = 0; a < s.num_one_sided; ++a)
    std::printf(
        "  %s\n",
        OneSidedName(s, s.one_sided_items[static_cast<size_t>(a)]).c_str());
  if (s.status != SensitivityStatus::kOk) return;
  auto row = [](const char* name, const Eigen::VectorXd& v) {
    std::printf("  %-13s", name);
    for (Eigen::Index i = 0; i < v.size(); ++i) std::printf(" %.6g", v(i));
    std::printf("\n");
  };
  row("dtwist/dmu", s.twist.col(SensitivityParameter::kMu));
  row("dtwist/deps", s.twist.col(SensitivityParameter::kEpsilon));
  row("dforces/dmu", s.forces.col(SensitivityParameter::kMu));
  std::printf(
      "  |dtwist/dstate|max %.6g, |dtwist/drates|max %.6g\n",
      s.twist.leftCols(SensitivityParameter::kNumState).cwiseAbs().maxCoeff(),
      s.twist.rightCols(6).cwiseAbs().maxCoeff());
}

// `solve --step-derivative`: one interval from theta and its derivative.
StepSensitivityResult StepDerivative(const SolveArgs& args,
                                     const bench::ResolvedSolve& resolved,
                                     const KinematicModel& model,
                                     const Configuration& theta,
                                     StepSensitivityOptions* o) {
  o->nlp = resolved.nlp;
  o->nlp_options = resolved.nlp_options;
  o->quasi_static = resolved.quasi_static;
  o->dt = args.dt ? *args.dt : resolved.scene.dt;
  o->coupling = CouplingFromString(args.coupling);
  if (!args.dae.empty()) o->dae = args.dae;
  o->substeps = args.substeps;
  StepSensitivity step(model, QuasiStaticParameters::FromScene(resolved.scene),
                       *o);
  StepSensitivityResult r;
  step.Compute(theta, &r);
  return r;
}

// The `step_sensitivities` object (docs/formats.md): the interval's setup,
// status, Theta_k and Theta_{k+1}, and the entries d<output>_d<input>
// while the derivative exists (OK, ONE_SIDED).
std::string StepSensitivityJson(const StepSensitivityOptions& o,
                                const Configuration& theta,
                                const StepSensitivityResult& r) {
  JsonWriter w;
  w.BeginObject();
  w.Key("status").Value(ToString(r.status));
  w.Key("message").Value(r.message);
  w.Key("method").Value(StepSensitivityResult::kMethod);
  w.Key("dae").Value(o.dae);
  w.Key("coupling").Value(ToString(o.coupling));
  w.Key("dt").Value(o.dt);
  w.Key("substeps").Value(o.substeps);
  w.Key("one_sided").Value(!r.one_sided.empty());
  w.Key("one_sided_constraints").BeginArray();
  for (const std::string& name : r.one_sided) w.Value(name);
  w.EndArray();
  w.Key("state_names").BeginArray();
  for (const char* name : StateNames()) w.Value(name);
  w.EndArray();
  w.Key("rate_names").BeginArray();
  for (const char* name : JointNames()) w.Value(name);
  w.EndArray();
  w.Key("state").Array(theta);
  w.Key("state_next").Array(r.theta_next);
  w.Key("drift").Value(r.drift);
  if (r.jacobian.allFinite()) {
    for (const SensitivityEntry& e : StepSensitivityEntries(r)) {
      w.Key(e.name);
      if (e.vector) {
        w.Array(Eigen::VectorXd(e.value.col(0)));
        continue;
      }
      w.BeginArray();
      for (Eigen::Index i = 0; i < e.value.rows(); ++i)
        w.Array(Eigen::VectorXd(e.value.row(i).transpose()));
      w.EndArray();
    }
  }
  w.EndObject();
  return w.str();
}

void PrintStepSensitivities(const StepSensitivityOptions& o,
                            const StepSensitivityResult& r) {
  std::printf("step derivative %s (%s, %s, dt %g, %d substep(s), %s)%s%s\n",
              ToString(r.status), o.dae.c_str(), ToString(o.coupling), o.dt,
              o.substeps, StepSensitivityResult::kMethod,
              r.message.empty() ? "" : ": ", r.message.c_str());
  for (const std::string& name : r.one_sided)
    std::printf("  one-sided at %s\n", name.c_str());
  if (!r.jacobian.allFinite()) return;
  std::printf(
      "  |dstate_next/dstate - I|max %.6g, |dstate_next/dmu|max %.6g, "
      "|dstate_next/drates|max %.6g, drift %.3g\n",
      (r.dstate() - Eigen::Matrix<double, 21, 21>::Identity())
          .cwiseAbs()
          .maxCoeff(),
      r.dmu().cwiseAbs().maxCoeff(), r.drates().cwiseAbs().maxCoeff(), r.drift);
}

}  // namespace

int RunSolve(const SolveArgs& args) {
  RegisterBuiltinNlpSolvers();
  bench::RunRequest request;
  SetSceneOverrides(args.overrides, &request);
  request.nlp = args.nlp;
  request.nlp_tol = args.nlp_tol;
  request.nlp_max_iter = args.nlp_max_iter;
  request.nlp_options = ParseOptionFlags(args.nlp_opts, "--nlp-opt");
  const bench::ResolvedSolve resolved =
      bench::ResolveSolveRequest(LoadScene(args.scene), request, FlagName);
  const Scene& scene = resolved.scene;
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  QuasiStaticOptions options = resolved.quasi_static;
  options.diagnostics = true;
  std::unique_ptr<NlpSolver> nlp = NlpSolverRegistry::Create(resolved.nlp);
  nlp->SetBackendOptions(resolved.nlp_options);
  QuasiStaticSolver solver(model, QuasiStaticParameters::FromScene(scene),
                           std::move(nlp), options);
  QuasiStaticSolution sol;
  const QuasiStaticStatus status = solver.Solve(theta, &sol);
  const bool ok = status == QuasiStaticStatus::kOk;
  QuasiStaticSensitivities sens;
  if (ok && args.sensitivities)
    SensitivityAnalyzer().Compute(solver.problem(), sol.z, &sens);
  StepSensitivityOptions step_options;
  StepSensitivityResult step;
  if (ok && args.step_derivative)
    step = StepDerivative(args, resolved, model, theta, &step_options);
  // 1-based wheel, or none (docs/cli.md, "No wheel").
  const int critical_wheel =
      sol.critical_contact >= 0 ? sol.critical_contact + 1 : 0;
  if (args.json) {
    std::string json = SolveJson(scene, args.nlp, status, sol,
                                 args.sensitivities ? &sens : nullptr);
    if (args.step_derivative) {  // additive: one more key at the end
      json.pop_back();           // the document's closing '}'
      json += ",\"step_sensitivities\":" +
              (ok ? StepSensitivityJson(step_options, theta, step)
                  : std::string("null")) +
              "}";
    }
    std::cout << json << "\n";
    return ok ? kExitOk : kExitNotOk;
  }
  std::printf("status       %s%s%s\n", ToString(status),
              sol.message.empty() ? "" : ": ", sol.message.c_str());
  std::printf(
      "nlp          %s, %d iterations in %d solves, %.1f us, scaled residual "
      "%.2e, "
      "condition %.3g\n",
      args.nlp.c_str(), sol.nlp_iterations, sol.nlp_solves,
      sol.wall_seconds * 1e6, sol.residual, sol.condition_number);
  std::printf("mode %s, mu = %g, mu_min = %.9g\n", ToString(scene.mode),
              scene.mu, sol.mu_min);
  if (!ok) {
    if (critical_wheel > 0) std::printf("critical wheel %d\n", critical_wheel);
    return kExitNotOk;
  }
  std::printf(
      "twist V^B    v = (%.9f, %.9f, %.9f) m/s  w = (%.9f, %.9f, %.9f) "
      "rad/s\n",
      sol.twist(0), sol.twist(1), sol.twist(2), sol.twist(3), sol.twist(4),
      sol.twist(5));
  std::printf("joint rates  ");
  for (double r : sol.joint_rates) std::printf("%.9f ", r);
  std::printf("rad/s\n");
  for (int i = 0; i < 3; ++i) {
    const ContactOutput& c = sol.contacts[i];
    std::printf(
        "wheel %d      N = %.6f N  traction lon/lat = %.6f / %.6f N  slip = "
        "(%.3e, %.3e) m/s  use = %.4f\n",
        i + 1, c.normal_force, c.traction(0), c.traction(1), c.slip(0),
        c.slip(1), c.friction_use);
  }
  std::printf("actuator torques ");
  for (double t : sol.actuator_torques) std::printf("%.6f ", t);
  std::printf("N m (nan = passive)\ngap G = %.3e W\n", sol.gap);
  if (args.sensitivities) PrintSensitivities(sens);
  if (args.step_derivative) PrintStepSensitivities(step_options, step);
  return kExitOk;
}

namespace {

// `quasiroll run --progress`: one line on stderr rewritten in place
// (carriage return), at most every 0.1 s of wall time.
class RunProgress {
 public:
  RunProgress(bool enabled, double t_end) : enabled_(enabled), t_end_(t_end) {}
  void Update(const SimulationResult& r, bool force = false) {
    if (!enabled_ || r.samples.empty()) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && printed_ && now - last_ < std::chrono::milliseconds(100))
      return;
    last_ = now;
    printed_ = true;
    const double t = r.samples.back().t;
    std::fprintf(stderr,
                 "\rrun: t = %.4g / %.4g s  %3.0f%%  %zu samples  %.1f s", t,
                 t_end_, 100.0 * t / t_end_, r.samples.size(),
                 std::chrono::duration<double>(now - start_).count());
    std::fflush(stderr);
  }
  void Finish(const SimulationResult& r) {
    if (!enabled_) return;
    Update(r, true);
    if (printed_) std::fputc('\n', stderr);
  }

 private:
  bool enabled_;
  double t_end_;
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_ =
      std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_;
};

}  // namespace

int RunRun(const RunArgs& args) {
  // Everything that can be checked is checked before the simulation.
  CheckOutputDirectory("--out", args.out);
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  bench::RunRequest request = args.request;
  SetSceneOverrides(args.overrides, &request);
  request.coupling = CouplingFromString(args.coupling);
  request.nlp_options = ParseOptionFlags(args.nlp_opts, "--nlp-opt");
  request.dae_options = ParseOptionFlags(args.dae_opts, "--dae-opt");
  bench::ResolvedRun resolved =
      bench::ResolveRunRequest(LoadScene(args.scene), request, FlagName);
  for (const std::string& note : resolved.notes)
    std::fprintf(stderr, "note: %s\n", note.c_str());
  const Scene& scene = resolved.scene;
  const SimulationOptions& options = resolved.options;
  Simulator sim(scene, options);

  const bool tty = ::isatty(STDERR_FILENO) == 1;
  RunProgress progress(
      args.progress == "bar" || (args.progress == "auto" && tty), sim.t_end());
  InstallInterruptFlag();
  SimulationResult result;
  sim.Begin(sim.initial_configuration(), &result);
  bool interrupted = false;
  while (true) {
    if (Interrupted()) {
      interrupted = true;
      break;
    }
    if (!sim.Advance(&result)) break;
    progress.Update(result);
  }
  progress.Finish(result);
  if (interrupted) {
    // The trajectory so far; run.json says so (docs/cli.md, "Interrupts").
    const double t = result.samples.empty() ? 0.0 : result.samples.back().t;
    result.status = "INTERRUPTED";
    result.t_reached = t;
    result.stop_reason = "interrupted (SIGINT) at t=" + bench::Num(t) + " s";
    if (!result.samples.empty())
      result.stop_configuration = result.samples.back().theta;
  }
  AtomicWriteFile(args.out + "/trajectory.csv", TrajectoryCsv(result));
  AtomicWriteFile(args.out + "/run.json",
                  RunJson(scene, options, sim.dt(), sim.t_end(), result));
  std::fprintf(stderr, "%s: %s, t = %.4g s, %zu samples, %.3f ms wall%s%s\n",
               scene.name.c_str(), result.status.c_str(), result.t_reached,
               result.samples.size(), result.wall_seconds * 1e3,
               result.stop_reason.empty() ? "" : "\n  stop: ",
               result.stop_reason.c_str());
  std::printf("%s/trajectory.csv\n", args.out.c_str());
  if (interrupted) return kExitInterrupted;
  return result.success() ? kExitOk : kExitNotOk;
}

}  // namespace quasiroll::cli
