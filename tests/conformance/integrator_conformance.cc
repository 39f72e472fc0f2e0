#include "quasiroll/conformance/integrator_conformance.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>
#include <utility>

#include "quasiroll/conformance/option_table_conformance.h"

namespace quasiroll::conformance {
namespace {

double ConstraintNorm(const ConstrainedOde& ode, const Eigen::VectorXd& y) {
  Eigen::VectorXd h(ode.num_constraints());
  ode.Constraints(y, h);
  return h.size() == 0 ? 0.0 : h.lpNorm<Eigen::Infinity>();
}

}  // namespace

void PrintTo(const IntegratorConformanceParam& param, std::ostream* os) {
  *os << param.backend;
  for (const auto& [name, value] : param.traits.backend_options)
    *os << " " << name << "=" << value;
  if (param.traits.andrews_step > 0)
    *os << " (Andrews step " << param.traits.andrews_step << ")";
}

// Tolerances: tests/integrators/integrators_test.cc (PendulumTest), whose
// bounds are the measured error times ~10. The loosest of its rtol = 1e-8
// cases applies to every backend here: 3e-6 is its bound for the BDF
// backends (ida, cvode-projection: measured 2.0e-7 - 7.0e-7, BDF global
// error ~ tens of rtol); 1e-7 its drift bound for rk-baumgarte (drift of
// RK local-error size, measured 1.1e-8) and ida index 1 (measured 1.3e-8).
void ExpectPendulumAccuracy(Integrator& integrator) {
  SCOPED_TRACE(integrator.name() + " on the pendulum");
  PendulumOde ode;
  const double theta0 = 0.5, hold = 0.05;
  const int holds = 40;
  Eigen::VectorXd y = ode.AtAngle(theta0);
  IntegratorOptions o;
  o.step = 0.01;
  o.rtol = 1e-8;
  o.atol = 1e-10;
  IntegratorResult r;
  for (int k = 0; k < holds; ++k) {
    ASSERT_EQ(integrator.Integrate(ode, k * hold, (k + 1) * hold, y, o, &r),
              IntegratorStatus::kSuccess)
        << "hold " << k << ": " << r.message;
    ASSERT_DOUBLE_EQ(r.t_reached, (k + 1) * hold);
  }
  const Eigen::Vector4d ref = ode.Reference(theta0, holds * hold);
  const double error = (y - ref).lpNorm<Eigen::Infinity>();
  const double drift = ConstraintNorm(ode, y);
  std::printf("[ measured ] %s pendulum: error %.3e  drift %.3e  steps %d\n",
              integrator.name().c_str(), error, drift, r.steps);
  EXPECT_LE(error, kPendulumPositionTolerance);
  EXPECT_LE(drift, kPendulumDriftTolerance);
}

// Tolerances: tests/integrators/robustness_test.cc (SevenBodyAdaptive,
// rtol 1e-9): 2e-5 rad is its bound for cvode-projection (measured 1.4e-6,
// variable-order BDF over ~1350 steps), the loosest; 1e-8 its drift bound
// for the RK backends (they stabilise or project; measured <= 1e-9).
void ExpectAndrewsAccuracy(Integrator& integrator, double step) {
  SCOPED_TRACE(integrator.name() + " on Andrews' mechanism");
  SevenBodyMechanismOde ode;
  IntegratorOptions o;
  o.step = step;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  Eigen::VectorXd y = SevenBodyMechanismOde::Initial();
  IntegratorResult r;
  ASSERT_EQ(integrator.Integrate(
                ode, 0.0, SevenBodyMechanismOde::kReferenceTime, y, o, &r),
            IntegratorStatus::kSuccess)
      << r.message;
  double error = 0.0;
  for (int i = 0; i < 3; ++i)
    error = std::max(
        error, std::abs(y(i) - SevenBodyMechanismOde::kReferenceAngles[i]));
  const double drift = ConstraintNorm(ode, y);
  std::printf("[ measured ] %s Andrews: error %.3e  drift %.3e  steps %d\n",
              integrator.name().c_str(), error, drift, r.steps);
  EXPECT_LE(error, kAndrewsAngleTolerance);
  EXPECT_LE(drift, kAndrewsDriftTolerance);
}

void ExpectOptionTableValid(Integrator& integrator) {
  ExpectBackendOptionTableValid(integrator);
}

std::unique_ptr<Integrator> IntegratorConformanceTest::Create() const {
  auto integrator = IntegratorRegistry::Create(GetParam().backend);
  integrator->SetBackendOptions(GetParam().traits.backend_options);
  return integrator;
}

IntegratorConformanceParam MakeIntegratorConformanceParam(
    const std::string& backend, IntegratorConformanceTraits traits) {
  return IntegratorConformanceParam{backend, std::move(traits)};
}

std::string IntegratorConformanceName(
    const ::testing::TestParamInfo<IntegratorConformanceParam>& info) {
  std::string name = info.param.backend;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

}  // namespace quasiroll::conformance

// ------------------------------------------------------------- suites ---

namespace quasiroll::conformance {
namespace {

// A binary may link the kit for one kind of backend only.
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(QuasirollIntegratorConformance);

TEST_P(QuasirollIntegratorConformance, PendulumMatchesReference) {
  ExpectPendulumAccuracy(*Create());
}

TEST_P(QuasirollIntegratorConformance, AndrewsMechanismMatchesReference) {
  ExpectAndrewsAccuracy(*Create(), GetParam().traits.andrews_step);
}

TEST_P(QuasirollIntegratorConformance, OptionTableIsValid) {
  // Without the traits' options: the table's defaults are what is checked.
  ExpectOptionTableValid(*IntegratorRegistry::Create(GetParam().backend));
}

}  // namespace
}  // namespace quasiroll::conformance
