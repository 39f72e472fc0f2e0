// Explicit Runge-Kutta stepping shared by rk-baumgarte and rk-projection.
//
// RungeKuttaDriver integrates y' = f(t, y) for a vector field supplied by an
// RkSystem (rk-baumgarte: the corrected field; rk-projection: plain F plus a
// projection after every accepted step):
//   * RK4 (classic, order 4): fixed step options.step (0 = one step over
//     [t0, t1]); the step count is ceil((t1 - t0) / step) and the last step is
//     shortened so that it ends exactly on t1.
//   * Dormand-Prince 5(4) and Bogacki-Shampine 3(2): embedded pairs, FSAL,
//     local extrapolation (the higher order solution is propagated). Error
//     norm  ||e_i / (atol + rtol * max(|y_i|, |y_new,i|))||_rms <= 1; the step
//     controller is h_new = h * min(max_growth, max(max_shrink,
//     safety * err^(-1/(q+1)))) with q the embedded (lower) order (defaults
//     5, 0.2, 0.9), and no growth right after a rejection.
//     First step: options.step if > 0, else the starting-step heuristic of
//     Hairer, Norsett & Wanner, "Solving ODEs I", II.4 (algorithm on p. 169):
//       d0 = ||y0||, d1 = ||f(t0, y0)||  (the error norm's weights),
//       h0 = 0.01 d0 / d1 (1e-6 if either is < 1e-5),
//       d2 = ||f(t0 + h0, y0 + h0 f0) - f0|| / h0,
//       h1 = (0.01 / max(d1, d2))^(1/(p+1)) (max(1e-6, 1e-3 h0) if both
//            are <= 1e-15),  h = min(100 h0, h1, t1 - t0).
//     A trial step whose stage field or post-step correction fails with
//     kConstraintFailure (J D J^T singular at a stage state far off the
//     manifold, a projection that does not converge from a long step) is
//     rejected like an error-test failure and retried with the step times
//     stage_failure_shrink; only below min_step does the failure stop the
//     integration. (A failure at an accepted state cannot be retried.)
//   * Events: after each accepted step the sign of ode.Roots is compared with
//     the previous one; on a change the root is located by re-stepping from
//     the last accepted state with a shortened step (Illinois regula falsi on
//     the step fraction), so the returned state is an actual RK solution (and
//     projected, for rk-projection). A component that is exactly 0 at the
//     start of a step does not fire.
// The driver owns every workspace; once sized for a problem it performs no
// heap allocation.
#pragma once

#include <Eigen/Core>
#include <string>

#include "quasiroll/core/dae.h"

namespace quasiroll::integrators_internal {

enum class RkMethod { kRk4, kDormandPrince54, kBogackiShampine32 };
const char* ToString(RkMethod method);  // "rk4", "dp54", "bs32"
// Throws std::invalid_argument naming the value on an unknown name.
RkMethod RkMethodFromString(const std::string& name);

// Settings of the Runge-Kutta driver (backend options of rk-baumgarte and
// rk-projection; RkOptionTable() documents them).
struct RkSettings {
  RkMethod method = RkMethod::kRk4;
  double safety = 0.9;
  double max_growth = 5.0;
  double max_shrink = 0.2;
  double stage_failure_shrink = 0.25;
};
// A backend's own options followed by those shared by the RK backends:
// rk_method, safety, max_growth, max_shrink, stage_failure_shrink.
OptionTable RkOptionTable(OptionTable own);
RkSettings RkSettingsFrom(const OptionValues& values);

// Butcher tableau, explicit (a strictly lower triangular).
struct ButcherTableau {
  int stages = 0;
  int order = 0;           // order of the propagated solution b
  int embedded_order = 0;  // order of b_hat; 0 = no error estimate
  bool fsal = false;       // last stage is f(t + h, y_new)
  Eigen::MatrixXd a;
  Eigen::VectorXd b, b_hat, c;
};

const ButcherTableau& Tableau(RkMethod method);

// f = ode.Rhs(t, y), counted in result->rhs_evaluations. Returns kSuccess, or
// kRhsFailure with result->message set when Rhs returned false.
IntegratorStatus EvaluateRhs(ConstrainedOde& ode, double t,
                             const Eigen::Ref<const Eigen::VectorXd>& y,
                             Eigen::Ref<Eigen::VectorXd> f,
                             IntegratorResult* result);

class RkSystem {
 public:
  virtual ~RkSystem() = default;
  // f = field(t, y). Returns kSuccess, or the failure status (result->message
  // set), e.g. kRhsFailure when ConstrainedOde::Rhs returned false.
  virtual IntegratorStatus Field(double t,
                                 const Eigen::Ref<const Eigen::VectorXd>& y,
                                 Eigen::Ref<Eigen::VectorXd> f,
                                 IntegratorResult* result) = 0;
  // Called on every new state (accepted step or root-location trial) before
  // its roots are evaluated; may modify y. *moved reports whether it did.
  virtual IntegratorStatus PostStep(double /*t*/,
                                    Eigen::Ref<Eigen::VectorXd> /*y*/,
                                    IntegratorResult* /*result*/, bool* moved) {
    *moved = false;
    return IntegratorStatus::kSuccess;
  }
};

class RungeKuttaDriver {
 public:
  // Integrates from (t0, y) to t1; sets result->status / t_reached /
  // root_index / message, increments steps / rejected_steps. On failure y is
  // the last accepted state.
  void Run(RkSystem& system, ConstrainedOde& ode, double t0, double t1,
           Eigen::Ref<Eigen::VectorXd> y, const IntegratorOptions& options,
           const RkSettings& settings, IntegratorResult* result);

 private:
  // One RK step of size h from (t, y_) into y_new_ (and err_ if embedded).
  // Stage 0 must already be in k_.col(0).
  IntegratorStatus Step(RkSystem& system, const ButcherTableau& tab, double t,
                        double h, IntegratorResult* result);
  // State of one Run(): the interval, the last accepted time and the step
  // size control.
  struct RunState {
    double t0 = 0.0, t1 = 0.0, span = 0.0;
    double t = 0.0;  // time of y_, the last accepted state
    double h = 0.0;  // next trial step (adaptive)
    bool adaptive = false;
    int fixed_steps = 1;  // RK4: steps over [t0, t1]
    int accepted = 0;
    bool last_rejected = false;
    double exponent = 0.0;  // -1 / (q + 1), q the embedded order
  };
  enum class ErrorTest { kAccepted, kRejected, kStepTooSmall };

  // Fixed step count (RK4) or first trial step (embedded pairs, options.step
  // given). False (message set) when RK4 would need more than max_steps.
  bool PlanSteps(const ButcherTableau& tab, const IntegratorOptions& options,
                 RunState* s, IntegratorResult* result) const;
  // End time and size of the next trial step. False (message set) when
  // max_steps or min_step stop an adaptive integration.
  bool NextTrial(const IntegratorOptions& options, const RunState& s,
                 double* t_new, double* h_try, IntegratorResult* result) const;
  // A trial step of an adaptive pair whose correction failed with
  // kConstraintFailure, or whose stage failed with kRhsFailure that the ODE
  // calls recoverable: true if it is rejected and retried with
  // h_try * stage_failure_shrink; false if the failure stands (another
  // status, RK4, or the new step below min_step; message extended).
  bool RetrySmaller(double h_try, IntegratorStatus failure,
                    bool rhs_failure_recoverable,
                    const IntegratorOptions& options,
                    const RkSettings& settings, RunState* s,
                    IntegratorResult* result) const;
  // Error test of the embedded pair on err_ and the next step size.
  ErrorTest TestErrorAndAdapt(double h_try, double t_new,
                              const IntegratorOptions& options,
                              const RkSettings& settings, RunState* s,
                              IntegratorResult* result) const;
  // Sign change of root component i between g_old_ and g.
  bool Fired(int i, const Eigen::VectorXd& g) const;
  // Whether any root component changed sign between g_old_ and g.
  bool AnyFired(const Eigen::VectorXd& g) const;
  // Locates the first root in (t, t + h], where y_ is the state at t and the
  // full step fired. Leaves the state at the root in y_new_ and sets *t_root,
  // *index.
  IntegratorStatus LocateRoot(RkSystem& system, ConstrainedOde& ode,
                              const ButcherTableau& tab, double t, double h,
                              IntegratorResult* result, double* t_root,
                              int* index);

  void Resize(int n, int stages, int roots);
  // Error norm ||v_i / (atol + rtol |y_i|)||_rms with the weights of y.
  double WeightedNorm(const Eigen::Ref<const Eigen::VectorXd>& v,
                      const Eigen::Ref<const Eigen::VectorXd>& y,
                      const IntegratorOptions& options) const;
  // Starting step (Hairer-Norsett-Wanner II.4), k_.col(0) = f(t0, y_). Uses
  // y_stage_ and k_.col(1) as scratch.
  double InitialStep(RkSystem& system, const ButcherTableau& tab, double t0,
                     double span, const IntegratorOptions& options,
                     IntegratorResult* result);

  Eigen::MatrixXd k_;  // n x stages
  Eigen::VectorXd y_, y_stage_, y_new_, err_;
  Eigen::VectorXd g_old_, g_new_, g_trial_, g_lo_, g_hi_;
  Eigen::VectorXd y_hi_;  // state at the upper end of the root bracket
};

}  // namespace quasiroll::integrators_internal
