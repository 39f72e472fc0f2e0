// A plugin that registers a backend under a name a built-in has: loading it
// must fail with an error naming the file and the name
// (tests/plugins/plugin_cli_test.sh).
#include <memory>

#include "quasiroll/core/dae.h"

namespace {
class NeverIntegrator final : public quasiroll::Integrator {
 public:
  std::string name() const override { return "rk-projection"; }

 private:
  void DoIntegrate(quasiroll::ConstrainedOde&, double, double,
                   Eigen::Ref<Eigen::VectorXd>,
                   const quasiroll::IntegratorOptions&,
                   quasiroll::IntegratorResult* result) override {
    result->status = quasiroll::IntegratorStatus::kConvergenceFailure;
  }
};
}  // namespace

extern "C" void quasiroll_register_plugin() {
  quasiroll::BackendInfo info;
  info.description = "test: clashes with a built-in name";
  quasiroll::IntegratorRegistry::Register("rk-projection", std::move(info), [] {
    return std::make_unique<NeverIntegrator>();
  });
}
