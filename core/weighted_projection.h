// Weighted minimal-norm constraint correction and Newton projection for a
// ConstrainedOde (y' = F(t, y), H(y) = 0, J = dH/dy, D = diag(d) with
// d = CorrectionWeights() >= 0), model.md §8.3–§8.5, §8.7:
//
//   A = J D J^T                 (m x m, LDLT with pivots p_1..p_m)
//   delta = D J^T A^{-1} r      the D^{-1}-weighted minimal-norm dy with
//                               J dy = r (coordinates with d_i = 0 never move)
//   projection: y <- y - D J^T A^{-1} H(y), repeated until ||H(y)||_inf <= tol
//
// Uses: the velocity correction of rk-baumgarte (r = J F + sigma H), the
// Newton projection of rk-projection / cvode-projection / ida's polish
// (r = H), CVODE's tangent projection of the error estimate (r = J e) and
// IDA's initial multipliers (lambda = A^{-1} r). Plugins may use it too
// (docs/plugins.md).
//
// Factorize() accepts A only if the LDLT succeeded, A is finite and
//   max_i p_i > 0   and   min_i p_i > 1e3 * eps * max_i p_i,
// i.e. A is positive definite and not singular to working precision (J rank
// deficient, or d = 0 on every coordinate some constraint depends on).
//
// All workspaces are members, sized in Begin() only when the problem size
// changes, so repeated use performs no heap allocation (a failure message
// aside).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <string>

#include "quasiroll/core/dae.h"

namespace quasiroll {

// The two backend options of a Newton projection, spelled alike by every
// backend that projects (rk-projection, cvode-projection, ida, plugins):
//   projection_tolerance       > 0: stop when ||H||_inf <= this
//   max_projection_iterations  >= 1: corrections per projection
struct ProjectionSettings {
  double tolerance = 1e-12;
  int max_iterations = 10;

  // The two OptionSpecs, with the defaults above and the given docs.
  static OptionTable Options(
      const std::string& tolerance_doc =
          "projection stops when ||H||_inf <= this",
      const std::string& iterations_doc = "Newton corrections per projection");
  // The two settings from resolved backend options.
  static ProjectionSettings From(const OptionValues& values);
};

class WeightedProjection {
 public:
  // Sizes the workspaces and loads the weights d from ode (call once per
  // Integrate). Throws std::invalid_argument on a negative / non-finite d_i.
  void Begin(const ConstrainedOde& ode);

  int n() const { return n_; }
  int m() const { return m_; }

  // Evaluates J(y) (counted in result->jacobian_evaluations) and factorises
  // A = J D J^T. Returns false, with message() set, when the pivot test above
  // fails. A no-op returning true when m = 0.
  bool Factorize(const ConstrainedOde& ode,
                 const Eigen::Ref<const Eigen::VectorXd>& y,
                 IntegratorResult* result);
  // lambda = A^{-1} r with the last factorisation (r, lambda: m rows).
  void SolveMultiplier(const Eigen::Ref<const Eigen::VectorXd>& r,
                       Eigen::Ref<Eigen::VectorXd> lambda) const;
  // delta = D J^T lambda with the last factorisation's J.
  void Lift(const Eigen::Ref<const Eigen::VectorXd>& lambda,
            Eigen::Ref<Eigen::VectorXd> delta) const;

  // Newton projection y <- y - D J^T A^{-1} H(y) until ||H||_inf <= tol, at
  // most max_iterations corrections; A is refactorised at the current y
  // unless the previous correction contracted ||H||_inf by 1e3 or more (then
  // the last factorisation is kept: a chord step). Corrections are counted in
  // result->projection_iterations). *moved tells whether y changed; on
  // success the entry state's ||H||_inf enters result->step_drift_max.
  // Returns kSuccess, or kConstraintFailure with message() set.
  IntegratorStatus Project(const ConstrainedOde& ode,
                           Eigen::Ref<Eigen::VectorXd> y, double tol,
                           int max_iterations, IntegratorResult* result,
                           bool* moved);
  IntegratorStatus Project(const ConstrainedOde& ode,
                           Eigen::Ref<Eigen::VectorXd> y,
                           const ProjectionSettings& settings,
                           IntegratorResult* result, bool* moved) {
    return Project(ode, y, settings.tolerance, settings.max_iterations, result,
                   moved);
  }

  // Why the last Factorize() / Project() failed. The caller decides where it
  // goes (result->message, or a backend's own record when the failure is
  // recoverable).
  const std::string& message() const { return message_; }

  // Workspaces / last evaluations, valid after Factorize() / Project().
  const Eigen::MatrixXd& jacobian() const { return jac_; }
  const Eigen::VectorXd& weights() const { return d_; }
  Eigen::VectorXd& h() { return h_; }
  Eigen::VectorXd& r() { return r_; }
  Eigen::VectorXd& lambda() { return lambda_; }

 private:
  int n_ = -1, m_ = -1;
  Eigen::VectorXd d_;    // n, diagonal of D
  Eigen::MatrixXd jac_;  // m x n
  Eigen::MatrixXd jd_;   // m x n, J D
  Eigen::MatrixXd a_;    // m x m
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  Eigen::VectorXd h_, r_, lambda_, delta_;
  std::string message_;
};

}  // namespace quasiroll
