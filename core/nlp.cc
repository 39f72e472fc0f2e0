#include "quasiroll/core/nlp.h"

#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/registry.h"
#include "quasiroll/core/square_lu.h"

namespace quasiroll {

int NlpProblem::CountEqualities() const {
  const int n = num_variables(), m = num_constraints();
  Eigen::VectorXd xl(n), xu(n), gl(m), gu(m);
  GetBounds(xl, xu, gl, gu);
  int count = 0;
  for (int i = 0; i < m; ++i) count += (gl(i) == gu(i));
  return count;
}

const char* ToString(NlpStatus status) {
  switch (status) {
    case NlpStatus::kConverged:
      return "converged";
    case NlpStatus::kInfeasible:
      return "infeasible";
    case NlpStatus::kIterationLimit:
      return "iteration_limit";
    case NlpStatus::kNumericalFailure:
      return "numerical_failure";
    case NlpStatus::kNotOptimal:
      return "not_optimal";
    case NlpStatus::kInvalidInput:
      return "invalid_input";
    case NlpStatus::kNotRun:
      return "not_run";
  }
  return "unknown";
}

bool NlpOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(std::isfinite(feasibility_tolerance) && feasibility_tolerance > 0))
    return fail("feasibility_tolerance: must be finite and > 0, got " +
                std::to_string(feasibility_tolerance));
  if (!(std::isfinite(optimality_tolerance) && optimality_tolerance > 0))
    return fail("optimality_tolerance: must be finite and > 0, got " +
                std::to_string(optimality_tolerance));
  if (!(std::isfinite(kkt_tolerance) && kkt_tolerance >= 0))
    return fail(
        "kkt_tolerance: must be finite and >= 0 (0 = "
        "sqrt(optimality_tolerance)), got " +
        std::to_string(kkt_tolerance));
  if (max_iterations < 1)
    return fail("max_iterations: must be >= 1, got " +
                std::to_string(max_iterations));
  if (stall_iterations < 0)
    return fail("stall_iterations: must be >= 0, got " +
                std::to_string(stall_iterations));
  if (verbosity < 0)
    return fail("verbosity: must be >= 0, got " + std::to_string(verbosity));
  return true;
}

double NlpOptions::EffectiveKktTolerance() const {
  return kkt_tolerance > 0 ? kkt_tolerance : std::sqrt(optimality_tolerance);
}

// ------------------------------------------------------------ KKT check ----

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// min over z >= 0 of max(|t - z|, z s), t >= 0: the error of one bound side
// with slack s (infinite slack: the side does not exist, t counts in full).
double SideError(double t, double slack) {
  if (!(slack < kInf)) return t;
  slack = std::max(slack, 0.0);
  return t * slack / (1.0 + slack);
}
}  // namespace

struct KktVerifier::Workspace {
  int n = -1, m = -1;
  Eigen::VectorXd grad, r, lambda, rhs, c, x_lb, x_ub, g_lb, g_ub, g, absr;
  Eigen::MatrixXd jac, ls;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  // Square equality systems (as many equality rows as variables, e.g. the
  // quasi-static problem): stage 1 by an LU of J_eq^T, 4-5x cheaper than
  // the pivoted QR; a singular J_eq shows in the residual, and stage 2 (QR)
  // follows.
  int num_equalities = 0;
  Eigen::VectorXi equality_rows;
  Eigen::MatrixXd square;
  SquareLu lu;
  // Active sides: -1 lower, +1 upper, 0 inactive (rows: inequality rows only;
  // variables: bounds). Fixed variables and equality rows are handled apart.
  Eigen::VectorXi row_side, var_side;

  void Resize(int nn, int mm) {
    if (nn == n && mm == m) return;
    n = nn;
    m = mm;
    grad.resize(n);
    r.resize(n);
    rhs.resize(n);
    c.resize(n);
    absr.resize(n);
    x_lb.resize(n);
    x_ub.resize(n);
    var_side.resize(n);
    lambda.resize(m);
    g_lb.resize(m);
    g_ub.resize(m);
    g.resize(m);
    row_side.resize(m);
    jac.resize(m, n);
    ls.resize(n, m);
    qr = Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(n, std::max(m, 1));
    equality_rows.resize(m);
    square.resize(n, n);
  }

  // Stage 1 for square equality systems: lambda_eq = -J_eq^{-T} grad f.
  void SolveSquareEqualities() {
    lambda.setZero();
    for (int k = 0; k < n; ++k)
      square.col(k) = jac.row(equality_rows(k)).transpose();
    lu.Compute(square);
    rhs = -grad;
    lu.Solve(rhs, c);
    for (int k = 0; k < n; ++k) lambda(equality_rows(k)) = c(k);
  }

  // lambda = argmin |grad f + J_A^T lambda_A| over the components not
  // absorbed by a bound (fixed or bound-active variables), A = equality rows
  // + rows with an active side; other multipliers 0. A fixed-size
  // n x max(m, 1) system (unused rows/columns zeroed) so that the
  // factorisation reuses its storage; rank-revealing (basic solution).
  void SolveLeastSquares() {
    lambda.setZero();
    if (m == 0) return;
    ls.setZero();
    for (int j = 0; j < n; ++j) {
      const bool absorbed = x_lb(j) == x_ub(j) || var_side(j) != 0;
      rhs(j) = absorbed ? 0.0 : -grad(j);
      if (absorbed) continue;
      for (int i = 0; i < m; ++i)
        if (g_lb(i) == g_ub(i) || row_side(i) != 0) ls(j, i) = jac(i, j);
    }
    qr.compute(ls);
    const Eigen::Index rank = qr.rank();
    if (rank == 0) return;
    c = rhs;
    qr.householderQ().setLength(rank).adjoint().applyThisOnTheLeft(c);
    qr.matrixQR()
        .topLeftCorner(rank, rank)
        .triangularView<Eigen::Upper>()
        .solveInPlace(c.head(rank));
    const auto& perm = qr.colsPermutation().indices();
    for (Eigen::Index k = 0; k < rank; ++k) lambda(perm(k)) = c(k);
  }

  // kkt_residual(x, lambda) with grad, jac, g and the bounds loaded.
  double Residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                  const Eigen::Ref<const Eigen::VectorXd>& lam) {
    r = grad;
    if (m > 0) r.noalias() += jac.transpose() * lam;
    absr.setZero();
    if (m > 0) absr.noalias() += jac.cwiseAbs().transpose() * lam.cwiseAbs();
    double scale = std::max(1.0, grad.lpNorm<Eigen::Infinity>());
    if (m > 0) scale = std::max(scale, absr.maxCoeff());
    // The complementarity error of a bound's or a row's multiplier w: w > 0
    // pairs with the slack `positive_slack`, w < 0 with `negative_slack`.
    auto side_error = [](double w, double positive_slack,
                         double negative_slack) {
      if (w > 0) return SideError(w, positive_slack);
      if (w < 0) return SideError(-w, negative_slack);
      return 0.0;
    };
    double err = 0.0;
    for (int j = 0; j < n; ++j) {
      if (x_lb(j) == x_ub(j)) continue;
      err = std::max(err, side_error(r(j), x(j) - x_lb(j), x_ub(j) - x(j)));
    }
    for (int i = 0; i < m; ++i) {
      if (g_lb(i) == g_ub(i)) continue;
      err = std::max(err, side_error(lam(i), g_ub(i) - g(i), g(i) - g_lb(i)));
    }
    return err / scale;
  }
};

KktVerifier::KktVerifier() : ws_(std::make_unique<Workspace>()) {}
KktVerifier::~KktVerifier() = default;

double KktVerifier::ResidualWith(
    const NlpProblem& problem, const Eigen::Ref<const Eigen::VectorXd>& x,
    const Eigen::Ref<const Eigen::VectorXd>& lambda) {
  Workspace& w = *ws_;
  w.Resize(problem.num_variables(), problem.num_constraints());
  problem.GetBounds(w.x_lb, w.x_ub, w.g_lb, w.g_ub);
  problem.Constraints(x, w.g);
  problem.ObjectiveGradient(x, w.grad);
  if (w.m > 0) problem.ConstraintJacobian(x, w.jac);
  return w.Residual(x, lambda);
}

double KktVerifier::Verify(const NlpProblem& problem,
                           const Eigen::Ref<const Eigen::VectorXd>& x,
                           const Eigen::Ref<const Eigen::VectorXd>& g,
                           const NlpBounds& bounds,
                           const Eigen::VectorXd* backend_multipliers,
                           double activity_tolerance, double accept_below) {
  Workspace& w = *ws_;
  const int n = problem.num_variables(), m = problem.num_constraints();
  w.Resize(n, m);
  w.x_lb = bounds.x_lb;
  w.x_ub = bounds.x_ub;
  w.g_lb = bounds.g_lb;
  w.g_ub = bounds.g_ub;
  w.g = g;
  problem.ObjectiveGradient(x, w.grad);
  if (m > 0) problem.ConstraintJacobian(x, w.jac);
  used_least_squares_ = false;
  double best = kInf;
  if (backend_multipliers != nullptr && backend_multipliers->size() == m &&
      backend_multipliers->allFinite()) {
    best = w.Residual(x, *backend_multipliers);
    if (best <= accept_below) return best;
  }
  if (!w.grad.allFinite() || !w.jac.allFinite()) return kInf;

  // Stage 1: least-squares multipliers of the equality rows alone
  // (inequality multipliers 0, bound multipliers from the closed form): the
  // answer for square systems and problems without active inequalities.
  w.row_side.setZero();
  w.var_side.setZero();
  w.num_equalities = 0;
  for (int i = 0; i < m; ++i)
    if (w.g_lb(i) == w.g_ub(i)) w.equality_rows(w.num_equalities++) = i;
  if (w.num_equalities == n) w.SolveSquareEqualities();
  // Exactly singular J_eq (non-finite LU solution): pivoted QR instead.
  if (w.num_equalities != n || !w.lambda.allFinite()) w.SolveLeastSquares();
  const double equality_only = w.Residual(x, w.lambda);
  if (equality_only < best) {
    best = equality_only;
    used_least_squares_ = true;
    best_lambda_ = w.lambda;
  }
  if (best <= accept_below) return best;

  // Stage 2: the active set A = equality rows + inequality sides and bounds
  // with slack <= activity_tolerance (bound-active components are absorbed
  // by their z). An active side whose multiplier has the wrong sign is
  // released and the least squares re-solved, until the signs are right;
  // only that sign-consistent estimate is a candidate (an estimate with a
  // wrong-sign multiplier can look small relative to large cancelling
  // multipliers of a degenerate active set).
  //
  // -1 / 1: v is within activity_tolerance of the lower / upper side of
  // [lb, ub] (the nearer one); 0: of neither, or lb == ub (an equality or a
  // fixed variable).
  auto active_side = [activity_tolerance](double v, double lb, double ub) {
    if (lb == ub) return 0;
    const double lo = v - lb, hi = ub - v;
    if (lo <= activity_tolerance && lo <= hi) return -1;
    return hi <= activity_tolerance ? 1 : 0;
  };
  for (int i = 0; i < m; ++i)
    w.row_side(i) = active_side(g(i), w.g_lb(i), w.g_ub(i));
  for (int j = 0; j < n; ++j)
    w.var_side(j) = active_side(x(j), w.x_lb(j), w.x_ub(j));
  const int active_sides =
      w.row_side.cwiseAbs().sum() + w.var_side.cwiseAbs().sum();
  if (active_sides == 0) return best;
  for (int pass = 0; pass <= active_sides; ++pass) {
    w.SolveLeastSquares();
    const double residual = w.Residual(x, w.lambda);
    // The active side whose multiplier has the wrong sign by most (rows:
    // lower side needs lambda <= 0, upper >= 0; bounds: z_L = r_j >= 0,
    // z_U = -r_j >= 0).
    double worst = 0.0;
    int worst_row = -1, worst_var = -1;
    for (int i = 0; i < m; ++i) {
      const double wrong =
          w.row_side(i) * w.lambda(i) < 0 ? std::abs(w.lambda(i)) : 0.0;
      if (wrong > worst) {
        worst = wrong;
        worst_row = i;
        worst_var = -1;
      }
    }
    for (int j = 0; j < n; ++j) {
      const double wrong = w.var_side(j) * w.r(j) > 0 ? std::abs(w.r(j)) : 0.0;
      if (wrong > worst) {
        worst = wrong;
        worst_var = j;
        worst_row = -1;
      }
    }
    if (worst_row < 0 && worst_var < 0) {
      if (residual < best) {
        best = residual;
        used_least_squares_ = true;
        best_lambda_ = w.lambda;
      }
      break;
    }
    if (worst_row >= 0) w.row_side(worst_row) = 0;
    if (worst_var >= 0) w.var_side(worst_var) = 0;
  }
  return best;
}

void NlpBounds::Load(const NlpProblem& problem) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  x_lb.resize(n);
  x_ub.resize(n);
  g_lb.resize(m);
  g_ub.resize(m);
  problem.GetBounds(x_lb, x_ub, g_lb, g_ub);
}

double MaxConstraintViolation(const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& g,
                              const NlpBounds& bounds) {
  return MaxConstraintViolation(x, g, bounds.x_lb, bounds.x_ub, bounds.g_lb,
                                bounds.g_ub);
}

double MaxConstraintViolation(const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& g,
                              const Eigen::Ref<const Eigen::VectorXd>& x_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& x_ub,
                              const Eigen::Ref<const Eigen::VectorXd>& g_lb,
                              const Eigen::Ref<const Eigen::VectorXd>& g_ub) {
  double v = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    v = std::max(v, x_lb(i) - x(i));
    v = std::max(v, x(i) - x_ub(i));
  }
  for (Eigen::Index i = 0; i < g.size(); ++i) {
    if (!std::isfinite(g(i))) return std::numeric_limits<double>::infinity();
    v = std::max(v, g_lb(i) - g(i));
    v = std::max(v, g(i) - g_ub(i));
  }
  return v;
}

namespace {
// Throws std::invalid_argument unless lb(i) <= ub(i), neither NaN, for all i.
void CheckBounds(const char* what, const Eigen::VectorXd& lb,
                 const Eigen::VectorXd& ub) {
  for (Eigen::Index i = 0; i < lb.size(); ++i) {
    if (std::isnan(lb(i)) || std::isnan(ub(i)) || lb(i) > ub(i)) {
      std::ostringstream os;
      os << "NlpSolver::Solve: " << what << " bounds [" << i << "] invalid: ["
         << lb(i) << ", " << ub(i) << "]";
      throw std::invalid_argument(os.str());
    }
  }
}
}  // namespace

void NlpSolver::SetBackendOptions(const GivenOptions& given) {
  OptionValues values =
      ResolveOptions(option_table(), given, "NLP backend '" + name() + "'");
  ApplyBackendOptions(values);
  backend_options_ = std::move(values);
}

const OptionValues& NlpSolver::backend_options() {
  if (!backend_options_) SetBackendOptions({});
  return *backend_options_;
}

NlpStatus NlpSolver::Solve(const NlpProblem& problem,
                           const Eigen::Ref<const Eigen::VectorXd>& x0,
                           const NlpOptions& options, NlpResult* result) {
  if (result == nullptr)
    throw std::invalid_argument("NlpSolver::Solve: result must not be null");
  ValidateInputs(problem, x0, options);
  const int n = problem.num_variables(), m = problem.num_constraints();
  result->status = NlpStatus::kNotRun;
  result->backend = name();
  result->backend_status.clear();
  result->has_multipliers = false;
  result->stalled = false;
  result->multipliers_estimated = false;
  result->native_iterations = -1;  // = iterations unless the backend sets it
  result->kkt_residual = std::numeric_limits<double>::quiet_NaN();
  result->iterations = result->objective_evaluations = 0;
  result->constraint_evaluations = result->jacobian_evaluations = 0;
  result->x.resize(n);
  result->x = x0;
  if (result->multipliers.size() != m) result->multipliers.setZero(m);

  if (!backend_options_) SetBackendOptions({});  // the table's defaults
  const auto start = std::chrono::steady_clock::now();
  try {
    DoSolve(problem, x0, options, result);
  } catch (const std::exception& e) {
    // Third-party exceptions are numerics, not misuse: map to a status.
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status = std::string("exception: ") + e.what();
  }
  result->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  if (result->native_iterations < 0)
    result->native_iterations = result->iterations;

  CheckAnswer(problem, options, result);
  return result->status;
}

void NlpSolver::ValidateInputs(const NlpProblem& problem,
                               const Eigen::Ref<const Eigen::VectorXd>& x0,
                               const NlpOptions& options) {
  std::string why;
  if (!options.IsValid(&why))
    throw std::invalid_argument("NlpSolver::Solve(" + name() +
                                "): invalid options: " + why);
  const int n = problem.num_variables(), m = problem.num_constraints();
  if (n <= 0)
    throw std::invalid_argument("NlpSolver::Solve: num_variables must be > 0");
  if (m < 0)
    throw std::invalid_argument(
        "NlpSolver::Solve: num_constraints must be >= 0");
  if (x0.size() != n) {
    std::ostringstream os;
    os << "NlpSolver::Solve: x0 has size " << x0.size() << ", problem has " << n
       << " variables";
    throw std::invalid_argument(os.str());
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(x0(i))) {
      std::ostringstream os;
      os << "NlpSolver::Solve: x0[" << i << "] is not finite (" << x0(i) << ")";
      throw std::invalid_argument(os.str());
    }
  }
  g_.resize(m);
  bounds_.Load(problem);
  CheckBounds("variable", bounds_.x_lb, bounds_.x_ub);
  CheckBounds("constraint", bounds_.g_lb, bounds_.g_ub);
  const int equalities =
      static_cast<int>((bounds_.g_lb.array() == bounds_.g_ub.array()).count());
  if (RequiresSquareSystem() && equalities != n) {
    std::ostringstream os;
    os << "NlpSolver::Solve(" << name()
       << "): backend needs as many equality rows as variables, got " << n
       << " variables, " << m << " constraints (" << equalities
       << " equalities)";
    throw std::invalid_argument(os.str());
  }
}

void NlpSolver::CheckAnswer(const NlpProblem& problem,
                            const NlpOptions& options, NlpResult* result) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  bool finite = result->x.size() == n && result->x.allFinite();
  if (finite) {
    problem.Constraints(result->x, g_);
    result->max_constraint_violation =
        MaxConstraintViolation(result->x, g_, bounds_);
    result->objective = problem.Objective(result->x);
    finite = std::isfinite(result->max_constraint_violation) &&
             std::isfinite(result->objective);
  } else {
    result->max_constraint_violation = std::numeric_limits<double>::infinity();
  }
  if (!finite) {
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status += " [non-finite solution]";
  } else if (result->status == NlpStatus::kConverged &&
             result->max_constraint_violation > options.feasibility_tolerance) {
    std::ostringstream os;
    os << " [claimed convergence rejected: max violation "
       << result->max_constraint_violation << " > "
       << options.feasibility_tolerance << "]";
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status += os.str();
  } else if (result->status == NlpStatus::kConverged) {
    // Independent first-order check (formula in nlp.h).
    const double tol = options.EffectiveKktTolerance();
    result->kkt_residual =
        kkt_.Verify(problem, result->x, g_, bounds_,
                    result->has_multipliers ? &result->multipliers : nullptr,
                    std::max(options.feasibility_tolerance, tol), tol);
    // Every converged result carries multipliers: the least-squares estimate
    // that certified the point when the backend gave none, or when its own
    // did not pass and the estimate did better (Verify() returns early when
    // the backend's pass).
    if (kkt_.used_least_squares() &&
        kkt_.least_squares_multipliers().size() == m) {
      result->multipliers = kkt_.least_squares_multipliers();
      result->has_multipliers = false;
      result->multipliers_estimated = true;
    }
    if (!(result->kkt_residual <= tol)) {
      std::ostringstream os;
      os << " [claimed convergence rejected: KKT residual "
         << result->kkt_residual << " > " << tol << " ("
         << (kkt_.used_least_squares() ? "least-squares" : "backend")
         << " multipliers)]";
      result->status = NlpStatus::kNotOptimal;
      result->backend_status += os.str();
    }
  }
}

template <>
Registry<NlpSolver>& BackendRegistry<NlpSolver>::Instance() {
  static Registry<NlpSolver> registry("NLP backend");
  return registry;
}
template class BackendRegistry<NlpSolver>;

}  // namespace quasiroll
