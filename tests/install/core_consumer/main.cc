// Uses quasiroll::core alone, through the installed <quasiroll/...> headers:
// the independent KKT check of core/nlp.h certifies the known optimum of a
// small problem defined here, and no NLP backend is linked in. (The
// reference problems are in the conformance kit, which needs GTest.)
#include <cmath>
#include <cstdio>

#include <quasiroll/core/nlp.h>

namespace {

// min (x1 - 2)^2 + (x2 - 1)^2  s.t.  x1 + x2 <= 2:  x* = (1.5, 0.5),
// multiplier 1 on the active row.
class SmallQp final : public quasiroll::NlpProblem {
 public:
  int num_variables() const override { return 2; }
  int num_constraints() const override { return 1; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu,
                 Eigen::Ref<Eigen::VectorXd> gl,
                 Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl.setConstant(-10.0);
    xu.setConstant(10.0);
    gl(0) = -10.0;
    gu(0) = 2.0;
  }
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return (x(0) - 2) * (x(0) - 2) + (x(1) - 1) * (x(1) - 1);
  }
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override {
    grad << 2 * (x(0) - 2), 2 * (x(1) - 1);
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override {
    g(0) = x(0) + x(1);
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    jac << 1.0, 1.0;
  }
};

}  // namespace

int main() {
  const SmallQp p;
  const Eigen::Vector2d x(1.5, 0.5);
  quasiroll::NlpBounds bounds;
  bounds.Load(p);
  Eigen::VectorXd g(1);
  p.Constraints(x, g);
  const double violation = quasiroll::MaxConstraintViolation(x, g, bounds);
  quasiroll::KktVerifier kkt;
  const double residual = kkt.ResidualWith(p, x, Eigen::VectorXd::Ones(1));
  const auto backends = quasiroll::NlpSolverRegistry::Names();
  std::printf(
      "small QP: violation %.2e, KKT residual %.2e, NLP backends linked: %zu\n",
      violation, residual, backends.size());
  // Exact data: both are rounding-free zeros.
  return violation <= 1e-15 && residual <= 1e-15 && backends.empty() ? 0 : 1;
}
