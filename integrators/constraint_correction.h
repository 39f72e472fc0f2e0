// Weighted minimal-norm constraint correction shared by the backends
// (model.md §8.3–§8.5):
//
//   A = J D J^T  (m x m, factorised by LDLT),   delta = D J^T A^{-1} r
//
// delta is the D^{-1}-weighted minimal-norm change dy with J dy = r. It is the
// velocity correction of rk-baumgarte (r = J F + sigma H), one Gauss-Newton
// step of the projection (r = H) and the multiplier term of IDA's consistent
// initial values. All workspaces are members, sized once per problem size, so
// repeated use performs no heap allocation.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "quasiroll/core/dae.h"

namespace quasiroll::integrators_internal {

class ConstraintCorrection {
 public:
  // Sizes the workspaces and loads the weights D from ode (called once per
  // Integrate). Throws std::invalid_argument on negative / non-finite weights.
  void Begin(const ConstrainedOde& ode);

  int n() const { return n_; }
  int m() const { return m_; }

  // Evaluates J(y) and factorises A = J D J^T. Returns false (and writes
  // result->message) when A is not numerically positive definite.
  bool Factorize(const ConstrainedOde& ode,
                 const Eigen::Ref<const Eigen::VectorXd>& y,
                 IntegratorResult* result);
  // lambda = A^{-1} r with the last factorisation (r, lambda: m rows).
  void SolveMultiplier(const Eigen::Ref<const Eigen::VectorXd>& r,
                       Eigen::Ref<Eigen::VectorXd> lambda) const;
  // delta = D J^T lambda.
  void Lift(const Eigen::Ref<const Eigen::VectorXd>& lambda,
            Eigen::Ref<Eigen::VectorXd> delta) const;

  // Newton projection y <- y - D J^T A^{-1} H(y) until ||H||_inf <= tol, at
  // most max_iterations corrections. *moved tells whether y changed.
  // Returns kSuccess or kConstraintFailure (message set).
  IntegratorStatus Project(const ConstrainedOde& ode,
                           Eigen::Ref<Eigen::VectorXd> y, double tol,
                           int max_iterations, IntegratorResult* result,
                           bool* moved);

  // Workspaces / last evaluations, valid after Factorize / Project.
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
};

}  // namespace quasiroll::integrators_internal
