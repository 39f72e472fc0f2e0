#include "quasiroll/integrators/rk_baumgarte.h"

#include <cmath>
#include <memory>

#include "quasiroll/core/weighted_projection.h"
#include "quasiroll/integrators/runge_kutta.h"

namespace quasiroll {

namespace {

class RkBaumgarteIntegrator final : public Integrator {
 public:
  RkBaumgarteIntegrator() = default;
  std::string name() const override { return "rk-baumgarte"; }
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  class CorrectedField final : public integrators_internal::RkSystem {
   public:
    IntegratorStatus Field(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                           Eigen::Ref<Eigen::VectorXd> f,
                           IntegratorResult* result) override;
    // Records ||H|| of every new state (result->step_drift_max): the field
    // only pulls drift back, so the steps' states carry the method's drift.
    IntegratorStatus PostStep(double t, Eigen::Ref<Eigen::VectorXd> y,
                              IntegratorResult* result, bool* moved) override;
    ConstrainedOde* ode = nullptr;
    double sigma = 0.0;
    WeightedProjection correction;
    Eigen::VectorXd delta, h_step;
  };

  void DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                   Eigen::Ref<Eigen::VectorXd> y,
                   const IntegratorOptions& options,
                   IntegratorResult* result) override;

  CorrectedField field_;
  integrators_internal::RkSettings settings_;
  double sigma_ = 5.0;
  integrators_internal::RungeKuttaDriver driver_;
};

}  // namespace

IntegratorStatus RkBaumgarteIntegrator::CorrectedField::Field(
    double t, const Eigen::Ref<const Eigen::VectorXd>& y,
    Eigen::Ref<Eigen::VectorXd> f, IntegratorResult* result) {
  const IntegratorStatus status =
      integrators_internal::EvaluateRhs(*ode, t, y, f, result);
  if (status != IntegratorStatus::kSuccess) return status;
  if (correction.m() == 0) return IntegratorStatus::kSuccess;
  ode->Constraints(y, correction.h());
  if (!correction.Factorize(*ode, y, result)) {
    result->message = correction.message();
    return IntegratorStatus::kConstraintFailure;
  }
  // r = J F + sigma H;  f <- F - D J^T (J D J^T)^{-1} r
  correction.r().noalias() = correction.jacobian() * f;
  correction.r() += sigma * correction.h();
  correction.SolveMultiplier(correction.r(), correction.lambda());
  correction.Lift(correction.lambda(), delta);
  f -= delta;
  return IntegratorStatus::kSuccess;
}

IntegratorStatus RkBaumgarteIntegrator::CorrectedField::PostStep(
    double /*t*/, Eigen::Ref<Eigen::VectorXd> y, IntegratorResult* result,
    bool* moved) {
  *moved = false;
  if (correction.m() == 0) return IntegratorStatus::kSuccess;
  ode->Constraints(y, h_step);
  result->step_drift_max =
      std::fmax(result->step_drift_max, h_step.lpNorm<Eigen::Infinity>());
  return IntegratorStatus::kSuccess;
}

OptionTable RkBaumgarteIntegrator::option_table() const {
  return integrators_internal::RkOptionTable(
      {OptionSpec::Double("baumgarte_sigma", 5.0,
                          "Baumgarte gain sigma [1/s]: J y' = -sigma H (RK4 "
                          "is stable for sigma h < 2.785)")
           .AtLeast(0)});
}

void RkBaumgarteIntegrator::ApplyBackendOptions(const OptionValues& values) {
  settings_ = integrators_internal::RkSettingsFrom(values);
  sigma_ = values.GetDouble("baumgarte_sigma");
}

void RkBaumgarteIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                        double t1,
                                        Eigen::Ref<Eigen::VectorXd> y,
                                        const IntegratorOptions& options,
                                        IntegratorResult* result) {
  field_.ode = &ode;
  field_.sigma = sigma_;
  field_.correction.Begin(ode);
  if (field_.delta.size() != y.size()) field_.delta.resize(y.size());
  if (field_.h_step.size() != field_.correction.m())
    field_.h_step.resize(field_.correction.m());
  driver_.Run(field_, ode, t0, t1, y, options, settings_, result);
}

std::unique_ptr<Integrator> MakeRkBaumgarteIntegrator() {
  return std::make_unique<RkBaumgarteIntegrator>();
}

}  // namespace quasiroll
