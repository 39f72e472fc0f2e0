// LU with partial pivoting of a small square matrix, P A = L U, for the hot
// Newton and KKT-verification solves of the quasi-static problem (15 x 15 on
// the paper scene, ~2,600 factorisations per 20 s run).
//
// Results are bit-identical to Eigen::PartialPivLU<Eigen::MatrixXd> (Eigen
// 3.4), so switching to it changes no trajectory:
//  - n <= kMaxFastSize: Eigen's unblocked right-looking algorithm, written as
//    plain loops over a fixed column-major array: column k takes the first
//    row of largest |a_ik|, i >= k; l_ik = a_ik / u_kk; then
//    a_ij <- a_ij - l_ik u_kj for i, j > k. Eigen runs the same arithmetic
//    through block expressions whose per-column overhead costs ~4x the
//    flops at this size (callgrind: 13.3k vs ~3k instructions per 15 x 15).
//    Solves replay Eigen's triangular_solve_vector: panels of 8 columns
//    substituted by columns, the rows below (above) a panel updated by one
//    sequential dot product each, rhs_r <- rhs_r - sum_j a_rj x_j.
//  - larger n: Eigen::PartialPivLU itself (it switches to a blocked
//    algorithm there, whose rounding the loops above do not replay).
// Both claims are tested bit-for-bit (tests/core/test_square_lu.cc); a build
// that contracts a*b + c into FMA would make the fast path differ and fail
// that test rather than drift silently.
//
// No heap allocation after the first Compute() of a size above kMaxFastSize
// (the fallback's storage is kept).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <array>

namespace quasiroll {

class SquareLu {
 public:
  static constexpr int kMaxFastSize = 16;  // Eigen's unblocked limit

  // Factors a square matrix. Throws std::invalid_argument if `a` is not
  // square. A singular matrix factors (a zero pivot) as in Eigen.
  void Compute(const Eigen::Ref<const Eigen::MatrixXd>& a);

  // x = A^{-1} b; x may be b itself. Throws std::invalid_argument on a size
  // mismatch or before Compute().
  void Solve(const Eigen::Ref<const Eigen::VectorXd>& b,
             Eigen::Ref<Eigen::VectorXd> x) const;

  int size() const { return n_; }
  // min_i |u_ii| and max_i |u_ii| (the rank test of a Newton solver).
  double MinAbsPivot() const;
  double MaxAbsPivot() const;

 private:
  bool fast() const { return n_ <= kMaxFastSize; }
  double& at(int i, int j) { return lu_[j * kMaxFastSize + i]; }
  double at(int i, int j) const { return lu_[j * kMaxFastSize + i]; }

  int n_ = -1;
  std::array<double, kMaxFastSize * kMaxFastSize> lu_{};
  std::array<int, kMaxFastSize> transpositions_{};
  Eigen::PartialPivLU<Eigen::MatrixXd> fallback_;
};

}  // namespace quasiroll
