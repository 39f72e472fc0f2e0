// What the built-in backends say about themselves (core/backend_info.h):
// the harness, the shard planner and the report read only this, so it must
// agree with the backends' own behaviour.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll {
namespace {

template <typename RegistryT>
int CountRole(BackendRole role) {
  int n = 0;
  for (const std::string& name : RegistryT::Names())
    n += RegistryT::Info(name).HasRole(role) ? 1 : 0;
  return n;
}

TEST(BackendInfo, EveryBuiltinDescribesItself) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  for (const std::string& name : NlpSolverRegistry::Names()) {
    const BackendInfo info = NlpSolverRegistry::Info(name);
    EXPECT_FALSE(info.description.empty()) << name;
    EXPECT_FALSE(info.family.empty()) << name;
    EXPECT_GT(info.cost_ratio, 0) << name;
    EXPECT_EQ(info.library.empty(), info.library_version.empty()) << name;
    // The harness schedules by the object's own answer: the two agree.
    EXPECT_EQ(info.thread_safe,
              NlpSolverRegistry::Create(name)->SupportsConcurrentInstances())
        << name;
  }
  for (const std::string& name : IntegratorRegistry::Names()) {
    const BackendInfo info = IntegratorRegistry::Info(name);
    EXPECT_FALSE(info.description.empty()) << name;
    EXPECT_FALSE(info.family.empty()) << name;
    EXPECT_GT(info.seconds_per_hold_zoh, 0) << name;
    EXPECT_GT(info.seconds_per_hold_coupled, 0) << name;
  }
  // Each role is held by exactly one backend (defaults, references).
  EXPECT_EQ(CountRole<NlpSolverRegistry>(BackendRole::kDefault), 1);
  EXPECT_EQ(CountRole<NlpSolverRegistry>(BackendRole::kReference), 1);
  EXPECT_EQ(CountRole<NlpSolverRegistry>(BackendRole::kContinuation), 1);
  EXPECT_EQ(CountRole<IntegratorRegistry>(BackendRole::kDefault), 1);
  EXPECT_EQ(CountRole<IntegratorRegistry>(BackendRole::kReference), 1);
  EXPECT_LE(CountRole<IntegratorRegistry>(BackendRole::kReferenceCheck), 1);
}

// Adaptivity and a-priori instability follow the options, as the cost model
// and the failure causes assume: an RK scheme other than RK4 is adaptive;
// a Baumgarte gain past RK4's real stability bound sigma h = 2.785 is
// "baumgarte_instability" (the bound of RK4's stability polynomial on the
// negative real axis).
TEST(BackendInfo, AdaptivityAndKnownInstabilityFollowTheOptions) {
  RegisterBuiltinIntegrators();
  for (const std::string& name : IntegratorRegistry::Names()) {
    std::unique_ptr<Integrator> integrator = IntegratorRegistry::Create(name);
    const OptionTable table = integrator->option_table();
    const BackendInfo info = IntegratorRegistry::Info(name);
    if (!FindOption(table, "rk_method")) continue;
    integrator->SetBackendOptions({{"rk_method", "rk4"}});
    EXPECT_FALSE(info.IsAdaptive(integrator->backend_options())) << name;
    integrator->SetBackendOptions({{"rk_method", "dp54"}});
    EXPECT_TRUE(info.IsAdaptive(integrator->backend_options())) << name;
    if (!FindOption(table, "baumgarte_sigma")) {
      EXPECT_EQ(info.KnownInstability(integrator->backend_options(), 100), "")
          << name;
      continue;
    }
    integrator->SetBackendOptions(
        {{"rk_method", "rk4"}, {"baumgarte_sigma", "10"}});
    EXPECT_EQ(info.KnownInstability(integrator->backend_options(), 0.2786),
              "baumgarte_instability")
        << name;
    EXPECT_EQ(info.KnownInstability(integrator->backend_options(), 0.2784), "")
        << name;
    integrator->SetBackendOptions(
        {{"rk_method", "dp54"}, {"baumgarte_sigma", "10"}});
    EXPECT_EQ(info.KnownInstability(integrator->backend_options(), 1.0), "")
        << name;
  }
}

TEST(BackendInfo, ANameOrARoleCannotBeTakenTwice) {
  RegisterBuiltinNlpSolvers();
  const std::string taken = NlpSolverRegistry::WithRole(BackendRole::kDefault);
  BackendInfo info;
  info.description = "test";
  EXPECT_THROW(
      NlpSolverRegistry::Register(
          taken, info, [] { return NlpSolverRegistry::Create("newton"); }),
      std::invalid_argument);
  info.roles = {BackendRole::kDefault};
  EXPECT_THROW(NlpSolverRegistry::Register(
                   "backend-info-test", info,
                   [] { return NlpSolverRegistry::Create("newton"); }),
               std::invalid_argument);
  EXPECT_FALSE(NlpSolverRegistry::Has("backend-info-test"));
}

}  // namespace
}  // namespace quasiroll
