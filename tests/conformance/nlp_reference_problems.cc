#include "quasiroll/conformance/nlp_reference_problems.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace quasiroll {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

// ------------------------------------------------------------ the base ---
ReferenceProblem::ReferenceProblem()
    : objective_([](const In&) { return 0.0; }),
      gradient_([](const In&, Out grad) { grad.setZero(); }) {}

void ReferenceProblem::GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                                 Eigen::Ref<Eigen::VectorXd> x_ub,
                                 Eigen::Ref<Eigen::VectorXd> g_lb,
                                 Eigen::Ref<Eigen::VectorXd> g_ub) const {
  x_lb = x_lb_;
  x_ub = x_ub_;
  g_lb = g_lb_;
  g_ub = g_ub_;
}

double ReferenceProblem::Objective(
    const Eigen::Ref<const Eigen::VectorXd>& x) const {
  return objective_(x);
}

void ReferenceProblem::ObjectiveGradient(
    const Eigen::Ref<const Eigen::VectorXd>& x,
    Eigen::Ref<Eigen::VectorXd> grad) const {
  gradient_(x, grad);
}

void ReferenceProblem::Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                                   Eigen::Ref<Eigen::VectorXd> g) const {
  constraints_(x, g);
}

void ReferenceProblem::ConstraintJacobian(
    const Eigen::Ref<const Eigen::VectorXd>& x,
    Eigen::Ref<Eigen::MatrixXd> jac) const {
  jacobian_(x, jac);
}

void ReferenceProblem::LagrangianHessian(
    const Eigen::Ref<const Eigen::VectorXd>& x, double sigma,
    const Eigen::Ref<const Eigen::VectorXd>& lambda,
    Eigen::Ref<Eigen::MatrixXd> hess) const {
  if (hessian_) hessian_(x, sigma, lambda, hess);
}

// ---------------------------------------------------------------- HS 71 ---
Hs071Problem::Hs071Problem() {
  name_ = "hs071";
  x0_ = Eigen::Vector4d(1.0, 5.0, 5.0, 1.0);
  // Exact KKT point (x1 = 1 at its bound, both constraints active), solved
  // with 40-digit arithmetic (mpmath.findroot on the 5x5 KKT system;
  // multipliers -0.55229366012, 0.16146856677, bound multiplier 1.0878712287).
  // The widely quoted 16-digit values x = (1, 4.7429996418092970,
  // 3.8211499817883077, 1.3794082897556983), f = 17.014017145179164 are an
  // Ipopt answer at default tolerances: they violate x1 x2 x3 x4 >= 25 by
  // 5.4e-8 and sit 1.4e-7 below the true optimum.
  x_star_ = Eigen::Vector4d(1.0, 4.7429996372644171, 3.8211499841848739,
                            1.3794082931726724);
  f_star_ = 17.014017289156302;
  source_ = "Hock-Schittkowski #71; exact KKT point at 40 digits";
  x_lb_ = Eigen::Vector4d::Constant(1.0);
  x_ub_ = Eigen::Vector4d::Constant(5.0);
  g_lb_ = Eigen::Vector2d(25.0, 40.0);
  g_ub_ = Eigen::Vector2d(kInf, 40.0);
  objective_ = [](const In& x) {
    return x(0) * x(3) * (x(0) + x(1) + x(2)) + x(2);
  };
  gradient_ = [](const In& x, Out grad) {
    grad(0) = x(3) * (2.0 * x(0) + x(1) + x(2));
    grad(1) = x(0) * x(3);
    grad(2) = x(0) * x(3) + 1.0;
    grad(3) = x(0) * (x(0) + x(1) + x(2));
  };
  constraints_ = [](const In& x, Out g) {
    g(0) = x(0) * x(1) * x(2) * x(3);
    g(1) = x.squaredNorm();
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac(0, 0) = x(1) * x(2) * x(3);
    jac(0, 1) = x(0) * x(2) * x(3);
    jac(0, 2) = x(0) * x(1) * x(3);
    jac(0, 3) = x(0) * x(1) * x(2);
    jac.row(1) = 2.0 * x.transpose();
  };
  hessian_ = [](const In& x, double sigma, const In& lambda, MatrixOut hess) {
    const double l0 = lambda(0), l1 = lambda(1);
    hess.setZero();
    // Objective.
    hess(0, 0) = sigma * 2.0 * x(3);
    hess(1, 0) = sigma * x(3);
    hess(2, 0) = sigma * x(3);
    hess(3, 0) = sigma * (2.0 * x(0) + x(1) + x(2));
    hess(3, 1) = sigma * x(0);
    hess(3, 2) = sigma * x(0);
    // Product constraint.
    hess(1, 0) += l0 * x(2) * x(3);
    hess(2, 0) += l0 * x(1) * x(3);
    hess(3, 0) += l0 * x(1) * x(2);
    hess(2, 1) += l0 * x(0) * x(3);
    hess(3, 1) += l0 * x(0) * x(2);
    hess(3, 2) += l0 * x(0) * x(1);
    // Sphere constraint.
    hess.diagonal().array() += 2.0 * l1;
    hess.triangularView<Eigen::StrictlyUpper>() = hess.transpose();
  };
}

// ---------------------------------------------------------------- HS 32 ---
Hs032Problem::Hs032Problem() {
  name_ = "hs032";
  x0_ = Eigen::Vector3d(0.1, 0.7, 0.2);
  x_star_ = Eigen::Vector3d(0.0, 0.0, 1.0);
  f_star_ = 1.0;
  source_ = "Hock-Schittkowski #32 (exact)";
  x_lb_ = Eigen::Vector3d::Zero();
  x_ub_ = Eigen::Vector3d::Constant(kInf);
  g_lb_ = Eigen::Vector2d(3.0, 1.0);
  g_ub_ = Eigen::Vector2d(kInf, 1.0);
  objective_ = [](const In& x) {
    const double s = x(0) + 3.0 * x(1) + x(2), d = x(0) - x(1);
    return s * s + 4.0 * d * d;
  };
  gradient_ = [](const In& x, Out grad) {
    const double s = x(0) + 3.0 * x(1) + x(2), d = x(0) - x(1);
    grad(0) = 2.0 * s + 8.0 * d;
    grad(1) = 6.0 * s - 8.0 * d;
    grad(2) = 2.0 * s;
  };
  constraints_ = [](const In& x, Out g) {
    g(0) = 6.0 * x(1) + 4.0 * x(2) - x(0) * x(0) * x(0);
    g(1) = x(0) + x(1) + x(2);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac(0, 0) = -3.0 * x(0) * x(0);
    jac(0, 1) = 6.0;
    jac(0, 2) = 4.0;
    jac.row(1).setOnes();
  };
  hessian_ = [](const In& x, double sigma, const In& lambda, MatrixOut hess) {
    hess << 10.0, -2.0, 2.0,  //
        -2.0, 26.0, 6.0,      //
        2.0, 6.0, 2.0;
    hess *= sigma;
    hess(0, 0) += lambda(0) * (-6.0 * x(0));
  };
}

// ---------------------------------------------------------------- HS 40 ---
Hs040Problem::Hs040Problem() {
  name_ = "hs040";
  x0_ = Eigen::Vector4d::Constant(0.8);
  x_star_ = Eigen::Vector4d(std::pow(2.0, -1.0 / 3.0), std::pow(2.0, -0.5),
                            std::pow(2.0, -11.0 / 12.0), std::pow(2.0, -0.25));
  f_star_ = -0.25;
  source_ = "Hock-Schittkowski #40 (closed form)";
  x_lb_ = Eigen::Vector4d::Constant(-kInf);
  x_ub_ = Eigen::Vector4d::Constant(kInf);
  g_lb_ = Eigen::Vector3d(1.0, 0.0, 0.0);
  g_ub_ = g_lb_;
  objective_ = [](const In& x) { return -x(0) * x(1) * x(2) * x(3); };
  gradient_ = [](const In& x, Out grad) {
    grad(0) = -x(1) * x(2) * x(3);
    grad(1) = -x(0) * x(2) * x(3);
    grad(2) = -x(0) * x(1) * x(3);
    grad(3) = -x(0) * x(1) * x(2);
  };
  constraints_ = [](const In& x, Out g) {
    g(0) = x(0) * x(0) * x(0) + x(1) * x(1);
    g(1) = x(0) * x(0) * x(3) - x(2);
    g(2) = x(3) * x(3) - x(1);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac.setZero();
    jac(0, 0) = 3.0 * x(0) * x(0);
    jac(0, 1) = 2.0 * x(1);
    jac(1, 0) = 2.0 * x(0) * x(3);
    jac(1, 2) = -1.0;
    jac(1, 3) = x(0) * x(0);
    jac(2, 1) = -1.0;
    jac(2, 3) = 2.0 * x(3);
  };
  hessian_ = [](const In& x, double sigma, const In& lambda, MatrixOut hess) {
    hess.setZero();
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        if (i == j) continue;
        double p = -sigma;
        for (int k = 0; k < 4; ++k)
          if (k != i && k != j) p *= x(k);
        hess(i, j) = p;
      }
    }
    hess(0, 0) += lambda(0) * 6.0 * x(0);
    hess(1, 1) += lambda(0) * 2.0;
    hess(0, 0) += lambda(1) * 2.0 * x(3);
    hess(0, 3) += lambda(1) * 2.0 * x(0);
    hess(3, 0) += lambda(1) * 2.0 * x(0);
    hess(3, 3) += lambda(2) * 2.0;
  };
}

// ---------------------------------------------------------------- HS 73 ---
namespace {
const double kHs73Var[4] = {0.28, 0.19, 20.5, 0.62};
}

Hs073Problem::Hs073Problem() {
  name_ = "hs073";
  x0_ = Eigen::Vector4d::Ones();
  // Published (HS 1981): f* = 29.894378, x* = (0.6355216, -0.12e-11,
  // 0.3127019, 0.05177655). The optimum is a vertex (x2 = 0 and all three
  // constraints active), refined by solving those 3 equations in x1, x3, x4
  // with 40-digit arithmetic (mpmath.findroot); agrees with every published
  // digit, and every backend converges to it.
  x_star_ = Eigen::Vector4d(0.63552156863506973, 0.0, 0.31270188075152350,
                            0.051776550613406777);
  f_star_ = 29.894378159143353;
  source_ = "Hock-Schittkowski #73, vertex refined at 40 digits";
  x_lb_ = Eigen::Vector4d::Zero();
  x_ub_ = Eigen::Vector4d::Constant(kInf);
  g_lb_ = Eigen::Vector3d(5.0, 21.0, 1.0);
  g_ub_ = Eigen::Vector3d(kInf, kInf, 1.0);
  objective_ = [](const In& x) {
    return 24.55 * x(0) + 26.75 * x(1) + 39.0 * x(2) + 40.50 * x(3);
  };
  gradient_ = [](const In& /*x*/, Out grad) {
    grad << 24.55, 26.75, 39.0, 40.50;
  };
  constraints_ = [](const In& x, Out g) {
    double s = 0.0;
    for (int i = 0; i < 4; ++i) s += kHs73Var[i] * x(i) * x(i);
    g(0) = 2.3 * x(0) + 5.6 * x(1) + 11.1 * x(2) + 1.3 * x(3);
    g(1) = 12.0 * x(0) + 11.9 * x(1) + 41.8 * x(2) + 52.1 * x(3) -
           1.645 * std::sqrt(s);
    g(2) = x(0) + x(1) + x(2) + x(3);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    double s = 0.0;
    for (int i = 0; i < 4; ++i) s += kHs73Var[i] * x(i) * x(i);
    const double q = std::sqrt(s);
    jac.row(0) << 2.3, 5.6, 11.1, 1.3;
    jac.row(1) << 12.0, 11.9, 41.8, 52.1;
    // d sqrt(s) / dx_i = var_i x_i / sqrt(s); the origin (s = 0) is excluded
    // by the equality row, use the one-sided limit 0 there.
    if (q > 0.0)
      for (int i = 0; i < 4; ++i) jac(1, i) -= 1.645 * kHs73Var[i] * x(i) / q;
    jac.row(2).setOnes();
  };
}

// ------------------------------------------------------- infeasible NLP ---
InfeasibleDiskProblem::InfeasibleDiskProblem() {
  name_ = "infeasible_disk";
  x0_ = Eigen::Vector2d(0.5, 0.25);
  x_star_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  f_star_ = std::numeric_limits<double>::quiet_NaN();
  feasible_ = false;
  source_ = "disk of radius 1 never meets the half-plane x1 + x2 >= 3";
  x_lb_ = Eigen::Vector2d::Constant(-kInf);
  x_ub_ = Eigen::Vector2d::Constant(kInf);
  g_lb_ = Eigen::Vector2d(-kInf, 3.0);
  g_ub_ = Eigen::Vector2d(1.0, kInf);
  objective_ = [](const In& x) { return x.squaredNorm(); };
  gradient_ = [](const In& x, Out grad) { grad = 2.0 * x; };
  constraints_ = [](const In& x, Out g) {
    g(0) = x.squaredNorm();
    g(1) = x(0) + x(1);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac.row(0) = 2.0 * x.transpose();
    jac.row(1).setOnes();
  };
}

// ----------------------------------------------------- circle and line ---
CircleLineSystem::CircleLineSystem() {
  name_ = "circle_line";
  x0_ = Eigen::Vector2d(1.0, 0.5);
  x_star_ = Eigen::Vector2d::Constant(std::sqrt(2.0));
  f_star_ = 0.0;
  source_ = "closed form (sqrt 2, sqrt 2)";
  x_lb_ = Eigen::Vector2d(0.0, -kInf);
  x_ub_ = Eigen::Vector2d::Constant(kInf);
  g_lb_ = Eigen::Vector3d(4.0, 0.0, -kInf);
  g_ub_ = Eigen::Vector3d(4.0, 0.0, 10.0);
  constraints_ = [](const In& x, Out g) {
    g(0) = x.squaredNorm();
    g(1) = x(0) - x(1);
    g(2) = x(0) + 2.0 * x(1);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac.row(0) = 2.0 * x.transpose();
    jac.row(1) << 1.0, -1.0;
    jac.row(2) << 1.0, 2.0;
  };
}

// ------------------------------------------------- contact-like system ---
ContactLikeSystem::ContactLikeSystem(int n) {
  if (n < 9)
    throw std::invalid_argument("ContactLikeSystem: n must be >= 9, got " +
                                std::to_string(n));
  name_ = "contact_like_" + std::to_string(n);
  Eigen::MatrixXd a(n, n);
  const double off = 3.4 / (n - 1);  // row sums of |off-diagonal| <= 3.4 < 4
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      a(i, j) = i == j ? 4.0 + 0.1 * i / n : off * std::cos(0.7 * i + 1.9 * j);
  x_star_.resize(n);
  for (int i = 0; i < n; ++i) x_star_(i) = 0.5 + 0.3 * std::sin(1.3 * i + 0.4);
  for (int j = 0; j < 3; ++j) {
    x_star_(2 * j) = 0.2 - 0.1 * j;  // tangential components
    x_star_(2 * j + 1) = -0.3 + 0.1 * j;
    x_star_(n - 3 + j) = 1.0 + 0.1 * j;  // normal forces
  }
  x0_.resize(n);
  for (int i = 0; i < n; ++i)
    x0_(i) = x_star_(i) + 0.15 * std::cos(2.1 * i + 0.3);
  f_star_ = 0.0;
  source_ = "exact root by construction";
  x_lb_ = Eigen::VectorXd::Constant(n, -kInf);
  x_lb_.tail(3).setZero();
  x_ub_ = Eigen::VectorXd::Constant(n, kInf);
  g_lb_ = Eigen::VectorXd::Zero(n + 3);
  g_ub_ = Eigen::VectorXd::Zero(n + 3);
  g_lb_.tail(3).setConstant(-kInf);
  constraints_ = [n, a, xs = x_star_](const In& x, Out g) {
    for (int i = 0; i < n; ++i) {
      double s = 0.0;
      for (int j = 0; j < n; ++j) s += a(i, j) * (x(j) - xs(j));
      const double di = x(i) - xs(i);
      const int k = (i + 1) % n;
      g(i) = s + 0.5 * di * di + 0.25 * std::sin(x(k) - xs(k));
    }
    for (int j = 0; j < 3; ++j) {
      const double fn = x(n - 3 + j);
      g(n + j) =
          x(2 * j) * x(2 * j) + x(2 * j + 1) * x(2 * j + 1) - 0.64 * fn * fn;
    }
  };
  jacobian_ = [n, a, xs = x_star_](const In& x, MatrixOut jac) {
    jac.topRows(n) = a;
    for (int i = 0; i < n; ++i) {
      const int k = (i + 1) % n;
      jac(i, i) += x(i) - xs(i);
      jac(i, k) += 0.25 * std::cos(x(k) - xs(k));
    }
    jac.bottomRows(3).setZero();
    for (int j = 0; j < 3; ++j) {
      jac(n + j, 2 * j) = 2.0 * x(2 * j);
      jac(n + j, 2 * j + 1) = 2.0 * x(2 * j + 1);
      jac(n + j, n - 3 + j) = -1.28 * x(n - 3 + j);
    }
  };
}

// ------------------------------------------------ infeasible-root system ---
InfeasibleRootSystem::InfeasibleRootSystem() {
  name_ = "infeasible_root";
  x0_ = Eigen::Vector2d(0.0, 1.0);
  // The root of the equalities, which violates x2 <= 2.
  x_star_ = Eigen::Vector2d(std::log(2.0), 3.0 - std::log(2.0));
  f_star_ = 0.0;
  feasible_ = false;
  source_ = "unique root (ln 2, 3 - ln 2) violates x2 <= 2";
  x_lb_ = Eigen::Vector2d::Constant(-kInf);
  x_ub_ = Eigen::Vector2d(kInf, 2.0);
  g_lb_ = Eigen::Vector2d(2.0, 3.0);
  g_ub_ = g_lb_;
  constraints_ = [](const In& x, Out g) {
    g(0) = std::exp(x(0));
    g(1) = x(0) + x(1);
  };
  jacobian_ = [](const In& x, MatrixOut jac) {
    jac(0, 0) = std::exp(x(0));
    jac(0, 1) = 0.0;
    jac.row(1).setOnes();
  };
}

// ------------------------------------------------------------- factory ---
std::vector<std::unique_ptr<ReferenceProblem>> MakeReferenceProblems() {
  std::vector<std::unique_ptr<ReferenceProblem>> v;
  v.push_back(std::make_unique<Hs071Problem>());
  v.push_back(std::make_unique<Hs032Problem>());
  v.push_back(std::make_unique<Hs040Problem>());
  v.push_back(std::make_unique<Hs073Problem>());
  v.push_back(std::make_unique<InfeasibleDiskProblem>());
  v.push_back(std::make_unique<CircleLineSystem>());
  v.push_back(std::make_unique<ContactLikeSystem>(18));
  v.push_back(std::make_unique<InfeasibleRootSystem>());
  return v;
}

std::unique_ptr<ReferenceProblem> MakeReferenceProblem(
    const std::string& name) {
  for (auto& p : MakeReferenceProblems())
    if (p->name() == name) return std::move(p);
  return nullptr;
}

}  // namespace quasiroll
