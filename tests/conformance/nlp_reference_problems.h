// Reference problems for NLP backends (tests, benchmarks, plugin authors).
//
// Every problem implements NlpProblem and exposes a starting point and its
// known answer:
//   * Hock-Schittkowski problems (W. Hock, K. Schittkowski, "Test Examples for
//     Nonlinear Programming Codes", LNEMS 187, Springer 1981) with their
//     published optimum, refined where the book gives few digits (see .cc);
//   * an infeasible NLP (no known solution, IsFeasible() == false);
//   * square nonlinear systems (as many equality rows as unknowns, plus
//     bounds / inequality rows checked at the root) for Newton-type backends,
//     one of them shaped like the quasi-static contact problem (18 unknowns,
//     3 lower bounds, 3 cone rows), one whose unique root violates a bound.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

// A reference problem is data plus callbacks: bounds, starting point and
// known answer are stored vectors, f, grad f, g, dg/dx and the optional
// Lagrangian Hessian are functions set by each problem's constructor (the
// classes below differ only there). The callbacks capture values, never
// `this`, so problems may be copied.
class ReferenceProblem : public NlpProblem {
 public:
  const std::string& name() const { return name_; }
  // Published starting point of the problem.
  const Eigen::VectorXd& starting_point() const { return x0_; }
  // False if the feasible set is empty (for square systems: the unique root
  // violates a bound or an inequality row).
  bool is_feasible() const { return feasible_; }
  // Known (local) solution and objective; meaningful only if is_feasible().
  const Eigen::VectorXd& known_solution() const { return x_star_; }
  double known_objective() const { return f_star_; }
  // Where the known solution comes from (citation / derivation).
  const std::string& solution_source() const { return source_; }
  // True if the equality rows alone determine x (num equalities == n).
  bool IsSquareSystem() const { return CountEqualities() == num_variables(); }

  int num_variables() const final { return static_cast<int>(x_lb_.size()); }
  int num_constraints() const final { return static_cast<int>(g_lb_.size()); }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const final;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const final;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const final;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const final;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const final;
  bool HasLagrangianHessian() const final {
    return static_cast<bool>(hessian_);
  }
  void LagrangianHessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                         double sigma,
                         const Eigen::Ref<const Eigen::VectorXd>& lambda,
                         Eigen::Ref<Eigen::MatrixXd> hess) const final;

 protected:
  using In = Eigen::Ref<const Eigen::VectorXd>;
  using Out = Eigen::Ref<Eigen::VectorXd>;
  using MatrixOut = Eigen::Ref<Eigen::MatrixXd>;

  ReferenceProblem();

  std::string name_;
  Eigen::VectorXd x0_;
  Eigen::VectorXd x_star_;
  double f_star_ = 0.0;
  bool feasible_ = true;
  std::string source_;
  // Sizes: n = x_lb_.size(), m = g_lb_.size().
  Eigen::VectorXd x_lb_, x_ub_, g_lb_, g_ub_;
  // f and grad f default to 0 (feasibility problems); the Hessian to none.
  std::function<double(const In&)> objective_;
  std::function<void(const In&, Out)> gradient_;
  std::function<void(const In&, Out)> constraints_;
  std::function<void(const In&, MatrixOut)> jacobian_;
  std::function<void(const In&, double, const In&, MatrixOut)> hessian_;
};

// HS 71: min x1 x4 (x1+x2+x3) + x3  s.t.  x1 x2 x3 x4 >= 25,
// sum xi^2 = 40, 1 <= x <= 5. Exact Hessian provided.
class Hs071Problem final : public ReferenceProblem {
 public:
  Hs071Problem();
};

// HS 32: min (x1+3x2+x3)^2 + 4(x1-x2)^2  s.t.  6x2 + 4x3 - x1^3 >= 3,
// x1+x2+x3 = 1, x >= 0. x* = (0,0,1), f* = 1 (bound on x1 weakly active).
// Exact Hessian provided.
class Hs032Problem final : public ReferenceProblem {
 public:
  Hs032Problem();
};

// HS 40: min -x1 x2 x3 x4  s.t.  x1^3 + x2^2 = 1, x1^2 x4 - x3 = 0,
// x4^2 - x2 = 0 (equalities only). x* = (2^-1/3, 2^-1/2, 2^-11/12, 2^-1/4),
// f* = -1/4. Exact Hessian provided.
class Hs040Problem final : public ReferenceProblem {
 public:
  Hs040Problem();
};

// HS 73 (cattle feed): linear objective, one linear and one chance
// (square-root) inequality, one equality, x >= 0. No Hessian on purpose, so
// that quasi-Newton code paths are exercised.
class Hs073Problem final : public ReferenceProblem {
 public:
  Hs073Problem();
};

// Infeasible: min x1^2 + x2^2  s.t.  x1^2 + x2^2 <= 1,  x1 + x2 >= 3.
class InfeasibleDiskProblem final : public ReferenceProblem {
 public:
  InfeasibleDiskProblem();
};

// Square system: circle x1^2 + x2^2 = 4 intersected with line x1 = x2, bound
// x1 >= 0 (selects the root (sqrt2, sqrt2)), inequality row x1 + 2 x2 <= 10
// inactive at the root. Objective 0 (feasibility problem).
class CircleLineSystem final : public ReferenceProblem {
 public:
  CircleLineSystem();
};

// Square system shaped like the quasi-static contact problem: n unknowns
// (n >= 9), n equality rows
//   F_i(x) = sum_j A_ij d_j + 0.5 d_i^2 + 0.25 sin(d_{i+1 mod n}),  d = x - x*,
// with A strictly diagonally dominant (so F'(x*) = A is nonsingular) and
// x* = O(1); lower bounds x_k >= 0 on the last three unknowns ("normal
// forces") and three cone rows x_a^2 + x_b^2 - (0.8 x_k)^2 <= 0, all strictly
// satisfied at x*. The root x* is exact by construction.
class ContactLikeSystem final : public ReferenceProblem {
 public:
  explicit ContactLikeSystem(int n = 18);
};

// Square system with a unique root that violates a bound:
//   exp(x1) = 2,  x1 + x2 = 3   =>  x = (ln 2, 3 - ln 2),  but x2 <= 2.
class InfeasibleRootSystem final : public ReferenceProblem {
 public:
  InfeasibleRootSystem();
};

// One instance of each problem above (ContactLikeSystem with n = 18).
std::vector<std::unique_ptr<ReferenceProblem>> MakeReferenceProblems();
// Looks a problem up by name(); returns nullptr if unknown.
std::unique_ptr<ReferenceProblem> MakeReferenceProblem(const std::string& name);

}  // namespace quasiroll
