// Generic nonlinear program and the abstract NLP solver.
//
//   min_x  f(x)   s.t.  x_lb <= x <= x_ub,   g_lb <= g(x) <= g_ub
//
// Row i of g is an equality when g_lb(i) == g_ub(i). Infinite bounds use
// +-std::numeric_limits<double>::infinity(). Nothing here knows about robots:
// the quasi-static problem (quasi_static.h) is one client, the
// Hock-Schittkowski reference problems of the conformance kit
// (conformance/nlp_reference_problems.h) are others.
//
// Style follows Drake's solvers/: the public non-virtual NlpSolver::Solve()
// validates inputs and options (misuse -> std::invalid_argument), calls the
// backend's private DoSolve(), then checks the answer independently: a backend
// that claims convergence with violated constraints or non-finite output is
// downgraded to kNumericalFailure, one whose point is not first-order optimal
// (KKT residual below) to kNotOptimal. Numerical failure is a status, never an
// exception.
//
// First-order optimality (KKT) residual, computed by NlpSolver::Solve() for
// every backend at a claimed convergence, in the problem's own (scaled) units.
// Multipliers follow Ipopt's convention: L = f + lambda^T g, lambda_i >= 0
// pushes against g_ub_i, lambda_i <= 0 against g_lb_i; bound multipliers
// z = z_L - z_U are eliminated in closed form. With
//   r      = grad f(x) + J(x)^T lambda                       (n)
//   w(t,s) = t s / (1 + s)  for a finite slack s >= 0,   w(t, inf) = t
// (w(t, s) = min over z >= 0 of max(|t - z|, z s): the best trade-off between
// stationarity and the complementarity product z s of one bound side), the
// per-entry errors are
//   variable j:  0 if x_lb_j == x_ub_j;  w(r_j, x_j - x_lb_j) if r_j > 0;
//                w(-r_j, x_ub_j - x_j) if r_j < 0
//   row i:       0 for equalities;  w(lambda_i, g_ub_i - g_i) if lambda_i > 0;
//                w(-lambda_i, g_i - g_lb_i) if lambda_i < 0
// (an infinite bound has infinite slack: a multiplier or a gradient pushing
// against a side that does not exist counts in full — the sign test), and
//   kkt_residual(x, lambda) = max(all errors) / s_d,
//   s_d = max(1, |grad f(x)|_inf, max_j sum_i |J_ij lambda_i|),
// relative to the magnitudes that cancel in r, so that round-off in r gives
// ~1e-16 whatever the scale of f. NlpResult::kkt_residual is the smallest
// residual over these multiplier estimates (each an upper bound of
// min over lambda of kkt_residual(x, lambda); a point passes if some
// multipliers certify it):
//   1. the backend's own (NlpResult::has_multipliers);
//   2. least squares on the equality rows alone (inequality multipliers 0):
//      the answer for square systems such as the quasi-static problem;
//   3. least squares on the active set: equality rows plus inequality sides
//      and bounds with slack <= max(feasibility, kkt tolerance); a side whose
//      multiplier comes out with the wrong sign is released and the least
//      squares re-solved until every sign is right (only that
//      sign-consistent estimate counts).
// Later estimates are skipped once one passes.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/backend_info.h"
#include "quasiroll/core/backend_registry.h"
#include "quasiroll/core/options.h"

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
  kNotOptimal,        // claimed convergence, but the KKT residual recomputed
                      // by Solve() exceeds NlpOptions::kkt_tolerance
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
  // Converged also requires  kkt_residual <= kkt_tolerance  (the relative
  // first-order residual defined at the top of this file), checked by
  // NlpSolver::Solve() for every backend. 0 (default) means
  // sqrt(optimality_tolerance): backends stop on measures of different order
  // (Ipopt's scaled KKT error, SLSQP's relative change of f or x, a penalty
  // method's inner gradient); a change of f of delta near a minimum with
  // Hessian O(1) leaves a gradient of O(sqrt(delta)), so sqrt is the
  // first-order counterpart every backend's own test can meet, while a point
  // that is not a KKT point (a residual O(1), e.g. ||grad f|| ~ 1e2 with no
  // active constraint) fails it by orders of magnitude. Side activity for the
  // least-squares multipliers uses the same tolerance.
  double kkt_tolerance = 0.0;
  // Upper bound on major iterations of the backend.
  int max_iterations = 200;
  // Give up early (status kIterationLimit) when the equality residual
  // max_i |r_i| has not halved over this many consecutive iterations; 0
  // (default) never does. For callers with a fallback that is cheaper than a
  // stall: a Newton iteration near a stick/slip switch can creep along at
  // |r| ~ 1e-9 for tens of iterations (docs/performance.md). Honoured by the
  // backends that iterate on the residual of a square system (newton);
  // others ignore it.
  int stall_iterations = 0;
  // Start from result->multipliers if they have the right size (Ipopt uses
  // them, others ignore them).
  bool warm_start_multipliers = false;
  // Backend print level, 0 = silent.
  int verbosity = 0;

  bool IsValid(std::string* why) const;
  // kkt_tolerance, or sqrt(optimality_tolerance) when it is 0.
  double EffectiveKktTolerance() const;
};

struct NlpResult {
  NlpStatus status = NlpStatus::kNotRun;
  Eigen::VectorXd x;
  Eigen::VectorXd multipliers;  // constraint multipliers, sign as in Ipopt
  // Set by a backend's DoSolve() when `multipliers` are its own estimate at
  // the returned x (Solve() clears it first); the KKT check then tries them.
  bool has_multipliers = false;
  // True when the backend gave up because of NlpOptions::stall_iterations
  // (status kIterationLimit); Solve() clears it first.
  bool stalled = false;
  double objective = 0.0;
  // Independently recomputed after the solve by NlpSolver::Solve().
  double max_constraint_violation = 0.0;
  // Relative first-order optimality residual at x (top of this file),
  // recomputed by Solve() whenever the backend claims convergence; NaN
  // otherwise.
  double kkt_residual = std::numeric_limits<double>::quiet_NaN();
  // Comparable across backends (docs/harness.md, "Iterations"): accepted
  // iterates, i.e. the number of times the backend moved x to a new point
  // computed from a fresh linearisation -- a Newton / SQP / interior-point
  // major iteration, an accepted trust-region or line-search step of an
  // inner solver, a Gauss-Newton step of a feasibility polish. Rejected
  // trial points (backtracking, unsuccessful trust-region steps) and extra
  // function evaluations do not count.
  int iterations = 0;
  // The backend's own count, as its library defines it, plus the steps of
  // the backend's own post-processing (e.g. slsqp: NLopt's objective-gradient
  // evaluations + polish steps; ceres: successful and unsuccessful LM steps +
  // BFGS iterations + polish steps). Solve() sets it to `iterations` when a
  // backend leaves it unset (-1), i.e. when the two counts agree.
  int native_iterations = 0;
  // True when Solve() replaced `multipliers` (and cleared has_multipliers)
  // with the least-squares estimate that certified a claimed convergence,
  // because the backend gave none (newton, slsqp, ceres on square systems)
  // or its own did not pass the check. So every kConverged result carries
  // multipliers (size m) with kkt_residual(x, multipliers) = kkt_residual.
  bool multipliers_estimated = false;
  int objective_evaluations = 0;
  int constraint_evaluations = 0;
  int jacobian_evaluations = 0;
  double wall_seconds = 0.0;
  std::string backend;         // registry name
  std::string backend_status;  // the backend's own return code / message
};

// The bounds of a problem (NlpProblem::GetBounds). Load() allocates only when
// the sizes change.
struct NlpBounds {
  Eigen::VectorXd x_lb, x_ub, g_lb, g_ub;
  void Load(const NlpProblem& problem);
};

// Evaluates the KKT residual defined at the top of this file with
// preallocated workspaces: after a first call with given sizes, Verify()
// does not allocate. NlpSolver::Solve() owns one; public for tests and
// diagnostics.
class KktVerifier {
 public:
  KktVerifier();
  ~KktVerifier();
  KktVerifier(const KktVerifier&) = delete;
  KktVerifier& operator=(const KktVerifier&) = delete;

  // kkt_residual(x, lambda) for the given multipliers (size m).
  double ResidualWith(const NlpProblem& problem,
                      const Eigen::Ref<const Eigen::VectorXd>& x,
                      const Eigen::Ref<const Eigen::VectorXd>& lambda);
  // min(residual with *backend_multipliers (if not null), residual with
  // least-squares multipliers on the active set at `activity_tolerance`);
  // the least squares are skipped when the backend's multipliers already
  // give <= `accept_below`. `g` = constraints at x.
  double Verify(const NlpProblem& problem,
                const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& g,
                const NlpBounds& bounds,
                const Eigen::VectorXd* backend_multipliers,
                double activity_tolerance, double accept_below);
  // True if the last Verify() result came from the least-squares multipliers.
  bool used_least_squares() const { return used_least_squares_; }
  // Those multipliers (size m), valid when used_least_squares().
  const Eigen::VectorXd& least_squares_multipliers() const {
    return best_lambda_;
  }

 private:
  struct Workspace;
  std::unique_ptr<Workspace> ws_;
  bool used_least_squares_ = false;
  Eigen::VectorXd best_lambda_;
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

  // Backend options (docs/plugins.md, "Backend options"): the settings this
  // backend owns (name, type, default, range, doc). Default: none.
  virtual OptionTable option_table() const { return {}; }
  // Checks `given` against option_table() and makes them (the others at
  // their defaults) this object's settings for every later Solve(). Throws
  // std::invalid_argument naming an unknown or ill-typed option and the
  // known ones; the previous settings are then kept.
  void SetBackendOptions(const GivenOptions& given);
  // The settings in effect: every option of option_table().
  const OptionValues& backend_options();

 protected:
  NlpSolver() = default;

 private:
  // Receives validated settings (every option of the table): before the
  // first Solve() the defaults, then whatever SetBackendOptions() was given.
  // Backends copy them into typed members here, so a solve does no lookup.
  virtual void ApplyBackendOptions(const OptionValues& /*values*/) {}

  // Called with validated inputs; result->x is sized, result->backend set.
  // Must fill status, x, iterations, evaluation counts, backend_status.
  virtual void DoSolve(const NlpProblem& problem,
                       const Eigen::Ref<const Eigen::VectorXd>& x0,
                       const NlpOptions& options, NlpResult* result) = 0;

  // Solve()'s phases. Misuse -> std::invalid_argument; loads the bounds
  // into the workspace below.
  void ValidateInputs(const NlpProblem& problem,
                      const Eigen::Ref<const Eigen::VectorXd>& x0,
                      const NlpOptions& options);
  // The independent acceptance check of DoSolve()'s answer (top of file).
  void CheckAnswer(const NlpProblem& problem, const NlpOptions& options,
                   NlpResult* result);

  NlpBounds bounds_;  // validation workspace
  Eigen::VectorXd g_;
  KktVerifier kkt_;
  std::optional<OptionValues> backend_options_;  // set before DoSolve
};

// Max violation of bounds and constraint bounds at x (>= 0; +inf when g has
// a non-finite entry).
double MaxConstraintViolation(const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& g,
                              const NlpBounds& bounds);
// The same with the bounds given one by one.
double MaxConstraintViolation(const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& x_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& x_ub,
                              const Eigen::Ref<const Eigen::VectorXd>& g_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& g_ub);

// Name -> factory registry of NLP backends (core/backend_registry.h).
using NlpSolverRegistry = BackendRegistry<NlpSolver>;

// Defined in solvers/registry.cc (library quasiroll::solvers): registers every
// backend compiled in. Idempotent and thread-safe; call once before Create().
void RegisterBuiltinNlpSolvers();

}  // namespace quasiroll
