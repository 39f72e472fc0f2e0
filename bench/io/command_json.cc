#include "quasiroll/bench/io/command_json.h"

#include <array>

#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/core/so3.h"

namespace quasiroll {

namespace {

// An array of `n` nulls: the JSON of a vector the solve did not produce.
void NullArray(JsonWriter* w, int n) {
  w->BeginArray();
  for (int i = 0; i < n; ++i) w->Null();
  w->EndArray();
}

void WriteSensitivities(JsonWriter* w, const QuasiStaticSensitivities& s) {
  w->BeginObject();
  w->Key("status").Value(ToString(s.status));
  w->Key("method").Value(QuasiStaticSensitivities::kMethod);
  w->Key("one_sided").Value(s.one_sided);
  w->Key("one_sided_constraints").BeginArray();
  for (int a = 0; a < s.num_one_sided; ++a)
    w->Value(OneSidedName(s, s.one_sided_items[static_cast<size_t>(a)]));
  w->EndArray();
  w->Key("state_names").BeginArray();
  for (const char* name : StateNames()) w->Value(name);
  w->EndArray();
  w->Key("rate_names").BeginArray();
  for (const char* name : JointNames()) w->Value(name);
  w->EndArray();
  if (s.status == SensitivityStatus::kOk) {
    w->Key("multiplier_values").Array(Eigen::VectorXd(s.multiplier_values));
    for (const SensitivityEntry& e : SensitivityEntries(s)) {
      w->Key(e.name);
      if (e.vector) {
        w->Array(Eigen::VectorXd(e.value.col(0)));
        continue;
      }
      w->BeginArray();
      for (Eigen::Index r = 0; r < e.value.rows(); ++r)
        w->Array(Eigen::VectorXd(e.value.row(r).transpose()));
      w->EndArray();
    }
  }
  w->EndObject();
}

}  // namespace

PoseView EvaluatePose(const KinematicModel& model, const Configuration& theta) {
  PoseView v;
  model.PlatformPose(theta, &v.R, &v.p);
  v.rpy = RpyFromRotation(v.R);
  for (int i = 0; i < 3; ++i) model.EvaluateChain(theta, i, &v.chains[i]);
  return v;
}

std::string PoseJson(const Scene& scene, const KinematicModel& model,
                     const Configuration& theta,
                     const InitialConfigurationReport& report) {
  const PoseView pose = EvaluatePose(model, theta);
  const Vec3& p = pose.p;
  const Vec3& rpy = pose.rpy;
  const auto& chains = pose.chains;
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
  return w.str();
}

std::string SolveJson(const Scene& scene, const std::string& nlp,
                      QuasiStaticStatus status, const QuasiStaticSolution& sol,
                      const QuasiStaticSensitivities* sensitivities) {
  const bool ok = status == QuasiStaticStatus::kOk;
  const int critical_wheel =
      sol.critical_contact >= 0 ? sol.critical_contact + 1 : 0;
  // A failed solve has no twist, rates, torques, gap or contact outputs:
  // those keys are null (arrays of nulls keep their length), never zeros.
  JsonWriter w;
  w.BeginObject();
  w.Key("status").Value(ToString(status));
  w.Key("message").Value(sol.message);
  w.Key("nlp").Value(nlp);
  w.Key("mode").Value(ToString(scene.mode));
  w.Key("mu").Value(scene.mu);
  w.Key("mu_min").Value(sol.mu_min);
  w.Key("twist");
  ok ? (void)w.Array(sol.twist) : NullArray(&w, 6);
  w.Key("joint_rates");
  ok ? (void)w.Array(sol.joint_rates) : NullArray(&w, 6);
  w.Key("actuator_torques");
  ok ? (void)w.Array(sol.actuator_torques) : NullArray(&w, 6);
  w.Key("gap");
  ok ? (void)w.Value(sol.gap) : (void)w.Null();
  w.Key("iterations").Value(sol.nlp_iterations);
  w.Key("nlp_solves").Value(sol.nlp_solves);
  w.Key("residual").Value(sol.residual);
  w.Key("condition_number").Value(sol.condition_number);
  w.Key("wall_s").Value(sol.wall_seconds);
  w.Key("critical_wheel");
  critical_wheel > 0 ? (void)w.Value(critical_wheel) : (void)w.Null();
  w.Key("contacts").BeginArray();
  for (const ContactOutput& c : sol.contacts) {
    w.BeginObject();
    if (ok) {
      w.Key("normal_force").Value(c.normal_force);
      w.Key("traction").Array(c.traction);
      w.Key("force_world").Array(c.force_world);
      w.Key("slip").Array(c.slip);
      w.Key("normal_velocity").Value(c.normal_velocity);
      w.Key("friction_use").Value(c.friction_use);
      w.Key("point").Array(c.point);
    } else {
      w.Key("normal_force").Null();
      w.Key("traction");
      NullArray(&w, 2);
      w.Key("force_world");
      NullArray(&w, 3);
      w.Key("slip");
      NullArray(&w, 2);
      w.Key("normal_velocity").Null();
      w.Key("friction_use").Null();
      w.Key("point");
      NullArray(&w, 3);
    }
    w.EndObject();
  }
  w.EndArray();
  if (sensitivities) {
    w.Key("sensitivities");
    ok ? WriteSensitivities(&w, *sensitivities) : (void)w.Null();
  }
  w.EndObject();
  return w.str();
}

}  // namespace quasiroll
