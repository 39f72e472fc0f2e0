#include "quasiroll/solvers/ipopt_solver.h"

#include <IpIpoptApplication.hpp>
#include <IpJournalist.hpp>
#include <IpTNLP.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "quasiroll/solvers/ipopt_dense_ma27_internal.h"

namespace quasiroll {
namespace {

using Ipopt::Index;
using Ipopt::Number;

constexpr double kIpoptInf = 2e19;  // beyond nlp_{lower,upper}_bound_inf

// TNLP adapter: forwards to the NlpProblem, counts evaluations, stores the
// answer in the NlpResult. Buffers persist across solves.
class Adapter final : public Ipopt::TNLP {
 public:
  // Per-solve state.
  const NlpProblem* problem = nullptr;
  const Eigen::VectorXd* x0 = nullptr;
  NlpResult* result = nullptr;
  bool warm = false;
  bool exact_hessian = false;
  int n = 0, m = 0;
  Eigen::VectorXd x_lb, x_ub, g_lb, g_ub, grad, reduced;
  Eigen::MatrixXd jac, hess;
  int max_iter_seen = 0;
  bool finalized = false;

  void Prepare(const NlpProblem& p) {
    problem = &p;
    n = p.num_variables();
    m = p.num_constraints();
    x_lb.resize(n);
    x_ub.resize(n);
    g_lb.resize(m);
    g_ub.resize(m);
    grad.resize(n);
    reduced.resize(n);
    jac.resize(m, n);
    p.GetBounds(x_lb, x_ub, g_lb, g_ub);
    exact_hessian = p.HasLagrangianHessian();
    if (exact_hessian) hess.resize(n, n);
    max_iter_seen = 0;
    finalized = false;
  }

  bool get_nlp_info(Index& nv, Index& mc, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    nv = n;
    mc = m;
    nnz_jac_g = n * m;  // dense
    nnz_h_lag = exact_hessian ? n * (n + 1) / 2 : 0;
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index, Number* xl, Number* xu, Index, Number* gl,
                       Number* gu) override {
    auto clip = [](double v) { return std::clamp(v, -kIpoptInf, kIpoptInf); };
    for (int j = 0; j < n; ++j) {
      xl[j] = clip(x_lb(j));
      xu[j] = clip(x_ub(j));
    }
    for (int i = 0; i < m; ++i) {
      gl[i] = clip(g_lb(i));
      gu[i] = clip(g_ub(i));
    }
    return true;
  }

  bool get_starting_point(Index, bool init_x, Number* x, bool init_z,
                          Number* z_l, Number* z_u, Index, bool init_lambda,
                          Number* lambda) override {
    if (init_x)
      for (int j = 0; j < n; ++j) x[j] = (*x0)(j);
    if (init_lambda) {
      if (!warm) return false;
      for (int i = 0; i < m; ++i) lambda[i] = result->multipliers(i);
    }
    if (init_z) {
      if (!warm) return false;
      // Stationarity grad f + J^T lambda - z_L + z_U = 0 at the warm point.
      problem->ObjectiveGradient(*x0, grad);
      problem->ConstraintJacobian(*x0, jac);
      reduced = grad;
      reduced.noalias() += jac.transpose() * result->multipliers;
      for (int j = 0; j < n; ++j) {
        const double r = std::isfinite(reduced(j)) ? reduced(j) : 0.0;
        z_l[j] = std::isfinite(x_lb(j)) ? std::max(r, 0.0) : 0.0;
        z_u[j] = std::isfinite(x_ub(j)) ? std::max(-r, 0.0) : 0.0;
      }
    }
    return true;
  }

  bool eval_f(Index nv, const Number* x, bool, Number& obj) override {
    obj = problem->Objective(Eigen::Map<const Eigen::VectorXd>(x, nv));
    ++result->objective_evaluations;
    return std::isfinite(obj);
  }

  bool eval_grad_f(Index nv, const Number* x, bool, Number* g) override {
    Eigen::Map<Eigen::VectorXd> gm(g, nv);
    problem->ObjectiveGradient(Eigen::Map<const Eigen::VectorXd>(x, nv), gm);
    return gm.allFinite();
  }

  bool eval_g(Index nv, const Number* x, bool, Index mc, Number* g) override {
    Eigen::Map<Eigen::VectorXd> gm(g, mc);
    problem->Constraints(Eigen::Map<const Eigen::VectorXd>(x, nv), gm);
    ++result->constraint_evaluations;
    return gm.allFinite();
  }

  bool eval_jac_g(Index nv, const Number* x, bool, Index mc, Index,
                  Index* i_row, Index* j_col, Number* values) override {
    if (values == nullptr) {  // structure: dense, row-major
      Index k = 0;
      for (Index i = 0; i < mc; ++i)
        for (Index j = 0; j < nv; ++j, ++k) {
          i_row[k] = i;
          j_col[k] = j;
        }
      return true;
    }
    problem->ConstraintJacobian(Eigen::Map<const Eigen::VectorXd>(x, nv), jac);
    ++result->jacobian_evaluations;
    Eigen::Map<
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        values, mc, nv) = jac;
    return jac.allFinite();
  }

  bool eval_h(Index nv, const Number* x, bool, Number obj_factor, Index mc,
              const Number* lambda, bool, Index, Index* i_row, Index* j_col,
              Number* values) override {
    if (!exact_hessian) return false;
    Index k = 0;
    if (values == nullptr) {  // lower triangle, row by row
      for (Index i = 0; i < nv; ++i)
        for (Index j = 0; j <= i; ++j, ++k) {
          i_row[k] = i;
          j_col[k] = j;
        }
      return true;
    }
    problem->LagrangianHessian(
        Eigen::Map<const Eigen::VectorXd>(x, nv), obj_factor,
        Eigen::Map<const Eigen::VectorXd>(lambda, mc), hess);
    for (Index i = 0; i < nv; ++i)
      for (Index j = 0; j <= i; ++j, ++k) values[k] = hess(i, j);
    return hess.allFinite();
  }

  void finalize_solution(Ipopt::SolverReturn, Index nv, const Number* x,
                         const Number*, const Number*, Index mc, const Number*,
                         const Number* lambda, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    result->x = Eigen::Map<const Eigen::VectorXd>(x, nv);
    if (lambda != nullptr) {
      result->multipliers = Eigen::Map<const Eigen::VectorXd>(lambda, mc);
      result->has_multipliers = true;
    }
    finalized = true;
  }

  bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number, Number,
                             Number, Number, Number, Number, Number, Number,
                             Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    max_iter_seen = std::max(max_iter_seen, static_cast<int>(iter));
    return true;
  }
};

const char* ReturnStatusName(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded:
      return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
      return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
      return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
      return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
      return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
      return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
      return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
      return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
      return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
      return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
      return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
      return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
      return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
      return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
      return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
      return "Insufficient_Memory";
    case Ipopt::Internal_Error:
      return "Internal_Error";
  }
  return "unknown Ipopt return status";
}

NlpStatus MapStatus(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded:
    // Only reachable with constraint violation <= feasibility_tolerance
    // (acceptable_constr_viol_tol below); NlpSolver::Solve re-checks it.
    case Ipopt::Solved_To_Acceptable_Level:
    // Square problems (no degrees of freedom): a feasible point is the answer.
    case Ipopt::Feasible_Point_Found:
      return NlpStatus::kConverged;
    case Ipopt::Infeasible_Problem_Detected:
      return NlpStatus::kInfeasible;
    case Ipopt::Maximum_Iterations_Exceeded:
      return NlpStatus::kIterationLimit;
    default:
      return NlpStatus::kNumericalFailure;
  }
}

// Structure of a solve, as far as Ipopt's ReOptimizeTNLP cares.
void Signature(const Adapter& a, std::vector<char>* sig) {
  sig->clear();
  sig->push_back(a.exact_hessian ? 'H' : 'L');
  for (int j = 0; j < a.n; ++j) {
    sig->push_back(a.x_lb(j) == a.x_ub(j)
                       ? 'f'
                       : static_cast<char>('0' + std::isfinite(a.x_lb(j)) +
                                           2 * std::isfinite(a.x_ub(j))));
  }
  sig->push_back('|');
  for (int i = 0; i < a.m; ++i) {
    sig->push_back(a.g_lb(i) == a.g_ub(i)
                       ? 'e'
                       : static_cast<char>('0' + std::isfinite(a.g_lb(i)) +
                                           2 * std::isfinite(a.g_ub(i))));
  }
}

bool AlgorithmUsable(Ipopt::ApplicationReturnStatus s) {
  return s >= Ipopt::Maximum_CpuTime_Exceeded;  // -4 .. 6: algorithm was built
}

class IpoptSolver final : public NlpSolver {
 public:
  explicit IpoptSolver(IpoptLinearSolver linear_solver);
  ~IpoptSolver() override;
  std::string name() const override;
  // True for the dense LDL^T (no global state; Ipopt's tags are
  // thread-local), false for MUMPS.
  bool SupportsConcurrentInstances() const override;
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace

struct IpoptSolver::Impl {
  IpoptLinearSolver linear_solver = IpoptLinearSolver::kDenseLdlt;
  // Backend options set per solve (the others go to Ipopt's option list in
  // ApplyBackendOptions).
  double mu_init = 0.1;
  double warm_start_mu_init = 1e-6;
  double warm_start_push = 1e-9;
  double bound_relax_factor = 0.0;
  std::string hessian_approximation = "auto";
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app;
  Ipopt::SmartPtr<Adapter> adapter;
  Eigen::VectorXd x0;
  std::vector<char> signature, last_signature;
  bool can_reoptimize = false;
  bool initialized = false;
};

IpoptSolver::IpoptSolver(IpoptLinearSolver linear_solver)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.linear_solver = linear_solver;
  s.app = IpoptApplicationFactory();
  s.adapter = new Adapter();
  auto opts = s.app->Options();
  // No banner: the library runs thousands of times in a loop.
  opts->SetStringValue("sb", "yes");
  // Silent by default; raised per solve from NlpOptions::verbosity.
  opts->SetIntegerValue("print_level", 0);
  if (linear_solver == IpoptLinearSolver::kDenseLdlt) {
    // The dense LDL^T behind Ipopt's MA27 interface
    // (ipopt_dense_ma27_internal.h); MC19 scaling is an HSL routine we do not
    // have, and a dense Bunch-Kaufman factorization does not need it.
    internal::InstallDenseMa27();
    opts->SetStringValue("linear_solver", "ma27");
    opts->SetStringValue("linear_system_scaling", "none");
  } else {
    opts->SetStringValue("linear_solver", "mumps");
  }
  // mu_strategy and the other backend options: ApplyBackendOptions().
  // "" = do not read an ipopt.opt file from the working directory.
  s.initialized = s.app->Initialize("") == Ipopt::Solve_Succeeded;
}

OptionTable IpoptSolver::option_table() const {
  OptionTable table = {
      // Ipopt picks the adaptive barrier update when the Hessian is L-BFGS;
      // its quality-function oracle solves the KKT system for extra
      // right-hand sides every iteration (~40 % of a warm paper-scene solve)
      // without saving iterations on these problems (6 either way).
      OptionSpec::Choice("mu_strategy", "monotone", {"monotone", "adaptive"},
                         "barrier update: Fiacco-McCormick monotone or "
                         "adaptive (Ipopt's mu_strategy)"),
      OptionSpec::Double("mu_init", 0.1,
                         "initial barrier parameter of a cold start")
          .GreaterThan(0),
      OptionSpec::Double("warm_start_mu_init", 1e-6,
                         "initial barrier parameter of a multiplier warm "
                         "start (near the previous final one)")
          .GreaterThan(0),
      OptionSpec::Double("warm_start_push", 1e-9,
                         "warm_start_{bound,slack_bound,mult_bound}_push and "
                         "_frac: how far a warm point is pushed inside")
          .GreaterThan(0)
          .LessThan(0.5),
      OptionSpec::Double("bound_relax_factor", 0.0,
                         "Ipopt's bound relaxation (its default 1e-8 lets "
                         "answers violate bounds beyond the tolerance)")
          .AtLeast(0),
      OptionSpec::Choice("hessian_approximation", "auto",
                         {"auto", "limited-memory"},
                         "auto: exact when the problem has a Lagrangian "
                         "Hessian, else L-BFGS; limited-memory: always L-BFGS"),
      OptionSpec::Int("limited_memory_max_history", 6,
                      "L-BFGS memory (Ipopt's limited_memory_max_history)")
          .AtLeast(0),
      OptionSpec::Choice("nlp_scaling_method", "gradient-based",
                         {"gradient-based", "none"},
                         "Ipopt's problem scaling (nlp_scaling_method)"),
      OptionSpec::Double("acceptable_tol", 1e-6,
                         "Ipopt's acceptable_tol (an 'acceptable' stop must "
                         "still be feasible to the feasibility tolerance)")
          .GreaterThan(0),
      OptionSpec::Int("acceptable_iter", 15,
                      "Ipopt's acceptable_iter (0 = never stop at an "
                      "acceptable point)")
          .AtLeast(0),
  };
  if (impl_->linear_solver == IpoptLinearSolver::kMumps) {
    table.push_back(OptionSpec::Double("mumps_pivtol", 1e-6,
                                       "MUMPS pivot tolerance (mumps_pivtol)")
                        .AtLeast(0)
                        .AtMost(1));
    table.push_back(OptionSpec::Int("mumps_mem_percent", 1000,
                                    "MUMPS workspace increase in percent "
                                    "(mumps_mem_percent)")
                        .AtLeast(0));
  }
  return table;
}

void IpoptSolver::ApplyBackendOptions(const OptionValues& values) {
  Impl& s = *impl_;
  auto opts = s.app->Options();
  opts->SetStringValue("mu_strategy", values.GetString("mu_strategy"));
  opts->SetIntegerValue(
      "limited_memory_max_history",
      static_cast<int>(values.GetInt("limited_memory_max_history")));
  opts->SetStringValue("nlp_scaling_method",
                       values.GetString("nlp_scaling_method"));
  opts->SetNumericValue("acceptable_tol", values.GetDouble("acceptable_tol"));
  opts->SetIntegerValue("acceptable_iter",
                        static_cast<int>(values.GetInt("acceptable_iter")));
  if (s.linear_solver == IpoptLinearSolver::kMumps) {
    opts->SetNumericValue("mumps_pivtol", values.GetDouble("mumps_pivtol"));
    opts->SetIntegerValue("mumps_mem_percent",
                          static_cast<int>(values.GetInt("mumps_mem_percent")));
  }
  s.mu_init = values.GetDouble("mu_init");
  s.warm_start_mu_init = values.GetDouble("warm_start_mu_init");
  s.warm_start_push = values.GetDouble("warm_start_push");
  s.bound_relax_factor = values.GetDouble("bound_relax_factor");
  s.hessian_approximation = values.GetString("hessian_approximation");
  // The barrier update strategy is built into Ipopt's algorithm objects:
  // rebuild them on the next solve instead of re-optimizing.
  s.can_reoptimize = false;
}

bool IpoptSolver::SupportsConcurrentInstances() const {
  return impl_->linear_solver == IpoptLinearSolver::kDenseLdlt;
}

std::string IpoptSolver::name() const {
  return impl_->linear_solver == IpoptLinearSolver::kMumps ? "ipopt-mumps"
                                                           : "ipopt";
}

IpoptSolver::~IpoptSolver() = default;

void IpoptSolver::DoSolve(const NlpProblem& problem,
                          const Eigen::Ref<const Eigen::VectorXd>& x0,
                          const NlpOptions& options, NlpResult* result) {
  Impl& s = *impl_;
  if (!s.initialized) {
    result->status = NlpStatus::kNumericalFailure;
    result->backend_status = "IpoptApplication::Initialize failed";
    return;
  }
  Adapter& a = *s.adapter;
  a.Prepare(problem);
  s.x0 = x0;
  a.x0 = &s.x0;
  a.result = result;
  a.warm = options.warm_start_multipliers &&
           result->multipliers.size() == problem.num_constraints() &&
           result->multipliers.allFinite();

  auto opts = s.app->Options();
  const int level = std::clamp(options.verbosity, 0, 12);
  // Console output level (the journal was created by Initialize()).
  opts->SetIntegerValue("print_level", level);
  if (auto console = s.app->Jnlst()->GetJournal("console");
      Ipopt::IsValid(console))
    console->SetAllPrintLevels(static_cast<Ipopt::EJournalLevel>(level));
  // Overall (scaled) KKT error target.
  opts->SetNumericValue("tol", options.optimality_tolerance);
  // Absolute constraint violation target, in the problem's own units.
  opts->SetNumericValue("constr_viol_tol", options.feasibility_tolerance);
  // An "acceptable" stop must still be feasible to the caller's tolerance.
  opts->SetNumericValue("acceptable_constr_viol_tol",
                        options.feasibility_tolerance);
  // Major iteration budget.
  opts->SetIntegerValue("max_iter", options.max_iterations);
  // Ipopt relaxes bounds by 1e-8 by default, which would let the answer
  // violate bounds/inequality rows beyond feasibility_tolerance.
  opts->SetNumericValue("bound_relax_factor", s.bound_relax_factor);
  // Exact second derivatives when the problem has them, else L-BFGS.
  if (s.hessian_approximation == "limited-memory") a.exact_hessian = false;
  opts->SetStringValue("hessian_approximation",
                       a.exact_hessian ? "exact" : "limited-memory");
  if (a.warm) {
    // Start from the given x and multipliers instead of Ipopt's own init.
    opts->SetStringValue("warm_start_init_point", "yes");
    // Keep the warm point (almost) where it is instead of pushing it 1e-2
    // into the interior.
    opts->SetNumericValue("warm_start_bound_push", s.warm_start_push);
    opts->SetNumericValue("warm_start_bound_frac", s.warm_start_push);
    opts->SetNumericValue("warm_start_slack_bound_push", s.warm_start_push);
    opts->SetNumericValue("warm_start_slack_bound_frac", s.warm_start_push);
    opts->SetNumericValue("warm_start_mult_bound_push", s.warm_start_push);
    // A barrier parameter near the previous final one, so the solution is not
    // pulled back to the central path of mu = 0.1.
    opts->SetNumericValue("mu_init", s.warm_start_mu_init);
  } else {
    // Cold start: Ipopt's defaults (options persist in the application).
    opts->SetStringValue("warm_start_init_point", "no");
    opts->SetNumericValue("mu_init", s.mu_init);
  }

  Signature(a, &s.signature);
  Ipopt::ApplicationReturnStatus st;
  if (s.can_reoptimize && s.signature == s.last_signature) {
    st = s.app->ReOptimizeTNLP(s.adapter);  // same structure: reuse algorithm
  } else {
    st = s.app->OptimizeTNLP(s.adapter);
  }
  s.can_reoptimize = AlgorithmUsable(st);
  s.last_signature.swap(s.signature);

  result->status = MapStatus(st);
  result->backend_status = ReturnStatusName(st);
  result->iterations = a.max_iter_seen;  // last iteration index reported
  if (!a.finalized) result->x = x0;  // Ipopt stopped before finalize_solution
}

std::unique_ptr<NlpSolver> MakeIpoptSolver(IpoptLinearSolver linear_solver) {
  return std::make_unique<IpoptSolver>(linear_solver);
}

}  // namespace quasiroll
