#include "quasiroll/core/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/checkpoints.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/loop_closure_ode.h"
#include "quasiroll/core/sensitivity.h"
#include "quasiroll/core/slip_regimes.h"
#include "quasiroll/core/solution_jumps.h"

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
  if (event_points < 0 || event_points > 1000)
    return fail("event_points: must be in [0, 1000], got " +
                std::to_string(event_points));
  if (!(event_tolerance > 0) || !std::isfinite(event_tolerance))
    return fail("event_tolerance: must be finite and > 0, got " +
                std::to_string(event_tolerance));
  for (std::size_t i = 0; i < checkpoints.size(); ++i)
    if (!std::isfinite(checkpoints[i]) || checkpoints[i] < 0 ||
        (i > 0 && checkpoints[i] < checkpoints[i - 1]))
      return fail("checkpoints: must be finite, >= 0 and ascending");
  if (!(switch_step_tolerance > 0))
    return fail("switch_step_tolerance: must be > 0, got " +
                std::to_string(switch_step_tolerance));
  if (probe_stall_iterations < 0)
    return fail("probe_stall_iterations: must be >= 0, got " +
                std::to_string(probe_stall_iterations));
  if (zoh_stall_iterations < 0)
    return fail("zoh_stall_iterations: must be >= 0, got " +
                std::to_string(zoh_stall_iterations));
  std::string inner;
  if (!integrator.IsValid(&inner)) return fail("integrator." + inner);
  if (!quasi_static.IsValid(&inner)) return fail("quasi_static." + inner);
  return true;
}

// The robot as a constrained ODE: Theta' = F(Theta, w) with w held (zoh) or
// re-solved at every evaluation (coupled); H and J from the kinematic model.
class Simulator::RobotOde final : public LoopClosureOde {
 public:
  RobotOde(const KinematicModel& model, Coupling coupling,
           QuasiStaticSolver* solver)
      : LoopClosureOde(model), coupling_(coupling), solver_(solver) {}

  void Hold(const Vec12& w) {
    w_ = w;
    have_first_ = false;
  }
  // zoh: F(q) with the held twist if it is the first right-hand side since
  // Hold() (an RK method's first stage at the interval's start), bitwise;
  // else false.
  bool FirstHeldRhs(const Configuration& q, Configuration* f) const {
    if (!have_first_ ||
        std::memcmp(q.data(), first_q_.data(), sizeof(double) * kConfigSize))
      return false;
    *f = first_f_;
    return true;
  }
  void ClearFailure() { nlp_failed_ = failed_in_call_ = false; }
  const QuasiStaticSolution& last_solution() const { return sol_; }
  bool nlp_failed() const { return nlp_failed_; }
  // A coupled solve that failed numerically (SOLVER_FAILURE: mu > mu_min
  // with regular statics, model.md §7.7) may succeed at a nearby trial
  // point; a physical failure (no quasi-static solution) would not.
  bool RhsFailureIsRecoverable() const override {
    return nlp_failed_ && sol_.status == QuasiStaticStatus::kSolverFailure;
  }
  // Every Integrate() call starts here: a call's failed solves are its own.
  void MakeConsistent(double /*t0*/,
                      Eigen::Ref<Eigen::VectorXd> /*y*/) override {
    failed_in_call_ = false;
  }
  // Whether an integrator call that ended with status st was stopped by a
  // failed quasi-static solve: the latest evaluation's, or, when the
  // integrator gave up on failing evaluations (kRhsFailure: e.g. IDA's
  // repeated recoverable residual errors, whose last trial may have
  // solved), any of the call's.
  bool SolveStopped(IntegratorStatus st) const {
    return nlp_failed_ ||
           (st == IntegratorStatus::kRhsFailure && failed_in_call_);
  }
  // The failed solve SolveStopped() refers to.
  const QuasiStaticSolution& stopping_solution() const {
    return nlp_failed_ ? sol_ : failed_sol_;
  }
  // That solve when SolveStopped(st) and it is a physical stop (not
  // SOLVER_FAILURE); else null.
  const QuasiStaticSolution* PhysicalStop(IntegratorStatus st) const {
    if (!SolveStopped(st) ||
        stopping_solution().status == QuasiStaticStatus::kSolverFailure)
      return nullptr;
    return &stopping_solution();
  }
  int nlp_solves() const { return nlp_solves_; }
  // Right-hand-side solves that needed a fallback or more Newton iterations
  // than a continuation step (coupled; a solution jump shows as one,
  // core/solution_jumps.h).
  int irregular_solves() const { return irregular_solves_; }
  void set_iteration_watch(int iterations) { iteration_watch_ = iterations; }
  // Max KKT residual of the accepted solves since ResetKkt() (NaN: none).
  double kkt_residual() const { return kkt_residual_; }
  void ResetKkt() { kkt_residual_ = std::numeric_limits<double>::quiet_NaN(); }
  long long nlp_iterations() const { return nlp_iterations_; }
  long long nlp_iterations_native() const { return nlp_iterations_native_; }

  // Whether coupled solves start from the past roots (model.md §7.5:
  // Newton backends; a least-squares or optimisation backend started on an
  // ended root can return the residual's minimum past the fold, below the
  // tolerance).
  void set_follow_past_roots(bool follow) { follow_past_ = follow; }
  // Forget the coupled right-hand sides' roots (a new run).
  void ForgetPastRoots() {
    past_roots_.Clear();
    have_last_ok_ = false;
  }
  // Coupled: the time and state of the latest right-hand side whose solve
  // converged (false before any).
  bool LastSolved(double* t, Configuration* q) const {
    if (!have_last_ok_) return false;
    *t = last_ok_t_;
    *q = last_ok_q_;
    return true;
  }
  // A root at time t for the coupled right-hand sides' warm starts.
  void RememberRoot(double t, const Eigen::VectorXd& z) {
    if (follow_past_) past_roots_.Remember(t, z);
  }

  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    // nlp_failed_ describes the latest call only: an implicit integrator may
    // recover from a failed solve at a trial point (see core/dae.h).
    nlp_failed_ = false;
    const Configuration q = y;
    if (!q.allFinite()) return false;
    Vec12 w = w_;
    if (coupling_ == Coupling::kCoupled) {
      const Eigen::VectorXd* z0 =
          follow_past_ ? past_roots_.StartFor(t) : nullptr;
      if (z0) solver_->SetWarmStart(*z0);
      Solve(q);
      if (sol_.nlp_solves > 1 || sol_.nlp_iterations > iteration_watch_)
        ++irregular_solves_;
      if (sol_.status != QuasiStaticStatus::kOk) {
        nlp_failed_ = failed_in_call_ = true;
        failed_sol_ = sol_;
        return false;
      }
      kkt_residual_ = std::fmax(kkt_residual_, sol_.kkt_residual);
      RememberRoot(t, sol_.z);
      last_ok_t_ = t;
      last_ok_q_ = q;
      have_last_ok_ = true;
      w = solver_->problem().JointSpaceVelocity(sol_.z);
    }
    Configuration qd;
    if (!model().Rhs(q, w, &qd)) return false;
    ydot = qd;
    if (coupling_ == Coupling::kZoh && !have_first_) {
      first_q_ = q;
      first_f_ = qd;
      have_first_ = true;
    }
    if (coupling_ == Coupling::kCoupled) {
      solved_q_ = q;
      have_solved_ = true;
    }
    return true;
  }

  // dF/dTheta (model.md §8.9). zoh: the held twist does not depend on the
  // state, dF/dTheta = dF/dTheta|_w (KinematicModel::RhsStateDerivative:
  // differences of the kinematics, no solve). coupled: F(Theta, w(Theta))
  // with w from the quasi-static solve, dF/dTheta = dF/dTheta|_w + dF/dw
  // dw/dTheta, dw/dTheta by the implicit function theorem
  // (SensitivityAnalyzer) at the solve at Theta (the last Rhs's when Theta
  // is its point, else one solve), dF/dw exact
  // (KinematicModel::RhsTwistDerivative). Returns false (the integrator
  // then differences Rhs for this Jacobian) where the derivative does not
  // exist or is one-sided (SINGULAR J_E, an inequality about to become
  // active) or F cannot be evaluated.
  bool RhsJacobian(double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::MatrixXd> dfdy) override {
    const Configuration q = y;
    if (!q.allFinite()) return Fallback();
    Vec12 w = w_;
    if (coupling_ == Coupling::kCoupled) {
      if (!have_solved_ || q != solved_q_ ||
          solver_->problem().configuration() != q ||
          sol_.status != QuasiStaticStatus::kOk) {
        have_solved_ = false;
        Solve(q);
        if (sol_.status != QuasiStaticStatus::kOk) return Fallback();
        kkt_residual_ = std::fmax(kkt_residual_, sol_.kkt_residual);
        solved_q_ = q;
        have_solved_ = true;
      }
      if (analyzer_.Compute(solver_->problem(), sol_.z, &sens_) !=
              SensitivityStatus::kOk ||
          sens_.one_sided)
        return Fallback();
      w = solver_->problem().JointSpaceVelocity(sol_.z);
    }
    if (!model().RhsStateDerivative(q, w, &dfdq_)) return Fallback();
    if (coupling_ == Coupling::kCoupled) {
      // The chain rule: dF/dTheta|_w + dF/dw dw/dTheta.
      if (!model().RhsTwistDerivative(q, &dfdw_)) return Fallback();
      constexpr int kState = SensitivityParameter::kState;
      constexpr int kNumState = SensitivityParameter::kNumState;
      dwdq_.topRows<6>() = sens_.twist.middleCols<kNumState>(kState);
      dwdq_.bottomRows<6>() = sens_.joint_rates.middleCols<kNumState>(kState);
      dfdq_.noalias() += dfdw_ * dwdq_;
    }
    dfdy = dfdq_;
    return true;
  }
  // RhsJacobian calls that returned false (the integrator differenced).
  int jacobian_fallbacks() const { return jacobian_fallbacks_; }
  // Rhs then RhsJacobian at theta, as an integrator calls them, into *out
  // (preallocated workspaces: no allocation once warmed up).
  void Probe(const Configuration& theta, RobotOdeProbe* out) {
    probe_y_ = theta;
    // No time: the solve starts from the last one, not from a past root.
    constexpr double kNoTime = std::numeric_limits<double>::quiet_NaN();
    out->rhs_ok = Rhs(kNoTime, probe_y_, probe_f_);
    if (out->rhs_ok) out->rhs = probe_f_;
    out->jacobian_ok = RhsJacobian(kNoTime, probe_y_, probe_jac_);
    if (out->jacobian_ok) out->jacobian = probe_jac_;
    out->jacobian_fallbacks = jacobian_fallbacks_;
  }

 private:
  bool Fallback() {
    ++jacobian_fallbacks_;
    return false;
  }
  // The quasi-static solve at q into sol_, counted.
  void Solve(const Configuration& q) {
    solver_->Solve(q, &sol_);
    nlp_solves_ += sol_.nlp_solves;
    nlp_iterations_ += sol_.nlp_iterations;
    nlp_iterations_native_ += sol_.nlp_iterations_native;
  }
  // Coupled right-hand sides start from the root at the latest earlier
  // time (model.md §7.5), not from the last evaluation.
  PastRoots past_roots_;
  bool follow_past_ = false;
  Coupling coupling_;
  QuasiStaticSolver* solver_;
  Vec12 w_ = Vec12::Zero();
  QuasiStaticSolution sol_;
  bool nlp_failed_ = false;
  // A solve failed in the current Integrate() call; the latest that did.
  bool failed_in_call_ = false;
  QuasiStaticSolution failed_sol_;
  int nlp_solves_ = 0;
  int irregular_solves_ = 0;
  int iteration_watch_ = kBranchStepIterations;
  long long nlp_iterations_ = 0;
  long long nlp_iterations_native_ = 0;
  double kkt_residual_ = std::numeric_limits<double>::quiet_NaN();
  // zoh: the first right-hand side since Hold() (FirstHeldRhs).
  Configuration first_q_ = Configuration::Zero(),
                first_f_ = Configuration::Zero();
  bool have_first_ = false;
  // RhsJacobian: the point of the last successful coupled solve, the
  // analyzer (cheap path: no multipliers' derivatives) and workspaces.
  Configuration solved_q_ = Configuration::Zero();
  bool have_solved_ = false;
  // LastSolved(): unlike solved_q_, which RhsJacobian clears before its own
  // solve, the latest success survives a failed solve, and has its time.
  double last_ok_t_ = 0;
  Configuration last_ok_q_ = Configuration::Zero();
  bool have_last_ok_ = false;
  SensitivityAnalyzer analyzer_{[] {
    SensitivityOptions o;
    o.multipliers = false;
    return o;
  }()};
  QuasiStaticSensitivities sens_;
  RhsStateJacobian dfdq_;
  RhsTwistJacobian dfdw_;
  Eigen::Matrix<double, 12, kConfigSize> dwdq_;
  int jacobian_fallbacks_ = 0;
  Eigen::VectorXd probe_y_ = Eigen::VectorXd::Zero(kConfigSize),
                  probe_f_ = Eigen::VectorXd::Zero(kConfigSize);
  Eigen::MatrixXd probe_jac_ = Eigen::MatrixXd::Zero(kConfigSize, kConfigSize);
};

double GeometricGap(const KinematicModel& model, const Configuration& theta,
                    double resolution) {
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
      const TerrainJet jet = terrain.EvaluateSecondOrder(pt.x(), pt.y());
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
      else if (-0.5 * grad.dot(step) <= resolution)
        break;
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
                       int index, const SlipIncrements* increments) const {
  TrajectorySample s;
  FillSample(*model_, t, theta, sol, &s);
  if (index > 0 && !result->samples.empty())
    AccumulateSlipDistances(result->samples.back(), scene_.epsilon, &s,
                            increments);
  result->samples.push_back(std::move(s));
}

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Residual tolerance of the switch-location probes (RestartAtSwitches).
constexpr double kLocationResidualTolerance = 1e-14;
// Sample roots looser than this are classified from a refined copy
// (ClassSlips): the default nlp_tol's roots (<= 1e-12) are read as they are.
constexpr double kClassSlipResidual = 1e-12;

// Zoh solves follow the path at regular steps: extrapolated warm starts,
// and a stall hands over to the fallbacks (zoh_stall_iterations).
QuasiStaticOptions SolverOptions(const SimulationOptions& options) {
  QuasiStaticOptions qs = options.quasi_static;
  if (options.coupling == Coupling::kZoh) {
    qs.extrapolate_warm_start = true;
    qs.stall_iterations = options.zoh_stall_iterations;
  }
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
// Adds a quasi-static solve's counters to the run's.
void AddSolveCounts(const QuasiStaticSolution& sol, SimulationResult* result) {
  result->nlp_solves += sol.nlp_solves;
  result->nlp_iterations += sol.nlp_iterations;
  result->nlp_iterations_native += sol.nlp_iterations_native;
}

// The solution-jump continuation's backend (core/solution_jumps.h): the one
// with BackendRole::kContinuation, a square-system Newton method; the run's
// options when the run uses it, else its defaults; null when none is
// registered.
std::unique_ptr<NlpSolver> ContinuationNlp(const SimulationOptions& options) {
  std::string name;
  for (const std::string& n : NlpSolverRegistry::Names())
    if (NlpSolverRegistry::Info(n).HasRole(BackendRole::kContinuation))
      name = n;
  if (name.empty()) return nullptr;
  std::unique_ptr<NlpSolver> nlp = NlpSolverRegistry::Create(name);
  if (!nlp->RequiresSquareSystem()) return nullptr;
  nlp->SetBackendOptions(name == options.nlp ? options.nlp_options
                                             : GivenOptions{});
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
        y(kConfigSize),
        y_event(kConfigSize),
        checkpoints(*sim.model_, sim.options_.coupling) {
    iopts = sim.options_.integrator;
    if (iopts.step <= 0) iopts.step = sim.dt_;
    newton_run = solver.nlp().RequiresSquareSystem();
    ode.set_follow_past_roots(newton_run);
    // Coupled checkpoints: a solver of their own (core/checkpoints.h).
    if (sim.options_.coupling == Coupling::kCoupled &&
        !sim.options_.checkpoints.empty()) {
      OptionValues unused;
      QuasiStaticOptions qs = SolverOptions(sim.options_);
      qs.extrapolate_warm_start = false;
      checkpoint_solver = std::make_unique<QuasiStaticSolver>(
          *sim.model_, QuasiStaticParameters::FromScene(sim.scene_),
          CreateNlp(sim.options_, &unused), qs);
    }
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
  // Located stops: the held twist and the state at the start of the last
  // integrated interval, the re-integration workspace, and a located stop
  // pending for the next Interval() (t_stop NaN: none).
  Vec12 w_held = Vec12::Zero();
  Configuration theta_prev = Configuration::Zero();
  double t_prev = 0;
  bool have_prev = false;
  Eigen::VectorXd y_event;
  QuasiStaticSolution sol_event, sol_b;
  LimitIndicators ind;
  double t_stop = kNaN, t_lower = kNaN, t_upper = kNaN;
  const char* pending_limit = "";
  bool done_located = false;  // LocateIntegratorStop recorded the stop
  // Where the last interval's resolved march stopped at a quasi-static
  // limit (t NaN: it did not); s.y holds the state there.
  ResolvedStop resolved_stop;
  // Relative-curvature margins at the last two samples (trend check).
  std::array<double, 3> curvature_now{kNaN, kNaN, kNaN},
      curvature_before{kNaN, kNaN, kNaN};
  int event_solves = 0;
  long long event_iterations = 0, event_iterations_native = 0;
  int pending_wheel = -1;
  CheckpointRecorder checkpoints;
  std::unique_ptr<QuasiStaticSolver> checkpoint_solver;
  double checkpoint_seconds_seen = 0;
  // Switches: a second solver for the probes of the location (created on
  // the first switch), so that locating leaves the run's warm starts alone.
  std::unique_ptr<QuasiStaticSolver> probe_solver;
  // Solution jumps (core/solution_jumps.h): the continuation's solver
  // (short local Newton solves; square-system backends only, else null),
  // its solution and last accepted root, the interval's jump brackets for
  // the slip quadrature, whether the run's backend is a Newton method (also
  // for the coupled warm starts, RobotOde::set_follow_past_roots), and
  // the irregular right-hand-side solves seen.
  std::unique_ptr<QuasiStaticSolver> branch_solver;
  QuasiStaticSolution branch_sol;
  Eigen::VectorXd branch_z;
  std::vector<std::array<double, 2>> slip_jumps;
  bool newton_run = false;
  int ode_irregular_seen = 0;
  // The interval's dense output (DenseState).
  struct Dense {
    Configuration th0 = Configuration::Zero(), th1 = Configuration::Zero(),
                  f0 = Configuration::Zero(), f1 = Configuration::Zero();
    double t0 = 0, h = 1;
    bool hermite = false;
  } dense;
  // The accepted solution at the previous sample (probe warm starts).
  Eigen::VectorXd z_prev;
  bool have_z_prev = false;
  // The converged probes of the current interval (RestartAtSwitches): the
  // warm starts' interpolation nodes, and by exact time their slips (the
  // slip quadrature's breaks are the located t_upper, already solved
  // there). The oldest is overwritten beyond capacity; sized with the probe
  // solver.
  struct KnownSolution {
    double t = kNaN;
    Eigen::VectorXd z;
    std::array<Eigen::Vector2d, 3> slip;
  };
  std::array<KnownSolution, 64> probe_known;
  int probe_known_count = 0;
  Eigen::VectorXd probe_warm;
  // Intervals starting before this time are integrated resolved.
  double resolve_until = -std::numeric_limits<double>::infinity();
  // The last interval was integrated resolved (step doubling).
  bool resolved_last = false;
  // SwitchStepTolerance(), set by Begin() (looking it up allocates).
  double switch_tolerance = std::numeric_limits<double>::infinity();
  // The slip vectors of the last sample (reversals).
  std::array<Eigen::Vector2d, 3> slip_prev;
  // The slips the class test reads at the last sample / at the one just
  // solved (ClassSlips): the sample's own unless its root is loose.
  std::array<Eigen::Vector2d, 3> class_prev, class_now;
  // class_prev's predecessor (the sample before the last): a creeping
  // wheel's turn that the grid splits over two intervals is located against
  // it (IsSplitReversal). A wheel's entry is zero, which no turn is measured
  // from, unless both samples were classified and the wheel had no event in
  // the interval between them.
  std::array<Eigen::Vector2d, 3> class_before{};
  bool class_prev_classified = false;
  // Bit i: wheel i + 1 had an event located in the current interval (its
  // turn is then not searched again against class_before).
  unsigned wheel_events = 0;
  // The slip integrals of the interval ending at slip_increments_t, split
  // at its located switches and sliding-level crossings
  // (RestartAtSwitches); NaN: none.
  SlipIncrements slip_increments;
  std::vector<double> slip_breaks;
  double slip_increments_t = std::numeric_limits<double>::quiet_NaN();
};

// A bisection bracket: the limit is not met at a, met at b (or the state at
// b could not be reached: have_b false).
struct Simulator::Bracket {
  double a = 0, b = 0;
  Configuration theta_a = Configuration::Zero(),
                theta_b = Configuration::Zero();
  bool have_b = false;
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

RobotOdeProbe Simulator::ProbeOde(const Configuration& theta,
                                  const Configuration& hold) {
  Session& s = *session_;
  RobotOdeProbe probe;
  const int solves = s.ode.nlp_solves();
  if (options_.coupling == Coupling::kZoh) {
    QuasiStaticSolution& sol = s.sol_event;
    s.solver.Solve(hold, &sol);
    probe.nlp_solves += sol.nlp_solves;
    if (sol.status != QuasiStaticStatus::kOk) return probe;
    s.ode.Hold(s.solver.problem().JointSpaceVelocity(sol.z));
  }
  s.ode.Probe(theta, &probe);
  probe.nlp_solves += s.ode.nlp_solves() - solves;
  probe.jacobian_fallbacks = s.ode.jacobian_fallbacks();
  return probe;
}

// The linear interpolation at tm between the nearest known solutions on
// either side among the interval's ends (s.t_prev, t_end) and the converged
// probes of RestartAtSwitches, in s.probe_warm.
const Eigen::VectorXd& Simulator::InterpolateKnown(double tm, double t_end) {
  Session& s = *session_;
  double ta = s.t_prev, tb = t_end;
  const Eigen::VectorXd *za = &s.z_prev, *zb = &s.sol.z;
  const int known = std::min<int>(s.probe_known_count, s.probe_known.size());
  for (int j = 0; j < known; ++j) {
    const Session::KnownSolution& k = s.probe_known[j];
    if (k.t <= tm && k.t > ta) ta = k.t, za = &k.z;
    if (k.t >= tm && k.t < tb) tb = k.t, zb = &k.z;
  }
  const double w = tb > ta ? (tm - ta) / (tb - ta) : 0.0;
  s.probe_warm = *za + w * (*zb - *za);
  return s.probe_warm;
}

// The solver of the switch probes (RestartAtSwitches): its own warm starts.
void Simulator::CreateProbeSolver() {
  OptionValues unused;
  QuasiStaticOptions probe_options = options_.quasi_static;
  probe_options.stall_iterations = options_.probe_stall_iterations;
  session_->probe_solver = std::make_unique<QuasiStaticSolver>(
      *model_, QuasiStaticParameters::FromScene(scene_),
      CreateNlp(options_, &unused), probe_options);
  // A continuation step is a local Newton solve whose iteration count
  // measures its contraction: the backend with the continuation role (the
  // run's own, with its options, when it is that one), whatever the run's.
  std::unique_ptr<NlpSolver> nlp = ContinuationNlp(options_);
  if (!nlp) return;
  QuasiStaticOptions branch_options = options_.quasi_static;
  branch_options.homotopy = false;
  branch_options.stall_iterations = 0;
  branch_options.max_iterations = kBranchStepIterations;
  branch_options.classify_failures = false;
  session_->branch_solver = std::make_unique<QuasiStaticSolver>(
      *model_, QuasiStaticParameters::FromScene(scene_), std::move(nlp),
      branch_options);
  session_->slip_jumps.reserve(4);
  // Iteration counts measure contraction only for a Newton method: other
  // backends' solves count as irregular on a fallback alone.
  session_->ode.set_iteration_watch(session_->newton_run
                                        ? kBranchStepIterations
                                        : std::numeric_limits<int>::max());
}

void Simulator::Begin(const Configuration& theta0, SimulationResult* result) {
  const auto start = std::chrono::steady_clock::now();
  if (!session_) session_ = std::make_unique<Session>(*this);
  Session& s = *session_;
  // Created here (and sized at the first sample), not at the first switch:
  // a warmed-up step does not allocate.
  if (options_.locate_switches && !s.probe_solver) CreateProbeSolver();
  s.solver.Reset();
  s.ode.ClearFailure();
  s.ode.ForgetPastRoots();
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
  s.have_prev = false;
  s.class_prev_classified = false;
  for (Eigen::Vector2d& r : s.class_before) r.setZero();
  s.t_stop = s.t_lower = s.t_upper = kNaN;
  s.pending_limit = "";
  s.pending_wheel = -1;
  s.curvature_now.fill(kNaN);
  s.curvature_before.fill(kNaN);
  s.done_located = false;
  s.resolve_until = -std::numeric_limits<double>::infinity();
  s.resolved_last = false;
  s.switch_tolerance = SwitchStepTolerance();
  s.done = false;
  s.checkpoint_seconds_seen = 0;
  *result = SimulationResult{};
  result->nlp_options = s.nlp_options;
  result->dae_options = s.dae_options;
  result->samples.reserve(s.n + 1);
  s.checkpoints.Begin(
      options_.checkpoints.empty() ? nullptr : &options_.checkpoints,
      s.checkpoint_solver.get(), &result->checkpoints);
  result->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
}

namespace {
// result->stop_retry from sol at (t, q); appends to *os the twist there and
// at the last sample before t with one.
void SetStopRetry(const KinematicModel& model, double t, const Configuration& q,
                  const QuasiStaticSolution& sol, SimulationResult* result,
                  std::ostringstream* os) {
  TrajectorySample sample;
  FillSample(model, t, q, sol, &sample);
  *os << "|v| = " << sample.velocity.norm()
      << " m/s, |w| = " << sample.angular_velocity.norm() << " rad/s";
  const std::vector<TrajectorySample>& samples = result->samples;
  for (auto it = samples.rbegin(); it != samples.rend(); ++it) {
    if (!(it->t < t) || !it->velocity.allFinite()) continue;
    *os << " (t = " << it->t << " s: " << it->velocity.norm() << " m/s, "
        << it->angular_velocity.norm() << " rad/s)";
    break;
  }
  result->stop_retry = std::move(sample);
}

}  // namespace

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
  result->step_drift_max = s.ires.step_drift_max;
  // Checkpoints are the harness's measurement, not the method's cost.
  const double checkpoint_seconds = s.checkpoints.seconds();
  result->checkpoint_solves = s.checkpoints.solves();
  result->checkpoint_iterations = s.checkpoints.iterations();
  result->wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count() -
      (checkpoint_seconds - s.checkpoint_seconds_seen);
  s.checkpoint_seconds_seen = checkpoint_seconds;
  s.done = !more;
  if (!more && result->status == ToString(QuasiStaticStatus::kSolverFailure))
    RetryStop(result);
  if (!more && !result->stop_retry && result->status != "success")
    ApproachStop(result);
  return more;
}

// The solver of the solves after the run (RetryStop, ApproachStop): the
// continuation backend (a square-system Newton method) when one is
// registered, else the run's, with the homotopy fallbacks of model.md §7.3.
std::unique_ptr<QuasiStaticSolver> Simulator::StopSolver() const {
  std::unique_ptr<NlpSolver> nlp = ContinuationNlp(options_);
  OptionValues unused;
  if (!nlp) nlp = CreateNlp(options_, &unused);
  return std::make_unique<QuasiStaticSolver>(
      *model_, QuasiStaticParameters::FromScene(scene_), std::move(nlp),
      options_.quasi_static);
}

// zoh, a run that stopped after its last sample's solve (a limit located
// inside the interval, or a sample whose solve gave up): the held twist
// hides the quasi-static twist on the way to the stop, and before a
// breakaway (model.md §8.8) it diverges there. Follows the root from the
// last sample's along the held path towards the stop (the located
// bracket's lower end, else the stop) by the continuation of solution
// jumps (FollowBranch, core/solution_jumps.h): each step reintegrated from
// the last sample and solved from the last accepted root (StopSolver), a
// step accepted only if no wheel's slip moved by more than
// kBranchStepSlipChange of the interval's change to the stop's root (a
// step that converges onto another root across a fold is not a follow;
// without a root at the stop any converged step is accepted). If the root
// ends (or the steps run out) before the last 1e-3 of the way (no
// quasi-static solution on the way to the stop: a breakaway's signature),
// the last root reached becomes result->stop_retry (not counted: after the
// run).
void Simulator::ApproachStop(SimulationResult* result) {
  Session& s = *session_;
  const double t_stop = std::isnan(s.t_lower) ? result->t_reached : s.t_lower;
  // The stop's own sample closes the interval that started at t_prev with
  // the held twist (an integrator failure inside an interval has none: its
  // held twist is not the one of the interval from t_prev).
  const bool stop_sampled =
      !result->samples.empty() && result->samples.back().t == result->t_reached;
  if (options_.coupling != Coupling::kZoh || !s.have_prev || !s.have_z_prev ||
      !stop_sampled || !(t_stop > s.t_prev) || !options_.locate_events)
    return;
  constexpr double kApproachResolution = 1e-3;
  struct Approach {
    std::unique_ptr<QuasiStaticSolver> solver;
    QuasiStaticSolution sol, root;
    Configuration q;
    double t = 0;
    double max_change = std::numeric_limits<double>::infinity();
    std::array<Eigen::Vector2d, 3> slip_now;
  } a;
  a.solver = StopSolver();
  a.q = s.theta_prev;
  a.t = s.t_prev;
  // The last sample's root (solved again by the stop solver from itself:
  // its slips, which the run no longer keeps).
  a.solver->SetWarmStart(s.z_prev);
  a.solver->Solve(s.theta_prev, &a.root);
  if (a.root.status != QuasiStaticStatus::kOk) return;
  for (int i = 0; i < 3; ++i) a.slip_now[i] = a.root.contacts[i].slip;
  if (s.sol.status == QuasiStaticStatus::kOk) {
    double change = 0;
    for (int i = 0; i < 3; ++i)
      change =
          std::max(change, (s.sol.contacts[i].slip - a.slip_now[i]).norm());
    if (std::isfinite(change))
      a.max_change = kBranchStepSlipChange * change +
                     kBranchSlipFloorOverEpsilon * scene_.epsilon;
  }
  const BranchStep step = [this, &a](double t) {
    Session& ss = *session_;
    if (Reintegrate(ss.t_prev, ss.theta_prev, t) != IntegratorStatus::kSuccess)
      return false;
    a.solver->SetWarmStart(a.root.z);
    a.solver->Solve(ss.y_event, &a.sol);
    if (a.sol.status != QuasiStaticStatus::kOk) return false;
    for (int i = 0; i < 3; ++i)
      if (!((a.sol.contacts[i].slip - a.slip_now[i]).norm() <= a.max_change))
        return false;
    for (int i = 0; i < 3; ++i) a.slip_now[i] = a.sol.contacts[i].slip;
    a.t = t;
    a.q = ss.y_event;
    std::swap(a.root, a.sol);
    return true;
  };
  const BranchEnd end =
      FollowBranch(s.t_prev, t_stop, options_.event_tolerance, step);
  // Followed to the stop, or lost within the last 1e-3 of the way: the
  // quasi-static solution exists up to the limit as far as this can tell,
  // and its twist there, which near a limit can change steeply but
  // boundedly (model.md §8.8), is left to the samples.
  if (end.outcome == BranchEnd::Outcome::kContinues || !(a.t > s.t_prev) ||
      t_stop - a.t <= options_.event_tolerance ||
      t_stop - a.t <= kApproachResolution * (t_stop - s.t_prev))
    return;
  std::ostringstream os;
  os << std::setprecision(9) << "; the root followed from the last sample's"
     << " along the held twist (" << a.solver->nlp().name() << ") "
     << (end.outcome == BranchEnd::Outcome::kEnds ? "ends" : "was followed")
     << " after t = " << a.t << " s"
     << (end.outcome == BranchEnd::Outcome::kEnds ? "" : " (steps used up)")
     << ": ";
  SetStopRetry(*model_, a.t, a.q, a.root, result, &os);
  result->stop_reason += os.str();
}

// A solve that gave up (SOLVER_FAILURE: mu > mu_min) may be a stall or the
// quasi-static breakaway (model.md §8.8): near it the path's twist grows
// without bound and the solves from the path's last root fail, but a cold
// start still finds the root (up to the breakaway itself, past which there
// is none). The stop's state is solved that way, by the continuation
// backend (a square-system Newton method) when one is registered, else the
// run's: the stop's sample's state, else the stage state whose solve
// failed, and if that has no root either, coupled, the latest right-hand
// side's state that solved (after the last sample). The first that
// converges is result->stop_retry; the stop reason says what they gave.
void Simulator::RetryStop(SimulationResult* result) {
  Session& s = *session_;
  const std::vector<TrajectorySample>& samples = result->samples;
  struct Candidate {
    double t;
    Configuration theta;
  };
  std::vector<Candidate> candidates;
  const double t_stop = result->t_reached;
  if (!samples.empty() && samples.back().t == t_stop)
    candidates.push_back({t_stop, samples.back().theta});
  else if (result->stop_configuration.allFinite())
    candidates.push_back({t_stop, result->stop_configuration});
  Candidate solved;
  if (options_.coupling == Coupling::kCoupled &&
      s.ode.LastSolved(&solved.t, &solved.theta) &&
      (samples.empty() || solved.t > samples.back().t))
    candidates.push_back(solved);
  if (candidates.empty()) return;
  std::unique_ptr<QuasiStaticSolver> solver = StopSolver();
  std::ostringstream os;
  os << std::setprecision(9) << "; solved again from a cold start ("
     << solver->nlp().name() << "):";
  for (const Candidate& c : candidates) {
    QuasiStaticSolution retry;
    solver->Reset();
    solver->Solve(c.theta, &retry);
    os << " the state at t = " << c.t << " s: ";
    if (retry.status != QuasiStaticStatus::kOk) {
      os << ToString(retry.status) << " too;";
      continue;
    }
    SetStopRetry(*model_, c.t, c.theta, retry, result, &os);
    break;
  }
  result->stop_reason += os.str();
}

bool Simulator::Interval(SimulationResult* result) {
  Session& s = *session_;
  const int k = s.k;
  // A located stop (CheckIntervalEvents) is recorded at its own time.
  const bool pending = !std::isnan(s.t_stop);
  double t = pending ? s.t_stop : k == s.n ? t_end_ : k * dt_;
  const double t_next = k + 1 == s.n ? t_end_ : (k + 1) * dt_;
  s.have_z_prev = s.have_prev && s.sol.status == QuasiStaticStatus::kOk;
  if (s.have_z_prev) s.z_prev = s.sol.z;
  s.solver.Solve(s.theta, &s.sol);
  QuasiStaticSolution& sol = s.sol;
  AddSolveCounts(sol, result);
  // Coupled: the interval's first right-hand side is at this very state.
  if (options_.coupling == Coupling::kCoupled &&
      sol.status == QuasiStaticStatus::kOk)
    s.ode.RememberRoot(t, sol.z);
  if (s.probe_solver && s.sol_event.z.size() == 0 &&
      sol.status == QuasiStaticStatus::kOk)
    SizeProbeSolvers(result);
  const bool classify = options_.locate_switches && !pending &&
                        sol.status == QuasiStaticStatus::kOk;
  if (classify) ClassSlips(result);
  s.wheel_events = 0;
  if (classify && s.have_prev) RestartAtSwitches(t, result);
  for (int i = 0; i < 3; ++i) s.slip_prev[i] = sol.contacts[i].slip;
  s.class_before = s.class_prev;
  for (int i = 0; i < 3; ++i)
    if (!(s.class_prev_classified && classify) || ((s.wheel_events >> i) & 1u))
      s.class_before[i].setZero();
  s.class_prev = classify ? s.class_now : s.slip_prev;
  s.class_prev_classified = classify;
  const bool check_contact =
      options_.second_contact_check_every > 0 &&
      (k % options_.second_contact_check_every == 0 || pending);
  if (check_contact && sol.status == QuasiStaticStatus::kOk) {
    const ValidityReport v = CheckValidity(*model_, s.theta, true);
    if (!v.ok()) {
      sol.status = QuasiStaticStatus::kDegenerateContact;
      sol.message = v.Describe();
    }
  }
  if (pending && sol.status == QuasiStaticStatus::kOk) {
    // The located state lies within event_tolerance past the crossing; the
    // solve's own checks may still pass there (a state reached only at the
    // bracket's lower end): the limit stands.
    sol.status = QuasiStaticStatus::kDegenerateContact;
    sol.critical_contact = s.pending_wheel;
    sol.message = "wheel " + std::to_string(s.pending_wheel + 1) + ": " +
                  s.pending_limit + " (located between samples)";
  }
  if (!pending && sol.status != QuasiStaticStatus::kOk &&
      sol.status != QuasiStaticStatus::kSolverFailure)
    LocateSampleStop(&t, result);
  Record(t, s.theta, s.sol, result, k,
         s.slip_increments_t == t ? &s.slip_increments : nullptr);
  s.slip_increments_t = kNaN;
  s.checkpoints.AtSample(result->samples.back(), &result->checkpoints);
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
    SetStopEvent(t, result);
    return false;
  }
  if (k == s.n) {
    result->status = "success";
    return false;
  }
  s.w_held = s.solver.problem().JointSpaceVelocity(sol.z);
  s.ode.Hold(s.w_held);
  const IntegratorStatus st = IntegrateInterval(t, t_next);
  if (st != IntegratorStatus::kSuccess) {
    result->t_reached = s.ires.t_reached;
    if (s.ode.SolveStopped(st)) {
      const bool resolved = !std::isnan(s.resolved_stop.t);
      if (resolved ? StopAtMarch(s.resolved_stop, result)
                   : LocateIntegratorStop(t, s.theta, t_next, result))
        return !s.done_located;
      const QuasiStaticSolution& f = s.ode.stopping_solution();
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
  s.theta_prev = s.theta;
  s.t_prev = t;
  s.have_prev = true;
  s.theta = s.y;
  s.k = k + 1;
  if (options_.locate_events) CheckIntervalEvents(t, t_next);
  s.checkpoints.InInterval(t, s.theta_prev, s.sol, s.w_held, t_next, s.y,
                           std::isnan(s.t_stop) ? t_next : s.t_stop,
                           &result->checkpoints);
  return true;
}

// Integrates the run's ODE (the held twist in zoh) with the run's own
// integrator from (t0, theta0) to t1 into s.y_event; false if it fails.
IntegratorStatus Simulator::Reintegrate(double t0, const Configuration& theta0,
                                        double t1) {
  Session& s = *session_;
  s.y_event = theta0;
  if (!(t1 > t0)) return IntegratorStatus::kSuccess;
  s.ode.Hold(s.w_held);
  return s.integrator->Integrate(s.ode, t0, t1, s.y_event, s.iopts, &s.ires);
}

// Bisects br->[a, b] down to event_tolerance. A time m is "before the limit"
// when the integrator reaches it from (t0, theta0) and the state there
// passes the geometric indicators (solve false) or the quasi-static solve
// does not fail physically (solve true; the failing solve at b is kept in
// s.sol_b).
void Simulator::Bisect(double t0, const Configuration& theta0, bool solve,
                       Bracket* br) {
  Session& s = *session_;
  const bool contact = options_.second_contact_check_every > 0;
  while (br->b - br->a > options_.event_tolerance) {
    const double m = 0.5 * (br->a + br->b);
    if (!(m > br->a && m < br->b)) break;  // round-off
    const bool reached =
        Reintegrate(t0, theta0, m) == IntegratorStatus::kSuccess;
    const Configuration y = s.y_event;
    bool good = reached;
    if (good && solve) {
      s.solver.Solve(y, &s.sol_event);
      s.event_solves += s.sol_event.nlp_solves;
      s.event_iterations += s.sol_event.nlp_iterations;
      s.event_iterations_native += s.sol_event.nlp_iterations_native;
      // SOLVER_FAILURE means mu > mu_min with regular statics (model.md
      // §7.7): the physical limit is not reached there.
      good = s.sol_event.status == QuasiStaticStatus::kOk ||
             s.sol_event.status == QuasiStaticStatus::kSolverFailure;
      if (good && contact) good = CheckValidity(*model_, y, true).ok();
    } else if (good) {
      EvaluateLimitIndicators(*model_, y, contact, &s.ind,
                              IndicatorDetail::kVerdict);
      good = s.ind.ok();
    }
    if (good) {
      br->a = m;
      br->theta_a = y;
    } else {
      br->b = m;
      br->have_b = reached;
      if (reached) br->theta_b = y;
      if (reached && solve) std::swap(s.sol_b, s.sol_event);
    }
  }
}

// After an interval [t0, t1] (state s.theta_prev at t0, s.theta at t1):
// looks for a geometric limit on the dense output (interior points and the
// end); if one is met, bisects the dense output for the first crossing,
// re-integrates from t0 to it with the run's own integrator and leaves that
// state in s.theta with s.t_stop set, for the next Interval() to record and
// stop. Returns true if so.
bool Simulator::CheckIntervalEvents(double t0, double t1) {
  Session& s = *session_;
  const Configuration& th0 = s.theta_prev;
  const Configuration th1 = s.theta;
  const double h = t1 - t0;
  const int m = options_.event_points;
  Configuration f0, f1;
  // zoh: F at the end with the held twist (exact); coupled: the end slope
  // of the quadratic through (Theta_0, F_0, Theta_1). Without a right-hand
  // side (K singular at an end) the dense output is linear.
  bool dense = m > 0 && (s.ode.FirstHeldRhs(th0, &f0) ||
                         model_->Rhs(th0, s.w_held, &f0));
  if (dense && options_.coupling == Coupling::kZoh) {
    dense = model_->Rhs(th1, s.w_held, &f1);
  } else if (dense) {
    f1 = 2.0 / h * (th1 - th0) - f0;
  }
  auto state = [&](double frac) -> Configuration {
    if (frac >= 1.0) return th1;
    if (dense) return HermiteState(th0, f0, th1, f1, h, frac);
    return (1.0 - frac) * th0 + frac * th1;
  };
  double fa = 0.0, fb = kNaN;
  for (int j = 1; j <= m + 1; ++j) {
    const double frac = static_cast<double>(j) / (m + 1);
    // The interior points' verdicts are all that is used; the end's values
    // feed the trend check below (from the chain cache: no terrain).
    EvaluateLimitIndicators(
        *model_, state(frac), false, &s.ind,
        frac < 1.0 ? IndicatorDetail::kVerdict : IndicatorDetail::kValues);
    if (!s.ind.ok()) {
      fb = frac;
      break;
    }
    fa = frac;
  }
  if (std::isnan(fb)) {
    // s.ind holds the end's indicators. A relative-curvature margin that,
    // extrapolated from the last two samples, reaches 0 inside this
    // interval while the end is valid may have been stepped over (the
    // contact rates grow like 1/margin, and a step across the singularity
    // can land back on the valid side): check on re-integrated states.
    bool suspect = false;
    for (int i = 0; i < 3; ++i) {
      const double now = s.curvature_now[i], before = s.curvature_before[i];
      if (now < before && now - (before - now) * (h / dt_) <= 0) suspect = true;
      s.curvature_before[i] = now;
      s.curvature_now[i] = s.ind.relative_curvature[i];
    }
    return suspect && ScanInterval(t0, t1);
  }
  const char* limit = s.ind.violated;
  int wheel = s.ind.wheel;
  while ((fb - fa) * h > options_.event_tolerance) {
    const double fm = 0.5 * (fa + fb);
    if (!(fm > fa && fm < fb)) break;  // round-off
    EvaluateLimitIndicators(*model_, state(fm), false, &s.ind,
                            IndicatorDetail::kVerdict);
    if (s.ind.ok()) {
      fa = fm;
    } else {
      fb = fm;
      limit = s.ind.violated;
      wheel = s.ind.wheel;
    }
  }
  s.t_lower = t0 + fa * h;
  s.t_upper = fb >= 1.0 ? t1 : t0 + fb * h;
  s.t_stop = s.t_upper;
  if (fb >= 1.0) {
    s.theta = th1;
  } else if (Reintegrate(t0, th0, s.t_stop) == IntegratorStatus::kSuccess) {
    s.theta = s.y_event;
  } else {
    s.theta = state(fb);
  }
  s.pending_limit = limit;
  s.pending_wheel = wheel;
  return true;
}

// Checks the states the run's integrator reaches from the start of the
// interval [t0, t1] at kScanPoints times t0 + j (t1 - t0)/kScanPoints; at
// the first one past a geometric limit (or not reached), bisects like
// LocateIntegratorStop and leaves the located stop pending. Returns true if
// so.
bool Simulator::ScanInterval(double t0, double t1) {
  constexpr int kScanPoints = 8;
  Session& s = *session_;
  const Configuration th0 = s.theta_prev;
  Bracket br;
  br.a = t0;
  br.theta_a = th0;
  for (int j = 1; j < kScanPoints; ++j) {
    const double tj = t0 + (t1 - t0) * j / kScanPoints;
    const bool reached = Reintegrate(t0, th0, tj) == IntegratorStatus::kSuccess;
    if (reached) {
      EvaluateLimitIndicators(*model_, s.y_event, false, &s.ind,
                              IndicatorDetail::kVerdict);
      if (s.ind.ok()) {
        br.a = tj;
        br.theta_a = s.y_event;
        continue;
      }
    }
    br.b = tj;
    br.have_b = reached;
    br.theta_b = s.y_event;
    Bisect(t0, th0, false, &br);
    s.t_lower = br.a;
    s.t_upper = br.b;
    s.t_stop = br.have_b ? br.b : br.a;
    s.theta = br.have_b ? br.theta_b : br.theta_a;
    const char* limit = "relative_curvature";
    int wheel = 0;
    if (br.have_b) {
      EvaluateLimitIndicators(*model_, s.theta, false, &s.ind);
      if (!s.ind.ok()) {
        limit = s.ind.violated;
        wheel = s.ind.wheel;
      }
    }
    s.pending_limit = limit;
    s.pending_wheel = wheel;
    return true;
  }
  return false;
}

// The solve at the sample time *t failed physically (or the sampled
// second-contact check did): locates the crossing inside the last interval
// and replaces s.theta, s.sol and *t by the located stop. Returns true if
// located.
bool Simulator::LocateSampleStop(double* t, SimulationResult* result) {
  Session& s = *session_;
  if (!options_.locate_events || !s.have_prev) return false;
  const bool contact = options_.second_contact_check_every > 0;
  // The sampled second-contact check (every N samples) may have failed
  // before the last interval: the start must pass it.
  if (contact && !CheckValidity(*model_, s.theta_prev, true).ok()) return false;
  Bracket br;
  br.a = s.t_prev;
  br.theta_a = s.theta_prev;
  br.b = *t;
  br.theta_b = s.theta;
  br.have_b = true;
  const QuasiStaticSolution original = s.sol;  // kept if not confirmed
  const Configuration theta_original = s.theta;
  std::swap(s.sol_b, s.sol);
  s.event_solves = 0;
  s.event_iterations = s.event_iterations_native = 0;
  Bisect(s.t_prev, s.theta_prev, true, &br);
  result->nlp_solves += s.event_solves;
  result->nlp_iterations += s.event_iterations;
  result->nlp_iterations_native += s.event_iterations_native;
  // Reproduce a failure to reach b (coupled) for its solution.
  const QuasiStaticSolution* stop =
      br.have_b ? nullptr
                : s.ode.PhysicalStop(Reintegrate(s.t_prev, s.theta_prev, br.b));
  if (br.have_b && s.sol_b.status != QuasiStaticStatus::kOk &&
      s.sol_b.status != QuasiStaticStatus::kSolverFailure) {
    std::swap(s.sol, s.sol_b);
    s.theta = br.theta_b;
    *t = br.b;
  } else if (stop) {
    // Coupled: the integrator itself failed past a; stop at a with the
    // failing stage's solution.
    s.sol = *stop;
    s.theta = br.theta_a;
    *t = br.a;
  } else {
    // The located end is no physical stop (a solver failure, or a state off
    // the path of a blown-up run): keep the sample's stop.
    s.sol = original;
    s.theta = theta_original;
    return false;
  }
  s.t_lower = br.a;
  s.t_upper = br.b;
  return true;
}

namespace {
// mu_min - mu at a located friction stop above which the stop is taken for
// a step's stages jumping a point where the solutions change abruptly
// (LocateIntegratorStop).
constexpr double kFrictionJump = 1e-6;
}  // namespace

// A quasi-static solve failed inside the integrator (coupled mode) on
// [t0, t1] (from theta0 at t0): locates the first time the integrator
// cannot reach, records a sample at the last reachable one and stops.
// Returns true if it did.
bool Simulator::LocateIntegratorStop(double t0, const Configuration& theta0,
                                     double t1, SimulationResult* result) {
  Session& s = *session_;
  if (!options_.locate_events ||
      s.ode.stopping_solution().status == QuasiStaticStatus::kSolverFailure)
    return false;
  const QuasiStaticSolution first = s.ode.stopping_solution();
  Bracket br;
  br.a = t0;
  br.theta_a = theta0;
  br.b = t1;
  Bisect(t0, theta0, false, &br);
  s.t_lower = br.a;
  s.t_upper = br.b;
  if (br.have_b) {
    // The integrator reaches b, where a geometric limit is violated: stop
    // there (recorded by the next Interval(), as for CheckIntervalEvents).
    EvaluateLimitIndicators(*model_, br.theta_b, false, &s.ind);
    s.theta = br.theta_b;
    s.t_stop = br.b;
    s.pending_limit = s.ind.violated;
    s.pending_wheel = s.ind.wheel;
    s.k += 1;
    return true;
  }
  // Reproduce the failure at b for its solution and stage state. Where the
  // NLP gives up before the limit (SOLVER_FAILURE: mu > mu_min there) the
  // integrator cannot go on towards it: the limit that stopped it stands.
  const IntegratorStatus st = Reintegrate(t0, theta0, br.b);
  const QuasiStaticSolution* stop =
      st == IntegratorStatus::kSuccess ? nullptr : s.ode.PhysicalStop(st);
  const QuasiStaticSolution located = stop ? *stop : first;
  // A friction limit the path meets has mu_min -> mu at the located stop
  // (measured 1e-11..1.3e-8 over mu); single steps whose stages jump a
  // point where the solutions change abruptly certify mu_min well above mu
  // (5.8e-5..2.1e-4): march instead (model.md §8.6, "A solve that gives up").
  if (located.status == QuasiStaticStatus::kInfeasibleFriction &&
      located.mu_min - scene_.mu > kFrictionJump &&
      MarchToStop(t0, theta0, t1, result))
    return true;
  RecordIntegratorStop(br.a, br.theta_a, located, "located", result);
  return true;
}

// Integrates [t0, t1] from theta0 by the resolved march (coupled,
// fixed-step) and stops where it fails (StopAtMarch). False (nothing
// recorded) if the march does not apply or gets to t1.
bool Simulator::MarchToStop(double t0, const Configuration& theta0, double t1,
                            SimulationResult* result) {
  Session& s = *session_;
  const double tolerance = s.switch_tolerance;
  if (options_.coupling != Coupling::kCoupled || !std::isfinite(tolerance) ||
      !(t1 - t0 > kSwitchMinStep))
    return false;
  s.y = theta0;
  ResolvedStop stop;
  if (IntegrateResolved(t0, t1, tolerance, kSwitchMinStep, Advance(), &s.y,
                        &stop) ||
      std::isnan(stop.t) || !s.ode.SolveStopped(s.ires.status))
    return false;
  return StopAtMarch(stop, result);
}

// The resolved march failed on a solve at stop (s.y: its state at stop.t):
// a certified limit is located from there (LocateIntegratorStop), a solve
// that gave up ends the run there. Returns true if a stop was recorded or
// left pending.
bool Simulator::StopAtMarch(const ResolvedStop& stop,
                            SimulationResult* result) {
  Session& s = *session_;
  if (s.ode.PhysicalStop(s.ires.status))
    return LocateIntegratorStop(stop.t, s.y, stop.t_failed, result);
  RecordIntegratorStop(stop.t, s.y, s.ode.stopping_solution(),
                       "the resolved march's last state", result);
  return true;
}

// Ends the run at t with the reached state theta: the last sample carries
// sol, the solve the integrator could not get past (`where` goes into
// stop_reason).
void Simulator::RecordIntegratorStop(double t, const Configuration& theta,
                                     const QuasiStaticSolution& sol,
                                     const char* where,
                                     SimulationResult* result) {
  Session& s = *session_;
  s.sol = sol;
  result->stop_configuration = s.solver.problem().configuration();
  s.theta = theta;
  Record(t, s.theta, s.sol, result, s.k);
  s.checkpoints.AtSample(result->samples.back(), &result->checkpoints);
  s.done_located = true;
  result->t_reached = t;
  result->status = ToString(s.sol.status);
  result->mu_min_at_stop = s.sol.mu_min;
  result->critical_contact =
      s.sol.critical_contact >= 0 ? s.sol.critical_contact + 1 : -1;
  result->stop_reason =
      "t=" + std::to_string(t) + " s: " + ToString(s.sol.status) +
      " inside the integrator (" + where + "): " + s.sol.message;
  SetStopEvent(t, result);
}

// The solve s.sol at the sample time t follows the interval [s.t_prev, t]
// (start s.theta_prev, held twist s.w_held). A wheel whose class
// (core/switch_events.h) differs from the last recorded sample's is
// located on the interval's cubic Hermite dense output (F at both ends from
// the twists solved there; zoh: the held twist), solving the quasi-static
// problem at each probe state with a separate solver; the interval's slip
// integrals are then split at the switches and where a wheel crosses the
// sliding/creep level (IntegrateSlipAcrossSwitches). Coupled mode then
// integrates the interval again from s.theta_prev with a restart at every
// located switch and re-solves at t; zoh keeps its trajectory.
void Simulator::RestartAtSwitches(double t, SimulationResult* result) {
  Session& s = *session_;
  if (result->samples.empty() || !(t > s.t_prev)) return;
  const std::array<Eigen::Vector2d, 3>& slip0 = s.class_prev;
  const std::array<Eigen::Vector2d, 3>& slip1 = s.class_now;
  bool change = false, band = false, regime = false;
  const double eps = scene_.epsilon;
  for (int i = 0; i < 3; ++i) {
    const double s0 = slip0[i].norm(), s1 = slip1[i].norm();
    const double g0 = SwitchIndicator(s0, eps);
    const double g1 = SwitchIndicator(s1, eps);
    change = change || (g0 >= 0) != (g1 >= 0);  // false for a NaN
    // A wheel whose slip reverses while it slides or while it creeps
    // (LocateSwitchesAndReversals).
    change = change || IsReversal(slip0[i], slip1[i], eps) ||
             IsSplitReversal(s.class_before[i], slip0[i], slip1[i], eps);
    band = band || InSwitchBand(s1, eps);
    // The sliding/creep split's level (below the switches') crossed.
    regime = regime || (std::isfinite(s0) && std::isfinite(s1) &&
                        IsSliding(s0, eps) != IsSliding(s1, eps));
  }
  const bool coupled = options_.coupling == Coupling::kCoupled;
  const double tolerance = s.switch_tolerance;
  // An interval integrated plain whose end lies in the creep band is
  // integrated again, resolved (core/switch_events.h).
  const bool redo =
      coupled && band && !s.resolved_last && std::isfinite(tolerance);
  const bool suspect = JumpSuspected(change || regime);
  if (!change && !redo && !regime && !suspect) return;
  const Configuration th0 = s.theta_prev, th1 = s.theta;
  const double h = t - s.t_prev;
  const Vec12 w1 =
      coupled ? s.solver.problem().JointSpaceVelocity(s.sol.z) : s.w_held;
  Session::Dense& d = s.dense;
  d.th0 = th0;
  d.th1 = th1;
  d.t0 = s.t_prev;
  d.h = h;
  d.hermite = model_->Rhs(th0, s.w_held, &d.f0) && model_->Rhs(th1, w1, &d.f1);
  QuasiStaticSolution& probe = s.sol_event;  // probe_solver: from Begin()
  // Each probe starts from the linear interpolation in time between the
  // nearest converged solutions on either side (the interval's ends and
  // every probe so far): an O(h^2) start that does not creep at the slip's
  // kinks, where the nearest solution alone did (tens of iterations). The
  // location's probes are then refined to kLocationResidualTolerance: a root
  // that merely meets the run's tolerance fixes the switching wheel's slip
  // at the switch level only to ~6e-10 m/s, i.e. the switch time to ~2.5e-8
  // s per 1e-12 of residual (paper scene), 25x the location tolerance.
  const bool ends = s.have_z_prev && s.sol.status == QuasiStaticStatus::kOk;
  s.probe_known_count = 0;
  bool refine = true;
  auto probe_at = [&](double tm, std::array<Eigen::Vector2d, 3>* slip) {
    const int known = std::min<int>(s.probe_known_count, s.probe_known.size());
    for (int j = 0; j < known; ++j) {
      if (s.probe_known[j].t == tm) {
        *slip = s.probe_known[j].slip;
        return true;
      }
    }
    const Configuration q = DenseState(tm);
    SolveProbe(q, ends ? &InterpolateKnown(tm, t) : nullptr, refine, &probe,
               result);
    if (probe.status != QuasiStaticStatus::kOk) return false;
    for (int i = 0; i < 3; ++i) (*slip)[i] = probe.contacts[i].slip;
    RememberProbe(tm, probe);
    return true;
  };
  // One captured reference: std::function keeps it without allocating.
  const SlipVectorEvaluator evaluate =
      [&probe_at](double tm, std::array<Eigen::Vector2d, 3>* slip) {
        return probe_at(tm, slip);
      };
  const std::size_t first = result->switches.size();
  if (change)
    LocateSwitchesAndReversals(s.t_prev, t, slip0, slip1, eps,
                               options_.event_tolerance, evaluate,
                               &result->switches, nullptr, &s.class_before);
  // After the switches, so that their probes start as before.
  const bool jumped = suspect && LocateSolutionJump(t, result);
  if (jumped) SortAppended(first, &result->switches);
  for (std::size_t j = first; j < result->switches.size(); ++j)
    s.wheel_events |= 1u << (result->switches[j].wheel - 1);
  // The zoh samples' linear predictor would extrapolate across the jump
  // (from the ended root through the new one): the next sample starts from
  // this one's root instead (model.md §7.3; kept across switches and creep
  // reversals, where dropping it cost more than it saved).
  if (jumped && !coupled) s.solver.SetWarmStart(s.sol.z);
  refine = false;
  if (change || regime || jumped)
    IntegrateSlipAcrossSwitches(t, first, evaluate, result);
  // A coupled interval is not restarted at a jump (model.md §8.6,
  // "Solution jumps"): its resolved steps cross it as before.
  if (!coupled || !(change || redo)) return;
  Eigen::VectorXd& y = s.y_event;
  y = th0;
  double ta = s.t_prev;
  for (std::size_t j = first; j <= result->switches.size(); ++j) {
    const bool end = j == result->switches.size();
    const double tb = end ? t : result->switches[j].t;
    if (!end && (!result->switches[j].located || result->switches[j].jump ||
                 !(tb > ta + options_.event_tolerance) || !(tb < t)))
      continue;
    if (!end && std::isfinite(tolerance))
      s.resolve_until = std::max(s.resolve_until, tb + kSwitchResolveWindow);
    // A failure keeps the interval as first integrated.
    if (!IntegrateResolved(ta, tb, tolerance, kSwitchMinStep, Advance(), &y))
      return;
    ta = tb;
  }
  s.theta = y;
  // The checkpoints of the interval came from the first integration.
  s.checkpoints.Rewind(s.t_prev, &result->checkpoints);
  s.checkpoints.InInterval(s.t_prev, th0, s.sol, s.w_held, t, s.theta, t,
                           &result->checkpoints);
  s.solver.Solve(s.theta, &s.sol);
  AddSolveCounts(s.sol, result);
  ClassSlips(result);  // the next interval's class test starts from this root
}

// Sizes the workspaces of the probe and continuation solvers: one solve
// each from the accepted solution s.sol.
void Simulator::SizeProbeSolvers(SimulationResult* result) {
  Session& s = *session_;
  const Eigen::VectorXd& z = s.sol.z;
  SolveProbe(s.theta, &z, false, &s.sol_event, result);
  for (Session::KnownSolution& k : s.probe_known) k.z = z;
  s.probe_warm = z;
  if (!s.branch_solver) return;
  s.branch_solver->SetWarmStart(z);
  s.branch_solver->Solve(s.theta, &s.branch_sol);
  AddSolveCounts(s.branch_sol, result);
  s.branch_z = z;
}

// Whether the interval ending at the sample s.sol may hold a solution jump
// (core/solution_jumps.h): a solve of the interval was not a continuation
// step (the sample's, or in coupled mode a right-hand side's, needed a
// fallback or, with a Newton backend, more than kBranchStepIterations
// iterations), or, with another backend, `structure_changed` (a wheel's
// class or regime changed). Marks the right-hand side's irregular solves so
// far as seen.
bool Simulator::JumpSuspected(bool structure_changed) {
  Session& s = *session_;
  const int irregular = s.ode.irregular_solves();
  const bool seen = irregular != s.ode_irregular_seen;
  s.ode_irregular_seen = irregular;
  // Other backends' iteration counts do not measure contraction: there a
  // change of a wheel's class or regime in the interval counts too.
  return s.branch_solver && s.have_z_prev &&
         s.sol.status == QuasiStaticStatus::kOk &&
         (s.sol.nlp_solves > 1 || seen ||
          (s.newton_run ? s.sol.nlp_iterations > kBranchStepIterations
                        : structure_changed));
}

Configuration Simulator::DenseState(double tm) const {
  const Session::Dense& d = session_->dense;
  const double frac = (tm - d.t0) / d.h;
  return d.hermite ? HermiteState(d.th0, d.f0, d.th1, d.f1, d.h, frac)
                   : Configuration((1 - frac) * d.th0 + frac * d.th1);
}

void Simulator::RememberProbe(double tm, const QuasiStaticSolution& sol) {
  Session& s = *session_;
  Session::KnownSolution& k =
      s.probe_known[s.probe_known_count++ % s.probe_known.size()];
  k.t = tm;
  k.z = sol.z;
  for (int i = 0; i < 3; ++i) k.slip[i] = sol.contacts[i].slip;
}

void Simulator::SolveProbe(const Configuration& q, const Eigen::VectorXd* warm,
                           bool refine, QuasiStaticSolution* probe,
                           SimulationResult* result) {
  QuasiStaticSolver& solver = *session_->probe_solver;
  if (warm) solver.SetWarmStart(*warm);
  solver.Solve(q, probe);
  if (refine) solver.Refine(kLocationResidualTolerance, probe);
  AddSolveCounts(*probe, result);
}

// The slips the class test (RestartAtSwitches) reads at the sample just
// solved: its own, or, when its root is looser than kClassSlipResidual, the
// same state's solved again and refined like a location probe. A root at a
// loose nlp_tol (1e-6) fixes a slip near the sliding level kappa eps only
// to about that level, so its class is noise; the location's probes are
// refined, and its brackets closed onto the samples: a wheel "switched" at
// each sample and back (33 events at sample times in the three nlp_tol 1e-6
// runs of the default suite). model.md §8.6.
void Simulator::ClassSlips(SimulationResult* result) {
  Session& s = *session_;
  for (int i = 0; i < 3; ++i) s.class_now[i] = s.sol.contacts[i].slip;
  if (!s.probe_solver || s.sol.status != QuasiStaticStatus::kOk ||
      !(s.sol.residual > kClassSlipResidual))
    return;
  QuasiStaticSolution& probe = s.sol_event;  // the probes' scratch
  SolveProbe(s.theta, &s.sol.z, true, &probe, result);
  if (probe.status != QuasiStaticStatus::kOk) return;
  for (int i = 0; i < 3; ++i) s.class_now[i] = probe.contacts[i].slip;
}

// Follows the root of the interval's start (s.z_prev at s.t_prev) towards t
// by continuation (core/solution_jumps.h). Where it ends, the root of the
// sample at t is followed back to the bracket's upper end; both roots
// become probes (the quadrature's one-sided ends, warm-start nodes) and the
// jump's events are appended. False (nothing appended) if the start's root
// reaches t, or the end's root does not reach the bracket.
bool Simulator::LocateSolutionJump(double t, SimulationResult* result) {
  Session& s = *session_;
  // Captures one reference: no allocation (see RestartAtSwitches).
  struct Follow {
    Simulator* sim;
    SimulationResult* result;
    double sign;        // +1 forward in time, -1 backward (u = -t)
    double max_change;  // of a wheel's slip in one step [m/s]
    std::array<Eigen::Vector2d, 3> slip_now;  // the last accepted root's
  } f{this, result, 1.0, 0.0, s.slip_prev};
  double interval_change = 0;
  for (int i = 0; i < 3; ++i)
    interval_change = std::max(
        interval_change, (s.sol.contacts[i].slip - s.slip_prev[i]).norm());
  if (!std::isfinite(interval_change)) return false;
  f.max_change = kBranchStepSlipChange * interval_change +
                 kBranchSlipFloorOverEpsilon * scene_.epsilon;
  const BranchStep step = [&f](double u) {
    Session& ss = *f.sim->session_;
    const double tm = f.sign * u;
    ss.branch_solver->SetWarmStart(ss.branch_z);
    ss.branch_solver->Solve(f.sim->DenseState(tm), &ss.branch_sol);
    AddSolveCounts(ss.branch_sol, f.result);
    if (ss.branch_sol.status != QuasiStaticStatus::kOk) return false;
    // A jump keeps its size however short the step; a continuous root's
    // change vanishes with the step.
    for (int i = 0; i < 3; ++i)
      if (!((ss.branch_sol.contacts[i].slip - f.slip_now[i]).norm() <=
            f.max_change))
        return false;
    ss.branch_z = ss.branch_sol.z;
    for (int i = 0; i < 3; ++i) f.slip_now[i] = ss.branch_sol.contacts[i].slip;
    f.sim->RememberProbe(tm, ss.branch_sol);
    return true;
  };
  const double tolerance = options_.event_tolerance;
  s.branch_z = s.z_prev;
  const BranchEnd forward = FollowBranch(s.t_prev, t, tolerance, step);
  // An end not narrowed inside the interval (a tolerance as long as it) is
  // not located.
  if (forward.outcome != BranchEnd::Outcome::kEnds || !(forward.t_upper < t))
    return false;
  // The ended root's slips: the last accepted step's, at t_lower.
  const std::array<Eigen::Vector2d, 3> before = f.slip_now;
  // The root the run goes on with, followed back from the sample at t.
  f.sign = -1.0;
  for (int i = 0; i < 3; ++i) f.slip_now[i] = s.sol.contacts[i].slip;
  s.branch_z = s.sol.z;
  const BranchEnd back = FollowBranch(-t, -forward.t_upper, tolerance, step);
  if (back.outcome != BranchEnd::Outcome::kContinues) return false;
  AppendSolutionJump(forward.t_lower, forward.t_upper, true, before, f.slip_now,
                     scene_.epsilon, &result->switches);
  return true;
}

// The interval's slip integrals split at its located switches (all of
// them located, else the trapezoid stays) for Record.
void Simulator::IntegrateSlipAcrossSwitches(double t, std::size_t first,
                                            const SlipVectorEvaluator& evaluate,
                                            SimulationResult* result) {
  Session& s = *session_;
  std::vector<double>& breaks = s.slip_breaks;
  std::vector<std::array<double, 2>>& jumps = s.slip_jumps;
  breaks.clear();
  jumps.clear();
  for (std::size_t j = first; j < result->switches.size(); ++j) {
    const SwitchEvent& e = result->switches[j];
    if (!e.located) return;
    breaks.push_back(e.t);
    if (!e.jump) continue;
    // A jump's pieces end on either root, its bracket between them.
    breaks.push_back(e.t_lower);
    jumps.push_back({e.t_lower, e.t_upper});
  }
  std::sort(breaks.begin(), breaks.end());
  std::array<double, 3> slip0, slip1;
  for (int i = 0; i < 3; ++i) {
    slip0[i] = s.slip_prev[i].norm();
    slip1[i] = s.sol.contacts[i].slip.norm();
  }
  // Captures one reference: no allocation (see RestartAtSwitches).
  const SlipEvaluator speeds = [&evaluate](double tm,
                                           std::array<double, 3>* f) {
    std::array<Eigen::Vector2d, 3> v;
    if (!evaluate(tm, &v)) return false;
    for (int i = 0; i < 3; ++i) (*f)[i] = v[i].norm();
    return true;
  };
  int evaluations = 0;
  if (IntegrateSlipRegimes(s.t_prev, t, slip0, slip1, breaks, scene_.epsilon,
                           speeds, &s.slip_increments, &evaluations, jumps))
    s.slip_increments_t = t;
}

// Step doubling for fixed-step integrators (core/switch_events.h,
// "Resolution"): SwitchResolutionTolerance(dt); +inf (no refinement) for
// adaptive ones.
double Simulator::SwitchStepTolerance() const {
  return IntegratorRegistry::Info(options_.dae)
                 .IsAdaptive(session_->dae_options)
             ? std::numeric_limits<double>::infinity()
             : SwitchResolutionTolerance(session_->iopts.step,
                                         options_.switch_step_tolerance);
}

SegmentAdvance Simulator::Advance() {
  Session* s = session_.get();
  return [s](double a, double b, Eigen::VectorXd* y) {
    return s->integrator->Integrate(s->ode, a, b, *y, s->iopts, &s->ires) ==
           IntegratorStatus::kSuccess;
  };
}

// Integrates s.theta over [t, t_next] into s.y: resolved (step doubling)
// within kSwitchResolveWindow after a located switch in coupled mode,
// falling back to one call of the integrator if that fails; a coupled
// fixed-step call that fails on a solve which gives up is followed by the
// resolved march too (its stop in s.resolved_stop).
IntegratorStatus Simulator::IntegrateInterval(double t, double t_next) {
  Session& s = *session_;
  s.y = s.theta;
  const double tolerance = s.switch_tolerance;
  const bool coupled = options_.coupling == Coupling::kCoupled;
  // Fixed-step, coupled, locating: a wheel in the creep band at t makes
  // the interval resolved.
  const bool watch =
      options_.locate_switches && coupled && std::isfinite(tolerance);
  bool band = false;
  for (int i = 0; watch && i < 3; ++i)
    band = band || InSwitchBand(s.sol.contacts[i].slip.norm(), scene_.epsilon);
  s.resolved_last = false;
  s.resolved_stop = ResolvedStop{};
  ResolvedStop stop;
  const bool resolved_first = t < s.resolve_until || band;
  if (resolved_first) {
    if (IntegrateResolved(t, t_next, tolerance, kSwitchMinStep, Advance(), &s.y,
                          &stop)) {
      s.resolved_last = std::isfinite(tolerance);
      return IntegratorStatus::kSuccess;
    }
    // The march cannot step past a quasi-static limit (a wheel's friction
    // use -> 1: the creep's square-root singularity makes the steps shrink
    // towards it): the stop is where the march got, located from there;
    // one unresolved step over the interval would jump the limit from
    // off-path stage states (model.md §8.6, "Quasi-static limits").
    if (!std::isnan(stop.t) && s.ode.PhysicalStop(s.ires.status))
      return StopResolved(stop);
    s.y = s.theta;
  }
  const IntegratorStatus st =
      s.integrator->Integrate(s.ode, t, t_next, s.y, s.iopts, &s.ires);
  // A coupled fixed-step interval whose step failed on a solve that gave
  // up (SOLVER_FAILURE: the step's stage states may lie off the path, past
  // a point the solves cannot pass) is marched resolved instead, and stops
  // where the march does, not at the last sample (model.md §8.6, "A solve
  // that gives up"). A physical stop keeps its bisection from t.
  if (st == IntegratorStatus::kSuccess || s.ode.PhysicalStop(st) ||
      !s.ode.SolveStopped(st) || resolved_first || !coupled ||
      !options_.locate_events || !std::isfinite(tolerance))
    return st;
  s.y = s.theta;
  if (IntegrateResolved(t, t_next, tolerance, kSwitchMinStep, Advance(), &s.y,
                        &stop)) {
    s.resolved_last = true;
    return IntegratorStatus::kSuccess;
  }
  if (!std::isnan(stop.t) && stop.t > t) return StopResolved(stop);
  s.ires.t_reached = t;
  return s.ires.status;
}

// The resolved march failed at stop (s.y: its state at stop.t): the
// interval ends there with the march's failure.
IntegratorStatus Simulator::StopResolved(const ResolvedStop& stop) {
  Session& s = *session_;
  s.resolved_stop = stop;
  s.ires.t_reached = stop.t;
  return s.ires.status;
}

namespace {
const char* LimitOfStatus(QuasiStaticStatus status) {
  switch (status) {
    case QuasiStaticStatus::kInfeasibleFriction:
      return "friction_limit";
    case QuasiStaticStatus::kLiftOff:
      return "lift_off";
    case QuasiStaticStatus::kSingular:
      return "singular";
    default:
      return "";
  }
}
}  // namespace

// Fills result->event for a stop at t with s.sol.
void Simulator::SetStopEvent(double t, SimulationResult* result) const {
  const Session& s = *session_;
  const QuasiStaticSolution& sol = s.sol;
  StopEvent& e = result->event;
  e = StopEvent{};
  EvaluateLimitIndicators(
      *model_, s.theta, options_.second_contact_check_every > 0, &e.indicators);
  if (sol.status == QuasiStaticStatus::kDegenerateContact) {
    e.limit = !std::isnan(s.t_stop) ? s.pending_limit
              : e.indicators.ok()   ? "degenerate_contact"
                                    : e.indicators.violated;
    e.wheel = !std::isnan(s.t_stop) ? s.pending_wheel + 1
              : e.indicators.ok()   ? result->critical_contact
                                    : e.indicators.wheel + 1;
  } else {
    e.limit = LimitOfStatus(sol.status);
    e.wheel = result->critical_contact;
  }
  if (e.limit.empty()) {  // SOLVER_FAILURE: numerical, no physical limit
    e = StopEvent{};
    return;
  }
  e.t = t;
  e.mu_min = sol.mu_min;
  e.min_normal_force = sol.min_normal_force;
  e.located = !std::isnan(s.t_upper);
  e.t_lower = e.located ? s.t_lower : s.have_prev ? s.t_prev : t;
  e.t_upper = e.located ? s.t_upper : t;
  e.tolerance = e.located
                    ? options_.event_tolerance
                    : dt_ * std::max(1, options_.second_contact_check_every);
}

}  // namespace quasiroll
