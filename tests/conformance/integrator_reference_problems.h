// Reference problems of the integrator conformance kit (docs/plugins.md,
// "Conformance kit"): constrained ODEs with independent reference solutions.
//   * PendulumOde: a planar pendulum in Cartesian coordinates, reference from
//     the unconstrained angle ODE;
//   * SevenBodyMechanismOde: Andrews' squeezing mechanism, reference from the
//     Bari IVP test set.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// Planar pendulum in Cartesian coordinates y = (x, y, vx, vy), length l,
// gravity g along -y. F is the "ODE form" with the tension computed from the
// state, lambda = (|v|^2 - g y) / (x^2 + y^2), so exact solutions keep
//   H1 = x^2 + y^2 - l^2 = 0   (position level)
//   H2 = x vx + y vy     = 0   (velocity level)
// but numerical ones drift.
class PendulumOde : public ConstrainedOde {
 public:
  PendulumOde(double length = 1.0, double gravity = 9.81)
      : l_(length), g_(gravity) {}
  int state_size() const override { return 4; }
  int num_constraints() const override { return 2; }
  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    const double r2 = y(0) * y(0) + y(1) * y(1);
    const double v2 = y(2) * y(2) + y(3) * y(3);
    const double lambda = (v2 - g_ * y(1)) / r2;
    ydot(0) = y(2);
    ydot(1) = y(3);
    ydot(2) = -lambda * y(0);
    ydot(3) = -lambda * y(1) - g_;
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    h(0) = y(0) * y(0) + y(1) * y(1) - l_ * l_;
    h(1) = y(0) * y(2) + y(1) * y(3);
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> j) const override {
    j << 2 * y(0), 2 * y(1), 0, 0,  //
        y(2), y(3), y(0), y(1);
  }
  // State at rest at angle theta from the downward vertical.
  Eigen::Vector4d AtAngle(double theta, double omega = 0.0) const {
    return {l_ * std::sin(theta), -l_ * std::cos(theta),
            l_ * omega * std::cos(theta), l_ * omega * std::sin(theta)};
  }
  // Reference: the angle ODE theta'' = -(g/l) sin(theta) (an independent,
  // unconstrained formulation), classic RK4 with h = 1e-5 written out here
  // (global error ~ 1e-17 * C, far below every tolerance tested).
  Eigen::Vector4d Reference(double theta0, double t_end) const {
    double th = theta0, om = 0.0;
    const int steps = static_cast<int>(std::llround(t_end / 1e-5));
    const double h = t_end / steps;
    auto acc = [this](double a) { return -(g_ / l_) * std::sin(a); };
    for (int i = 0; i < steps; ++i) {
      const double k1t = om, k1o = acc(th);
      const double k2t = om + 0.5 * h * k1o, k2o = acc(th + 0.5 * h * k1t);
      const double k3t = om + 0.5 * h * k2o, k3o = acc(th + 0.5 * h * k2t);
      const double k4t = om + h * k3o, k4o = acc(th + h * k3t);
      th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      om += h / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    }
    return AtAngle(th, om);
  }
  double length() const { return l_; }

 private:
  double l_, g_;
};

// Andrews' squeezing mechanism, the seven-body planar mechanism of Hairer &
// Wanner, "Solving ODEs II", sec. VII.7 (also the "andrews" problem of the
// Bari IVP test set): seven bodies on revolute joints, angles
// q = (beta, Theta, gamma, Phi, delta, Omega, epsilon), a driving torque
// mom on the crank and a spring on the third body. Here in the explicit ODE
// form y = (q, v), y' = (v, M(q)^{-1} (f(q, v) - G(q)^T lambda)) with the
// multipliers from the index-1 condition d^2/dt^2 g(q) = 0,
//   (G M^{-1} G^T) lambda = G M^{-1} f + Q,   Q = (d^2 g / dq^2)[v, v],
// and H(y) = (g(q), G(q) v) (12 rows: positions and velocities of the three
// loop closures). Every g_i is a sum of terms coef * cos|sin(sum of angles)
// plus a constant, so g, G = dg/dq, Q and d(G v)/dq come from one table of
// terms and are consistent by construction. All data (masses, inertias,
// geometry, spring, torque, consistent initial values) are the test set's.
// The motion is fast (beta turns by ~16 rad in 0.03 s; |v'| = 1.4e4 at t0),
// which is what makes a first step of the whole interval hopeless.
class SevenBodyMechanismOde : public ConstrainedOde {
 public:
  static constexpr double m1 = .04325, m2 = .00365, m3 = .02373, m4 = .00706,
                          m5 = .07050, m6 = .00706, m7 = .05498;
  static constexpr double i1 = 2.194e-6, i2 = 4.410e-7, i3 = 5.255e-6,
                          i4 = 5.667e-7, i5 = 1.169e-5, i6 = 5.667e-7,
                          i7 = 1.912e-5;
  static constexpr double xa = -.06934, ya = -.00227, xb = -.03635, yb = .03273,
                          xc = .014, yc = .072;
  static constexpr double d = 28e-3, da = 115e-4, e = 2e-2, ea = 1421e-5;
  static constexpr double rr = 7e-3, ra = 92e-5;
  static constexpr double ss = 35e-3, sa = 1874e-5, sb = 1043e-5, sc = 18e-3,
                          sd = 2e-2;
  static constexpr double ta = 2308e-5, tb = 916e-5;
  static constexpr double u = 4e-2, ua = 1228e-5, ub = 449e-5;
  static constexpr double zf = 2e-2, zt = 4e-2, fa = 1421e-5;
  static constexpr double mom = 0.033, c0 = 4530.0, l0 = 0.07785;

  int state_size() const override { return 14; }
  int num_constraints() const override { return 12; }

  // The test set's reference solution at t = kReferenceTime: the angles
  // beta, Theta, gamma (y(0..2)).
  static constexpr double kReferenceTime = 0.03;
  static constexpr double kReferenceAngles[3] = {
      15.81077119629904, -15.75637105984298, 0.04082224013073101};

  // The test set's consistent initial angles (velocities 0).
  static Eigen::VectorXd Initial() {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(14);
    y << -0.0617138900142764496358948458001, 0.0,
        0.455279819163070380255912382449, 0.222668390165885884674473185609,
        0.487364979543842550225598953530, -0.222668390165885884674473185609,
        1.23054744454982119249735015568, 0, 0, 0, 0, 0, 0, 0;
    return y;
  }

  bool Rhs(double, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    Eigen::Matrix<double, 7, 1> acc;
    Accelerations(y, &acc, nullptr);
    ydot.head(7) = y.tail(7);
    ydot.tail(7) = acc;
    return ydot.allFinite();
  }

  // q'' and (optionally) the multipliers lambda (first 6 entries) at y.
  void Accelerations(const Eigen::Ref<const Eigen::VectorXd>& y,
                     Eigen::Matrix<double, 7, 1>* acc,
                     Eigen::Matrix<double, 6, 1>* lambda_out) const {
    const Eigen::Matrix<double, 7, 1> q = y.head(7), v = y.tail(7);
    Eigen::Matrix<double, 7, 7> m;
    MassMatrix(q, &m);
    Eigen::Matrix<double, 7, 1> f;
    Forces(q, v, &f);
    Eigen::Matrix<double, 6, 7> g;
    Eigen::Matrix<double, 6, 1> qv;
    PositionJacobian(q, &g);
    Curvature(q, v, &qv);
    const Eigen::LDLT<Eigen::Matrix<double, 7, 7>> mass(m);
    const Eigen::Matrix<double, 7, 6> minv_gt = mass.solve(g.transpose());
    const Eigen::Matrix<double, 7, 1> minv_f = mass.solve(f);
    const Eigen::Matrix<double, 6, 6> s = g * minv_gt;
    const Eigen::Matrix<double, 6, 1> lambda =
        s.partialPivLu().solve(g * minv_f + qv);
    *acc = minv_f - minv_gt * lambda;
    if (lambda_out) *lambda_out = lambda;
  }

  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    const Eigen::Matrix<double, 7, 1> q = y.head(7), v = y.tail(7);
    for (int i = 0; i < 6; ++i) h(i) = Offset(i);
    for (const Term& t : Terms()) h(t.row) += t.coef * Trig(t, q, 0);
    Eigen::Matrix<double, 6, 7> g;
    PositionJacobian(q, &g);
    h.tail(6) = g * v;
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    const Eigen::Matrix<double, 7, 1> q = y.head(7), v = y.tail(7);
    Eigen::Matrix<double, 6, 7> g;
    PositionJacobian(q, &g);
    jac.setZero();
    jac.topLeftCorner(6, 7) = g;
    jac.bottomRightCorner(6, 7) = g;
    // d(G v)/dq: term coef * trig''(phi) (c . v) c^T.
    for (const Term& t : Terms()) {
      const double cv = v(t.a) + (t.b >= 0 ? v(t.b) : 0.0);
      const double w = t.coef * Trig(t, q, 2) * cv;
      jac(6 + t.row, t.a) += w;
      if (t.b >= 0) jac(6 + t.row, t.b) += w;
    }
  }

 private:
  struct Term {
    int row;
    double coef;
    bool cosine;
    int a, b;  // angle = q(a) + q(b) (b = -1: q(a) alone)
  };
  static const std::vector<Term>& Terms() {
    static const std::vector<Term> terms = {
        {0, rr, true, 0, -1},  {0, -d, true, 0, 1},    {0, -ss, false, 2, -1},
        {1, rr, false, 0, -1}, {1, -d, false, 0, 1},   {1, ss, true, 2, -1},
        {2, rr, true, 0, -1},  {2, -d, true, 0, 1},    {2, -e, false, 3, 4},
        {2, -zt, true, 4, -1}, {3, rr, false, 0, -1},  {3, -d, false, 0, 1},
        {3, e, true, 3, 4},    {3, -zt, false, 4, -1}, {4, rr, true, 0, -1},
        {4, -d, true, 0, 1},   {4, -zf, true, 5, 6},   {4, -u, false, 6, -1},
        {5, rr, false, 0, -1}, {5, -d, false, 0, 1},   {5, -zf, false, 5, 6},
        {5, u, true, 6, -1}};
    return terms;
  }
  static double Offset(int row) {
    const double offsets[6] = {-xb, -yb, -xa, -ya, -xa, -ya};
    return offsets[row];
  }
  // k-th derivative of the term's trig function at its angle.
  static double Trig(const Term& t, const Eigen::Matrix<double, 7, 1>& q,
                     int k) {
    const double phi = q(t.a) + (t.b >= 0 ? q(t.b) : 0.0);
    // cos, -sin, -cos ; sin, cos, -sin
    if (t.cosine)
      return k == 0 ? std::cos(phi) : k == 1 ? -std::sin(phi) : -std::cos(phi);
    return k == 0 ? std::sin(phi) : k == 1 ? std::cos(phi) : -std::sin(phi);
  }
  static void PositionJacobian(const Eigen::Matrix<double, 7, 1>& q,
                               Eigen::Matrix<double, 6, 7>* g) {
    g->setZero();
    for (const Term& t : Terms()) {
      const double w = t.coef * Trig(t, q, 1);
      (*g)(t.row, t.a) += w;
      if (t.b >= 0) (*g)(t.row, t.b) += w;
    }
  }
  // Q = (d^2 g / dq^2)[v, v].
  static void Curvature(const Eigen::Matrix<double, 7, 1>& q,
                        const Eigen::Matrix<double, 7, 1>& v,
                        Eigen::Matrix<double, 6, 1>* qv) {
    qv->setZero();
    for (const Term& t : Terms()) {
      const double cv = v(t.a) + (t.b >= 0 ? v(t.b) : 0.0);
      (*qv)(t.row) += t.coef * Trig(t, q, 2) * cv * cv;
    }
  }
  static void MassMatrix(const Eigen::Matrix<double, 7, 1>& q,
                         Eigen::Matrix<double, 7, 7>* m) {
    const double coth = std::cos(q(1)), siph = std::sin(q(3)),
                 siom = std::sin(q(5));
    m->setZero();
    (*m)(0, 0) =
        m1 * ra * ra + m2 * (rr * rr - 2 * da * rr * coth + da * da) + i1 + i2;
    (*m)(1, 0) = (*m)(0, 1) = m2 * (da * da - da * rr * coth) + i2;
    (*m)(1, 1) = m2 * da * da + i2;
    (*m)(2, 2) = m3 * (sa * sa + sb * sb) + i3;
    (*m)(3, 3) = m4 * (e - ea) * (e - ea) + i4;
    (*m)(4, 3) = (*m)(3, 4) =
        m4 * ((e - ea) * (e - ea) + zt * (e - ea) * siph) + i4;
    (*m)(4, 4) =
        m4 * (zt * zt + 2 * zt * (e - ea) * siph + (e - ea) * (e - ea)) +
        m5 * (ta * ta + tb * tb) + i4 + i5;
    (*m)(5, 5) = m6 * (zf - fa) * (zf - fa) + i6;
    (*m)(6, 5) = (*m)(5, 6) =
        m6 * ((zf - fa) * (zf - fa) - u * (zf - fa) * siom) + i6;
    (*m)(6, 6) =
        m6 * ((zf - fa) * (zf - fa) - 2 * u * (zf - fa) * siom + u * u) +
        m7 * (ua * ua + ub * ub) + i6 + i7;
  }
  static void Forces(const Eigen::Matrix<double, 7, 1>& q,
                     const Eigen::Matrix<double, 7, 1>& v,
                     Eigen::Matrix<double, 7, 1>* f) {
    const double sith = std::sin(q(1)), siga = std::sin(q(2)),
                 coga = std::cos(q(2)), coph = std::cos(q(3)),
                 coom = std::cos(q(5));
    const double xd = sd * coga + sc * siga + xb;
    const double yd = sd * siga - sc * coga + yb;
    const double lang = std::hypot(xd - xc, yd - yc);
    const double force = -c0 * (lang - l0) / lang;
    const double fx = force * (xd - xc), fy = force * (yd - yc);
    (*f)(0) = mom - m2 * da * rr * v(1) * (v(1) + 2 * v(0)) * sith;
    (*f)(1) = m2 * da * rr * v(0) * v(0) * sith;
    (*f)(2) = fx * (sc * coga - sd * siga) + fy * (sd * coga + sc * siga);
    (*f)(3) = m4 * zt * (e - ea) * v(4) * v(4) * coph;
    (*f)(4) = -m4 * zt * (e - ea) * v(3) * (v(3) + 2 * v(4)) * coph;
    (*f)(5) = -m6 * u * (zf - fa) * v(6) * v(6) * coom;
    (*f)(6) = m6 * u * (zf - fa) * v(5) * (v(5) + 2 * v(6)) * coom;
  }
};

}  // namespace quasiroll
