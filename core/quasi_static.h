// The quasi-static problem of one configuration (model.md §7; paper §IV,
// eqs. (10)-(11), (19)-(22) replaced as explained in model.md §7.4).
//
// Unknowns z = (V^B, qdot_p, f), f_i = (f_x, f_y, f_n) in the wheel contact
// frame {C_W}; the force of the ground on wheel i is F_i = R_GCW (f_x, f_y,
// -f_n). With w(z) = (V^B, thetadot(z)) and [v; omega]_i = L_i w
// (kinematics.h):
//   E1  v_zi = 0                                           (3)
//   E2  sum_i L_i^{vV T} f~_i + [R^T m g_vec; 0] = 0        (6)
//   E3  tau_j = sum_i L_i^{v theta_j T} f~_i = 0, j passive (n_p, pvc only)
//   C   sigma_i f_ti + mu f_ni s_i = 0,
//       sigma_i = sqrt(|s_i|^2 + eps^2), s_i = (v_x, v_y)_i  (6)
//   I1  f_ni >= 0 (variable bounds),  I2  mu^2 f_ni^2 - |f_ti|^2 >= 0  (3)
//   min J = 1/(2 (m g)^2) sum_i |f_ti|^2   (tie-break only: the equality
//   system is square, 15 x 15 in paper mode and 18 x 18 in pvc mode).
//
// Everything the NlpProblem interface sees is scaled (model.md §7.3):
// v0 = max(rho max|thetadot_d|, 0.01), F0 = m g, L0 = a + b; variables
// v^B/v0, omega^B/(v0/L0), qdot_p/(v0/rho), f/F0; rows E1/v0, E2 force rows
// /F0, E2 moment rows and E3 /(F0 L0), C/(F0 v0), I2/F0^2.
// Variable order: [v^B (3), omega^B (3), qdot_p (n_p), f_1, f_2, f_3 (3 each)].
// Row order: [E1 (3), E2 (6), E3 (n_p), C (6), I2 (3)].
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <memory>
#include <string>

#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/scene.h"

namespace quasiroll {

struct QuasiStaticParameters {
  double mass = 5.0;
  double gravity = 9.8;
  double mu = 0.5;
  double epsilon = 1e-8;  // regularisation velocity [m/s]
  ActuationMode mode = ActuationMode::kPaper;
  std::array<double, 6> joint_rates = {0, 0.6, 0, 0.6, 0, 0.6};

  static QuasiStaticParameters FromScene(const Scene& scene);
  bool IsValid(std::string* why) const;
};

class QuasiStaticProblem final : public NlpProblem {
 public:
  static constexpr int kMaxVariables = 18;
  static constexpr int kMaxRows = 21;

  // `model` must outlive the problem.
  QuasiStaticProblem(const KinematicModel& model,
                     const QuasiStaticParameters& params);

  // Evaluates the chains and all maps that are constant for fixed Theta.
  void SetConfiguration(const Configuration& theta);
  void set_mu(double mu) { params_.mu = mu; }
  void set_epsilon(double epsilon) { params_.epsilon = epsilon; }
  // Sets the commanded joint rates (passive entries are ignored) and keeps
  // the scaling v0 of construction, so z keeps its meaning (sensitivity.h).
  void set_joint_rates(const std::array<double, 6>& rates);
  const QuasiStaticParameters& parameters() const { return params_; }
  const Configuration& configuration() const { return theta_; }
  const std::array<ChainState, 3>& chains() const { return chains_; }

  int num_passive() const { return num_passive_; }
  int num_motion() const { return 6 + num_passive_; }
  int num_equalities() const { return 15 + num_passive_; }
  // Indices into theta of the passive joints (pvc: alpha1, delta2, delta3).
  const std::array<int, 3>& passive_joints() const { return passive_; }

  // NlpProblem.
  int num_variables() const override { return 15 + num_passive_; }
  int num_constraints() const override { return 18 + num_passive_; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& z) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& z,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& z,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& z,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;

  // Cold-start guess (model.md §7.3): f = least-norm solution of E2(+E3);
  // motion = least-squares solution of s_i = 0, v_zi = 0.
  void ColdStartGuess(Eigen::Ref<Eigen::VectorXd> z) const;

  // Physical joint-space velocity w = (V^B, thetadot) of a scaled z.
  Vec12 JointSpaceVelocity(const Eigen::Ref<const Eigen::VectorXd>& z) const;
  // Max |scaled equality residual| at z.
  double EqualityResidual(const Eigen::Ref<const Eigen::VectorXd>& z) const;
  // 2-norm condition number of the scaled equality Jacobian at z.
  double ConditionNumber(const Eigen::Ref<const Eigen::VectorXd>& z) const;

  // (v_x, v_y, v_z) of the three contacts [m/s] at scaled unknowns z.
  Eigen::Matrix<double, 9, 1> ContactLinearVelocities(
      const Eigen::Ref<const Eigen::VectorXd>& z) const;
  // Constraints g with the contact velocities `vel` (9) given instead of
  // those of z (Constraints(z) = this with vel = ContactLinearVelocities(z)).
  void ConstraintsAtVelocities(const Eigen::Ref<const Eigen::VectorXd>& z,
                               const Eigen::Matrix<double, 9, 1>& vel,
                               Eigen::Ref<Eigen::VectorXd> g) const;
  // dg/dvel at fixed forces (num_constraints x 9): E1 and C rows only, the
  // C blocks dC/ds / v0 of model.md §7.3.
  void ConstraintVelocityJacobian(const Eigen::Ref<const Eigen::VectorXd>& z,
                                  Eigen::Ref<Eigen::MatrixXd> dg_dvel) const;

  // Static friction requirement mu_min (model.md §7.7): min over forces
  // satisfying E2(, E3), f_n >= 0 of max_i |f_ti|/f_ni. +inf when no such
  // force exists (lift-off). `critical` receives the contact that attains it
  // (or the one that would have to pull). Paper mode: bisection on t with a
  // smoothed convex feasibility test, to relative width
  // `relative_tolerance` (the solver's classification uses 1e-11); pvc mode:
  // explicit.
  double MinimumFriction(int* critical, double* min_normal_force,
                         double relative_tolerance = 1e-11) const;

  // True if the statics rows (E2, E3) have full row rank.
  bool StaticsFullRank() const;

  double v0() const { return v0_; }
  double F0() const { return f0_; }
  double L0() const { return l0_; }
  double rho() const { return rho_; }

 private:
  // What the constraints at z and their Jacobian both start from.
  struct ConstraintTerms {
    int nm, ns;                          // motion unknowns, statics rows
    Eigen::Matrix<double, 9, 1> f, vel;  // contact forces, linear velocities
    double inv_v0, mu, eps2;             // 1 / v0, mu, epsilon^2
  };
  ConstraintTerms Terms(const Eigen::Ref<const Eigen::VectorXd>& z,
                        const Eigen::Matrix<double, 9, 1>& vel) const;
  // dC_i/ds_i = f_t s^T / sigma + mu f_n I (model.md §7.3), unscaled.
  static Mat2 SlipDerivative(const Vec2& s, const Vec2& ft, double fn,
                             double mu, double eps2);

  const KinematicModel& model_;
  QuasiStaticParameters params_;
  int num_passive_ = 0;
  std::array<int, 3> passive_ = {-1, -1, -1};
  double v0_ = 0, f0_ = 0, l0_ = 0, rho_ = 0;

  Configuration theta_ = Configuration::Zero();
  std::array<ChainState, 3> chains_;
  std::array<ContactVelocityMap, 3> L_;
  // Contact linear velocities (v_x, v_y, v_z) of all contacts, affine in the
  // scaled motion unknowns m: vel = vel_m_ * m + vel_0_.
  Eigen::Matrix<double, 9, Eigen::Dynamic, 0, 9, 9> vel_m_;
  Eigen::Matrix<double, 9, 1> vel_0_;
  // Statics rows (scaled E2, E3) = statics_f_ * fhat + statics_0_.
  Eigen::Matrix<double, Eigen::Dynamic, 9, 0, 9, 9> statics_f_;
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 9, 1> statics_0_;
  // Scaling of motion unknowns: physical = motion_scale_ .* scaled.
  Eigen::Matrix<double, 12, Eigen::Dynamic, 0, 12, 9> w_from_m_;
  Vec12 w_fixed_;
};

enum class QuasiStaticStatus {
  kOk,
  kLiftOff,
  kInfeasibleFriction,
  kDegenerateContact,
  kSingular,
  kSolverFailure,
};
const char* ToString(QuasiStaticStatus status);  // "OK", "LIFT_OFF", ...

struct ContactOutput {
  Vec3 point = Vec3::Zero();        // contact point (world)
  double normal_force = 0.0;        // F . n_g [N]
  Vec2 traction = Vec2::Zero();     // (longitudinal, lateral) [N]
  Vec3 force_world = Vec3::Zero();  // F_i [N]
  Vec2 slip = Vec2::Zero();         // s_i in {C_W} [m/s]
  double normal_velocity = 0.0;     // v_z [m/s]
  double friction_use = 0.0;        // |f_t| / (mu f_n)
};

struct QuasiStaticSolution {
  QuasiStaticStatus status = QuasiStaticStatus::kSolverFailure;
  Vec6 twist = Vec6::Zero();            // V^B = (v^B, omega^B)
  std::array<double, 6> joint_rates{};  // incl. passive rates
  std::array<ContactOutput, 3> contacts;
  // Actuator torques of actuated joints [N m]; NaN for passive joints.
  std::array<double, 6> actuator_torques{};
  double gap = 0.0;           // bipotential gap G [W]
  double mu_min = 0.0;        // NaN unless computed (failure or requested)
  int critical_contact = -1;  // contact naming the failure (0-based)
  double min_normal_force = 0.0;
  double residual = 0.0;  // max scaled equality residual
  // First-order optimality residual of the accepted NLP solve
  // (NlpResult::kkt_residual, core/nlp.h); NaN unless status is kOk.
  double kkt_residual = std::numeric_limits<double>::quiet_NaN();
  double condition_number = 0.0;  // NaN unless requested
  NlpStatus nlp_status = NlpStatus::kNotRun;
  int nlp_iterations =
      0;  // summed over homotopy stages (NlpResult::iterations)
  int nlp_iterations_native = 0;  // NlpResult::native_iterations, summed
  int nlp_solves = 0;
  double wall_seconds = 0.0;
  std::string message;  // why, for non-OK statuses
  Eigen::VectorXd z;    // scaled unknowns (warm start)
};

struct QuasiStaticOptions {
  // Accept when max |scaled equality residual| <= residual_tolerance
  // (model.md §7.3: 1e-12 on the scaled system).
  double residual_tolerance = 1e-12;
  int max_iterations = 100;
  // Try the epsilon homotopy and a cold start when the warm solve fails.
  bool homotopy = true;
  // NlpOptions::stall_iterations of the first attempts (0 = off): a backend
  // that stalls gives up early and the fallbacks above take over; only if
  // they fail too are the attempts repeated without the stall watch
  // (model.md §7.3). Newton near a stick/slip switch can creep for tens of
  // iterations at |r| ~ 1e-9 before it converges. Off by default: the root
  // a fallback finds instead differs within the problem's conditioning, and
  // a trajectory that depends on it moves at round-off; the simulator sets it
  // for its zoh sample solves and its probe solves (SimulationOptions::
  // zoh_stall_iterations, probe_stall_iterations).
  int stall_iterations = 0;
  // Compute mu_min and the condition number at every solve (costly in paper
  // mode); they are always computed on failure.
  bool diagnostics = false;
  // Also hand the previous solve's constraint multipliers to the backend
  // (only Ipopt uses them). Off by default: on the paper scene Ipopt's
  // primal-dual warm start took 11 iterations (11 ms) per step against 6
  // (3.8 ms) from the primal point alone (docs/performance.md).
  bool warm_start_multipliers = false;
  // Start from the linear extrapolation 2 z_k - z_{k-1} of the last two
  // solutions instead of z_k. Pays off for solves along a path at regular
  // steps (zoh: 2199 -> 1500 Newton iterations on the paper scene), not for
  // the stage states of coupled mode (5433 -> 8591), so off by default; the
  // simulator turns it on in zoh mode.
  bool extrapolate_warm_start = false;
  // Classify a failed solve (mu_min and the statics' rank, model.md §7.7:
  // ~1 ms in paper mode). Off only where failures are expected and carry
  // no physical meaning: the continuation steps of core/solution_jumps.h,
  // which then report SOLVER_FAILURE.
  bool classify_failures = true;
  bool IsValid(std::string* why) const;
};

// Solves the quasi-static problem with a pluggable NLP backend, warm-started
// from its previous solution, with the fallbacks of model.md §7.3 and the
// classification of §7.7.
class QuasiStaticSolver {
 public:
  QuasiStaticSolver(const KinematicModel& model,
                    const QuasiStaticParameters& params,
                    std::unique_ptr<NlpSolver> nlp,
                    const QuasiStaticOptions& options = {});

  // Status is also stored in *out. Never throws for numerical trouble.
  QuasiStaticStatus Solve(const Configuration& theta, QuasiStaticSolution* out);
  // Re-solves from *out (a kOk solution of the last Solve()) to the tighter
  // residual tolerance `tolerance`; on success *out becomes the refined
  // solution and the warm start, else *out keeps its solution (its counters
  // include the attempt). False if not attempted or not reached.
  bool Refine(double tolerance, QuasiStaticSolution* out);
  // Forget the warm start.
  void Reset() { have_warm_ = have_previous_ = false; }
  // Start the next Solve() from z (scaled unknowns, num_variables() rows),
  // as if the last solve had returned it (no extrapolation from it).
  void SetWarmStart(const Eigen::VectorXd& z) {
    warm_z_ = z;
    have_warm_ = true;
    have_previous_ = false;
  }

  QuasiStaticProblem& problem() { return problem_; }
  const NlpSolver& nlp() const { return *nlp_; }
  const QuasiStaticOptions& options() const { return options_; }

 private:
  bool TrySolve(const Eigen::VectorXd& z0, QuasiStaticSolution* out);
  // The epsilon homotopy from a cold start, then a cold start at epsilon.
  bool HomotopyAndColdStart(QuasiStaticSolution* out);
  void FillOutputs(QuasiStaticSolution* out) const;
  void Classify(QuasiStaticSolution* out);

  const KinematicModel& model_;
  QuasiStaticProblem problem_;
  std::unique_ptr<NlpSolver> nlp_;
  QuasiStaticOptions options_;
  NlpOptions nlp_options_;
  NlpResult result_;
  // z0_: this Solve()'s start (kept for the retry without the stall
  // watch); z_homotopy_: the homotopy's iterate.
  Eigen::VectorXd warm_z_, previous_z_, z0_, z_homotopy_;
  bool have_warm_ = false, have_previous_ = false;
  bool stalled_ = false;  // an attempt of this Solve() gave up on a stall
};

}  // namespace quasiroll
