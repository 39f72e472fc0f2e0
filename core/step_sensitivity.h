// The derivative of one whole hold interval (model.md §7.9): Theta_{k+1} =
// Phi(Theta_k, p), p = (mu, epsilon, commanded rates), for the explicit
// fixed-step integrators rk-projection and rk-baumgarte (RK4, `substeps`
// steps per interval), with its Jacobians dPhi/dTheta_k (21 x 21), dPhi/dmu,
// dPhi/deps (21) and dPhi/drates (21 x 6): what a planner or an optimiser
// linearising the simulator around a nominal interval would call.
//
// Value. The interval is the simulator's (core/simulator.h) with located
// switches and events off: the quasi-static twist w = (V^B, thetadot) is
// solved at Theta_k and held (zoh), or re-solved at every stage state
// (coupled); the RK4 arithmetic of integrators/runge_kutta.cc is replicated
// operation for operation (y_i = y + (h a_ij) k_j, y_new = y + sum (h b_j)
// k_j, step ends t0 + (s+1) h as the driver computes them), the field is
// F(Y, w) = KinematicModel::Rhs (rk-projection) or the Baumgarte field
//   g(Y, w) = F - D J^T (J D J^T)^{-1} (J F + sigma H)    (model.md §8.3)
// (rk-baumgarte), and rk-projection projects the initial state and every
// step's end with WeightedProjection::Project (model.md §8.4), the code the
// backend itself calls. The value agrees with a one-interval Simulator run
// to round-off in zoh and to the NLP tolerance in coupled mode (its stage
// solves are warm-started differently); measured: bit for bit in both
// (tests/core/test_step_sensitivity.cc). The simulator's other paths are
// not this map: coupled intervals it integrates resolved (step doubling,
// locate_switches with a wheel in the creep band) and located stops.
//
// Derivative (chain rule through the stages, the variational equations of
// the discrete map). Parameters pi = (Theta_k, mu, eps, rates), 29 columns
// in SensitivityParameter order; S = dY/dpi (21 x 29) of the state carried:
//   S_0 = [P(Theta_k) 0] (rk-projection) or [I 0] (rk-baumgarte),
//   stage i:  S_i  = S + h a_{i,i-1} dK_{i-1},
//             dw_i = W(Theta_k)                      (zoh: held twist)
//                  = W_Th(Y_i) S_i + [0 W_p(Y_i)]    (coupled),
//             dK_i = g_Y(Y_i, w_i) S_i + g_w(Y_i) dw_i,
//   step end: S <- S + h sum_i b_i dK_i, then S <- P(y_new) S (projection),
// with W = dw/dpi (12 x 29) = [twist; joint_rates] rows of the quasi-static
// sensitivities (SensitivityAnalyzer, model.md §7.8; IFT on the KKT system)
// at Theta_k (zoh) or at each stage state (coupled), and
//   g_Y  at fixed w by central differences of the field (kinematics only,
//        no NLP solve): F's by KinematicModel::RhsStateDerivative, the
//        Baumgarte field's column by column with its step
//        (core/central_difference_internal.h), error ~eps_mach^(2/3)
//        relative;
//   g_w  exact: F_w = KinematicModel::RhsTwistDerivative (F is linear in
//        w), and the Baumgarte correction is affine in F:
//        g_w = (I - D J^T (J D J^T)^{-1} J) F_w.
// Projection: at a converged projection y* = Pi(y), H(y*) = 0, y* - y in
// range(D J^T); differentiating J dy* = 0 and dy* - dy = D J^T dl gives, to
// first order in the distance moved (the drift of one step, ~1e-9),
//   dy* = P dy,   P = I - D J^T (J D J^T)^{-1} J   at y*,
// the D-oblique projector onto the tangent space (P D J^T = 0, J P = 0).
// The initial projection contributes P(Theta_k) always: the backend leaves
// a state with ||H||_inf <= projection_tolerance alone, a band of width
// 1e-12 no perturbation resolves; P is the derivative of the projection it
// stands for. Perturbations of Theta_k off H = 0 are meaningful only up to
// that; tangent directions (J dTheta = 0) are the planner's.
//
// Status, never a silently wrong value: a quasi-static failure, a right-hand
// side or projection failure (no value: NaN), a singular quasi-static
// Jacobian J_E at any solve (value, NaN derivatives), or an inequality about
// to become active at any solve (value and the one-sided derivative of the
// branch on which it stays inactive, kOneSided, the constraints named with
// the stage: "stage 2 of step 1: I2 wheel 3 (...)").
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/options.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/sensitivity.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/weighted_projection.h"

namespace quasiroll {

enum class StepSensitivityStatus {
  kOk,
  kOneSided,            // derivative of the inactive branch (names given)
  kSingular,            // J_E singular at a solve: value only
  kQuasiStaticFailure,  // a solve failed: no value
  kRhsFailure,          // KinematicModel::Rhs failed (curvature lost)
  kConstraintFailure,   // projection / J D J^T failed
  kNotComputed,
};
// "OK", "ONE_SIDED", "SINGULAR", "QUASI_STATIC_FAILURE", "RHS_FAILURE",
// "CONSTRAINT_FAILURE", "NOT_COMPUTED".
const char* ToString(StepSensitivityStatus status);

struct StepSensitivityOptions {
  std::string nlp = "newton";  // quasi-static backend (registry name)
  GivenOptions nlp_options;
  std::string dae = "rk-projection";  // rk-projection or rk-baumgarte
  std::string rk_method = "rk4";      // fixed step only (no adaptive pair)
  Coupling coupling = Coupling::kZoh;
  double dt = 0.05;  // interval length [s], > 0
  int substeps = 1;  // RK4 steps per interval (step dt / substeps)
  double t0 = 0.0;   // interval start: only for the driver's step ends
  double baumgarte_sigma = 5.0;   // rk-baumgarte's default
  ProjectionSettings projection;  // rk-projection's defaults
  QuasiStaticOptions quasi_static;
  // Activity / singularity tolerances of the quasi-static sensitivities
  // (their multipliers' derivatives are never computed here).
  SensitivityOptions sensitivity;
  bool derivatives = true;  // false: the value only
  // Throws nothing; *why names the field and value.
  bool IsValid(std::string* why) const;
};

struct StepSensitivityResult {
  using Jacobian =
      Eigen::Matrix<double, kConfigSize, SensitivityParameter::kCount>;
  // Chain rule through the RK4 stages, quasi-static sensitivities by the
  // IFT (core/sensitivity.h), the field's state derivative by differences.
  static constexpr const char* kMethod = "rk4-chain-rule+ift-kkt+central-fd";
  StepSensitivityStatus status = StepSensitivityStatus::kNotComputed;
  std::string message;  // why, for statuses other than kOk
  Configuration theta_next = Configuration::Zero();
  // d Theta_{k+1} / d pi, columns as SensitivityParameter: Theta_k (21), mu,
  // eps, rates (6). NaN where not computed.
  Jacobian jacobian = Jacobian::Zero();
  auto dstate() const {
    return jacobian.middleCols<kConfigSize>(SensitivityParameter::kState);
  }
  auto dmu() const { return jacobian.col(SensitivityParameter::kMu); }
  auto deps() const { return jacobian.col(SensitivityParameter::kEpsilon); }
  auto drates() const {
    return jacobian.middleCols<6>(SensitivityParameter::kRates);
  }
  std::vector<std::string> one_sided;  // constraints named, with the stage
  double min_rcond = 0.0;  // smallest J_E reciprocal condition over solves
  double drift = 0.0;      // ||H(Theta_{k+1})||_inf
  int quasi_static_solves = 0;
  // Field evaluations, incl. differences (F's evaluate one chain each).
  int rhs_evaluations = 0;
};

// The front ends' view (docs/cli.md, `solve --step-derivative`): entries
// dstate_next_dstate (21 x 21), dstate_next_dmu, dstate_next_deps (vectors)
// and dstate_next_drates (21 x 6); rows Theta_{k+1} (StateNames()).
std::vector<SensitivityEntry> StepSensitivityEntries(
    const StepSensitivityResult& result);

// One interval and its derivative, with preallocated workspaces: after the
// first call Compute() does not allocate (messages and one-sided names
// aside; tests/core/test_step_sensitivity.cc counts it).
class StepSensitivity {
 public:
  // `model` must outlive this. Validates options (std::invalid_argument
  // naming the field and value: dt, substeps, dae, rk_method, ...) and
  // creates the NLP backend (NlpSolverRegistry: register it first).
  StepSensitivity(const KinematicModel& model,
                  const QuasiStaticParameters& params,
                  const StepSensitivityOptions& options);
  ~StepSensitivity();

  // Theta_{k+1} and its derivatives from Theta_k = theta (finite, else
  // std::invalid_argument). The solver starts cold for every call.
  StepSensitivityStatus Compute(const Eigen::Ref<const Configuration>& theta,
                                StepSensitivityResult* out);

  const StepSensitivityOptions& options() const { return options_; }
  const QuasiStaticParameters& parameters() const { return params_; }

 private:
  class FieldOde;
  using ParamJac = Eigen::Matrix<double, 12, SensitivityParameter::kCount>;
  using StateJac = StepSensitivityResult::Jacobian;

  // Solves at y (and the sensitivities there if wanted) into w_, dw_dpi_.
  bool SolveAt(const Configuration& y, StepSensitivityResult* out);
  // "Theta_k" or "stage i of step s" (1-based) for messages and names.
  std::string Where() const;
  // Field value at (y, w); false on failure (status set in out).
  bool Field(const Configuration& y, const Vec12& w, Configuration* f,
             StepSensitivityResult* out);
  // dK = g_Y S + g_w dw at (y, w), g_Y and g_w as above.
  bool FieldDerivative(const Configuration& y, const Vec12& w,
                       const StateJac& s, const ParamJac& dw, StateJac* dk,
                       StepSensitivityResult* out);
  // The stage's twist and its derivative: held (zoh) or solved at y.
  bool StageTwist(const Configuration& y, const StateJac& s,
                  StepSensitivityResult* out);
  // P = I - D J^T (J D J^T)^{-1} J at y.
  bool Projector(const Configuration& y, Eigen::Matrix<double, 21, 21>* p,
                 StepSensitivityResult* out);
  bool Project(Configuration* y, StepSensitivityResult* out);
  bool RkStep(double h, int step, Configuration* y, StateJac* s,
              StepSensitivityResult* out);
  void Fail(StepSensitivityStatus status, const std::string& message,
            StepSensitivityResult* out) const;

  const KinematicModel& model_;
  QuasiStaticParameters params_;
  StepSensitivityOptions options_;
  bool baumgarte_ = false;
  std::unique_ptr<QuasiStaticSolver> solver_;
  SensitivityAnalyzer analyzer_;
  QuasiStaticSensitivities sens_;
  QuasiStaticSolution sol_;
  std::unique_ptr<FieldOde> ode_;
  WeightedProjection correction_;
  IntegratorResult counters_;  // WeightedProjection's bookkeeping
  Eigen::VectorXd yv_, fv_;    // dynamic views for WeightedProjection
  Vec12 w_ = Vec12::Zero(), w_held_ = Vec12::Zero();
  ParamJac dw_ = ParamJac::Zero(), dw_held_ = ParamJac::Zero();
  bool have_singular_ = false;
  int stage_ = -1, step_ = 0;  // where the interval is (Where())
};

// Convenience: the scene's model and parameters, Theta_k = the scene's
// initial configuration when theta is null. The caller registers the NLP
// backends first (as for Simulator).
StepSensitivityResult ComputeStepSensitivity(
    const Scene& scene, const StepSensitivityOptions& options,
    const Configuration* theta = nullptr);

}  // namespace quasiroll
