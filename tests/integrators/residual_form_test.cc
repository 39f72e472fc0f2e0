// The optional residual form F(t, y, y') = 0 of ConstrainedOde on the `ida`
// backend: a semi-explicit index-1 DAE with a known solution.
#include <gtest/gtest.h>

#include <cmath>

#include "quasiroll/core/dae.h"

namespace quasiroll {
namespace {

// y1' = y2 y3,  y2' = -y1 y3,  0 = y3 - (1 + cos t)/2 ... written implicitly:
//   r1 = y1' - y2 y3,  r2 = y2' + y1 y3,  r3 = y3 - w(t),  w(t) = 1 + sin(t)/2
// Solution: the rotation by the angle phi(t) = t + (1 - cos t)/2:
//   y1 = sin(phi), y2 = cos(phi), y3 = w(t).
class RotationDae final : public ConstrainedOde {
 public:
  int state_size() const override { return 3; }
  int num_constraints() const override { return 0; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>&,
           Eigen::Ref<Eigen::VectorXd>) override {
    return false;  // residual form only
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd>) const override {}
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd>) const override {}
  bool HasResidualForm() const override { return true; }
  static double W(double t) { return 1.0 + 0.5 * std::sin(t); }
  bool Residual(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::VectorXd>& yp,
                Eigen::Ref<Eigen::VectorXd> r) override {
    ++evaluations;
    r(0) = yp(0) - y(1) * y(2);
    r(1) = yp(1) + y(0) * y(2);
    r(2) = y(2) - W(t);
    return fail_after < 0 || evaluations < fail_after;
  }
  void DifferentialIds(Eigen::Ref<Eigen::VectorXd> ids) const override {
    ids << 1, 1, 0;
  }
  bool ConsistentDerivative(double t,
                            const Eigen::Ref<const Eigen::VectorXd>& y,
                            Eigen::Ref<Eigen::VectorXd> yp) override {
    yp << y(1) * y(2), -y(0) * y(2), 0.5 * std::cos(t);
    return true;
  }
  int evaluations = 0;
  int fail_after = -1;
};

TEST(ResidualForm, IdaIntegratesAnIndexOneDae) {
  RegisterBuiltinIntegrators();
  if (!IntegratorRegistry::Has("ida")) GTEST_SKIP() << "built without SUNDIALS";
  auto ida = IntegratorRegistry::Create("ida");
  RotationDae dae;
  IntegratorOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  IntegratorResult result;
  Eigen::VectorXd y(3);
  y << 0.0, 1.0, RotationDae::W(0.0);
  ASSERT_EQ(ida->Integrate(dae, 0.0, 2.0, y, options, &result),
            IntegratorStatus::kSuccess)
      << result.message;
  const double t = 2.0, phi = t + 0.5 * (1.0 - std::cos(t));
  // Global error of IDA's BDF at rtol 1e-10 over 2 s: ~1e-9 (margin 10x).
  EXPECT_NEAR(y(0), std::sin(phi), 1e-8);
  EXPECT_NEAR(y(1), std::cos(phi), 1e-8);
  EXPECT_NEAR(y(2), RotationDae::W(t), 1e-10);  // algebraic: solved each step
  EXPECT_GT(result.steps, 10);
}

TEST(ResidualForm, FailingResidualIsRhsFailure) {
  RegisterBuiltinIntegrators();
  if (!IntegratorRegistry::Has("ida")) GTEST_SKIP() << "built without SUNDIALS";
  auto ida = IntegratorRegistry::Create("ida");
  RotationDae dae;
  dae.fail_after = 20;
  IntegratorResult result;
  Eigen::VectorXd y(3);
  y << 0.0, 1.0, RotationDae::W(0.0);
  EXPECT_EQ(ida->Integrate(dae, 0.0, 2.0, y, IntegratorOptions{}, &result),
            IntegratorStatus::kRhsFailure);
  EXPECT_TRUE(y.allFinite());
}

}  // namespace
}  // namespace quasiroll
