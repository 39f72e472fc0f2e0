#include "bench/cli/commands.h"

#include <cstdio>
#include <iostream>

#include "bench/json_writer.h"
#include "bench/run_output.h"
#include "core/dae.h"
#include "core/initial_configuration.h"
#include "core/kinematics.h"
#include "core/nlp.h"
#include "core/quasi_static.h"
#include "core/scene.h"
#include "core/simulator.h"

namespace quasiroll::cli {

void Commands::Register(CLI::App& app) {
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
      ->capture_default_str();
  solve->add_option("--mu", solve_.mu,
                    "Override the friction coefficient (> 0)");
  solve->add_option("--mode", solve_.mode, "Override the actuation mode")
      ->check(CLI::IsMember({"paper", "pvc"}));
  solve->add_flag("--json", solve_.json, "Print JSON instead of text");
  solve->callback([this] { selected_ = [this] { return RunSolve(solve_); }; });

  CLI::App* run = app.add_subcommand(
      "run", "Simulate a scene; writes DIR/trajectory.csv and DIR/run.json");
  run->add_option("--scene", run_.scene, "Scene YAML file")->required();
  run->add_option("--nlp", run_.nlp, "NLP backend")->capture_default_str();
  run->add_option("--dae", run_.dae, "Integrator backend")
      ->capture_default_str();
  run->add_option("--coupling", run_.coupling, "zoh | coupled")
      ->check(CLI::IsMember({"zoh", "coupled"}))
      ->capture_default_str();
  run->add_option("--dt", run_.dt,
                  "Hold/output interval [s] (default: scene's)");
  run->add_option("--t-end", run_.t_end, "End time [s] (default: scene's)");
  run->add_option("--mu", run_.mu, "Override the friction coefficient (> 0)");
  run->add_option("--mode", run_.mode, "Override the actuation mode")
      ->check(CLI::IsMember({"paper", "pvc"}));
  run->add_option("--rk", run_.rk_method, "RK scheme: rk4 | dp54 | bs32")
      ->capture_default_str();
  run->add_option("--sigma", run_.sigma, "Baumgarte gain [1/s]")
      ->capture_default_str();
  run->add_option("--rtol", run_.rtol, "Relative tolerance (adaptive RK, IDA)")
      ->capture_default_str();
  run->add_option("--atol", run_.atol, "Absolute tolerance (adaptive RK, IDA)")
      ->capture_default_str();
  run->add_option("--dae-index", run_.dae_index,
                  "IDA formulation: 2 (GGL) or 1 (Baumgarte)")
      ->capture_default_str();
  run->add_option("--out", run_.out, "Output directory")->capture_default_str();
  run->callback([this] { selected_ = [this] { return RunRun(run_); }; });

  CLI::App* list = app.add_subcommand(
      "list", "List the registered NLP backends and integrators");
  list->callback([this] { selected_ = [] { return RunList(); }; });

  bench_.Register(app, &selected_);
}

int Commands::Run() { return selected_ ? selected_() : 2; }

int RunPose(const PoseArgs& args) {
  const Scene scene = LoadScene(args.scene);
  const KinematicModel model(scene.geometry, scene.terrain);
  InitialConfigurationReport report;
  const Configuration theta = SolveInitialConfiguration(model, scene, &report);
  Mat3 R;
  Vec3 p;
  model.PlatformPose(theta, &R, &p);
  const Vec3 rpy = RpyFromRotation(R);

  std::array<ChainState, 3> chains;
  for (int i = 0; i < 3; ++i) model.EvaluateChain(theta, i, &chains[i]);

  if (args.json) {
    JsonWriter w;
    w.BeginObject();
    w.Key("scene").Value(scene.name);
    w.Key("position").Array(p);
    w.Key("rpy").Array(rpy);
    w.Key("joint_angles").Array(theta.tail<6>());
    w.Key("H_norm").Value(report.loop_closure);
    w.Key("contact_residual").Value(report.contact_residual);
    w.Key("contacts").BeginArray();
    for (int i = 0; i < 3; ++i) {
      w.BeginObject();
      w.Key("point").Array(chains[i].p_c);
      w.Key("normal").Array(Vec3(chains[i].ground.frame.col(2)));
      w.Key("psi").Value(theta(ConfigIndex::Psi(i)));
      w.Key("u_w").Value(theta(ConfigIndex::U(i)));
      w.Key("v_w").Value(theta(ConfigIndex::V(i)));
      w.EndObject();
    }
    w.EndArray();
    w.EndObject();
    std::cout << w.str() << "\n";
    return 0;
  }
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

int RunList() {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  std::printf("NLP backends (--nlp):\n");
  for (const std::string& name : NlpSolverRegistry::Names())
    std::printf("  %-14s %s\n", name.c_str(),
                NlpSolverRegistry::Description(name).c_str());
  std::printf("DAE integrators (--dae):\n");
  for (const std::string& name : IntegratorRegistry::Names())
    std::printf("  %-14s %s\n", name.c_str(),
                IntegratorRegistry::Description(name).c_str());
  return 0;
}

namespace {

void ApplyOverrides(Scene* scene, double mu, const std::string& mode) {
  if (mu != 0) {
    if (!(std::isfinite(mu) && mu > 0))
      throw SceneError("--mu: must be finite and > 0, got " +
                       std::to_string(mu));
    scene->mu = mu;
  }
  if (mode == "paper") scene->mode = ActuationMode::kPaper;
  if (mode == "pvc") scene->mode = ActuationMode::kPvc;
}

}  // namespace

int RunSolve(const SolveArgs& args) {
  RegisterBuiltinNlpSolvers();
  Scene scene = LoadScene(args.scene);
  ApplyOverrides(&scene, args.mu, args.mode);
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta = SolveInitialConfiguration(model, scene);
  QuasiStaticOptions options;
  options.diagnostics = true;
  QuasiStaticSolver solver(model, QuasiStaticParameters::FromScene(scene),
                           NlpSolverRegistry::Create(args.nlp), options);
  QuasiStaticSolution sol;
  const QuasiStaticStatus status = solver.Solve(theta, &sol);
  const bool ok = status == QuasiStaticStatus::kOk;
  if (args.json) {
    JsonWriter w;
    w.BeginObject();
    w.Key("status").Value(ToString(status));
    w.Key("message").Value(sol.message);
    w.Key("nlp").Value(args.nlp);
    w.Key("mode").Value(ToString(scene.mode));
    w.Key("mu").Value(scene.mu);
    w.Key("mu_min").Value(sol.mu_min);
    w.Key("twist").Array(sol.twist);
    w.Key("joint_rates").Array(sol.joint_rates);
    w.Key("actuator_torques").Array(sol.actuator_torques);
    w.Key("gap").Value(sol.gap);
    w.Key("iterations").Value(sol.nlp_iterations);
    w.Key("nlp_solves").Value(sol.nlp_solves);
    w.Key("residual").Value(sol.residual);
    w.Key("condition_number").Value(sol.condition_number);
    w.Key("wall_s").Value(sol.wall_seconds);
    w.Key("critical_wheel").Value(sol.critical_contact + 1);
    w.Key("contacts").BeginArray();
    for (const ContactOutput& c : sol.contacts) {
      w.BeginObject();
      w.Key("normal_force").Value(c.normal_force);
      w.Key("traction").Array(c.traction);
      w.Key("force_world").Array(c.force_world);
      w.Key("slip").Array(c.slip);
      w.Key("normal_velocity").Value(c.normal_velocity);
      w.Key("friction_use").Value(c.friction_use);
      w.Key("point").Array(c.point);
      w.EndObject();
    }
    w.EndArray();
    w.EndObject();
    std::cout << w.str() << "\n";
    return ok ? 0 : 1;
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
  if (!ok) return 1;
  std::printf(
      "twist V^B    v = (%.9f, %.9f, %.9f) m/s  w = (%.9f, %.9f, %.9f) rad/s\n",
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
  return 0;
}

int RunRun(const RunArgs& args) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Scene scene = LoadScene(args.scene);
  ApplyOverrides(&scene, args.mu, args.mode);
  SimulationOptions options;
  options.nlp = args.nlp;
  options.dae = args.dae;
  options.coupling = CouplingFromString(args.coupling);
  options.dt = args.dt;
  options.t_end = args.t_end;
  options.integrator.rk_method = RkMethodFromString(args.rk_method);
  options.integrator.baumgarte_sigma = args.sigma;
  options.integrator.rtol = args.rtol;
  options.integrator.atol = args.atol;
  options.integrator.dae_index = args.dae_index;
  Simulator sim(scene, options);
  const SimulationResult result = sim.Run();
  AtomicWriteFile(args.out + "/trajectory.csv", TrajectoryCsv(result));
  AtomicWriteFile(args.out + "/run.json",
                  RunJson(scene, options, sim.dt(), sim.t_end(), result));
  std::fprintf(stderr, "%s: %s, t = %.4g s, %zu samples, %.3f ms wall%s%s\n",
               scene.name.c_str(), result.status.c_str(), result.t_reached,
               result.samples.size(), result.wall_seconds * 1e3,
               result.stop_reason.empty() ? "" : "\n  stop: ",
               result.stop_reason.c_str());
  std::printf("%s/trajectory.csv\n", args.out.c_str());
  return result.success() ? 0 : 1;
}

}  // namespace quasiroll::cli
