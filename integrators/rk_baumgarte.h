// rk-baumgarte: explicit Runge-Kutta on the Baumgarte-corrected field
// (model.md §8.3)
//
//   y' = F - D J^T (J D J^T)^{-1} (J F + sigma H),
//
// the D^{-1}-weighted minimal-norm change of F with J y' = -sigma H, so that
// ||H(t)|| = ||H(0)|| e^{-sigma t} in exact arithmetic. RK4 is stable for
// sigma * h < 2.785. Methods, step control and events:
// integrators/runge_kutta.h.
// Options (option_table()): baumgarte_sigma and the RK driver's (rk_method,
// safety, max_growth, max_shrink, stage_failure_shrink).
#pragma once

#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/weighted_projection.h"
#include "quasiroll/integrators/runge_kutta.h"

namespace quasiroll {

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
    ConstrainedOde* ode = nullptr;
    double sigma = 0.0;
    WeightedProjection correction;
    Eigen::VectorXd delta;
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

}  // namespace quasiroll
