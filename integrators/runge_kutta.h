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
//     controller is h_new = h * min(5, max(0.2, 0.9 * err^(-1/(q+1)))) with q
//     the embedded (lower) order, and no growth right after a rejection.
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

#include "core/dae.h"

namespace quasiroll::integrators_internal {

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
           IntegratorResult* result);

 private:
  // One RK step of size h from (t, y_) into y_new_ (and err_ if embedded).
  // Stage 0 must already be in k_.col(0).
  IntegratorStatus Step(RkSystem& system, const ButcherTableau& tab, double t,
                        double h, IntegratorResult* result);
  // Sign change of root component i between g_old_ and g.
  bool Fired(int i, const Eigen::VectorXd& g) const;
  // Locates the first root in (t, t + h], where y_ is the state at t and the
  // full step fired. Leaves the state at the root in y_new_ and sets *t_root,
  // *index.
  IntegratorStatus LocateRoot(RkSystem& system, ConstrainedOde& ode,
                              const ButcherTableau& tab, double t, double h,
                              IntegratorResult* result, double* t_root,
                              int* index);

  void Resize(int n, int stages, int roots);

  Eigen::MatrixXd k_;  // n x stages
  Eigen::VectorXd y_, y_stage_, y_new_, err_;
  Eigen::VectorXd g_old_, g_new_, g_trial_, g_lo_, g_hi_;
  Eigen::VectorXd y_hi_;  // state at the upper end of the root bracket
};

}  // namespace quasiroll::integrators_internal
