#include "quasiroll/integrators/rk_projection.h"

namespace quasiroll {

IntegratorStatus RkProjectionIntegrator::System::Field(
    double t, const Eigen::Ref<const Eigen::VectorXd>& y,
    Eigen::Ref<Eigen::VectorXd> f, IntegratorResult* result) {
  return integrators_internal::EvaluateRhs(*ode, t, y, f, result);
}

IntegratorStatus RkProjectionIntegrator::System::PostStep(
    double /*t*/, Eigen::Ref<Eigen::VectorXd> y, IntegratorResult* result,
    bool* moved) {
  const IntegratorStatus status =
      correction.Project(*ode, y, tolerance, max_iterations, result, moved);
  if (status != IntegratorStatus::kSuccess)
    result->message = correction.message();
  return status;
}

OptionTable RkProjectionIntegrator::option_table() const {
  OptionTable table = {
      OptionSpec::Double("projection_tolerance", 1e-12,
                         "projection stops when ||H||_inf <= this")
          .GreaterThan(0),
      OptionSpec::Int("max_projection_iterations", 10,
                      "Newton corrections per projection before "
                      "constraint_failure")
          .AtLeast(1)};
  for (OptionSpec& s : integrators_internal::RkOptionTable())
    table.push_back(std::move(s));
  return table;
}

void RkProjectionIntegrator::ApplyBackendOptions(const OptionValues& values) {
  settings_ = integrators_internal::RkSettingsFrom(values);
  projection_tolerance_ = values.GetDouble("projection_tolerance");
  max_projection_iterations_ =
      static_cast<int>(values.GetInt("max_projection_iterations"));
}

void RkProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                         double t1,
                                         Eigen::Ref<Eigen::VectorXd> y,
                                         const IntegratorOptions& options,
                                         IntegratorResult* result) {
  system_.ode = &ode;
  system_.tolerance = projection_tolerance_;
  system_.max_iterations = max_projection_iterations_;
  system_.correction.Begin(ode);
  bool moved = false;
  const IntegratorStatus status = system_.PostStep(t0, y, result, &moved);
  if (status != IntegratorStatus::kSuccess) {
    result->status = status;
    result->t_reached = t0;
    result->message = "initial state: " + result->message;
    return;
  }
  driver_.Run(system_, ode, t0, t1, y, options, settings_, result);
}

}  // namespace quasiroll
