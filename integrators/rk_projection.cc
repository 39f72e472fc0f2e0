#include "quasiroll/integrators/rk_projection.h"

#include <memory>

#include "quasiroll/core/weighted_projection.h"
#include "quasiroll/integrators/runge_kutta.h"

namespace quasiroll {

namespace {

class RkProjectionIntegrator final : public Integrator {
 public:
  RkProjectionIntegrator() = default;
  std::string name() const override { return "rk-projection"; }
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  class System final : public integrators_internal::RkSystem {
   public:
    IntegratorStatus Field(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> f,
                           IntegratorResult* result) override;
    IntegratorStatus PostStep(double t, Eigen::Ref<Eigen::VectorXd> y,
                              IntegratorResult* result, bool* moved) override;
    ConstrainedOde* ode = nullptr;
    ProjectionSettings projection;
    WeightedProjection correction;
  };

  void DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                   Eigen::Ref<Eigen::VectorXd> y,
                   const IntegratorOptions& options,
                   IntegratorResult* result) override;

  System system_;
  integrators_internal::RkSettings settings_;
  ProjectionSettings projection_;
  integrators_internal::RungeKuttaDriver driver_;
};

}  // namespace

IntegratorStatus RkProjectionIntegrator::System::Field(
    double t, const Eigen::Ref<const Eigen::VectorXd>& y,
    Eigen::Ref<Eigen::VectorXd> f, IntegratorResult* result) {
  return integrators_internal::EvaluateRhs(*ode, t, y, f, result);
}

IntegratorStatus RkProjectionIntegrator::System::PostStep(
    double /*t*/, Eigen::Ref<Eigen::VectorXd> y, IntegratorResult* result,
    bool* moved) {
  const IntegratorStatus status =
      correction.Project(*ode, y, projection, result, moved);
  if (status != IntegratorStatus::kSuccess)
    result->message = correction.message();
  return status;
}

OptionTable RkProjectionIntegrator::option_table() const {
  return integrators_internal::RkOptionTable(ProjectionSettings::Options(
      "projection stops when ||H||_inf <= this",
      "Newton corrections per projection before constraint_failure"));
}

void RkProjectionIntegrator::ApplyBackendOptions(const OptionValues& values) {
  settings_ = integrators_internal::RkSettingsFrom(values);
  projection_ = ProjectionSettings::From(values);
}

void RkProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                         double t1,
                                         Eigen::Ref<Eigen::VectorXd> y,
                                         const IntegratorOptions& options,
                                         IntegratorResult* result) {
  system_.ode = &ode;
  system_.projection = projection_;
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

std::unique_ptr<Integrator> MakeRkProjectionIntegrator() {
  return std::make_unique<RkProjectionIntegrator>();
}

}  // namespace quasiroll
