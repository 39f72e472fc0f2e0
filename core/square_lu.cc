#include "quasiroll/core/square_lu.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace quasiroll {
namespace {
constexpr int kLd = SquareLu::kMaxFastSize;  // leading dimension

// Eigen's partial_lu_impl::unblocked_lu, element for element. N is a
// compile-time size so that the short loops unroll (the arithmetic and its
// order do not depend on it).
template <int N>
void Factor(double* lu, int* transpositions) {
  for (int k = 0; k < N; ++k) {
    double* col_k = lu + k * kLd;
    // Pivot: the first row of largest |a_ik|, as Eigen's scan with a strict
    // '>' (for finite entries). The maximum in four independent chains, then
    // the first row attaining it: the scan's serial compare-and-select chain
    // was the factorisation's critical path.
    double m0 = std::abs(col_k[k]), m1 = m0, m2 = m0, m3 = m0;
    int r = k + 1;
    for (; r + 4 <= N; r += 4) {
      m0 = std::max(m0, std::abs(col_k[r]));
      m1 = std::max(m1, std::abs(col_k[r + 1]));
      m2 = std::max(m2, std::abs(col_k[r + 2]));
      m3 = std::max(m3, std::abs(col_k[r + 3]));
    }
    for (; r < N; ++r) m0 = std::max(m0, std::abs(col_k[r]));
    const double biggest = std::max(std::max(m0, m1), std::max(m2, m3));
    int pivot = k;
    while (pivot < N - 1 && std::abs(col_k[pivot]) != biggest) ++pivot;
    transpositions[k] = pivot;
    // l_k in a local array, written as it is computed: the update below
    // then neither aliases the matrix nor reloads what was just stored.
    double l[kLd];
    if (biggest != 0.0) {
      if (pivot != k)
        for (int j = 0; j < N; ++j)
          std::swap(lu[j * kLd + k], lu[j * kLd + pivot]);
      const double ukk = col_k[k];
      for (int i = k + 1; i < N; ++i) {
        l[i] = col_k[i] / ukk;
        col_k[i] = l[i];
      }
    } else {
      for (int i = k + 1; i < N; ++i) l[i] = col_k[i];
    }
    for (int j = k + 1; j < N; ++j) {
      double* col_j = lu + j * kLd;
      const double ukj = col_j[k];
      for (int i = k + 1; i < N; ++i) col_j[i] -= l[i] * ukj;
    }
  }
}

using FactorKernel = void (*)(double*, int*);

template <int... N>
constexpr std::array<FactorKernel, sizeof...(N)> MakeFactorKernels(
    std::integer_sequence<int, N...>) {
  return {&Factor<N>...};
}

// kFactor[n] for n = 0..kMaxFastSize.
constexpr auto kFactor =
    MakeFactorKernels(std::make_integer_sequence<int, kLd + 1>{});
}  // namespace

void SquareLu::Compute(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  if (a.rows() != a.cols()) {
    throw std::invalid_argument("SquareLu::Compute: matrix is " +
                                std::to_string(a.rows()) + " x " +
                                std::to_string(a.cols()) + ", not square");
  }
  n_ = static_cast<int>(a.rows());
  if (abs_pivots_.size() != n_) abs_pivots_.resize(n_);
  if (!fast()) {
    fallback_.compute(a);
    abs_pivots_ = fallback_.matrixLU().diagonal().cwiseAbs();
    return;
  }
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < n_; ++i) at(i, j) = a(i, j);
  kFactor[n_](lu_.data(), transpositions_.data());
  for (int k = 0; k < n_; ++k) abs_pivots_(k) = std::abs(at(k, k));
  // P b = b gathered through the transpositions applied to 0..n-1 (one
  // load per entry in Solve instead of a chain of dependent swaps).
  for (int k = 0; k < n_; ++k) row_of_[k] = k;
  for (int k = 0; k < n_; ++k)
    std::swap(row_of_[k], row_of_[transpositions_[k]]);
}

void SquareLu::Solve(const Eigen::Ref<const Eigen::VectorXd>& b,
                     Eigen::Ref<Eigen::VectorXd> x) const {
  if (n_ < 0) throw std::invalid_argument("SquareLu::Solve before Compute");
  if (b.size() != n_ || x.size() != n_) {
    throw std::invalid_argument("SquareLu::Solve: rhs has " +
                                std::to_string(b.size()) + " rows, solution " +
                                std::to_string(x.size()) + ", matrix " +
                                std::to_string(n_));
  }
  if (!fast()) {
    x = fallback_.solve(b);
    return;
  }
  // PartialPivLU::_solve_impl: x = P b, then Eigen's own triangular solves
  // on the factor in place (the very code PartialPivLU runs).
  if (x.data() == b.data()) {  // gather through a copy
    std::array<double, kMaxFastSize> copy;
    for (int k = 0; k < n_; ++k) copy[k] = b(k);
    for (int k = 0; k < n_; ++k) x(k) = copy[row_of_[k]];
  } else {
    for (int k = 0; k < n_; ++k) x(k) = b(row_of_[k]);
  }
  const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> lu(
      lu_.data(), n_, n_, Eigen::OuterStride<>(kMaxFastSize));
  lu.triangularView<Eigen::UnitLower>().solveInPlace(x);
  lu.triangularView<Eigen::Upper>().solveInPlace(x);
}

}  // namespace quasiroll
