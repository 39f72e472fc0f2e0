// Cost of one Integrate() call over one zoh hold interval (0.05 s) per
// integrator backend, on a planar Cartesian pendulum with position- and
// velocity-level constraints (state 4, constraints 2). The integrator object
// and the state persist across iterations, as in the simulation loop, so the
// numbers include the per-call overhead (validation, IDAReInit, consistent
// initial values) but not first-call workspace allocation.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <string>

#include "quasiroll/core/dae.h"

namespace {

class Pendulum final : public quasiroll::ConstrainedOde {
 public:
  int state_size() const override { return 4; }
  int num_constraints() const override { return 2; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    const double r2 = y(0) * y(0) + y(1) * y(1);
    const double lambda = (y(2) * y(2) + y(3) * y(3) - kG * y(1)) / r2;
    ydot << y(2), y(3), -lambda * y(0), -lambda * y(1) - kG;
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    h(0) = y(0) * y(0) + y(1) * y(1) - 1.0;
    h(1) = y(0) * y(2) + y(1) * y(3);
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> j) const override {
    j << 2 * y(0), 2 * y(1), 0, 0,  //
        y(2), y(3), y(0), y(1);
  }

 private:
  static constexpr double kG = 9.81;
};

void BM_IntegrateHoldInterval(benchmark::State& state,
                              const std::string& backend,
                              const std::string& rk_method) {
  quasiroll::RegisterBuiltinIntegrators();
  if (!quasiroll::IntegratorRegistry::Has(backend)) {
    state.SkipWithError((backend + " not built").c_str());
    return;
  }
  auto integrator = quasiroll::IntegratorRegistry::Create(backend);
  if (!rk_method.empty())
    integrator->SetBackendOptions({{"rk_method", rk_method}});
  Pendulum ode;
  const double theta0 = 0.5, hold = 0.05;
  Eigen::VectorXd y(4);
  y << std::sin(theta0), -std::cos(theta0), 0.0, 0.0;
  quasiroll::IntegratorOptions options;  // RK4: one step per hold interval
  quasiroll::IntegratorResult result;
  double t = 0.0;
  for (auto _ : state) {
    integrator->Integrate(ode, t, t + hold, y, options, &result);
    if (result.status != quasiroll::IntegratorStatus::kSuccess) {
      state.SkipWithError(result.message.c_str());
      break;
    }
    t += hold;
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["steps/call"] = benchmark::Counter(
      static_cast<double>(result.steps), benchmark::Counter::kAvgIterations);
  state.counters["rhs/call"] =
      benchmark::Counter(static_cast<double>(result.rhs_evaluations),
                         benchmark::Counter::kAvgIterations);
}

BENCHMARK_CAPTURE(BM_IntegrateHoldInterval, rk_baumgarte_rk4,
                  std::string("rk-baumgarte"), std::string("rk4"));
BENCHMARK_CAPTURE(BM_IntegrateHoldInterval, rk_projection_rk4,
                  std::string("rk-projection"), std::string("rk4"));
BENCHMARK_CAPTURE(BM_IntegrateHoldInterval, rk_projection_dp54,
                  std::string("rk-projection"), std::string("dp54"));
BENCHMARK_CAPTURE(BM_IntegrateHoldInterval, ida, std::string("ida"),
                  std::string());

}  // namespace
