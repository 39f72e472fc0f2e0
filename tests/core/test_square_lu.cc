// SquareLu against Eigen::PartialPivLU: factors' pivots and solutions must be
// bit-identical (the Newton and KKT solves switched to it must not move any
// trajectory), including ties in the pivot search, exactly zero pivots and
// right-hand sides with zeros (Eigen skips those columns).
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>

#include "quasiroll/core/square_lu.h"

namespace quasiroll {
namespace {

bool BitEqual(double a, double b) {
  std::uint64_t ua, ub;
  std::memcpy(&ua, &a, sizeof a);
  std::memcpy(&ub, &b, sizeof b);
  return ua == ub;
}

// Entries of mixed magnitude (condition numbers up to ~1e8), so that
// rounding differences in any step would show.
Eigen::MatrixXd RandomMatrix(int n, std::mt19937_64* engine) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-4, 4);
  Eigen::MatrixXd a(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      a(i, j) = unit(*engine) * std::ldexp(1.0, 2 * exponent(*engine));
  return a;
}

void ExpectSameAsEigen(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                       const char* what) {
  const int n = static_cast<int>(a.rows());
  Eigen::PartialPivLU<Eigen::MatrixXd> eigen(a);
  SquareLu lu;
  lu.Compute(a);
  const Eigen::VectorXd expected = eigen.solve(b);
  Eigen::VectorXd x(n);
  lu.Solve(b, x);
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(BitEqual(x(i), expected(i)))
        << what << " n = " << n << " x(" << i << ") = " << x(i) << " vs Eigen "
        << expected(i);
  }
  const auto diag = eigen.matrixLU().diagonal().cwiseAbs();
  EXPECT_TRUE(BitEqual(lu.MinAbsPivot(), diag.minCoeff())) << what;
  EXPECT_TRUE(BitEqual(lu.MaxAbsPivot(), diag.maxCoeff())) << what;
  Eigen::VectorXd in_place = b;  // x aliasing b
  lu.Solve(in_place, in_place);
  for (int i = 0; i < n; ++i) ASSERT_TRUE(BitEqual(in_place(i), x(i)));
}

TEST(SquareLu, BitIdenticalToEigenOnRandomSystems) {
  std::mt19937_64 engine(20261127);
  for (int n = 1; n <= 20; ++n) {  // both sides of kMaxFastSize
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::MatrixXd a = RandomMatrix(n, &engine);
      Eigen::VectorXd b = RandomMatrix(n, &engine).col(0);
      if (trial % 2 == 1) b(trial % n) = 0.0;  // a skipped column
      ExpectSameAsEigen(a, b, "random");
    }
  }
}

TEST(SquareLu, BitIdenticalOnTiesAndZeroPivots) {
  std::mt19937_64 engine(7);
  for (int n = 2; n <= 17; ++n) {
    // Ties: entries from {-1, 1, 2}: equal |a_ik| everywhere.
    std::uniform_int_distribution<int> pick(0, 2);
    Eigen::MatrixXd ties(n, n);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) ties(i, j) = pick(engine) == 0 ? -1.0 : 1.0;
    ExpectSameAsEigen(ties, Eigen::VectorXd::LinSpaced(n, 1.0, 2.0), "ties");
    // A zero column: an exactly zero pivot (Eigen factors on; inf/nan in x).
    Eigen::MatrixXd singular = RandomMatrix(n, &engine);
    singular.col(n / 2).setZero();
    SquareLu lu;
    lu.Compute(singular);
    EXPECT_EQ(lu.MinAbsPivot(), 0.0) << n;
    Eigen::PartialPivLU<Eigen::MatrixXd> eigen(singular);
    EXPECT_TRUE(BitEqual(lu.MaxAbsPivot(),
                         eigen.matrixLU().diagonal().cwiseAbs().maxCoeff()));
  }
}

TEST(SquareLu, RejectsMisuse) {
  SquareLu lu;
  Eigen::VectorXd x(3);
  EXPECT_THROW(lu.Solve(Eigen::VectorXd::Zero(3), x), std::invalid_argument);
  EXPECT_THROW(lu.Compute(Eigen::MatrixXd::Zero(3, 2)), std::invalid_argument);
  lu.Compute(Eigen::MatrixXd::Identity(3, 3));
  Eigen::VectorXd y(4);
  EXPECT_THROW(lu.Solve(Eigen::VectorXd::Zero(4), y), std::invalid_argument);
}

}  // namespace
}  // namespace quasiroll
