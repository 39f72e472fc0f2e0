#include "quasiroll/core/weighted_projection.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace quasiroll {

namespace {
// Contraction of ||H|| by the last correction below which Project() keeps
// the factorisation (a chord step) instead of refactorising.
constexpr double kChordContraction = 1e-3;
}  // namespace

OptionTable ProjectionSettings::Options(const std::string& tolerance_doc,
                                        const std::string& iterations_doc) {
  const ProjectionSettings defaults;
  return {OptionSpec::Double("projection_tolerance", defaults.tolerance,
                             tolerance_doc)
              .GreaterThan(0),
          OptionSpec::Int("max_projection_iterations", defaults.max_iterations,
                          iterations_doc)
              .AtLeast(1)};
}

ProjectionSettings ProjectionSettings::From(const OptionValues& values) {
  ProjectionSettings settings;
  settings.tolerance = values.GetDouble("projection_tolerance");
  settings.max_iterations =
      static_cast<int>(values.GetInt("max_projection_iterations"));
  return settings;
}

void WeightedProjection::Begin(const ConstrainedOde& ode) {
  const int n = ode.state_size(), m = ode.num_constraints();
  if (n != n_ || m != m_) {
    n_ = n;
    m_ = m;
    d_.resize(n);
    jac_.resize(m, n);
    jd_.resize(m, n);
    a_.resize(m, m);
    h_.resize(m);
    r_.resize(m);
    lambda_.resize(m);
    delta_.resize(n);
  }
  d_.setOnes();
  ode.CorrectionWeights(d_);
  for (int i = 0; i < n; ++i) {
    if (!(std::isfinite(d_(i)) && d_(i) >= 0)) {
      std::ostringstream os;
      os << "ConstrainedOde::CorrectionWeights: d[" << i
         << "] must be finite and >= 0, got " << d_(i);
      throw std::invalid_argument(os.str());
    }
  }
}

bool WeightedProjection::Factorize(const ConstrainedOde& ode,
                                   const Eigen::Ref<const Eigen::VectorXd>& y,
                                   IntegratorResult* result) {
  if (m_ == 0) return true;
  ode.ConstraintJacobian(y, jac_);
  ++result->jacobian_evaluations;
  jd_.noalias() = jac_ * d_.asDiagonal();
  a_.noalias() = jd_ * jac_.transpose();
  ldlt_.compute(a_);
  bool ok = ldlt_.info() == Eigen::Success && a_.allFinite();
  if (ok) {
    const auto pivots = ldlt_.vectorD();
    const double max_pivot = pivots.maxCoeff();
    // Pivot ratio below ~1e3 eps: J D J^T is singular to working precision
    // (J rank deficient, or D zero on every coordinate a constraint sees).
    ok = max_pivot > 0 &&
         pivots.minCoeff() >
             1e3 * std::numeric_limits<double>::epsilon() * max_pivot;
  }
  if (!ok) {
    std::ostringstream os;
    os << "J D J^T is singular or not positive definite (m = " << m_ << ")";
    message_ = os.str();
  }
  return ok;
}

void WeightedProjection::SolveMultiplier(
    const Eigen::Ref<const Eigen::VectorXd>& r,
    Eigen::Ref<Eigen::VectorXd> lambda) const {
  if (m_ == 0) return;
  lambda = ldlt_.solve(r);
}

void WeightedProjection::Lift(const Eigen::Ref<const Eigen::VectorXd>& lambda,
                              Eigen::Ref<Eigen::VectorXd> delta) const {
  if (m_ == 0) {
    delta.setZero();
    return;
  }
  delta.noalias() = jd_.transpose() * lambda;
}

IntegratorStatus WeightedProjection::Project(const ConstrainedOde& ode,
                                             Eigen::Ref<Eigen::VectorXd> y,
                                             double tol, int max_iterations,
                                             IntegratorResult* result,
                                             bool* moved) {
  *moved = false;
  if (m_ == 0) return IntegratorStatus::kSuccess;
  double entry = 0.0;      // ||H|| of the state handed in
  double corrected = 0.0;  // ||H|| before the last correction
  for (int it = 0;; ++it) {
    ode.Constraints(y, h_);
    const double violation = h_.lpNorm<Eigen::Infinity>();
    if (it == 0) entry = violation;
    if (violation <= tol) {
      result->step_drift_max = std::fmax(result->step_drift_max, entry);
      return IntegratorStatus::kSuccess;
    }
    if (!std::isfinite(violation) || it == max_iterations) {
      std::ostringstream os;
      os << "projection: ||H||_inf = " << violation << " > tolerance " << tol
         << " after " << it << " iterations";
      message_ = os.str();
      return IntegratorStatus::kConstraintFailure;
    }
    // Chord steps: the factorisation is kept while the last correction
    // contracted ||H|| by kChordContraction or more. Then J moved by
    // O(|correction|) ~ O(||H_prev||) since it was factorised, and the
    // chord step contracts ||H|| by about that much again (after an RK4
    // step with ||H|| ~ 1e-6 the second correction meets 1e-12 either way).
    // (it > 0: an earlier pass factorised, or it would have returned.)
    const bool reuse = it > 0 && violation <= kChordContraction * corrected;
    if (!reuse && !Factorize(ode, y, result)) {
      message_ = "projection: " + message_;
      return IntegratorStatus::kConstraintFailure;
    }
    corrected = violation;
    lambda_ = ldlt_.solve(h_);
    delta_.noalias() = jd_.transpose() * lambda_;
    y -= delta_;
    *moved = true;
    ++result->projection_iterations;
  }
}

}  // namespace quasiroll
