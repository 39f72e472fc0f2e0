// LU with partial pivoting of a small square matrix, P A = L U, for the hot
// Newton and KKT-verification solves of the quasi-static problem (15 x 15 on
// the paper scene, ~2,650 factorisations per 20 s run: the largest single
// item of a step's time, docs/performance.md).
//
// Results are bit-identical to Eigen::PartialPivLU<Eigen::MatrixXd> (Eigen
// 3.4), so switching to it changes no trajectory:
//  - n <= kMaxFastSize: Eigen's unblocked right-looking algorithm as plain
//    loops over a fixed column-major array, compiled per size: column k
//    takes the first row of largest |a_ik|, i >= k; l_ik = a_ik / u_kk;
//    then a_ij <- a_ij - l_ik u_kj for i, j > k (the same operations on the
//    same values as Eigen's). Faster because the pivot's maximum is taken
//    in four independent chains before the first row attaining it is
//    found: Eigen's serial compare-and-select scan, one per column, is the
//    factorisation's critical path (15 x 15 on this machine: ~480 against
//    ~750 ns per factorisation). Solves gather P b, then run Eigen's own
//    triangular solves on the factor.
//  - larger n: Eigen::PartialPivLU itself (it switches to a blocked
//    algorithm there, whose rounding the loops above do not replay).
// Both claims are tested bit-for-bit for finite matrices
// (tests/core/test_square_lu.cc); a build that contracted a*b + c into FMA
// in one place and not the other would fail that test rather than drift.
//
// No heap allocation after the first Compute() of a given size (the pivot
// magnitudes and, above kMaxFastSize, the fallback's storage are kept).
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

  // min_i |u_ii| and max_i |u_ii| (the rank test of a Newton solver).
  double MinAbsPivot() const { return n_ > 0 ? abs_pivots_.minCoeff() : 0.0; }
  double MaxAbsPivot() const { return n_ > 0 ? abs_pivots_.maxCoeff() : 0.0; }

 private:
  bool fast() const { return n_ <= kMaxFastSize; }
  double& at(int i, int j) { return lu_[j * kMaxFastSize + i]; }
  double at(int i, int j) const { return lu_[j * kMaxFastSize + i]; }

  int n_ = -1;
  std::array<double, kMaxFastSize * kMaxFastSize> lu_{};
  std::array<int, kMaxFastSize> transpositions_{};
  std::array<int, kMaxFastSize> row_of_{};  // (P b)_k = b_{row_of_k}
  Eigen::PartialPivLU<Eigen::MatrixXd> fallback_;
  Eigen::VectorXd abs_pivots_;  // |u_kk|
};

}  // namespace quasiroll
