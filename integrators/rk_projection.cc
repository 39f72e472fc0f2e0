#include "integrators/rk_projection.h"

namespace quasiroll {

IntegratorStatus RkProjectionIntegrator::System::Field(
    double t, const Eigen::Ref<const Eigen::VectorXd>& y,
    Eigen::Ref<Eigen::VectorXd> f, IntegratorResult* result) {
  return integrators_internal::EvaluateRhs(*ode, t, y, f, result);
}

IntegratorStatus RkProjectionIntegrator::System::PostStep(
    double /*t*/, Eigen::Ref<Eigen::VectorXd> y, IntegratorResult* result,
    bool* moved) {
  return correction.Project(*ode, y, tolerance, max_iterations, result, moved);
}

void RkProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                         double t1,
                                         Eigen::Ref<Eigen::VectorXd> y,
                                         const IntegratorOptions& options,
                                         IntegratorResult* result) {
  system_.ode = &ode;
  system_.tolerance = options.projection_tolerance;
  system_.max_iterations = options.max_projection_iterations;
  system_.correction.Begin(ode);
  bool moved = false;
  const IntegratorStatus status = system_.PostStep(t0, y, result, &moved);
  if (status != IntegratorStatus::kSuccess) {
    result->status = status;
    result->t_reached = t0;
    result->message = "initial state: " + result->message;
    return;
  }
  driver_.Run(system_, ode, t0, t1, y, options, result);
}

}  // namespace quasiroll
