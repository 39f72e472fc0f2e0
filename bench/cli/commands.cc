#include "bench/cli/commands.h"

#include <cstdio>
#include <iostream>

#include "bench/json_writer.h"
#include "core/dae.h"
#include "core/initial_configuration.h"
#include "core/kinematics.h"
#include "core/nlp.h"
#include "core/scene.h"

namespace quasiroll::cli {

void Commands::Register(CLI::App& app) {
  CLI::App* pose = app.add_subcommand(
      "pose", "Print the initial consistent configuration of a scene");
  pose->add_option("--scene", pose_.scene, "Scene YAML file")->required();
  pose->add_flag("--json", pose_.json, "Print JSON instead of text");
  pose->callback([this] { selected_ = [this] { return RunPose(pose_); }; });

  CLI::App* list = app.add_subcommand(
      "list", "List the registered NLP backends and integrators");
  list->callback([this] { selected_ = [] { return RunList(); }; });
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
  std::printf("joints       phi1=%.6f alpha1=%.6f delta2=%.6f alpha2=%.6f "
              "delta3=%.6f alpha3=%.6f rad\n",
              theta(15), theta(16), theta(17), theta(18), theta(19),
              theta(20));
  for (int i = 0; i < 3; ++i) {
    const Vec3& c = chains[i].p_c;
    const Vec3 n = chains[i].ground.frame.col(2);
    std::printf("wheel %d      contact (%.9f, %.9f, %.9f) normal (%.6f, %.6f, "
                "%.6f) psi=%.9f u_w=%.6f v_w=%.6f\n",
                i + 1, c.x(), c.y(), c.z(), n.x(), n.y(), n.z(),
                theta(ConfigIndex::Psi(i)), theta(ConfigIndex::U(i)),
                theta(ConfigIndex::V(i)));
  }
  std::printf("||H||_inf    %.3e   (contact residual %.3e, %d Newton "
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

}  // namespace quasiroll::cli
