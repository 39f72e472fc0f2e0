#include "quasiroll/core/square_lu.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace quasiroll {
namespace {
constexpr int kPanel = 8;  // Eigen's EIGEN_TUNE_TRIANGULAR_PANEL_WIDTH
constexpr int kLd = SquareLu::kMaxFastSize;  // leading dimension

// Eigen's partial_lu_impl::unblocked_lu, element for element. N is a
// compile-time size so that the short loops unroll (the arithmetic and its
// order do not depend on it).
template <int N>
void Factor(double* lu, int* transpositions) {
  for (int k = 0; k < N; ++k) {
    double* col_k = lu + k * kLd;
    int pivot = k;
    double biggest = std::abs(col_k[k]);
    for (int i = k + 1; i < N; ++i) {
      const double score = std::abs(col_k[i]);
      if (score > biggest) {  // first of equals, as Eigen's maxCoeff
        biggest = score;
        pivot = i;
      }
    }
    transpositions[k] = pivot;
    if (biggest != 0.0) {
      if (pivot != k)
        for (int j = 0; j < N; ++j)
          std::swap(lu[j * kLd + k], lu[j * kLd + pivot]);
      const double ukk = col_k[k];
      for (int i = k + 1; i < N; ++i) col_k[i] /= ukk;
    }
    // A local copy of l_k lets the compiler vectorise (no aliasing).
    double l[kLd];
    for (int i = k + 1; i < N; ++i) l[i] = col_k[i];
    for (int j = k + 1; j < N; ++j) {
      double* col_j = lu + j * kLd;
      const double ukj = col_j[k];
      for (int i = k + 1; i < N; ++i) col_j[i] -= l[i] * ukj;
    }
  }
}

// PartialPivLU::_solve_impl: x = P b, then L and U by Eigen's
// triangular_solve_vector (column panels of kPanel, gemv for the rest).
template <int N>
void Solve(const double* lu, const int* transpositions, double* x) {
  auto at = [lu](int i, int j) { return lu[j * kLd + i]; };
  for (int k = 0; k < N; ++k) std::swap(x[k], x[transpositions[k]]);
  // Unit lower: panels from the top.
  for (int pi = 0; pi < N; pi += kPanel) {
    const int end = std::min(N, pi + kPanel);
    for (int i = pi; i < end; ++i) {
      if (x[i] == 0.0) continue;
      for (int r = i + 1; r < end; ++r) x[r] -= x[i] * at(r, i);
    }
    for (int r = end; r < N; ++r) {
      double dot = 0.0;
      for (int j = pi; j < end; ++j) dot += at(r, j) * x[j];
      x[r] -= dot;
    }
  }
  // Upper: panels from the bottom.
  for (int pi = N; pi > 0; pi -= kPanel) {
    const int start = std::max(0, pi - kPanel);
    for (int i = pi - 1; i >= start; --i) {
      if (x[i] == 0.0) continue;
      x[i] /= at(i, i);
      for (int r = start; r < i; ++r) x[r] -= x[i] * at(r, i);
    }
    for (int r = 0; r < start; ++r) {
      double dot = 0.0;
      for (int j = start; j < pi; ++j) dot += at(r, j) * x[j];
      x[r] -= dot;
    }
  }
}

struct Kernels {
  void (*factor)(double*, int*);
  void (*solve)(const double*, const int*, double*);
};

template <int... N>
constexpr std::array<Kernels, sizeof...(N)> MakeKernels(
    std::integer_sequence<int, N...>) {
  return {Kernels{&Factor<N>, &Solve<N>}...};
}

// kKernels[n] for n = 0..kMaxFastSize.
constexpr auto kKernels =
    MakeKernels(std::make_integer_sequence<int, kLd + 1>{});
}  // namespace

void SquareLu::Compute(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  if (a.rows() != a.cols()) {
    throw std::invalid_argument("SquareLu::Compute: matrix is " +
                                std::to_string(a.rows()) + " x " +
                                std::to_string(a.cols()) + ", not square");
  }
  n_ = static_cast<int>(a.rows());
  if (!fast()) {
    fallback_.compute(a);
    return;
  }
  for (int j = 0; j < n_; ++j)
    for (int i = 0; i < n_; ++i) at(i, j) = a(i, j);
  kKernels[n_].factor(lu_.data(), transpositions_.data());
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
  if (x.data() != b.data()) x = b;
  kKernels[n_].solve(lu_.data(), transpositions_.data(), x.data());
}

double SquareLu::MinAbsPivot() const {
  if (n_ <= 0) return 0.0;
  if (!fast()) return fallback_.matrixLU().diagonal().cwiseAbs().minCoeff();
  double m = std::abs(at(0, 0));
  for (int k = 1; k < n_; ++k) m = std::min(m, std::abs(at(k, k)));
  return m;
}

double SquareLu::MaxAbsPivot() const {
  if (n_ <= 0) return 0.0;
  if (!fast()) return fallback_.matrixLU().diagonal().cwiseAbs().maxCoeff();
  double m = std::abs(at(0, 0));
  for (int k = 1; k < n_; ++k) m = std::max(m, std::abs(at(k, k)));
  return m;
}

}  // namespace quasiroll
