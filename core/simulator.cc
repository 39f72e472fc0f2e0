#include "core/simulator.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/initial_configuration.h"

namespace quasiroll {

const char* ToString(Coupling coupling) {
  return coupling == Coupling::kZoh ? "zoh" : "coupled";
}

Coupling CouplingFromString(const std::string& name) {
  if (name == "zoh") return Coupling::kZoh;
  if (name == "coupled") return Coupling::kCoupled;
  throw std::invalid_argument("coupling: must be 'zoh' or 'coupled', got '" +
                              name + "'");
}

bool SimulationOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!std::isfinite(dt) || dt < 0)
    return fail("dt: must be finite and >= 0 (0 = scene's), got " + std::to_string(dt));
  if (!std::isfinite(t_end) || t_end < 0)
    return fail("t_end: must be finite and >= 0 (0 = scene's), got " +
                std::to_string(t_end));
  if (second_contact_check_every < 0)
    return fail("second_contact_check_every: must be >= 0");
  std::string inner;
  if (!integrator.IsValid(&inner)) return fail("integrator." + inner);
  if (!quasi_static.IsValid(&inner)) return fail("quasi_static." + inner);
  return true;
}

// The robot as a constrained ODE: Theta' = F(Theta, w) with w held (zoh) or
// re-solved at every evaluation (coupled); H and J from the kinematic model.
class Simulator::RobotOde final : public ConstrainedOde {
 public:
  RobotOde(const KinematicModel& model, Coupling coupling,
           QuasiStaticSolver* solver)
      : model_(model), coupling_(coupling), solver_(solver),
        weights_(model.CorrectionWeights()) {}

  void Hold(const Vec12& w) { w_ = w; }
  const QuasiStaticSolution& last_solution() const { return sol_; }
  bool nlp_failed() const { return nlp_failed_; }
  int nlp_solves() const { return nlp_solves_; }
  long long nlp_iterations() const { return nlp_iterations_; }

  int state_size() const override { return kConfigSize; }
  int num_constraints() const override { return kNumConstraints; }

  bool Rhs(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    const Configuration q = y;
    if (!q.allFinite()) return false;
    Vec12 w = w_;
    if (coupling_ == Coupling::kCoupled) {
      solver_->Solve(q, &sol_);
      nlp_solves_ += sol_.nlp_solves;
      nlp_iterations_ += sol_.nlp_iterations;
      if (sol_.status != QuasiStaticStatus::kOk) {
        nlp_failed_ = true;
        return false;
      }
      w = solver_->problem().JointSpaceVelocity(sol_.z);
    }
    Configuration qd;
    if (!model_.Rhs(q, w, &qd)) return false;
    ydot = qd;
    return true;
  }

  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    LoopClosure hh;
    model_.Constraints(y, &hh);
    h = hh;
  }

  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    LoopClosureJacobian j;
    model_.ConstraintJacobian(y, &j);
    jac = j;
  }

  void CorrectionWeights(Eigen::Ref<Eigen::VectorXd> d) const override {
    d = weights_;
  }

 private:
  const KinematicModel& model_;
  Coupling coupling_;
  QuasiStaticSolver* solver_;
  Configuration weights_;
  Vec12 w_ = Vec12::Zero();
  QuasiStaticSolution sol_;
  bool nlp_failed_ = false;
  int nlp_solves_ = 0;
  long long nlp_iterations_ = 0;
};

double GeometricGap(const KinematicModel& model, const Configuration& theta) {
  Mat3 R;
  Vec3 p;
  model.PlatformPose(theta, &R, &p);
  const RobotGeometry& geo = model.geometry();
  const Terrain& terrain = model.terrain();
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) {
    Mat3 R_PW;
    Vec3 p_PW;
    std::array<Vec3, 2> axes, points;
    const int j = ConfigIndex::kTheta + 2 * i;
    model.Mount(i, theta(j), theta(j + 1), &R_PW, &p_PW, &axes, &points);
    const Mat3 R_GW = R * R_PW;
    const Vec3 p_W = p + R * p_PW;
    // Vertical clearance of the torus point (u, v) above the terrain.
    auto clearance = [&](double u, double v) {
      const double rr = geo.major_radius + geo.tube_radius * std::cos(v);
      const Vec3 pt = p_W + R_GW * Vec3(rr * std::cos(u), rr * std::sin(u),
                                        geo.tube_radius * std::sin(v));
      return pt.z() - terrain.Height(pt.x(), pt.y());
    };
    // Newton on the clearance over (u, v), finite-difference derivatives,
    // from the contact coordinates of chain i (the minimum is near them).
    double u = theta(ConfigIndex::U(i));
    double v = theta(ConfigIndex::V(i));
    const double h = 1e-4;
    double g0 = clearance(u, v);
    for (int it = 0; it < 8; ++it) {
      const double gu_p = clearance(u + h, v), gu_m = clearance(u - h, v);
      const double gv_p = clearance(u, v + h), gv_m = clearance(u, v - h);
      const double guv = (clearance(u + h, v + h) - clearance(u + h, v - h) -
                          clearance(u - h, v + h) + clearance(u - h, v - h)) /
                         (4 * h * h);
      const Vec2 grad((gu_p - gu_m) / (2 * h), (gv_p - gv_m) / (2 * h));
      Mat2 hess;
      hess << (gu_p - 2 * g0 + gu_m) / (h * h), guv, guv,
          (gv_p - 2 * g0 + gv_m) / (h * h);
      Vec2 step = -hess.ldlt().solve(grad);
      if (!step.allFinite() || hess.determinant() <= 0) step = -grad * 1e-2;
      const double g1 = clearance(u + step(0), v + step(1));
      if (!(g1 < g0)) break;
      u += step(0);
      v += step(1);
      g0 = g1;
      if (step.norm() < 1e-12) break;
    }
    worst = std::max(worst, std::abs(g0));
  }
  return worst;
}

Simulator::Simulator(const Scene& scene, const SimulationOptions& options)
    : scene_(scene), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument(why);
  if (!NlpSolverRegistry::Has(options_.nlp))
    NlpSolverRegistry::Create(options_.nlp);  // throws, naming known names
  if (!IntegratorRegistry::Has(options_.dae))
    IntegratorRegistry::Create(options_.dae);
  dt_ = options_.dt > 0 ? options_.dt : scene_.dt;
  t_end_ = options_.t_end > 0 ? options_.t_end : scene_.t_end;
  if (dt_ > t_end_)
    throw std::invalid_argument("dt: must be <= t_end (" +
                                std::to_string(t_end_) + "), got " +
                                std::to_string(dt_));
  QuasiStaticParameters params = QuasiStaticParameters::FromScene(scene_);
  if (!params.IsValid(&why)) throw std::invalid_argument(why);
  model_ = std::make_unique<KinematicModel>(scene_.geometry, scene_.terrain);
  theta0_ = SolveInitialConfiguration(*model_, scene_);
}

Simulator::~Simulator() = default;

void Simulator::Record(double t, const Configuration& theta,
                       const QuasiStaticSolution& sol,
                       SimulationResult* result, int index) const {
  TrajectorySample s;
  s.t = t;
  s.theta = theta;
  Mat3 R;
  model_->PlatformPose(theta, &R, &s.position);
  s.rpy = RpyFromRotation(R);
  const bool ok = sol.status == QuasiStaticStatus::kOk;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.velocity = ok ? Vec3(R * sol.twist.head<3>()) : Vec3::Constant(nan);
  s.angular_velocity = ok ? Vec3(R * sol.twist.tail<3>()) : Vec3::Constant(nan);
  for (int j = 0; j < 6; ++j) s.joints[j] = theta(ConfigIndex::kTheta + j);
  for (int i = 0; i < 3; ++i) {
    ContactSample& c = s.contacts[i];
    const ContactOutput& o = sol.contacts[i];
    c.point = Vec3(theta(ConfigIndex::Xg(i)), theta(ConfigIndex::Yg(i)),
                   model_->terrain().Height(theta(ConfigIndex::Xg(i)),
                                            theta(ConfigIndex::Yg(i))));
    c.normal_force = ok ? o.normal_force : nan;
    c.traction_lon = ok ? o.traction(0) : nan;
    c.traction_lat = ok ? o.traction(1) : nan;
    c.slip = ok ? o.slip.norm() : nan;
    c.friction_use = ok ? o.friction_use : nan;
  }
  LoopClosure h;
  model_->Constraints(theta, &h);
  s.drift = h.lpNorm<Eigen::Infinity>();
  s.gap_max = GeometricGap(*model_, theta);
  s.nlp_status = ToString(sol.status);
  s.nlp_iterations = sol.nlp_iterations;
  (void)index;
  result->samples.push_back(std::move(s));
}

SimulationResult Simulator::Run(const Configuration& theta0) {
  const auto start = std::chrono::steady_clock::now();
  SimulationResult result;
  QuasiStaticSolver solver(*model_, QuasiStaticParameters::FromScene(scene_),
                           NlpSolverRegistry::Create(options_.nlp),
                           options_.quasi_static);
  std::unique_ptr<Integrator> integrator =
      IntegratorRegistry::Create(options_.dae);
  RobotOde ode(*model_, options_.coupling, &solver);
  IntegratorOptions iopts = options_.integrator;
  if (iopts.step <= 0) iopts.step = dt_;

  const int n = static_cast<int>(std::llround(t_end_ / dt_));
  result.samples.reserve(n + 1);
  Configuration theta = theta0;
  Eigen::VectorXd y(kConfigSize);
  IntegratorResult ires;
  QuasiStaticSolution sol;
  for (int k = 0; k <= n; ++k) {
    const double t = k * dt_;
    solver.Solve(theta, &sol);
    result.nlp_solves += sol.nlp_solves;
    result.nlp_iterations += sol.nlp_iterations;
    if (options_.second_contact_check_every > 0 &&
        k % options_.second_contact_check_every == 0 &&
        sol.status == QuasiStaticStatus::kOk) {
      const ValidityReport v = CheckValidity(*model_, theta, true);
      if (!v.ok()) {
        sol.status = QuasiStaticStatus::kDegenerateContact;
        sol.message = v.Describe();
      }
    }
    Record(t, theta, sol, &result, k);
    result.t_reached = t;
    if (sol.status != QuasiStaticStatus::kOk) {
      result.status = ToString(sol.status);
      result.mu_min_at_stop = sol.mu_min;
      result.critical_contact =
          sol.critical_contact >= 0 ? sol.critical_contact + 1 : -1;
      std::ostringstream os;
      os << "t=" << t << " s: " << ToString(sol.status) << " (mu=" << scene_.mu
         << ", mu_min=" << sol.mu_min;
      if (result.critical_contact > 0) os << ", wheel " << result.critical_contact;
      os << "): " << sol.message;
      result.stop_reason = os.str();
      break;
    }
    if (k == n) {
      result.status = "success";
      break;
    }
    ode.Hold(solver.problem().JointSpaceVelocity(sol.z));
    y = theta;
    const IntegratorStatus st =
        integrator->Integrate(ode, t, t + dt_, y, iopts, &ires);
    if (st != IntegratorStatus::kSuccess) {
      result.t_reached = ires.t_reached;
      if (ode.nlp_failed()) {
        const QuasiStaticSolution& f = ode.last_solution();
        result.status = ToString(f.status);
        result.mu_min_at_stop = f.mu_min;
        result.critical_contact =
            f.critical_contact >= 0 ? f.critical_contact + 1 : -1;
        result.stop_reason = "t~" + std::to_string(ires.t_reached) + " s: " +
                             ToString(f.status) + " inside the integrator: " +
                             f.message;
      } else {
        result.status = ToString(st);
        result.stop_reason = "t=" + std::to_string(ires.t_reached) + " s: " +
                             options_.dae + ": " + ToString(st) + ": " +
                             ires.message;
      }
      break;
    }
    theta = y;
  }
  result.nlp_solves += ode.nlp_solves();
  result.nlp_iterations += ode.nlp_iterations();
  result.rhs_evaluations = ires.rhs_evaluations;
  result.jacobian_evaluations = ires.jacobian_evaluations;
  result.steps = ires.steps;
  result.rejected_steps = ires.rejected_steps;
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return result;
}

}  // namespace quasiroll
