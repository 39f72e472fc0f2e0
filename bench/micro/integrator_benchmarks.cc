// Cost of one Integrate() call over one zoh hold interval (0.05 s) per
// integrator backend, on a planar Cartesian pendulum with position- and
// velocity-level constraints (state 4, constraints 2). The integrator object
// and the state persist across iterations, as in the simulation loop, so the
// numbers include the per-call overhead (validation, IDAReInit, consistent
// initial values) but not first-call workspace allocation.
//
// BM_CoupledInterval/<dae>/<ift|fd>: one warmed-up coupled output interval
// (dt = 0.05 s) of the paper scene (Simulator::Advance: the solve at the
// sample, the record and the integration, every Rhs an NLP solve) with the
// robot ODE's exact Jacobian (jacobian=ift, model.md §8.9) or the
// integrator's differences (jacobian=fd); counters per interval.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "quasiroll/bench/micro/benchmark_support.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/simulator.h"

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

void BM_CoupledInterval(benchmark::State& state, const std::string& dae,
                        const std::string& jacobian) {
  using quasiroll::SimulationResult;
  quasiroll::RegisterBuiltinNlpSolvers();
  quasiroll::RegisterBuiltinIntegrators();
  if (!quasiroll::IntegratorRegistry::Has(dae)) {
    state.SkipWithError((dae + " not built").c_str());
    return;
  }
  const quasiroll::Scene scene = quasiroll::LoadScene(
      std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  quasiroll::SimulationOptions options;
  options.dae = dae;
  options.coupling = quasiroll::Coupling::kCoupled;
  options.dae_options["jacobian"] = jacobian;
  quasiroll::Simulator sim(scene, options);
  SimulationResult result;
  sim.Begin(sim.initial_configuration(), &result);
  sim.Advance(&result);  // warm up: the first solve is cold
  long long intervals = 0, rhs = 0, jacobians = 0, steps = 0;
  long long rhs_seen = result.rhs_evaluations,
            jac_seen = result.jacobian_evaluations, steps_seen = result.steps;
  const auto reset = [&] {
    rhs_seen = result.rhs_evaluations;
    jac_seen = result.jacobian_evaluations;
    steps_seen = result.steps;
  };
  for (auto _ : state) {
    const quasiroll::AdvanceOutcome outcome =
        quasiroll::AdvanceOrRestart(state, sim, &result, {}, reset);
    if (outcome == quasiroll::AdvanceOutcome::kFailed) break;
    if (outcome == quasiroll::AdvanceOutcome::kRestarted) continue;
    ++intervals;
    rhs += result.rhs_evaluations - rhs_seen;
    jacobians += result.jacobian_evaluations - jac_seen;
    steps += result.steps - steps_seen;
    rhs_seen = result.rhs_evaluations;
    jac_seen = result.jacobian_evaluations;
    steps_seen = result.steps;
  }
  const double n = static_cast<double>(std::max(1LL, intervals));
  state.counters["rhs/interval"] = static_cast<double>(rhs) / n;
  state.counters["jac/interval"] = static_cast<double>(jacobians) / n;
  state.counters["steps/interval"] = static_cast<double>(steps) / n;
  state.SetLabel("solve + record + one coupled 0.05 s interval");
}

BENCHMARK_CAPTURE(BM_CoupledInterval, ida_ift, std::string("ida"),
                  std::string("ift"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_CoupledInterval, ida_fd, std::string("ida"),
                  std::string("fd"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_CoupledInterval, cvode_projection_ift,
                  std::string("cvode-projection"), std::string("ift"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_CoupledInterval, cvode_projection_fd,
                  std::string("cvode-projection"), std::string("fd"))
    ->Unit(benchmark::kMicrosecond);

}  // namespace
