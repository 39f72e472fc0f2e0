// Integrator "midpoint-projection" (example plugin): the explicit midpoint
// rule (RK2, fixed step) on y' = F(t, y), each step followed by the Newton
// projection onto H = 0
//   y <- y - D J^T (J D J^T)^{-1} H(y)   until ||H||_inf <=
//   projection_tolerance
// (at most max_projection_iterations corrections, else kConstraintFailure),
// done by the public helper quasiroll::WeightedProjection
// (core/weighted_projection.h) on the ConstrainedOde interface (core/dae.h).
//
// Step: options.step / midpoint_steps (step 0 = one step over [t0, t1]); the
// last step ends exactly on t1; more than max_steps steps -> kStepSizeTooSmall.
// Backend options (option_table(), the plugin's own): projection_tolerance,
// max_projection_iterations, midpoint_steps. Events: after each
// step the signs of ode.Roots() are compared with the previous ones; on a
// change the root is bracketed by bisection on the step fraction (re-stepping
// from the last accepted state) and y is the (projected) state at the root.
#pragma once

#include <Eigen/Core>
#include <string>

#include <quasiroll/core/dae.h>
#include <quasiroll/core/weighted_projection.h>

namespace example {

class MidpointProjectionIntegrator final : public quasiroll::Integrator {
 public:
  std::string name() const override { return "midpoint-projection"; }
  quasiroll::OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const quasiroll::OptionValues& values) override;

  void DoIntegrate(quasiroll::ConstrainedOde& ode, double t0, double t1,
                   Eigen::Ref<Eigen::VectorXd> y,
                   const quasiroll::IntegratorOptions& options,
                   quasiroll::IntegratorResult* result) override;

  // One midpoint step of size h from (t, y) into out, then projected.
  quasiroll::IntegratorStatus Step(quasiroll::ConstrainedOde& ode, double t,
                                   double h, const Eigen::VectorXd& y,
                                   Eigen::VectorXd& out,
                                   const quasiroll::IntegratorOptions& options,
                                   quasiroll::IntegratorResult* result);
  quasiroll::IntegratorStatus Project(
      quasiroll::ConstrainedOde& ode, Eigen::VectorXd& y,
      const quasiroll::IntegratorOptions& options,
      quasiroll::IntegratorResult* result);
  // Index of the first root component whose sign changed from g_old_ to g,
  // -1 if none (a component exactly 0 at the start does not fire).
  int Fired(const Eigen::VectorXd& g) const;

  quasiroll::ProjectionSettings projection_settings_;
  int substeps_ = 1;
  quasiroll::WeightedProjection projection_;
  Eigen::VectorXd y0_, y1_, y_mid_, y_hi_, k_;
  Eigen::VectorXd g_old_, g_new_;
};

}  // namespace example
