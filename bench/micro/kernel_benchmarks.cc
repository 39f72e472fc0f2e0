// The hot kernels of the fast path (docs/performance.md, "The LU's critical
// path and the terrain's passes"), each against what it replaced:
//   BM_Lu15/<impl>/factor, BM_Lu15/<impl>/solve   a 15 x 15 LU with partial
//       pivoting (the quasi-static Newton and KKT systems of the paper
//       scene), impl = square (SquareLu) or eigen (Eigen::PartialPivLU);
//       seeded random matrices with entries over 8 decades, one perturbed
//       entry per iteration so that no work is hoisted.
//   BM_TerrainJet/<order>   the paper scene's 30-bump R1 terrain at points
//       along its path: second (EvaluateSecondOrder, what the kinematics
//       calls) or third (Evaluate, the one-loop form of the same sums).
#include <benchmark/benchmark.h>

#include <Eigen/LU>
#include <cmath>
#include <random>
#include <string>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/square_lu.h"
#include "quasiroll/core/terrain.h"

namespace quasiroll {
namespace {

constexpr int kLuSize = 15;

Eigen::MatrixXd LuMatrix() {
  std::mt19937_64 engine(22);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> decade(-4, 4);
  Eigen::MatrixXd a(kLuSize, kLuSize);
  for (int j = 0; j < kLuSize; ++j)
    for (int i = 0; i < kLuSize; ++i)
      a(i, j) = unit(engine) * std::pow(10.0, decade(engine));
  return a;
}

template <typename Lu>
void Factor(Lu* lu, const Eigen::MatrixXd& a);
template <>
void Factor(SquareLu* lu, const Eigen::MatrixXd& a) {
  lu->Compute(a);
}
template <>
void Factor(Eigen::PartialPivLU<Eigen::MatrixXd>* lu,
            const Eigen::MatrixXd& a) {
  lu->compute(a);
}
void Solve(const SquareLu& lu, const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  lu.Solve(b, *x);
}
void Solve(const Eigen::PartialPivLU<Eigen::MatrixXd>& lu,
           const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  *x = lu.solve(b);
}

template <typename Lu>
void BM_Lu15Factor(benchmark::State& state) {
  Eigen::MatrixXd a = LuMatrix();
  Lu lu;
  Factor(&lu, a);  // sizes the storage
  for (auto _ : state) {
    a(0, 0) += 1e-12;
    Factor(&lu, a);
    benchmark::DoNotOptimize(&lu);
  }
}

template <typename Lu>
void BM_Lu15Solve(benchmark::State& state) {
  Lu lu;
  Factor(&lu, LuMatrix());
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(kLuSize, -1.0, 1.0);
  Eigen::VectorXd x(kLuSize);
  for (auto _ : state) {
    b(0) += 1e-12;
    Solve(lu, b, &x);
    benchmark::DoNotOptimize(x.data());
  }
}

void BM_TerrainJet(benchmark::State& state, bool second_order) {
  const Scene scene =
      LoadScene(std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/paper.yaml");
  const Terrain& terrain = *scene.terrain;
  double x = 0.0, sum = 0.0;
  for (auto _ : state) {
    x = x < 1.2 ? x + 1e-4 : 0.0;  // the robot's 20 s path along +x
    const TerrainJet j = second_order ? terrain.EvaluateSecondOrder(x, 0.02)
                                      : terrain.Evaluate(x, 0.02);
    sum += j.hxx;
  }
  benchmark::DoNotOptimize(sum);
}

int RegisterKernels() {
  benchmark::RegisterBenchmark("BM_Lu15/square/factor",
                               BM_Lu15Factor<SquareLu>);
  benchmark::RegisterBenchmark(
      "BM_Lu15/eigen/factor",
      BM_Lu15Factor<Eigen::PartialPivLU<Eigen::MatrixXd>>);
  benchmark::RegisterBenchmark("BM_Lu15/square/solve", BM_Lu15Solve<SquareLu>);
  benchmark::RegisterBenchmark(
      "BM_Lu15/eigen/solve",
      BM_Lu15Solve<Eigen::PartialPivLU<Eigen::MatrixXd>>);
  benchmark::RegisterBenchmark("BM_TerrainJet/second", BM_TerrainJet, true);
  benchmark::RegisterBenchmark("BM_TerrainJet/third", BM_TerrainJet, false);
  return 0;
}

const int kernels_registered = RegisterKernels();

}  // namespace
}  // namespace quasiroll
