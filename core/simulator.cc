#include "quasiroll/core/simulator.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/slip_regimes.h"

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
    return fail("dt: must be finite and >= 0 (0 = scene's), got " +
                std::to_string(dt));
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
      : model_(model),
        coupling_(coupling),
        solver_(solver),
        weights_(model.CorrectionWeights()) {}

  void Hold(const Vec12& w) { w_ = w; }
  void ClearFailure() { nlp_failed_ = false; }
  const QuasiStaticSolution& last_solution() const { return sol_; }
  bool nlp_failed() const { return nlp_failed_; }
  int nlp_solves() const { return nlp_solves_; }
  // Max KKT residual of the accepted solves since ResetKkt() (NaN: none).
  double kkt_residual() const { return kkt_residual_; }
  void ResetKkt() { kkt_residual_ = std::numeric_limits<double>::quiet_NaN(); }
  long long nlp_iterations() const { return nlp_iterations_; }
  long long nlp_iterations_native() const { return nlp_iterations_native_; }

  int state_size() const override { return kConfigSize; }
  int num_constraints() const override { return kNumConstraints; }

  bool Rhs(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    // nlp_failed_ describes the latest call only: an implicit integrator may
    // recover from a failed solve at a trial point (see core/dae.h).
    nlp_failed_ = false;
    const Configuration q = y;
    if (!q.allFinite()) return false;
    Vec12 w = w_;
    if (coupling_ == Coupling::kCoupled) {
      solver_->Solve(q, &sol_);
      nlp_solves_ += sol_.nlp_solves;
      nlp_iterations_ += sol_.nlp_iterations;
      nlp_iterations_native_ += sol_.nlp_iterations_native;
      if (sol_.status != QuasiStaticStatus::kOk) {
        nlp_failed_ = true;
        return false;
      }
      kkt_residual_ = std::fmax(kkt_residual_, sol_.kkt_residual);
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
  long long nlp_iterations_native_ = 0;
  double kkt_residual_ = std::numeric_limits<double>::quiet_NaN();
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
    // Vertical clearance g(u, v) = z - h(x, y) of the torus point (u, v),
    // with its exact gradient and Hessian (torus derivatives and the terrain
    // jet); Newton from the contact coordinates of chain i, where the
    // minimum is.
    const double R0 = geo.major_radius, r0 = geo.tube_radius;
    auto clearance = [&](double u, double v, Vec2* grad, Mat2* hess) {
      const double su = std::sin(u), cu = std::cos(u), sv = std::sin(v),
                   cv = std::cos(v), rr = R0 + r0 * cv;
      const Vec3 pt = p_W + R_GW * Vec3(rr * cu, rr * su, r0 * sv);
      const TerrainJet jet = terrain.Evaluate(pt.x(), pt.y());
      if (grad) {
        const Vec3 pu = R_GW * Vec3(-rr * su, rr * cu, 0);
        const Vec3 pv = R_GW * Vec3(-r0 * sv * cu, -r0 * sv * su, r0 * cv);
        const Vec3 puu = R_GW * Vec3(-rr * cu, -rr * su, 0);
        const Vec3 puv = R_GW * Vec3(r0 * sv * su, -r0 * sv * cu, 0);
        const Vec3 pvv = R_GW * Vec3(-r0 * cv * cu, -r0 * cv * su, -r0 * sv);
        const Vec3 up(-jet.hx, -jet.hy, 1.0);  // d g / d point
        Mat2 hh;
        hh << jet.hxx, jet.hxy, jet.hxy, jet.hyy;
        *grad = Vec2(pu.dot(up), pv.dot(up));
        const Vec2 a = pu.head<2>(), b = pv.head<2>();
        *hess << puu.dot(up) - a.dot(hh * a), puv.dot(up) - a.dot(hh * b),
            puv.dot(up) - a.dot(hh * b), pvv.dot(up) - b.dot(hh * b);
      }
      return pt.z() - jet.h;
    };
    double u = theta(ConfigIndex::U(i));
    double v = theta(ConfigIndex::V(i));
    Vec2 grad;
    Mat2 hess;
    double g0 = clearance(u, v, &grad, &hess);
    for (int it = 0; it < 10 && grad.norm() > 1e-15; ++it) {
      Vec2 step = -hess.ldlt().solve(grad);
      if (!step.allFinite() || !(hess(0, 0) > 0 && hess.determinant() > 0))
        step = -1e-2 * grad;
      Vec2 grad1;
      Mat2 hess1;
      bool accepted = false;
      for (double alpha = 1.0; alpha > 1e-9; alpha *= 0.5) {
        const double g1 =
            clearance(u + alpha * step(0), v + alpha * step(1), &grad1, &hess1);
        if (g1 <= g0) {
          u += alpha * step(0);
          v += alpha * step(1);
          g0 = g1;
          grad = grad1;
          hess = hess1;
          accepted = alpha * step.norm() >= 1e-13;
          break;
        }
      }
      if (!accepted) break;
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
  // Creates the backends now, so that bad backend options are reported here
  // (std::invalid_argument) rather than at the first step.
  session_ = std::make_unique<Session>(*this);
}

Simulator::~Simulator() = default;

void Simulator::Record(double t, const Configuration& theta,
                       const QuasiStaticSolution& sol, SimulationResult* result,
                       int index) const {
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
    ChainState chain;
    model_->EvaluateChain(theta, i, &chain);  // cached by the solve at theta
    c.point = chain.p_c;
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
  if (index > 0 && !result->samples.empty())
    AccumulateSlipDistances(result->samples.back(), scene_.epsilon, &s);
  result->samples.push_back(std::move(s));
}

namespace {
// Zoh solves follow the path at regular steps: extrapolated warm starts.
QuasiStaticOptions SolverOptions(const SimulationOptions& options) {
  QuasiStaticOptions qs = options.quasi_static;
  qs.extrapolate_warm_start = options.coupling == Coupling::kZoh;
  return qs;
}

// The backends, configured with the given backend options; *used receives
// the options in effect.
std::unique_ptr<NlpSolver> CreateNlp(const SimulationOptions& options,
                                     OptionValues* used) {
  std::unique_ptr<NlpSolver> nlp = NlpSolverRegistry::Create(options.nlp);
  nlp->SetBackendOptions(options.nlp_options);
  *used = nlp->backend_options();
  return nlp;
}
std::unique_ptr<Integrator> CreateIntegrator(const SimulationOptions& options,
                                             OptionValues* used) {
  std::unique_ptr<Integrator> integrator =
      IntegratorRegistry::Create(options.dae);
  integrator->SetBackendOptions(options.dae_options);
  *used = integrator->backend_options();
  return integrator;
}
}  // namespace

struct Simulator::Session {
  Session(const Simulator& sim)
      : solver(*sim.model_, QuasiStaticParameters::FromScene(sim.scene_),
               CreateNlp(sim.options_, &nlp_options),
               SolverOptions(sim.options_)),
        integrator(CreateIntegrator(sim.options_, &dae_options)),
        ode(*sim.model_, sim.options_.coupling, &solver),
        y(kConfigSize) {
    iopts = sim.options_.integrator;
    if (iopts.step <= 0) iopts.step = sim.dt_;
  }
  // Declared before the backends, which fill them while being created.
  OptionValues nlp_options, dae_options;
  QuasiStaticSolver solver;
  std::unique_ptr<Integrator> integrator;
  RobotOde ode;
  IntegratorOptions iopts;
  Eigen::VectorXd y;
  IntegratorResult ires;
  QuasiStaticSolution sol;
  Configuration theta;
  int k = 0, n = 0;
  int ode_solves_seen = 0;
  long long ode_iterations_seen = 0;
  long long ode_native_iterations_seen = 0;
  bool done = true;
};

SimulationResult Simulator::Run(const Configuration& theta0) {
  SimulationResult result;
  Begin(theta0, &result);
  while (Advance(&result)) {
  }
  return result;
}

const OptionValues& Simulator::nlp_options_used() const {
  return session_->nlp_options;
}
const OptionValues& Simulator::dae_options_used() const {
  return session_->dae_options;
}

void Simulator::Begin(const Configuration& theta0, SimulationResult* result) {
  const auto start = std::chrono::steady_clock::now();
  if (!session_) session_ = std::make_unique<Session>(*this);
  Session& s = *session_;
  s.solver.Reset();
  s.ode.ClearFailure();
  s.ires = IntegratorResult{};
  s.theta = theta0;
  s.k = 0;
  // Output times t_k = k dt, k < n, and t_n = t_end (the last interval is
  // shorter when dt does not divide t_end; 1e-9 absorbs round-off in t/dt).
  s.n = static_cast<int>(std::ceil(t_end_ / dt_ - 1e-9));
  s.ode_solves_seen = s.ode.nlp_solves();
  s.ode_iterations_seen = s.ode.nlp_iterations();
  s.ode_native_iterations_seen = s.ode.nlp_iterations_native();
  s.ode.ResetKkt();
  s.done = false;
  *result = SimulationResult{};
  result->nlp_options = s.nlp_options;
  result->dae_options = s.dae_options;
  result->samples.reserve(s.n + 1);
  result->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
}

bool Simulator::Advance(SimulationResult* result) {
  if (!session_ || session_->done) return false;
  const auto start = std::chrono::steady_clock::now();
  Session& s = *session_;
  const bool more = Interval(result);
  // Counters cover everything since Begin().
  result->nlp_solves += s.ode.nlp_solves() - s.ode_solves_seen;
  result->nlp_iterations += s.ode.nlp_iterations() - s.ode_iterations_seen;
  result->nlp_iterations_native +=
      s.ode.nlp_iterations_native() - s.ode_native_iterations_seen;
  s.ode_native_iterations_seen = s.ode.nlp_iterations_native();
  s.ode_solves_seen = s.ode.nlp_solves();
  s.ode_iterations_seen = s.ode.nlp_iterations();
  result->kkt_residual = std::fmax(result->kkt_residual, s.ode.kkt_residual());
  result->rhs_evaluations = s.ires.rhs_evaluations;
  result->jacobian_evaluations = s.ires.jacobian_evaluations;
  result->steps = s.ires.steps;
  result->rejected_steps = s.ires.rejected_steps;
  result->wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  s.done = !more;
  return more;
}

bool Simulator::Interval(SimulationResult* result) {
  Session& s = *session_;
  const int k = s.k;
  const double t = k == s.n ? t_end_ : k * dt_;
  const double t_next = k + 1 == s.n ? t_end_ : (k + 1) * dt_;
  s.solver.Solve(s.theta, &s.sol);
  QuasiStaticSolution& sol = s.sol;
  result->nlp_solves += sol.nlp_solves;
  result->nlp_iterations += sol.nlp_iterations;
  result->nlp_iterations_native += sol.nlp_iterations_native;
  if (options_.second_contact_check_every > 0 &&
      k % options_.second_contact_check_every == 0 &&
      sol.status == QuasiStaticStatus::kOk) {
    const ValidityReport v = CheckValidity(*model_, s.theta, true);
    if (!v.ok()) {
      sol.status = QuasiStaticStatus::kDegenerateContact;
      sol.message = v.Describe();
    }
  }
  Record(t, s.theta, sol, result, k);
  result->t_reached = t;
  if (sol.status == QuasiStaticStatus::kOk)
    result->kkt_residual = std::fmax(result->kkt_residual, sol.kkt_residual);
  if (sol.status != QuasiStaticStatus::kOk) {
    result->status = ToString(sol.status);
    result->stop_configuration = s.theta;
    result->mu_min_at_stop = sol.mu_min;
    result->critical_contact =
        sol.critical_contact >= 0 ? sol.critical_contact + 1 : -1;
    std::ostringstream os;
    os << "t=" << t << " s: " << ToString(sol.status) << " (mu=" << scene_.mu
       << ", mu_min=" << sol.mu_min;
    if (result->critical_contact > 0)
      os << ", wheel " << result->critical_contact;
    os << "): " << sol.message;
    result->stop_reason = os.str();
    return false;
  }
  if (k == s.n) {
    result->status = "success";
    return false;
  }
  s.ode.Hold(s.solver.problem().JointSpaceVelocity(sol.z));
  s.y = s.theta;
  const IntegratorStatus st =
      s.integrator->Integrate(s.ode, t, t_next, s.y, s.iopts, &s.ires);
  if (st != IntegratorStatus::kSuccess) {
    result->t_reached = s.ires.t_reached;
    if (s.ode.nlp_failed()) {
      const QuasiStaticSolution& f = s.ode.last_solution();
      result->status = ToString(f.status);
      result->stop_configuration = s.solver.problem().configuration();
      result->mu_min_at_stop = f.mu_min;
      result->critical_contact =
          f.critical_contact >= 0 ? f.critical_contact + 1 : -1;
      result->stop_reason = "t~" + std::to_string(s.ires.t_reached) +
                            " s: " + ToString(f.status) +
                            " inside the integrator: " + f.message;
    } else {
      result->status = ToString(st);
      result->stop_configuration = s.y;
      result->stop_reason = "t=" + std::to_string(s.ires.t_reached) +
                            " s: " + options_.dae + ": " + ToString(st) + ": " +
                            s.ires.message;
    }
    return false;
  }
  s.theta = s.y;
  s.k = k + 1;
  return true;
}

}  // namespace quasiroll
