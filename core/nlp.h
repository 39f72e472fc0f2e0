// Generic nonlinear program and the abstract NLP solver.
//
//   min_x  f(x)   s.t.  x_lb <= x <= x_ub,   g_lb <= g(x) <= g_ub
//
// Row i of g is an equality when g_lb(i) == g_ub(i). Infinite bounds use
// +-std::numeric_limits<double>::infinity(). Nothing here knows about robots:
// the quasi-static problem (quasi_static.h) is one client, the
// Hock-Schittkowski reference problems (nlp_reference_problems.h) are others.
//
// Style follows Drake's solvers/: the public non-virtual NlpSolver::Solve()
// validates inputs and options (misuse -> std::invalid_argument), calls the
// backend's private DoSolve(), then checks the answer independently (a backend
// that claims convergence with violated constraints or non-finite output is
// downgraded). Numerical failure is a status, never an exception.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace quasiroll {

class NlpProblem {
 public:
  virtual ~NlpProblem() = default;

  virtual int num_variables() const = 0;
  virtual int num_constraints() const = 0;

  // All four outputs are preallocated to the right sizes by the caller.
  virtual void GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                         Eigen::Ref<Eigen::VectorXd> x_ub,
                         Eigen::Ref<Eigen::VectorXd> g_lb,
                         Eigen::Ref<Eigen::VectorXd> g_ub) const = 0;

  virtual double Objective(
      const Eigen::Ref<const Eigen::VectorXd>& x) const = 0;
  virtual void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> grad) const = 0;
  virtual void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                           Eigen::Ref<Eigen::VectorXd> g) const = 0;
  // Dense Jacobian dg/dx, num_constraints x num_variables. The problems this
  // testbed solves have <= 21 unknowns, where dense kernels beat sparse ones.
  virtual void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                  Eigen::Ref<Eigen::MatrixXd> jac) const = 0;

  // Optional exact Hessian of the Lagrangian
  //   sigma * d2f/dx2 + sum_i lambda_i d2g_i/dx2   (full symmetric matrix).
  // Backends that need second derivatives fall back to quasi-Newton otherwise.
  virtual bool HasLagrangianHessian() const { return false; }
  virtual void LagrangianHessian(
      const Eigen::Ref<const Eigen::VectorXd>& /*x*/, double /*sigma*/,
      const Eigen::Ref<const Eigen::VectorXd>& /*lambda*/,
      Eigen::Ref<Eigen::MatrixXd> /*hess*/) const {}

  // Number of constraint rows that are equalities (g_lb == g_ub).
  int CountEqualities() const;
};

enum class NlpStatus {
  kConverged,         // optimality and feasibility tolerances met
  kInfeasible,        // backend detected (local) infeasibility
  kIterationLimit,    // max_iterations reached before convergence
  kNumericalFailure,  // NaN/Inf, line-search failure, singular system, ...
  kInvalidInput,      // only set by Solve() for problems rejected at run time
  kNotRun,            // default state of a fresh result
};

const char* ToString(NlpStatus status);

struct NlpOptions {
  // Converged requires  max_i viol_i(x) <= feasibility_tolerance,  where viol
  // is the bound/constraint violation in the problem's own (scaled) units.
  double feasibility_tolerance = 1e-10;
  // Converged requires the backend's optimality measure (KKT residual, relative
  // step or cost change) <= optimality_tolerance.
  double optimality_tolerance = 1e-10;
  // Upper bound on major iterations of the backend.
  int max_iterations = 200;
  // Start from result->multipliers if they have the right size (Ipopt uses
  // them, others ignore them).
  bool warm_start_multipliers = false;
  // Backend print level, 0 = silent.
  int verbosity = 0;

  bool IsValid(std::string* why) const;
};

struct NlpResult {
  NlpStatus status = NlpStatus::kNotRun;
  Eigen::VectorXd x;
  Eigen::VectorXd multipliers;  // constraint multipliers, sign as in Ipopt
  double objective = 0.0;
  // Independently recomputed after the solve by NlpSolver::Solve().
  double max_constraint_violation = 0.0;
  int iterations = 0;
  int objective_evaluations = 0;
  int constraint_evaluations = 0;
  int jacobian_evaluations = 0;
  double wall_seconds = 0.0;
  std::string backend;         // registry name
  std::string backend_status;  // the backend's own return code / message
};

class NlpSolver {
 public:
  virtual ~NlpSolver() = default;
  NlpSolver(const NlpSolver&) = delete;
  NlpSolver& operator=(const NlpSolver&) = delete;

  // Solves `problem` from `x0`. `result` is in/out so that its vectors can be
  // reused without allocation and its multipliers can warm-start the next
  // solve. Throws std::invalid_argument on misuse (x0 of the wrong size or
  // non-finite, invalid options, lb > ub, a problem this backend cannot take).
  NlpStatus Solve(const NlpProblem& problem,
                  const Eigen::Ref<const Eigen::VectorXd>& x0,
                  const NlpOptions& options, NlpResult* result);

  virtual std::string name() const = 0;
  // True for backends that need exactly num_variables() equality rows (a
  // square system; inequality rows and bounds are then only checked at the
  // root), e.g. plain Newton.
  virtual bool RequiresSquareSystem() const { return false; }
  // True if separate solver objects of this backend may solve in different
  // threads at the same time (no unsynchronised global state in the backend
  // or its libraries). False by default, so that a plugin is serialised by
  // the harness until it says otherwise; one object is never shared.
  virtual bool SupportsConcurrentInstances() const { return false; }

 protected:
  NlpSolver() = default;

 private:
  // Called with validated inputs; result->x is sized, result->backend set.
  // Must fill status, x, iterations, evaluation counts, backend_status.
  virtual void DoSolve(const NlpProblem& problem,
                       const Eigen::Ref<const Eigen::VectorXd>& x0,
                       const NlpOptions& options, NlpResult* result) = 0;

  Eigen::VectorXd x_lb_, x_ub_, g_lb_, g_ub_, g_;  // validation workspace
};

// Max violation of bounds and constraint bounds at x (>= 0).
double MaxConstraintViolation(const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& x_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& x_ub,
                              const Eigen::Ref<const Eigen::VectorXd>& g_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& g_ub);

// Name -> factory registry. Built-in backends are added by
// RegisterBuiltinNlpSolvers() (solvers/registry.cc, one line each); plugins
// call Register() themselves.
class NlpSolverRegistry {
 public:
  using Factory = std::function<std::unique_ptr<NlpSolver>()>;
  static void Register(const std::string& name, const std::string& description,
                       Factory factory);
  // Throws std::invalid_argument naming the unknown backend and the known ones.
  static std::unique_ptr<NlpSolver> Create(const std::string& name);
  static bool Has(const std::string& name);
  static std::vector<std::string> Names();
  static std::string Description(const std::string& name);
};

// Defined in solvers/registry.cc (library quasiroll::solvers): registers every
// backend compiled in. Idempotent and thread-safe; call once before Create().
void RegisterBuiltinNlpSolvers();

}  // namespace quasiroll
