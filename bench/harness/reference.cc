#include "quasiroll/bench/harness/reference.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "quasiroll/bench/harness/metrics.h"
#include "quasiroll/bench/harness/reference_retry.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_reader.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/so3.h"

namespace quasiroll::bench {

namespace fs = std::filesystem;

const char* ToString(AnalyticCase c) {
  switch (c) {
    case AnalyticCase::kNone:
      return "none";
    case AnalyticCase::kFlatStraight:
      return "flat";
    case AnalyticCase::kCircle:
      return "circle";
    case AnalyticCase::kIncline:
      return "incline";
  }
  return "none";
}

namespace {

bool Close(double a, double b) {
  return std::abs(a - b) <= 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
}

// Angle difference wrapped to (-pi, pi].
double WrapAngle(double a) {
  a = std::remainder(a, 2 * std::numbers::pi);
  return a;
}

// Friction coefficient needed to roll on an incline (0 if none is needed).
double InclineMuRequired(const Scene& s, double beta, double nose_up) {
  const RobotGeometry& g = s.geometry;
  const double hc = g.z_h + g.rho();
  if (s.mode == ActuationMode::kPaper) return std::abs(std::tan(beta));
  const double sb = std::sin(std::abs(beta)), cb = std::cos(beta);
  // Nose up when the heading points uphill (beta > 0 and nose_up = +1).
  const double up = (beta > 0 ? 1.0 : -1.0) * nose_up;
  return g.wheelbase() * sb / (g.a * cb + up * hc * sb);
}

}  // namespace

AnalyticCase DetectAnalyticCase(const Scene& s, const TerrainSpec& t,
                                std::string* why_not) {
  auto no = [why_not](const std::string& why) {
    if (why_not) *why_not = why;
    return AnalyticCase::kNone;
  };
  const auto& q = s.joint_angles;
  const auto& r = s.joint_rates;
  const bool pvc = s.mode == ActuationMode::kPvc;
  if (t.type != TerrainSpec::Type::kPlane &&
      t.type != TerrainSpec::Type::kIncline)
    return no("terrain is neither plane nor incline");
  if (s.geometry.camber_offset != 0) return no("camber_offset != 0");
  if (q[2] != 0 || q[4] != 0) return no("initial cambers != 0");
  if (r[0] != 0) return no("steer rate != 0");
  if (!pvc && (r[2] != 0 || r[4] != 0)) return no("camber rates != 0");
  const bool equal_rear = Close(r[3], r[5]);
  const bool equal_all = equal_rear && (pvc || Close(r[1], r[3]));
  if (t.type == TerrainSpec::Type::kPlane) {
    if (q[0] == 0) {
      if (!equal_all) return no("unequal spin rates with phi1 = 0");
      return AnalyticCase::kFlatStraight;
    }
    if (!(std::abs(q[0]) < std::numbers::pi / 2)) return no("|phi1| >= pi/2");
    const RobotGeometry& g = s.geometry;
    const double rho = g.rho(), L = g.wheelbase();
    const double v = rho * (r[3] + r[5]) / 2;
    const double omega = v * std::tan(q[0]) / L;
    if (!(std::abs(rho * (r[5] - r[3]) - omega * g.track) <=
          1e-12 * std::max(1.0, std::abs(omega * g.track))))
      return no("rear rates inconsistent with the steer angle (O2)");
    if (!pvc && !Close(r[1], v / (rho * std::cos(q[0]))))
      return no("front spin rate inconsistent with the steer angle (O2)");
    return AnalyticCase::kCircle;
  }
  // Incline.
  if (q[0] != 0) return no("phi1 != 0 on an incline");
  if (!equal_all) return no("unequal spin rates on an incline");
  if (t.slope_rad == 0) return no("zero slope (use a plane)");
  const double d = WrapAngle(s.yaw0 - t.azimuth_rad);
  double nose_up;
  if (std::abs(d) <= 1e-12)
    nose_up = 1;
  else if (std::abs(std::abs(d) - std::numbers::pi) <= 1e-12)
    nose_up = -1;
  else
    return no("heading not along the gradient");
  const double mu_req = InclineMuRequired(s, t.slope_rad, nose_up);
  if (!(mu_req > 0 && s.mu > mu_req))
    return no("friction insufficient for rolling (mu <= mu_required)");
  return AnalyticCase::kIncline;
}

AnalyticSolution::AnalyticSolution(const Scene& scene, const TerrainSpec& t,
                                   AnalyticCase kind)
    : scene_(scene), kind_(kind) {
  if (kind == AnalyticCase::kNone)
    throw std::logic_error("AnalyticSolution: no analytic case");
  const RobotGeometry& g = scene.geometry;
  rho_ = g.rho();
  h_c_ = g.z_h + rho_;
  L_ = g.wheelbase();
  mg_ = scene.mass * scene.gravity;
  const auto& r = scene.joint_rates;
  const auto& q = scene.joint_angles;
  const bool pvc = scene.mode == ActuationMode::kPvc;
  rates_ = r;
  rates_[0] = 0;
  rates_[2] = rates_[4] = 0;
  const double alpha = (r[3] + r[5]) / 2;  // mean rear spin rate
  v_ = rho_ * alpha;                       // rear-axle centre speed

  // Static load distribution on a plane tilted by beta about the lateral
  // axis (beta = 0 on flat ground); tractions balance the slope.
  double beta = 0, nose_up = 1;
  if (kind == AnalyticCase::kIncline) {
    beta = t.slope_rad;
    nose_up = std::abs(WrapAngle(scene.yaw0 - t.azimuth_rad)) <= 1e-12 ? 1 : -1;
  }
  // Pitch of the platform: +1 = front higher than rear.
  const double up = (beta >= 0 ? 1.0 : -1.0) * nose_up;
  const double sb = std::sin(std::abs(beta)), cb = std::cos(beta);
  normal_[0] = mg_ * (g.b * cb - up * h_c_ * sb) / L_;
  normal_[1] = normal_[2] = mg_ * (g.a * cb + up * h_c_ * sb) / (2 * L_);
  // Longitudinal traction along the heading (the ground pushes the wheel
  // uphill when nose up): paper mode in proportion to the load, pvc on the
  // rear wheels only (front passive).
  for (int i = 0; i < 3; ++i) traction_[i] = 0;
  if (kind == AnalyticCase::kIncline) {
    if (pvc) {
      traction_[1] = traction_[2] = up * mg_ * sb / 2;
    } else {
      for (int i = 0; i < 3; ++i)
        traction_[i] = up * std::tan(std::abs(beta)) * normal_[i];
    }
  }
  for (int i = 0; i < 3; ++i) {
    const double qf = std::abs(traction_[i]) / (scene.mu * normal_[i]);
    slip_[i] = scene.epsilon * qf / std::sqrt(1 - qf * qf);
  }
  // The driven rear wheels creep downhill (the slip opposes the uphill
  // traction): the platform advances at rho alpha' - up |s|.
  v_ -= up * slip_[1];

  // Initial pose.
  switch (kind) {
    case AnalyticCase::kFlatStraight:
    case AnalyticCase::kCircle: {
      R0_ = Rz(scene.yaw0);
      p0_ = Vec3(scene.x0, scene.y0, t.height + h_c_);
      break;
    }
    case AnalyticCase::kIncline: {
      const double gm = t.azimuth_rad;
      const Vec3 uphill(std::cos(beta) * std::cos(gm),
                        std::cos(beta) * std::sin(gm), std::sin(beta));
      const Vec3 n(-std::sin(beta) * std::cos(gm),
                   -std::sin(beta) * std::sin(gm), std::cos(beta));
      const Vec3 x = nose_up * uphill;
      R0_.col(0) = x;
      R0_.col(1) = n.cross(x);
      R0_.col(2) = n;
      const double h0 = t.height + std::tan(beta) * (std::cos(gm) * scene.x0 +
                                                     std::sin(gm) * scene.y0);
      p0_ = Vec3(scene.x0, scene.y0, h0 + h_c_ / std::cos(beta));
      break;
    }
    case AnalyticCase::kNone:
      break;
  }
  if (kind == AnalyticCase::kCircle) {
    omega_ = v_ * std::tan(q[0]) / L_;
    rear_radius_ = L_ / std::tan(q[0]);
    const Vec3 xp = R0_.col(0), yp = R0_.col(1);
    icr_ = p0_ - g.b * xp + rear_radius_ * yp;
    rates_[1] = v_ / (rho_ * std::cos(q[0]));
  } else {
    rates_[1] = v_ / rho_;  // straight: the passive front wheel rolls freely
  }
  if (!pvc) rates_[1] = r[1];
}

TrajectorySample AnalyticSolution::Sample(double t) const {
  TrajectorySample s;
  s.t = t;
  Mat3 R = R0_;
  if (kind_ == AnalyticCase::kCircle) {
    R = Rz(omega_ * t) * R0_;
    const Vec3 xp = R.col(0), yp = R.col(1);
    s.position = icr_ - rear_radius_ * yp + scene_.geometry.b * xp;
    s.position.z() = p0_.z();
    s.velocity = omega_ * (rear_radius_ * xp + scene_.geometry.b * yp);
    s.velocity.z() = 0;
    s.angular_velocity = Vec3(0, 0, omega_);
  } else {
    const Vec3 xp = R.col(0);
    s.position = p0_ + v_ * t * xp;
    s.velocity = v_ * xp;
    s.angular_velocity = Vec3::Zero();
  }
  s.rpy = RpyFromRotation(R);
  for (int j = 0; j < 6; ++j)
    s.joints[j] = scene_.joint_angles[j] + rates_[j] * t;
  const RobotGeometry& g = scene_.geometry;
  const std::array<Vec3, 3> attach = {Vec3(g.a, 0, -h_c_),
                                      Vec3(-g.b, g.track / 2, -h_c_),
                                      Vec3(-g.b, -g.track / 2, -h_c_)};
  for (int i = 0; i < 3; ++i) {
    ContactSample& c = s.contacts[i];
    c.point = s.position + R * attach[i];
    c.normal_force = normal_[i];
    c.traction_lon = traction_[i];
    c.traction_lat = 0;
    c.slip = slip_[i];
    c.friction_use = std::abs(traction_[i]) / (scene_.mu * normal_[i]);
  }
  s.drift = 0;
  s.gap_max = 0;
  s.nlp_status = "OK";
  s.nlp_iterations = 0;
  return s;
}

std::vector<TrajectorySample> Reference::ForTimes(
    const std::vector<double>& times) const {
  if (!analytic) return samples;
  const double t_last = samples.empty() ? 0.0 : samples.back().t;
  std::vector<TrajectorySample> out;
  out.reserve(times.size());
  for (double t : times)
    if (t <= t_last + 1e-9) out.push_back(analytic->Sample(t));
  return out;
}

std::string ReferenceKey(const Scene& scene, const TerrainSpec& terrain,
                         const std::string& heightmap_digest,
                         const ReferenceSettings& settings) {
  return SceneCanonicalText(scene, terrain, heightmap_digest) + "|" +
         settings.Canonical();
}

namespace {

// The numerical reference's options: "rk4" at a fixed step (the primary
// method), "dp54" at rtol 1e-10 (the fallback after a numerical breakdown).
SimulationOptions NumericalReferenceOptions(const Scene& scene,
                                            const ReferenceSettings& settings,
                                            const std::string& method) {
  SimulationOptions o;
  o.nlp = settings.Nlp();
  o.dae = ReferenceSettings::Integrator();
  o.coupling = Coupling::kCoupled;
  o.dt = scene.dt / settings.dt_divisor;
  o.t_end = scene.t_end;
  o.dae_options = {{"rk_method", method}};
  o.integrator.step = o.dt / settings.substeps;
  o.integrator.max_steps = 100000000;
  if (method != "rk4") {
    o.integrator.rtol = 1e-10;
    o.integrator.atol = 1e-12;
  }
  o.quasi_static.residual_tolerance = settings.residual_tolerance;
  // The ground truth resolves switches as tightly as the solves allow
  // (docs/model.md §8.6: the methods' 1e-12 floor moved its rtol ladders'
  // floor to ~7e-9 m).
  o.switch_step_tolerance = 1e-13;
  return o;
}

}  // namespace

SimulationResult ComputeNumericalReference(const Scene& scene,
                                           const ReferenceSettings& settings,
                                           std::string* method,
                                           ReferenceRetryLog* log) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  ReferenceRetryLog local;
  if (!log) log = &local;
  SimulationOptions o = NumericalReferenceOptions(scene, settings, "rk4");
  SimulationResult result = RunReferenceWithRetries(scene, o, log);
  if (method) *method = "rk4";
  if (log->stop != "reference_failure") return result;
  // A numerical breakdown the retry ladder could not pass: rerun the whole
  // reference with DP5(4) at rtol 1e-10 (other stage points) and keep
  // whichever gets further.
  o = NumericalReferenceOptions(scene, settings, "dp54");
  Simulator alt(scene, o);
  SimulationResult second = alt.Run();
  log->attempts.push_back({"rerun", DescribeReferenceMethod(o), 0, alt.t_end(),
                           second.status, second.t_reached});
  if (second.success() || second.t_reached > result.t_reached) {
    if (method) *method = "dp54";
    log->stop = ReferenceStopOf(second, scene);
    return second;
  }
  return result;
}

SimulationOptions CheckReferenceOptions(const Scene& scene,
                                        const ReferenceSettings& settings,
                                        const std::string& primary_method) {
  SimulationOptions o;
  o.nlp = settings.Nlp();
  o.coupling = Coupling::kCoupled;
  o.dt = scene.dt / settings.dt_divisor;
  o.t_end = scene.t_end;
  o.integrator.max_steps = 100000000;
  o.integrator.rtol = 1e-10;
  o.integrator.atol = 1e-12;
  o.quasi_static.residual_tolerance = settings.residual_tolerance;
  if (primary_method == "rk4") {
    o.dae = ReferenceSettings::Integrator();
    o.dae_options = {{"rk_method", "dp54"}};
    o.integrator.step = o.dt;  // initial step; DP5(4) controls it
  } else {
    // An implicit method (IDA: index 2 + final projection, model.md §8).
    o.dae = IntegratorRegistry::WithRole(BackendRole::kReferenceCheck);
    o.integrator.step = o.dt;
  }
  return o;
}

std::string DescribeReferenceMethod(const SimulationOptions& o) {
  std::ostringstream os;
  os << ToString(o.coupling) << " " << o.dae;
  const auto rk = o.dae_options.find("rk_method");
  const std::string scheme = rk == o.dae_options.end() ? "rk4" : rk->second;
  // A scheme is named for integrators that have one (the RK family).
  const bool has_scheme =
      FindOption(IntegratorRegistry::Create(o.dae)->option_table(),
                 "rk_method") != nullptr;
  if (has_scheme) os << " " << scheme;
  if (has_scheme && scheme == "rk4")
    os << " step " << Num(o.integrator.step) << " s";
  else
    os << " rtol " << Num(o.integrator.rtol) << " atol "
       << Num(o.integrator.atol);
  os << ", output every " << Num(o.dt) << " s, " << o.nlp << " at residual "
     << Num(o.quasi_static.residual_tolerance);
  return os.str();
}

double PathMinimumFriction(const Scene& scene,
                           const std::vector<TrajectorySample>& samples,
                           int stride) {
  const KinematicModel model(scene.geometry, scene.terrain);
  QuasiStaticProblem problem(model, QuasiStaticParameters::FromScene(scene));
  auto at = [&](std::size_t k) {
    const TrajectorySample& s = samples[k];
    if (!s.theta.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    problem.SetConfiguration(s.theta);
    return problem.MinimumFriction(nullptr, nullptr, kPathMuMinTolerance);
  };
  const std::size_t n = samples.size();
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t step = static_cast<std::size_t>(std::max(1, stride));
  double worst = std::numeric_limits<double>::quiet_NaN();
  std::size_t arg = 0;
  auto consider = [&](std::size_t k) {
    const double v = at(k);
    if (!std::isnan(v) && !(v <= worst)) {
      worst = v;
      arg = k;
    }
  };
  for (std::size_t k = 0; k < n; k += step) consider(k);
  if (n > 1 && (n - 1) % step != 0) consider(n - 1);  // the last sample
  // Refine around the coarse maximum on the full grid.
  const std::size_t lo = arg >= step ? arg - step + 1 : 0;
  const std::size_t hi = std::min(n - 1, arg + step - 1);
  for (std::size_t k = lo; k <= hi; ++k)
    if (k % step != 0) consider(k);
  return worst;
}

// ------------------------------------------------------------- parsing ----

namespace {

double ParseNumber(const std::string& s, int line) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size())
    throw std::runtime_error("trajectory csv line " + std::to_string(line) +
                             ": not a number: '" + s + "'");
  return v;
}

// A top-level string member ("" if absent or not a string).
std::string StringMember(const JsonValue& json, const std::string& name) {
  const JsonValue* v = json.Find(name);
  return v && v->is_string() ? v->str() : "";
}

// A top-level number member (JsonWriter: a number or null); NaN if absent or
// not a number, `*present` says whether the key exists.
double NumberMember(const JsonValue& json, const std::string& name,
                    bool* present) {
  const JsonValue* v = json.Find(name);
  *present = v != nullptr;
  return v && v->is_number() ? v->number()
                             : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

std::vector<TrajectorySample> ParseTrajectoryCsv(const std::string& text) {
  std::vector<TrajectorySample> out;
  std::stringstream in(text);
  std::string line;
  if (!std::getline(in, line))
    throw std::runtime_error("trajectory csv: empty");
  const std::vector<std::string> header = SplitCsvLine(line);
  std::map<std::string, std::size_t> col;
  for (std::size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  auto index = [&col](const std::string& name) {
    auto it = col.find(name);
    if (it == col.end())
      throw std::runtime_error("trajectory csv: missing column '" + name + "'");
    return it->second;
  };
  const std::array<const char*, 6> joints = {"phi1",   "alpha1", "delta2",
                                             "alpha2", "delta3", "alpha3"};
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    const std::vector<std::string> cells = SplitCsvLine(line);
    if (cells.size() != header.size())
      throw std::runtime_error("trajectory csv line " +
                               std::to_string(line_no) + ": expected " +
                               std::to_string(header.size()) + " cells, got " +
                               std::to_string(cells.size()));
    auto num = [&](const std::string& name) {
      return ParseNumber(cells[index(name)], line_no);
    };
    TrajectorySample s;
    s.t = num("t");
    s.position = Vec3(num("x"), num("y"), num("z"));
    s.rpy = Vec3(num("roll"), num("pitch"), num("yaw"));
    s.velocity = Vec3(num("vx"), num("vy"), num("vz"));
    s.angular_velocity = Vec3(num("wx"), num("wy"), num("wz"));
    for (int j = 0; j < 6; ++j) s.joints[j] = num(joints[j]);
    for (int i = 0; i < 3; ++i) {
      const std::string k = std::to_string(i + 1);
      ContactSample& c = s.contacts[i];
      c.point =
          Vec3(num("c" + k + "_x"), num("c" + k + "_y"), num("c" + k + "_z"));
      c.normal_force = num("n" + k);
      c.traction_lon = num("t" + k + "_lon");
      c.traction_lat = num("t" + k + "_lat");
      c.slip = num("slip" + k);
      c.friction_use = num("use" + k);
    }
    s.drift = num("drift");
    s.gap_max = num("gap_max");
    s.nlp_status = cells[index("nlp_status")];
    s.nlp_iterations = static_cast<int>(num("nlp_iters"));
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

// Side results of computing a reference that go to the cache's json only
// (not into Reference); NaN / "" when not computed, as for an analytic case.
struct ReferenceRunInfo {
  std::string check_status;
  double check_t_reached = std::numeric_limits<double>::quiet_NaN();
  double check_wall = std::numeric_limits<double>::quiet_NaN();
  double mu_min_wall = std::numeric_limits<double>::quiet_NaN();
  ReferenceRetryLog retries;  // the ladder's attempts (none if analytic)
  int check_rescues = 0;      // intervals the check's ladder rescued
};

// Fills *ref from the cache files if they hold this key; true on a complete
// hit. On a miss *ref may keep fields read before the miss was detected; the
// compute path overwrites what it sets, as it always has.
bool LoadCachedReference(const std::string& csv_path,
                         const std::string& json_path, const Scene& scene,
                         const TerrainSpec& terrain, AnalyticCase ac,
                         Reference* ref) {
  std::string json_text, csv;
  if (!ReadTextFile(json_path, &json_text)) return false;
  JsonValue json;
  try {
    json = ParseJson(json_text, json_path);
  } catch (const JsonError&) {
    return false;  // corrupt cache: recompute
  }
  // The key (not just the hash) must match: a hash collision is a miss.
  if (StringMember(json, "key") != ref->key) return false;
  if (!ReadTextFile(csv_path, &csv)) return false;
  try {
    ref->samples = ParseTrajectoryCsv(csv);
    ref->kind = StringMember(json, "kind");
    ref->status = StringMember(json, "status");
    ref->stop_reason = StringMember(json, "stop_reason");
    ref->method = StringMember(json, "method");
    ref->check_method = StringMember(json, "check_method");
    ref->stop = StringMember(json, "reference_stop");
    bool has_mu = false, has_err = false, has_rescues = false;
    ref->mu_min_max = NumberMember(json, "ref_mu_min", &has_mu);
    ref->err_est = NumberMember(json, "ref_err_est", &has_err);
    bool present = false;  // absent or null: NaN, and so is the difference
    ref->check_t_diff = NumberMember(json, "t_reached", &present) -
                        NumberMember(json, "check_t_reached", &present);
    ref->rescues =
        static_cast<int>(NumberMember(json, "rescues", &has_rescues));
    if (ac != AnalyticCase::kNone) ref->analytic.emplace(scene, terrain, ac);
    // A cache written before these fields existed (or before the retry
    // ladder), or under older stop rules, is recomputed.
    bool has_rules = false;
    const double rules = NumberMember(json, "stop_rules", &has_rules);
    if (has_mu && has_err && has_rescues && !ref->stop.empty() && has_rules &&
        rules == kReferenceStopRules)
      return true;
    ref->samples.clear();
  } catch (const std::runtime_error&) {
    ref->samples.clear();  // corrupt cache: recompute
  }
  return false;
}

// The closed-form solution sampled on the reference output grid.
SimulationResult ComputeAnalyticReference(const Scene& scene,
                                          const TerrainSpec& terrain,
                                          const ReferenceSettings& settings,
                                          AnalyticCase ac, Reference* ref) {
  SimulationResult result;
  ref->analytic.emplace(scene, terrain, ac);
  ref->kind = std::string("analytic:") + ToString(ac);
  const double dt = scene.dt / settings.dt_divisor;
  const int n = static_cast<int>(std::llround(scene.t_end / dt));
  for (int k = 0; k <= n; ++k)
    result.samples.push_back(ref->analytic->Sample(k * dt));
  result.status = "success";
  result.t_reached = n * dt;
  ref->method = std::string("closed form (") + ToString(ac) + ")";
  return result;
}

// mu_min along the path (every 2nd scene-dt sample, refined around the
// maximum) and, for a reference that stopped, at the state where it stopped
// (in coupled mode a stage state between samples), so that a reference
// stopped by friction has ref_mu_min >= mu.
double ReferenceMinimumFriction(const Scene& scene,
                                const ReferenceSettings& settings,
                                const SimulationResult& result) {
  double mu_min_max =
      PathMinimumFriction(scene, result.samples, 2 * settings.dt_divisor);
  if (!result.success() && result.stop_configuration.allFinite()) {
    std::vector<TrajectorySample> stop(1);
    stop[0].theta = result.stop_configuration;
    mu_min_max = std::fmax(mu_min_max, PathMinimumFriction(scene, stop));
  }
  return mu_min_max;
}

// The check reference: another method family on the same output grid; the
// estimate is their largest position difference over common times. A failed
// check leaves err_est NaN and records why in info->check_status.
void RunCheckReference(const Scene& scene, const ReferenceSettings& settings,
                       const std::string& method,
                       const SimulationResult& result, Reference* ref,
                       ReferenceRunInfo* info) {
  const SimulationOptions co = CheckReferenceOptions(scene, settings, method);
  ref->check_method = DescribeReferenceMethod(co);
  try {
    // The check runs the same retry ladder, so that a rescued stretch of the
    // reference is checked too.
    ReferenceRetryLog check_log;
    const SimulationResult check =
        RunReferenceWithRetries(scene, co, &check_log);
    info->check_rescues = check_log.rescues;
    info->check_status = check.status;
    info->check_t_reached = check.t_reached;
    ref->check_t_diff = result.t_reached - check.t_reached;
    info->check_wall = check.wall_seconds;
    ref->err_est =
        CompareTrajectories(result.samples, check.samples, false).pos_max;
  } catch (const std::exception& e) {
    info->check_status = std::string("error: ") + e.what();
  }
}

// Numerical reference plus its quality estimates (mu_min, check reference).
SimulationResult ComputeCheckedNumericalReference(
    const Scene& scene, const ReferenceSettings& settings, Reference* ref,
    ReferenceRunInfo* info) {
  std::string method;
  SimulationResult result =
      ComputeNumericalReference(scene, settings, &method, &info->retries);
  ref->kind = method == "rk4" ? "numerical" : "numerical:" + method;
  ref->method = DescribeReferenceMethod(
      NumericalReferenceOptions(scene, settings, method));
  const auto mu_start = std::chrono::steady_clock::now();
  ref->mu_min_max = ReferenceMinimumFriction(scene, settings, result);
  info->mu_min_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - mu_start)
          .count();
  RunCheckReference(scene, settings, method, result, ref, info);
  return result;
}

// The csv first, the json last: a json marks the pair complete, so an
// interrupted write is a cache miss rather than a truncated reference.
void WriteReferenceCache(const std::string& csv_path,
                         const std::string& json_path, const Reference& ref,
                         const SimulationResult& result,
                         const ReferenceRunInfo& info, const std::string& csv) {
  JsonWriter w;
  w.BeginObject();
  w.Key("hash").Value(ref.hash);
  w.Key("kind").Value(ref.kind);
  w.Key("scene").Value(ref.scene);
  w.Key("status").Value(ref.status);
  w.Key("stop_reason").Value(ref.stop_reason);
  w.Key("t_reached").Value(result.t_reached);
  w.Key("samples").Value(static_cast<int>(result.samples.size()));
  w.Key("wall_s").Value(result.wall_seconds);
  w.Key("method").Value(ref.method);
  w.Key("ref_mu_min").Value(ref.mu_min_max);
  w.Key("ref_mu_min_wall_s").Value(info.mu_min_wall);
  w.Key("ref_err_est").Value(ref.err_est);
  w.Key("check_method").Value(ref.check_method);
  w.Key("check_status").Value(info.check_status);
  w.Key("check_t_reached").Value(info.check_t_reached);
  w.Key("check_wall_s").Value(info.check_wall);
  w.Key("reference_stop").Value(ref.stop);
  w.Key("stop_rules").Value(kReferenceStopRules);
  w.Key("rescues").Value(ref.rescues);
  w.Key("check_rescues").Value(info.check_rescues);
  w.Key("retries").BeginArray();
  for (const ReferenceAttempt& a : info.retries.attempts) {
    w.BeginObject();
    w.Key("rung").Value(a.rung);
    w.Key("detail").Value(a.detail);
    w.Key("t_start").Value(a.t_start);
    w.Key("t_end").Value(a.t_end);
    w.Key("status").Value(a.status);
    w.Key("t_reached").Value(a.t_reached);
    w.EndObject();
  }
  w.EndArray();
  w.Key("key").Value(ref.key);
  w.EndObject();
  AtomicWriteFile(csv_path, csv);
  AtomicWriteFile(json_path, w.str() + "\n");  // written last: marks complete
}

}  // namespace

Reference LoadOrComputeReference(const std::string& dir, const Scene& scene,
                                 const TerrainSpec& terrain,
                                 const std::string& heightmap_digest,
                                 const ReferenceSettings& settings,
                                 const std::string& scene_label) {
  Reference ref;
  ref.scene = scene_label;
  ref.key = ReferenceKey(scene, terrain, heightmap_digest, settings);
  ref.hash = Hex64(Fnv1a64(ref.key));
  const AnalyticCase ac = settings.analytic ? DetectAnalyticCase(scene, terrain)
                                            : AnalyticCase::kNone;
  const std::string csv_path = dir + "/references/" + ref.hash + ".csv";
  const std::string json_path = dir + "/references/" + ref.hash + ".json";

  if (!dir.empty() &&
      LoadCachedReference(csv_path, json_path, scene, terrain, ac, &ref)) {
    return ref;
  }

  ReferenceRunInfo info;
  const SimulationResult result =
      ac != AnalyticCase::kNone
          ? ComputeAnalyticReference(scene, terrain, settings, ac, &ref)
          : ComputeCheckedNumericalReference(scene, settings, &ref, &info);
  ref.status = result.status;
  ref.stop_reason = result.stop_reason;
  ref.stop = ReferenceStopOf(result, scene);
  ref.rescues = info.retries.rescues;
  const std::string csv = TrajectoryCsv(result);
  // Always use the samples as stored (exact round trip), so that a cached
  // and a fresh reference give bit-identical metrics.
  ref.samples = ParseTrajectoryCsv(csv);
  if (!dir.empty()) {
    WriteReferenceCache(csv_path, json_path, ref, result, info, csv);
  }
  return ref;
}

}  // namespace quasiroll::bench
