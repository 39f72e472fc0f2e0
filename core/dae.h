// Generic constrained ODE / DAE and the abstract integrator.
//
//   y' = F(t, y),   H(y) = 0   (holonomic constraints, J = dH/dy)
//
// Backends (integrators/) enforce H = 0 in different ways:
//   rk-baumgarte   y' = F - D J^T (J D J^T)^{-1} (J F + sigma H)   (model.md
//   §8.3) rk-projection  RK step of y' = F, then y <- y - D J^T (J D J^T)^{-1}
//   H(y)
//                  repeated until ||H||_inf <= tol                (model.md
//                  §8.4)
//   ida            residual [y' - F - D J^T nu ; H(y)] = 0, nu algebraic
//                  (index 2, GGL type), or [..; J y' + sigma H] (index 1)
//                                                                 (model.md
//                                                                 §8.5)
// D = diag(CorrectionWeights()) >= 0 chooses which coordinates the correction
// may move (weight 0 = never corrected). Nothing here knows about robots.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/backend_info.h"
#include "quasiroll/core/backend_registry.h"
#include "quasiroll/core/options.h"

namespace quasiroll {

class ConstrainedOde {
 public:
  virtual ~ConstrainedOde() = default;

  virtual int state_size() const = 0;
  virtual int num_constraints() const = 0;

  // y' = F(t, y). Returns false if F cannot be evaluated at (t, y) (e.g. the
  // quasi-static problem behind it has no solution there). Explicit backends
  // then stop with IntegratorStatus::kRhsFailure (adaptive ones retry a
  // recoverable failure first, below); `ida` first retries with smaller steps
  // (the point may be a trial point off the path) and stops with kRhsFailure
  // only when the retries fail too.
  virtual bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> ydot) = 0;
  // Whether the latest Rhs that returned false failed for numerical reasons
  // a nearby point may not share (a solve that missed its tolerance), not
  // because F does not exist there. Adaptive explicit backends then reject
  // the trial step and retry it smaller, as `ida` and `cvode-projection` do
  // with every failure; otherwise they stop. Default: not recoverable.
  virtual bool RhsFailureIsRecoverable() const { return false; }

  // H(y), num_constraints() rows. Problems without constraints return 0 rows.
  virtual void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> h) const = 0;
  // J = dH/dy, num_constraints() x state_size().
  virtual void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                                  Eigen::Ref<Eigen::MatrixXd> jac) const = 0;
  // Diagonal of D (>= 0). Default: all ones.
  virtual void CorrectionWeights(Eigen::Ref<Eigen::VectorXd> d) const {
    d.setOnes();
  }

  // Optional dF/dy (state_size x state_size). Default: returns false and the
  // integrator uses forward differences of Rhs.
  virtual bool RhsJacobian(double /*t*/,
                           const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                           Eigen::Ref<Eigen::MatrixXd> /*dfdy*/) {
    return false;
  }

  // Optional root functions g(t, y); an integrator that supports events stops
  // at the first sign change of any component and reports
  // IntegratorStatus::kEvent.
  virtual int num_roots() const { return 0; }
  virtual void Roots(double /*t*/,
                     const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                     Eigen::Ref<Eigen::VectorXd> /*g*/) const {}

  // Optional residual form F(t, y, y') = 0 of the whole state, for implicit
  // backends (`ida`): when HasResidualForm() is true they integrate this
  // residual directly instead of building the GGL residual from Rhs, H and J.
  // DifferentialIds() marks each component differential (1) or algebraic
  // (0, excluded from the error test); ConsistentDerivative() supplies y'
  // at t0 with F(t0, y, y') = 0 (y itself must already be consistent; use
  // MakeConsistent). Residual() returns false where F cannot be evaluated
  // (-> kRhsFailure). Explicit backends ignore the residual form.
  virtual bool HasResidualForm() const { return false; }
  virtual bool Residual(double /*t*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
                        const Eigen::Ref<const Eigen::VectorXd>& /*ydot*/,
                        Eigen::Ref<Eigen::VectorXd> /*r*/) {
    return false;
  }
  virtual void DifferentialIds(Eigen::Ref<Eigen::VectorXd> ids) const {
    ids.setOnes();
  }
  virtual bool ConsistentDerivative(
      double /*t*/, const Eigen::Ref<const Eigen::VectorXd>& /*y*/,
      Eigen::Ref<Eigen::VectorXd> /*ydot*/) {
    return false;
  }

  // Hook called by integrators before they start on [t0, t1] so the problem can
  // make y consistent (e.g. project onto H = 0). Default: nothing.
  virtual void MakeConsistent(double /*t0*/,
                              Eigen::Ref<Eigen::VectorXd> /*y*/) {}
};

enum class IntegratorStatus {
  kSuccess,
  kStepSizeTooSmall,
  kConvergenceFailure,  // Newton / nonlinear solver inside the method failed
  kConstraintFailure,   // projection could not reach the tolerance
  kEvent,               // a root function changed sign; t_reached is the root
  kInvalidInput,
  kRhsFailure,  // ConstrainedOde::Rhs returned false
  kNotRun,
};

const char* ToString(IntegratorStatus status);

// Settings every integrator understands. Settings of one method (the RK
// scheme, the Baumgarte gain, the projection tolerance, IDA's index, ...)
// are backend options (Integrator::option_table(); docs/plugins.md), so a
// setting a method does not use is never validated against it here.
struct IntegratorOptions {
  // Fixed step of fixed-step methods (0 = one step over [t0, t1]) and the
  // initial step of adaptive ones (0 = the method's own estimate, e.g. the
  // Hairer-Norsett-Wanner starting-step heuristic of the embedded RK pairs).
  double step = 0.0;
  // Error test of adaptive methods:
  //   ||e_i / (atol + rtol * |y_i|)||_rms <= 1.
  double rtol = 1e-8;
  double atol = 1e-10;
  // Smallest step an adaptive method may take before kStepSizeTooSmall.
  double min_step = 1e-12;
  int max_steps = 100000;

  bool IsValid(std::string* why) const;
};

struct IntegratorResult {
  IntegratorStatus status = IntegratorStatus::kNotRun;
  double t_reached = 0.0;
  int steps = 0;
  int rejected_steps = 0;  // error-test failures of adaptive methods
  int rhs_evaluations = 0;
  int jacobian_evaluations = 0;  // J = dH/dy (and IDA Jacobian) evaluations
  int projection_iterations = 0;
  // Loop-closure drift the method itself commits: the largest ||H(y)||_inf
  // of a state it produced at the end of a step before any correction moved
  // it (the input of a successful projection, an accepted rk-baumgarte
  // step, the end state of every Integrate() call). A running maximum over
  // the calls, like the counters. Projection methods return states with
  // ||H|| at their projection tolerance; this is what the projection removed.
  double step_drift_max = 0.0;
  int root_index = -1;  // component that fired for kEvent
  double wall_seconds = 0.0;
  std::string message;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  // Integrates y from t0 to t1 in place. Throws std::invalid_argument on
  // misuse (size mismatch, non-finite y, t1 <= t0, invalid options).
  // Counters in *result (including wall_seconds) accumulate, so one result
  // can span many calls; status, t_reached, root_index and message describe
  // this call. ode.MakeConsistent(t0, y) is called before integrating. On a
  // failure y holds the last accepted state (at t_reached); on kEvent it holds
  // the state at the root. Exceptions other than std::invalid_argument thrown
  // by the backend or by ode are caught and reported as kConvergenceFailure.
  // A final non-finite y turns kSuccess/kEvent into kConvergenceFailure.
  // The end state's ||H||_inf enters result->step_drift_max.
  IntegratorStatus Integrate(ConstrainedOde& ode, double t0, double t1,
                             Eigen::Ref<Eigen::VectorXd> y,
                             const IntegratorOptions& options,
                             IntegratorResult* result);

  virtual std::string name() const = 0;

  // Backend options (docs/plugins.md, "Backend options"): the settings this
  // method owns (name, type, default, range, doc). Default: none.
  virtual OptionTable option_table() const { return {}; }
  // Checks `given` against option_table() and makes them (the others at
  // their defaults) this object's settings for every later Integrate().
  // Throws std::invalid_argument naming an unknown or ill-typed option and
  // the known ones; the previous settings are then kept.
  void SetBackendOptions(const GivenOptions& given);
  // The settings in effect: every option of option_table().
  const OptionValues& backend_options();

 protected:
  Integrator() = default;

 private:
  // Receives validated settings (every option of the table): before the
  // first Integrate() the defaults, then whatever SetBackendOptions() was
  // given. Backends copy them into typed members here.
  virtual void ApplyBackendOptions(const OptionValues& /*values*/) {}
  std::optional<OptionValues> backend_options_;
  void RecordEndDrift(const ConstrainedOde& ode,
                      const Eigen::Ref<const Eigen::VectorXd>& y,
                      IntegratorResult* result);
  Eigen::VectorXd end_constraints_;  // H at the end of a call (workspace)

  virtual void DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                           Eigen::Ref<Eigen::VectorXd> y,
                           const IntegratorOptions& options,
                           IntegratorResult* result) = 0;
};

// Name -> factory registry of integrator backends
// (core/backend_registry.h).
using IntegratorRegistry = BackendRegistry<Integrator>;

// Defined in integrators/registry.cc. Idempotent; call once before Create().
void RegisterBuiltinIntegrators();

}  // namespace quasiroll
