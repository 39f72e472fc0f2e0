// The forward-motion loop (paper §IV steps i–iii; model.md §8):
//   for t_k = k dt:  solve the quasi-static problem at Theta_k,  record,
//                    integrate Theta' = F(Theta, w) over [t_k, t_k + dt].
// Coupling modes (model.md §8.2):
//   zoh      w = (V^B, thetadot) held over the interval (the paper); contact
//            velocities are recomputed from Theta(t) at every stage;
//   coupled  w = w(Theta) re-solved (warm-started) at every RHS evaluation.
// The NLP backend and the integrator are chosen by registry name. Any non-OK
// quasi-static status or integrator failure stops the run cleanly; every
// sample computed before it is kept and the reason recorded.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/limit_events.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/switch_events.h"

namespace quasiroll {

enum class Coupling { kZoh, kCoupled };
const char* ToString(Coupling coupling);
// Throws std::invalid_argument naming the value.
Coupling CouplingFromString(const std::string& name);

struct SimulationOptions {
  std::string nlp = "newton";
  std::string dae = "rk-projection";
  Coupling coupling = Coupling::kZoh;
  // Hold / output interval and end time; <= 0 means "take the scene's".
  double dt = 0.0;
  double t_end = 0.0;
  // Integrator options; step <= 0 means one RK4 step per hold interval.
  IntegratorOptions integrator;
  // Backend options (docs/plugins.md): name -> value text, checked against
  // the backend's option_table() by the Simulator constructor (unknown or
  // ill-typed -> std::invalid_argument naming the option and the known ones).
  GivenOptions nlp_options;
  GivenOptions dae_options;
  QuasiStaticOptions quasi_static;
  // Run the sampled second-contact check every N samples (0 = never).
  int second_contact_check_every = 0;
  // Located stops (model.md §8.6, core/limit_events.h). When on, the
  // geometric limits (tread angle, relative curvature, leaving the terrain)
  // are checked along every hold interval on `event_points` interior points
  // of a cubic Hermite dense output and at its end, and a stop (a crossing
  // there, or a physical quasi-static failure at the next sample) is located
  // by bisection on states the run's own integrator reaches from the
  // interval's start, to `event_tolerance` seconds; the run then stops at
  // the located time. Off: stops are seen at the samples only (as before).
  bool locate_events = true;
  int event_points = 3;
  double event_tolerance = 1e-9;  // [s]
  // Checkpoints (core/checkpoints.h): times [s], sorted ascending, >= 0, at
  // which the method's state is recorded into SimulationResult::checkpoints
  // from each interval's dense output (the stepping is unchanged). Empty:
  // none.
  std::vector<double> checkpoints;
  // Switches (model.md §8.6, core/switch_events.h): when a wheel's
  // stick/slide class differs at two consecutive samples, the change is
  // located by bisection (to event_tolerance) on quasi-static solves at
  // states of the interval's cubic Hermite dense output and recorded in
  // SimulationResult::switches; in coupled mode the interval is then
  // integrated again as [t_k, t_s1], [t_s1, t_s2], ..., [t_sn, t_k+1]. A
  // sliding wheel whose slip vector reverses within an interval is split
  // there and both its class changes located (LocateSwitchesAndReversals).
  // Coupled fixed-step methods also integrate resolved every interval with
  // a wheel in the creep band (InSwitchBand) at its start, and again one
  // whose end has one. zoh records only (its held-twist right-hand side has
  // no kink inside an interval). Off: nothing is located or recorded and no
  // interval is restarted or resolved. Runs without a switch, a reversal or
  // a wheel in the band are the same either way.
  bool locate_switches = true;
  // QuasiStaticOptions::stall_iterations of those probe solves (switch
  // location and the slip quadrature; model.md §7.3 "Stall watch"); 0 =
  // off. The trajectory does not depend on the probes' roots beyond their
  // class, so a stalled probe may hand over to the homotopy at once; since
  // the probes start from interpolated solutions they rarely stall, and on
  // the paper scene the watch costs more than it saves (zoh, 20 s: 1975
  // Newton iterations at 10, 1923 off), hence off by default.
  int probe_stall_iterations = 0;
  // QuasiStaticOptions::stall_iterations of the zoh sample solves (the held
  // twist; model.md §7.3 "Stall watch"); 0 = patient. A Newton that stalls
  // there mostly ends in the homotopy anyway, after up to max_iterations
  // (paper scene: 3 of its 4 long sample solves); with the watch the held
  // twist of a solve that would have converged patiently comes from the
  // homotopy's root instead, which moves a zoh trajectory at round-off
  // (paper scene, 20 s: 5e-15 m). Coupled solves stay patient (their roots
  // feed the integrator's stages).
  int zoh_stall_iterations = 10;
  // Coupled mode, fixed-step integrators: those segments, and every
  // interval starting within kSwitchResolveWindow after a located switch,
  // are integrated with step doubling until one step and two half steps
  // agree to max(switch_step_tolerance, kSwitchToleranceRate h^4), h the step
  // (infinity norm of Theta; SwitchResolutionTolerance), down to pieces of
  // kSwitchMinStep (core/switch_events.h, "Resolution"). This is the floor,
  // reached at h <= 0.13 s.
  double switch_step_tolerance = 1e-12;
  bool IsValid(std::string* why) const;
};

struct ContactSample {
  Vec3 point = Vec3::Zero();
  double normal_force = 0, traction_lon = 0, traction_lat = 0;
  double slip = 0;  // |s_i| [m/s]
  double friction_use = 0;
  // Cumulative since the start, int |s_i| dt split by regime
  // (core/slip_regimes.h): while on the friction cone, and the
  // regularisation's creep below it (proportional to epsilon) [m].
  double sliding_distance = 0, creep_distance = 0;
};

// One output row (docs/formats.md, trajectory.csv).
struct TrajectorySample {
  double t = 0;
  Vec3 position = Vec3::Zero();          // COM, world [m]
  Vec3 rpy = Vec3::Zero();               // [rad]
  Vec3 velocity = Vec3::Zero();          // COM velocity, world frame [m/s]
  Vec3 angular_velocity = Vec3::Zero();  // world frame [rad/s]
  std::array<double, 6> joints{};
  std::array<ContactSample, 3> contacts;
  double drift = 0;    // ||H(Theta)||_inf
  double gap_max = 0;  // max_i |terrain height - wheel lowest point| [m]
  std::string nlp_status;
  int nlp_iterations = 0;
  Configuration theta = Configuration::Zero();
};

// The physical limit a run stopped on (model.md §8.6); limit "" when the run
// met none (success, or a numerical stop).
struct StopEvent {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  // relative_curvature, tread_angle, second_contact, outside_terrain
  // (DEGENERATE_CONTACT), friction_limit, lift_off, singular.
  std::string limit;
  int wheel = -1;  // 1-based, -1 if none
  // located: the crossing was bracketed in [t_lower, t_upper] with
  // t_upper - t_lower <= tolerance on the run's own states, and the run
  // stopped at t (one of the two ends, = t_reached). Not located (locating
  // off, or the first sample): the bracket is the sample interval.
  bool located = false;
  double t = kNaN, t_lower = kNaN, t_upper = kNaN, tolerance = kNaN;
  // The indicators (core/limit_events.h) at the stop state, and the
  // quasi-static solve's mu_min and smallest normal force there (NaN unless
  // computed).
  LimitIndicators indicators;
  double mu_min = kNaN, min_normal_force = kNaN;
};

struct SimulationResult {
  // "success", a quasi-static status ("INFEASIBLE_FRICTION", ...) or an
  // integrator status ("step_size_too_small", ...).
  std::string status = "not_run";
  std::string stop_reason;  // human-readable, "" on success
  double t_reached = 0;
  double mu_min_at_stop = std::numeric_limits<double>::quiet_NaN();
  int critical_contact = -1;  // 1-based wheel, -1 if none
  // The configuration at which the run stopped (for a quasi-static failure
  // inside the integrator, the stage state where the solve failed), so the
  // failure can be reproduced with the quasi-static solver alone.
  Configuration stop_configuration =
      Configuration::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<TrajectorySample> samples;
  // The method's state at SimulationOptions::checkpoints up to the stop
  // (core/checkpoints.h: dense output; forces held in zoh, solved in
  // coupled mode); cumulative slip distances NaN.
  std::vector<TrajectorySample> checkpoints;
  // Quasi-static solves made for checkpoints (coupled mode), not in
  // nlp_solves / nlp_iterations; their time is not in wall_seconds.
  int checkpoint_solves = 0;
  long long checkpoint_iterations = 0;
  // The located physical stop (limit "" if none).
  StopEvent event;
  // The twist at or just before the stop, solved after the run (not in the
  // counters or wall_seconds), as a sample at that state's time: after a
  // SOLVER_FAILURE stop the stop's state solved again from a cold start
  // (Simulator::RetryStop: which state, which backend); zoh, otherwise, the
  // last root followed from the last sample's along the held twist when it
  // is lost before the stop (Simulator::ApproachStop). A root whose twist
  // dwarfs the samples' before it is the quasi-static breakaway of model.md
  // §8.8 (the minimum-energy problem's twist diverges along the path), not
  // a solver's stall; QuasiStaticInertiaRatio(result, scene) reads it.
  // Empty otherwise, or when no such state solves.
  std::optional<TrajectorySample> stop_retry;
  // The located stick/slide switches and creeping wheels' slip reversals
  // (SwitchEvent::reversal), in time order (locate_switches).
  std::vector<SwitchEvent> switches;
  // Cost counters.
  int nlp_solves = 0;
  long long nlp_iterations = 0;         // comparable count (core/nlp.h)
  long long nlp_iterations_native = 0;  // the backends' own counts
  long long rhs_evaluations = 0;
  long long jacobian_evaluations = 0;
  int steps = 0;
  int rejected_steps = 0;
  // IntegratorResult::step_drift_max over every integration of the run: the
  // loop-closure drift the method commits within its steps, before any
  // projection (samples show ||H|| after it).
  double step_drift_max = 0;
  double wall_seconds = 0;
  // Max over the run's accepted quasi-static solves (output times and, in
  // coupled mode, every right-hand side) of NlpResult::kkt_residual, the
  // independently recomputed first-order optimality residual (core/nlp.h);
  // NaN if no solve was accepted.
  double kkt_residual = std::numeric_limits<double>::quiet_NaN();
  // The backend options the run used: every option of each backend's table
  // (given ones and defaults), as in Ceres' Solver::Summary.
  OptionValues nlp_options, dae_options;
  bool success() const { return status == "success"; }
};

// Largest vertical distance between the terrain and each wheel's lowest point
// (relative to the terrain), from the platform pose of chain 1 and the joint
// angles by a closest-point search over the torus: an independent check of
// the contact kinematics (0 for exact contact). Newton's method on the
// torus coordinates (u, v) from the state's own contact coordinates stops
// once its predicted decrease g^T H^-1 g / 2 of the clearance is at most
// `resolution` [m]. The default is the clearance's own rounding (ulp of a
// 0.1 m height: 1.4e-17 m), so that a state on the contact manifold costs
// one evaluation per wheel; 0 iterates until no step decreases it.
inline constexpr double kGapResolution = 1e-17;
double GeometricGap(const KinematicModel& model, const Configuration& theta,
                    double resolution = kGapResolution);

// The robot ODE as the integrators see it (core/dae.h), evaluated at one
// state by Simulator::ProbeOde (tests, diagnostics): F = Theta' and
// dF/dTheta (ConstrainedOde::RhsJacobian, model.md §8.9).
struct RobotOdeProbe {
  bool rhs_ok = false;       // Rhs returned true
  bool jacobian_ok = false;  // RhsJacobian returned true (false: fallback)
  Configuration rhs = Configuration::Zero();
  Eigen::Matrix<double, kConfigSize, kConfigSize> jacobian =
      Eigen::Matrix<double, kConfigSize, kConfigSize>::Zero();
  int nlp_solves = 0;          // solves made by the probe
  int jacobian_fallbacks = 0;  // RhsJacobian calls so far that returned false
};

class Simulator {
 public:
  // Backends are looked up by name in the registries: call
  // RegisterBuiltinNlpSolvers() / RegisterBuiltinIntegrators() (and register
  // any plugin) first. Throws std::invalid_argument for unknown backend names
  // or invalid options
  // and GeometryError if the scene has no valid initial configuration.
  Simulator(const Scene& scene, const SimulationOptions& options);
  ~Simulator();

  const Configuration& initial_configuration() const { return theta0_; }
  const KinematicModel& model() const { return *model_; }
  const SimulationOptions& options() const { return options_; }
  double dt() const { return dt_; }
  double t_end() const { return t_end_; }
  // The backend options in effect (every option of the tables).
  const OptionValues& nlp_options_used() const;
  const OptionValues& dae_options_used() const;

  SimulationResult Run() { return Run(theta0_); }
  // Starts from a given configuration instead of the scene's consistent one
  // (e.g. a perturbed start to study constraint stabilisation).
  SimulationResult Run(const Configuration& theta0);

  // Stepping API (Run() is Begin() then Advance() until false). Advance()
  // solves at t_k, records the sample and integrates to t_{k+1}; it returns
  // false once the run has ended (end time, or a stop). The solver,
  // integrator and workspaces persist across Begin() calls, so a warmed-up
  // Advance() does not allocate (tests/core/test_simulator.cc checks it).
  void Begin(const Configuration& theta0, SimulationResult* result);
  bool Advance(SimulationResult* result);

  // Evaluates the run's ODE at theta: zoh with the twist held at the
  // quasi-static solve at `hold`, coupled re-solving at theta (`hold`
  // unused). Uses the run's solver (its warm start moves), so call it
  // between runs, not inside one.
  RobotOdeProbe ProbeOde(const Configuration& theta, const Configuration& hold);

 private:
  class RobotOde;
  struct Session;
  bool Interval(SimulationResult* result);
  // Located stops.
  struct Bracket;
  IntegratorStatus Reintegrate(double t0, const Configuration& theta0,
                               double t1);
  void Bisect(double t0, const Configuration& theta0, bool solve, Bracket* br);
  bool CheckIntervalEvents(double t0, double t1);
  bool ScanInterval(double t0, double t1);
  bool LocateSampleStop(double* t, SimulationResult* result);
  bool LocateIntegratorStop(double t0, const Configuration& theta0, double t1,
                            SimulationResult* result);
  bool MarchToStop(double t0, const Configuration& theta0, double t1,
                   SimulationResult* result);
  bool StopAtMarch(const ResolvedStop& stop, SimulationResult* result);
  void RecordIntegratorStop(double t, const Configuration& theta,
                            const QuasiStaticSolution& sol, const char* where,
                            SimulationResult* result);
  void SetStopEvent(double t, SimulationResult* result) const;
  // Switches (core/switch_events.h): locates class changes between the last
  // sample and s.sol at t; in coupled mode restarts the interval there.
  void CreateProbeSolver();
  void SizeProbeSolvers(SimulationResult* result);
  bool JumpSuspected(bool structure_changed);
  const Eigen::VectorXd& InterpolateKnown(double tm, double t_end);
  void RestartAtSwitches(double t, SimulationResult* result);
  // The class test's slips at the sample just solved (session class_now).
  void ClassSlips(SimulationResult* result);
  void RetryStop(SimulationResult* result);
  void ApproachStop(SimulationResult* result);
  std::unique_ptr<QuasiStaticSolver> StopSolver() const;
  // Solution jumps (core/solution_jumps.h) between the last sample and t:
  // appends their events; true if one was located.
  bool LocateSolutionJump(double t, SimulationResult* result);
  // The interval's state at tm (RestartAtSwitches: cubic Hermite on the
  // ends' states and slopes, else linear).
  Configuration DenseState(double tm) const;
  // Stores a converged probe of the interval (warm-start node, slip cache).
  void RememberProbe(double tm, const QuasiStaticSolution& sol);
  // One probe solve on the probe solver at q (from *warm when given),
  // refined to the location tolerance when refine, counted in result.
  void SolveProbe(const Configuration& q, const Eigen::VectorXd* warm,
                  bool refine, QuasiStaticSolution* probe,
                  SimulationResult* result);
  void IntegrateSlipAcrossSwitches(double t, std::size_t first,
                                   const SlipVectorEvaluator& evaluate,
                                   SimulationResult* result);
  double SwitchStepTolerance() const;
  SegmentAdvance Advance();
  IntegratorStatus IntegrateInterval(double t, double t_next);
  IntegratorStatus StopResolved(const ResolvedStop& stop);
  void Record(double t, const Configuration& theta,
              const QuasiStaticSolution& sol, SimulationResult* result,
              int index, const SlipIncrements* increments = nullptr) const;

  Scene scene_;
  SimulationOptions options_;
  double dt_ = 0, t_end_ = 0;
  std::unique_ptr<KinematicModel> model_;
  Configuration theta0_;
  std::unique_ptr<Session> session_;
};

}  // namespace quasiroll
