#include "core/nlp.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/registry.h"

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
  if (max_iterations < 1)
    return fail("max_iterations: must be >= 1, got " +
                std::to_string(max_iterations));
  if (verbosity < 0)
    return fail("verbosity: must be >= 0, got " + std::to_string(verbosity));
  return true;
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

NlpStatus NlpSolver::Solve(const NlpProblem& problem,
                           const Eigen::Ref<const Eigen::VectorXd>& x0,
                           const NlpOptions& options, NlpResult* result) {
  if (result == nullptr)
    throw std::invalid_argument("NlpSolver::Solve: result must not be null");
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
  x_lb_.resize(n);
  x_ub_.resize(n);
  g_lb_.resize(m);
  g_ub_.resize(m);
  g_.resize(m);
  problem.GetBounds(x_lb_, x_ub_, g_lb_, g_ub_);
  for (int i = 0; i < n; ++i) {
    if (std::isnan(x_lb_(i)) || std::isnan(x_ub_(i)) || x_lb_(i) > x_ub_(i)) {
      std::ostringstream os;
      os << "NlpSolver::Solve: variable bounds [" << i << "] invalid: ["
         << x_lb_(i) << ", " << x_ub_(i) << "]";
      throw std::invalid_argument(os.str());
    }
  }
  int equalities = 0;
  for (int i = 0; i < m; ++i) {
    if (std::isnan(g_lb_(i)) || std::isnan(g_ub_(i)) || g_lb_(i) > g_ub_(i)) {
      std::ostringstream os;
      os << "NlpSolver::Solve: constraint bounds [" << i << "] invalid: ["
         << g_lb_(i) << ", " << g_ub_(i) << "]";
      throw std::invalid_argument(os.str());
    }
    equalities += (g_lb_(i) == g_ub_(i));
  }
  if (RequiresSquareSystem() && equalities != n) {
    std::ostringstream os;
    os << "NlpSolver::Solve(" << name()
       << "): backend needs as many equality rows as variables, got " << n
       << " variables, " << m << " constraints (" << equalities
       << " equalities)";
    throw std::invalid_argument(os.str());
  }

  result->status = NlpStatus::kNotRun;
  result->backend = name();
  result->backend_status.clear();
  result->iterations = result->objective_evaluations = 0;
  result->constraint_evaluations = result->jacobian_evaluations = 0;
  result->x.resize(n);
  result->x = x0;
  if (result->multipliers.size() != m) result->multipliers.setZero(m);

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

  // Independent acceptance check.
  bool finite = result->x.size() == n && result->x.allFinite();
  if (finite) {
    problem.Constraints(result->x, g_);
    result->max_constraint_violation =
        MaxConstraintViolation(result->x, g_, x_lb_, x_ub_, g_lb_, g_ub_);
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
  }
  return result->status;
}

namespace {
Registry<NlpSolver>& NlpSolverRegistryInstance() {
  static Registry<NlpSolver> registry("NLP backend");
  return registry;
}
}  // namespace

void NlpSolverRegistry::Register(const std::string& name,
                                 const std::string& description,
                                 Factory factory) {
  NlpSolverRegistryInstance().Register(name, description, std::move(factory));
}

std::unique_ptr<NlpSolver> NlpSolverRegistry::Create(const std::string& name) {
  return NlpSolverRegistryInstance().Create(name);
}

bool NlpSolverRegistry::Has(const std::string& name) {
  return NlpSolverRegistryInstance().Has(name);
}

std::vector<std::string> NlpSolverRegistry::Names() {
  return NlpSolverRegistryInstance().Names();
}

std::string NlpSolverRegistry::Description(const std::string& name) {
  return NlpSolverRegistryInstance().Description(name);
}

}  // namespace quasiroll
