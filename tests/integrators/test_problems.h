// Small constrained / unconstrained ODEs with known solutions for the
// integrator tests.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "quasiroll/conformance/integrator_reference_problems.h"
#include "quasiroll/core/dae.h"

namespace quasiroll::testing {

// The kit's reference problems, under the names the tests use.
using ::quasiroll::PendulumOde;
using ::quasiroll::SevenBodyMechanismOde;

// y' = A y with A = [[0, w], [-w, 0]]: y(t) = rotation of y0 by angle w t.
class HarmonicOde : public ConstrainedOde {
 public:
  explicit HarmonicOde(double omega = 1.0) : omega_(omega) {}
  int state_size() const override { return 2; }
  int num_constraints() const override { return 0; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    ydot(0) = omega_ * y(1);
    ydot(1) = -omega_ * y(0);
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd>) const override {}
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd>) const override {}
  Eigen::Vector2d Exact(double t, const Eigen::Vector2d& y0) const {
    const double c = std::cos(omega_ * t), s = std::sin(omega_ * t);
    return {c * y0(0) + s * y0(1), -s * y0(0) + c * y0(1)};
  }

 private:
  double omega_;
};

// Nonlinear 3-D field with the linear constraint H = y0 + 2 y1 - y2 - c.
// Under rk-baumgarte H obeys H' = -sigma H exactly, and because H is linear
// the RK iterates obey H_{k+1} = R(-sigma h) H_k with R the method's
// stability function (model.md §9.1, O8).
class LinearConstraintOde : public ConstrainedOde {
 public:
  explicit LinearConstraintOde(double c = 1.0) : c_(c) {}
  int state_size() const override { return 3; }
  int num_constraints() const override { return 1; }
  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    ydot(0) = -y(1) + 0.3 * std::sin(t);
    ydot(1) = y(0) - 0.1 * y(1) * y(1);
    ydot(2) = 0.5 * std::sin(y(0));
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    h(0) = y(0) + 2 * y(1) - y(2) - c_;
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd> j) const override {
    j << 1, 2, -1;
  }
  void CorrectionWeights(Eigen::Ref<Eigen::VectorXd> d) const override {
    d << 1.0, 0.5, 0.0;  // y2 is never corrected
  }

 private:
  double c_;
};

// Falling body y = (height, velocity), y'' = -g, root function g = height.
class FallingBodyOde : public ConstrainedOde {
 public:
  explicit FallingBodyOde(double gravity = 9.81) : g_(gravity) {}
  int state_size() const override { return 2; }
  int num_constraints() const override { return 0; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    ydot(0) = y(1);
    ydot(1) = -g_;
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>&,
                   Eigen::Ref<Eigen::VectorXd>) const override {}
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>&,
                          Eigen::Ref<Eigen::MatrixXd>) const override {}
  int num_roots() const override { return 2; }
  void Roots(double, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override {
    g(0) = y(0) + 100.0;  // never fires in the tests
    g(1) = y(0);          // ground contact
  }
  double gravity() const { return g_; }

 private:
  double g_;
};

// Sizes of the robot loop-closure client: state 21, 12 nonlinear holonomic
// constraints, correction weights D with zeros. Synthetic but smooth:
//   H_i = y_i + 0.2 sin(y_{12 + i % 9}) y_{(i + 1) % 12} - c_i,  i < 12
// (J has the identity in its first 12 columns, so J D J^T is nonsingular as
// long as the first 12 weights are positive). Like the quasi-static velocity
// of the client, F is tangent to the constraint manifold (J F = 0): a smooth
// drift G projected with the unweighted J^+ , F = G - J^T (J J^T)^{-1} J G.
// (For a field with J F != 0, "RK step of F + projection" is a splitting of
// order 1 only; see integrators/rk_projection.h.)
class RobotSizedOde : public ConstrainedOde {
 public:
  int state_size() const override { return 21; }
  int num_constraints() const override { return 12; }
  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    Eigen::VectorXd g(21);
    for (int j = 0; j < 21; ++j)
      g(j) = std::cos(t + 0.1 * j) - 0.1 * y(j) + 0.05 * y((j + 5) % 21);
    Eigen::MatrixXd jac(12, 21);
    ConstraintJacobian(y, jac);
    const Eigen::VectorXd mult = (jac * jac.transpose()).ldlt().solve(jac * g);
    ydot = g - jac.transpose() * mult;
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    for (int i = 0; i < 12; ++i)
      h(i) = y(i) + 0.2 * std::sin(y(12 + i % 9)) * y((i + 1) % 12) - 0.1 * i;
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> j) const override {
    j.setZero();
    for (int i = 0; i < 12; ++i) {
      const int a = 12 + i % 9, b = (i + 1) % 12;
      j(i, i) += 1.0;
      j(i, a) += 0.2 * std::cos(y(a)) * y(b);
      j(i, b) += 0.2 * std::sin(y(a));
    }
  }
  void CorrectionWeights(Eigen::Ref<Eigen::VectorXd> d) const override {
    d.setOnes();
    d(14) = d(17) = d(20) = 0.0;
    d(3) = 0.5;
  }
  Eigen::VectorXd Initial() const {
    Eigen::VectorXd y(21);
    for (int j = 0; j < 21; ++j) y(j) = 0.1 * std::sin(1.0 + j);
    return y;  // inconsistent: the backends project / correct it
  }
};

// Wraps a problem; Rhs returns false for t > fail_after.
class FailingRhsOde : public PendulumOde {
 public:
  explicit FailingRhsOde(double fail_after) : fail_after_(fail_after) {}
  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    if (t > fail_after_) return false;
    return PendulumOde::Rhs(t, y, ydot);
  }

 private:
  double fail_after_;
};

// A pendulum whose Rhs fails on the listed call numbers (1-based) and nowhere
// else: a stand-in for an F that cannot be evaluated at some trial points
// (a corrector iterate, a finite-difference perturbation) although the
// solution path itself stays inside its domain.
class FlakyRhsOde : public PendulumOde {
 public:
  explicit FlakyRhsOde(std::vector<int> failing_calls)
      : failing_calls_(std::move(failing_calls)) {}
  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    ++calls_;
    if (std::find(failing_calls_.begin(), failing_calls_.end(), calls_) !=
        failing_calls_.end()) {
      ++failures_;
      return false;
    }
    return PendulumOde::Rhs(t, y, ydot);
  }
  int failures() const { return failures_; }

 private:
  std::vector<int> failing_calls_;
  int calls_ = 0;
  int failures_ = 0;
};

}  // namespace quasiroll::testing
