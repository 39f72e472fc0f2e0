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
#include <memory>
#include <string>
#include <vector>

#include "quasiroll/core/nlp.h"

namespace quasiroll {

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

 protected:
  std::string name_;
  Eigen::VectorXd x0_;
  Eigen::VectorXd x_star_;
  double f_star_ = 0.0;
  bool feasible_ = true;
  std::string source_;
};

// HS 71: min x1 x4 (x1+x2+x3) + x3  s.t.  x1 x2 x3 x4 >= 25,
// sum xi^2 = 40, 1 <= x <= 5. Exact Hessian provided.
class Hs071Problem final : public ReferenceProblem {
 public:
  Hs071Problem();
  int num_variables() const override { return 4; }
  int num_constraints() const override { return 2; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
  bool HasLagrangianHessian() const override { return true; }
  void LagrangianHessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                         double sigma,
                         const Eigen::Ref<const Eigen::VectorXd>& lambda,
                         Eigen::Ref<Eigen::MatrixXd> hess) const override;
};

// HS 32: min (x1+3x2+x3)^2 + 4(x1-x2)^2  s.t.  6x2 + 4x3 - x1^3 >= 3,
// x1+x2+x3 = 1, x >= 0. x* = (0,0,1), f* = 1 (bound on x1 weakly active).
// Exact Hessian provided.
class Hs032Problem final : public ReferenceProblem {
 public:
  Hs032Problem();
  int num_variables() const override { return 3; }
  int num_constraints() const override { return 2; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
  bool HasLagrangianHessian() const override { return true; }
  void LagrangianHessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                         double sigma,
                         const Eigen::Ref<const Eigen::VectorXd>& lambda,
                         Eigen::Ref<Eigen::MatrixXd> hess) const override;
};

// HS 40: min -x1 x2 x3 x4  s.t.  x1^3 + x2^2 = 1, x1^2 x4 - x3 = 0,
// x4^2 - x2 = 0 (equalities only). x* = (2^-1/3, 2^-1/2, 2^-11/12, 2^-1/4),
// f* = -1/4. Exact Hessian provided.
class Hs040Problem final : public ReferenceProblem {
 public:
  Hs040Problem();
  int num_variables() const override { return 4; }
  int num_constraints() const override { return 3; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
  bool HasLagrangianHessian() const override { return true; }
  void LagrangianHessian(const Eigen::Ref<const Eigen::VectorXd>& x,
                         double sigma,
                         const Eigen::Ref<const Eigen::VectorXd>& lambda,
                         Eigen::Ref<Eigen::MatrixXd> hess) const override;
};

// HS 73 (cattle feed): linear objective, one linear and one chance
// (square-root) inequality, one equality, x >= 0. No Hessian on purpose, so
// that quasi-Newton code paths are exercised.
class Hs073Problem final : public ReferenceProblem {
 public:
  Hs073Problem();
  int num_variables() const override { return 4; }
  int num_constraints() const override { return 3; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
};

// Infeasible: min x1^2 + x2^2  s.t.  x1^2 + x2^2 <= 1,  x1 + x2 >= 3.
class InfeasibleDiskProblem final : public ReferenceProblem {
 public:
  InfeasibleDiskProblem();
  int num_variables() const override { return 2; }
  int num_constraints() const override { return 2; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
};

// Square system: circle x1^2 + x2^2 = 4 intersected with line x1 = x2, bound
// x1 >= 0 (selects the root (sqrt2, sqrt2)), inequality row x1 + 2 x2 <= 10
// inactive at the root. Objective 0 (feasibility problem).
class CircleLineSystem final : public ReferenceProblem {
 public:
  CircleLineSystem();
  int num_variables() const override { return 2; }
  int num_constraints() const override { return 3; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
};

// Square system shaped like the quasi-static contact problem: n unknowns
// (n >= 6), n equality rows
//   F_i(x) = sum_j A_ij d_j + 0.5 d_i^2 + 0.25 sin(d_{i+1 mod n}),  d = x - x*,
// with A strictly diagonally dominant (so F'(x*) = A is nonsingular) and
// x* = O(1); lower bounds x_k >= 0 on the last three unknowns ("normal
// forces") and three cone rows x_a^2 + x_b^2 - (0.8 x_k)^2 <= 0, all strictly
// satisfied at x*. The root x* is exact by construction.
class ContactLikeSystem final : public ReferenceProblem {
 public:
  explicit ContactLikeSystem(int n = 18);
  int num_variables() const override { return n_; }
  int num_constraints() const override { return n_ + 3; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;

 private:
  int n_;
  Eigen::MatrixXd a_;
};

// Square system with a unique root that violates a bound:
//   exp(x1) = 2,  x1 + x2 = 3   =>  x = (ln 2, 3 - ln 2),  but x2 <= 2.
class InfeasibleRootSystem final : public ReferenceProblem {
 public:
  InfeasibleRootSystem();
  int num_variables() const override { return 2; }
  int num_constraints() const override { return 2; }
  void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                 Eigen::Ref<Eigen::VectorXd> x_ub,
                 Eigen::Ref<Eigen::VectorXd> g_lb,
                 Eigen::Ref<Eigen::VectorXd> g_ub) const override;
  double Objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override;
  void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                         Eigen::Ref<Eigen::VectorXd> grad) const override;
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                   Eigen::Ref<Eigen::VectorXd> g) const override;
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override;
};

// One instance of each problem above (ContactLikeSystem with n = 18).
std::vector<std::unique_ptr<ReferenceProblem>> MakeReferenceProblems();
// Looks a problem up by name(); returns nullptr if unknown.
std::unique_ptr<ReferenceProblem> MakeReferenceProblem(const std::string& name);

}  // namespace quasiroll
