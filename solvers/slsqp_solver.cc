#include "quasiroll/solvers/slsqp_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <nlopt.hpp>
#include <stdexcept>
#include <vector>

#include "quasiroll/core/nlp_polish.h"

namespace quasiroll {
namespace {

struct SlsqpImpl {
  struct Settings {
    double ftol_rel = 0.0, xtol_rel = 0.0, ftol_abs = 0.0;
    int maxeval_per_iteration = 3;
    double polish_active_tol = 1e-7;
    int polish_max_iterations = 20;
  } settings;
  std::unique_ptr<nlopt::opt> opt;
  // Structure the nlopt::opt was built for.
  int n = -1, n_eq = -1, n_ineq = -1;
  double con_tol = -1.0;

  const NlpProblem* problem = nullptr;
  NlpBounds bounds;
  std::vector<int> eq_rows, ineq_rows;
  std::vector<double> ineq_sign;  // +1: g - g_ub <= 0, -1: g_lb - g <= 0
  std::vector<double> x, lb, ub, tol_eq, tol_ineq;

  // Constraint / Jacobian cache keyed on x (NLopt calls the objective and
  // both mconstraints at the same point).
  Eigen::VectorXd cache_x, g;
  Eigen::MatrixXd jac;
  bool g_valid = false, jac_valid = false;

  int obj_evals = 0, grad_evals = 0, con_evals = 0, jac_evals = 0;
  bool nonfinite = false;

  // Accepted iterates (the comparable iteration count, core/nlp.h). NLopt
  // does not report SLSQP's major iterations, but its driver (nlopt_slsqp in
  // NLopt's slsqp.c) tells them apart through the gradient argument: after
  // x0, every line search starts with the full step x_k + d_k evaluated with
  // the gradient (Kraft's mode -2, in case it is accepted); a backtrack
  // (mode 1) is evaluated without it; when a backtrack is accepted the same
  // point is evaluated again with the gradient (mode -1). So a call with a
  // gradient ends the pending trial as accepted, a call without one rejects
  // it, and the trial pending at the end counts if it is the point NLopt
  // returns (its best point).
  Eigen::VectorXd trial;
  bool started = false, have_trial = false;
  int accepted = 0;
  void TrackPoint(const double* xp, bool with_gradient) {
    Eigen::Map<const Eigen::VectorXd> e(xp, n);
    if (!started) {  // x0
      started = true;
      return;
    }
    if (with_gradient && have_trial) ++accepted;
    if (with_gradient && have_trial && e == trial) {
      have_trial = false;  // re-evaluation of an accepted backtrack
      return;
    }
    trial = e;
    have_trial = true;
  }
  void FinishTracking(const Eigen::VectorXd& x) {
    if (have_trial && x == trial) ++accepted;
  }

  void Touch(const double* xp) {
    const size_t bytes = sizeof(double) * static_cast<size_t>(n);
    if (std::memcmp(cache_x.data(), xp, bytes) != 0) {
      std::memcpy(cache_x.data(), xp, bytes);
      g_valid = jac_valid = false;
    }
  }
  void EnsureG(const double* xp) {
    Ensure(xp, &g_valid, &con_evals, g,
           [this] { problem->Constraints(cache_x, g); });
  }
  void EnsureJac(const double* xp) {
    Ensure(xp, &jac_valid, &jac_evals, jac,
           [this] { problem->ConstraintJacobian(cache_x, jac); });
  }
  // `value` (g or jac) at xp: evaluated (counted in *evals) unless still
  // valid for the cached x.
  template <typename Value, typename Evaluate>
  void Ensure(const double* xp, bool* valid, int* evals, const Value& value,
              Evaluate evaluate) {
    Touch(xp);
    if (*valid) return;
    evaluate();
    ++*evals;
    *valid = true;
    if (!value.allFinite()) Fail();
  }
  [[noreturn]] void Fail() {
    nonfinite = true;
    throw nlopt::forced_stop();  // caught by nlopt.hpp, re-thrown by optimize()
  }

  static double ObjectiveCb(unsigned n, const double* xp, double* grad,
                            void* data) {
    auto* s = static_cast<SlsqpImpl*>(data);
    Eigen::Map<const Eigen::VectorXd> xm(xp, n);
    s->TrackPoint(xp, grad != nullptr);
    const double f = s->problem->Objective(xm);
    ++s->obj_evals;
    if (!std::isfinite(f)) s->Fail();
    if (grad != nullptr) {
      Eigen::Map<Eigen::VectorXd> gm(grad, n);
      s->problem->ObjectiveGradient(xm, gm);
      ++s->grad_evals;
      if (!gm.allFinite()) s->Fail();
    }
    return f;
  }
  static void EqualityCb(unsigned m, double* res, unsigned n, const double* xp,
                         double* grad, void* data) {
    auto* s = static_cast<SlsqpImpl*>(data);
    s->EnsureG(xp);
    for (unsigned k = 0; k < m; ++k) {
      const int i = s->eq_rows[k];
      res[k] = s->g(i) - s->bounds.g_lb(i);
    }
    if (grad != nullptr) {
      s->EnsureJac(xp);
      for (unsigned k = 0; k < m; ++k)
        for (unsigned j = 0; j < n; ++j)
          grad[k * n + j] = s->jac(s->eq_rows[k], j);
    }
  }
  static void InequalityCb(unsigned m, double* res, unsigned n,
                           const double* xp, double* grad, void* data) {
    auto* s = static_cast<SlsqpImpl*>(data);
    s->EnsureG(xp);
    for (unsigned k = 0; k < m; ++k) {
      const int i = s->ineq_rows[k];
      res[k] = s->ineq_sign[k] > 0 ? s->g(i) - s->bounds.g_ub(i)
                                   : s->bounds.g_lb(i) - s->g(i);
    }
    if (grad != nullptr) {
      s->EnsureJac(xp);
      for (unsigned k = 0; k < m; ++k)
        for (unsigned j = 0; j < n; ++j)
          grad[k * n + j] = s->ineq_sign[k] * s->jac(s->ineq_rows[k], j);
    }
  }

  void Build(int nv, double tol) {
    opt = std::make_unique<nlopt::opt>(nlopt::LD_SLSQP,
                                       static_cast<unsigned>(nv));
    opt->set_min_objective(&SlsqpImpl::ObjectiveCb, this);
    tol_eq.assign(eq_rows.size(), tol);
    tol_ineq.assign(ineq_rows.size(), tol);
    if (!eq_rows.empty())
      opt->add_equality_mconstraint(&SlsqpImpl::EqualityCb, this, tol_eq);
    if (!ineq_rows.empty())
      opt->add_inequality_mconstraint(&SlsqpImpl::InequalityCb, this, tol_ineq);
    n = nv;
    n_eq = static_cast<int>(eq_rows.size());
    n_ineq = static_cast<int>(ineq_rows.size());
    con_tol = tol;
  }

  // DoSolve()'s phases (defined below).
  enum class Outcome { kSuccess, kMaxEval, kRoundoff, kFailure, kNonFinite };
  void Prepare(const NlpProblem& p, const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options);
  Outcome Optimize(NlpResult* result);
  void PolishAndClassify(const NlpOptions& options, Outcome outcome,
                         NlpResult* result);
};

const char* NloptResultName(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "SUCCESS";
    case nlopt::STOPVAL_REACHED:
      return "STOPVAL_REACHED";
    case nlopt::FTOL_REACHED:
      return "FTOL_REACHED";
    case nlopt::XTOL_REACHED:
      return "XTOL_REACHED";
    case nlopt::MAXEVAL_REACHED:
      return "MAXEVAL_REACHED";
    case nlopt::MAXTIME_REACHED:
      return "MAXTIME_REACHED";
    case nlopt::FAILURE:
      return "FAILURE";
    case nlopt::INVALID_ARGS:
      return "INVALID_ARGS";
    case nlopt::OUT_OF_MEMORY:
      return "OUT_OF_MEMORY";
    case nlopt::ROUNDOFF_LIMITED:
      return "ROUNDOFF_LIMITED";
    case nlopt::FORCED_STOP:
      return "FORCED_STOP";
    default:
      return "UNKNOWN";
  }
}

// Rows by kind, the NLopt object (rebuilt when the structure changed), the
// per-solve counters and the box-clamped start.
void SlsqpImpl::Prepare(const NlpProblem& p,
                        const Eigen::Ref<const Eigen::VectorXd>& x0,
                        const NlpOptions& options) {
  const int nv = p.num_variables(), m = p.num_constraints();
  problem = &p;
  bounds.Load(p);
  const NlpBounds& b = bounds;

  ClassifyRows(b, &eq_rows, &ineq_rows, &ineq_sign);
  const double tol = options.feasibility_tolerance;
  if (!opt || n != nv || n_eq != static_cast<int>(eq_rows.size()) ||
      n_ineq != static_cast<int>(ineq_rows.size()) || con_tol != tol) {
    Build(nv, tol);  // new structure: (re)create the NLopt object
  }
  cache_x.resize(nv);
  g.resize(m);
  jac.resize(m, nv);
  g_valid = jac_valid = false;
  cache_x.setConstant(std::numeric_limits<double>::quiet_NaN());
  obj_evals = grad_evals = con_evals = jac_evals = 0;
  nonfinite = false;
  trial.resize(nv);
  started = have_trial = false;
  accepted = 0;

  lb.resize(static_cast<size_t>(nv));
  ub.resize(static_cast<size_t>(nv));
  x.resize(static_cast<size_t>(nv));
  for (int j = 0; j < nv; ++j) {
    lb[j] = b.x_lb(j);
    ub[j] = b.x_ub(j);
    x[j] = std::clamp(x0(j), b.x_lb(j), b.x_ub(j));
  }
  opt->set_lower_bounds(lb);
  opt->set_upper_bounds(ub);
  opt->set_ftol_rel(settings.ftol_rel > 0 ? settings.ftol_rel
                                          : options.optimality_tolerance);
  opt->set_xtol_rel(settings.xtol_rel > 0 ? settings.xtol_rel
                                          : options.optimality_tolerance);
  opt->set_ftol_abs(settings.ftol_abs);
  opt->set_maxeval(settings.maxeval_per_iteration * options.max_iterations);
}

// NLopt's run, its result code / exception mapped to an Outcome; x and the
// counters copied into `result`.
SlsqpImpl::Outcome SlsqpImpl::Optimize(NlpResult* result) {
  Outcome outcome = Outcome::kFailure;
  double f_opt = 0.0;
  try {
    const nlopt::result r = opt->optimize(x, f_opt);
    result->backend_status = NloptResultName(r);
    outcome = (r == nlopt::MAXEVAL_REACHED || r == nlopt::MAXTIME_REACHED)
                  ? Outcome::kMaxEval
                  : Outcome::kSuccess;
  } catch (const nlopt::roundoff_limited&) {
    result->backend_status = "ROUNDOFF_LIMITED";
    outcome = Outcome::kRoundoff;
  } catch (const nlopt::forced_stop&) {
    result->backend_status = "FORCED_STOP";
    outcome = nonfinite ? Outcome::kNonFinite : Outcome::kFailure;
  } catch (const std::bad_alloc&) {
    result->backend_status = "OUT_OF_MEMORY";
    outcome = Outcome::kFailure;
  } catch (const std::invalid_argument& e) {
    result->backend_status = std::string("INVALID_ARGS: ") + e.what();
    outcome = Outcome::kFailure;
  } catch (const std::runtime_error& e) {
    result->backend_status = std::string("FAILURE: ") + e.what();
    outcome = Outcome::kFailure;
  }
  for (int j = 0; j < n; ++j) result->x(j) = x[j];
  FinishTracking(result->x);
  result->iterations = accepted;
  result->native_iterations = grad_evals;
  result->objective_evaluations = obj_evals;
  result->constraint_evaluations = con_evals;
  result->jacobian_evaluations = jac_evals;
  return outcome;
}

// Independent feasibility check (+ active-set Newton polish if needed) of a
// finished run, and its status.
void SlsqpImpl::PolishAndClassify(const NlpOptions& options, Outcome outcome,
                                  NlpResult* result) {
  const PolishStats ps =
      PolishActiveConstraints(*problem, bounds, settings.polish_active_tol,
                              options.feasibility_tolerance,
                              settings.polish_max_iterations, &result->x);
  result->constraint_evaluations += ps.constraint_evaluations;
  result->jacobian_evaluations += ps.jacobian_evaluations;
  result->iterations += ps.accepted_steps;
  result->native_iterations += ps.iterations;
  char msg[128];
  if (ps.iterations > 0) {
    std::snprintf(msg, sizeof msg, " + %d polish step(s) -> violation %.2e",
                  ps.iterations, ps.max_violation);
    result->backend_status += msg;
  }
  if (ps.success &&
      (outcome == Outcome::kSuccess || outcome == Outcome::kRoundoff)) {
    result->status = NlpStatus::kConverged;
    return;
  }
  if (LooksLocallyInfeasible(*problem, bounds, result->x)) {
    result->status = NlpStatus::kInfeasible;
    result->backend_status += " (stationary point of the constraint violation)";
    return;
  }
  result->status = NlpStatus::kNumericalFailure;
  if (!ps.success) {
    std::snprintf(msg, sizeof msg, " (constraints violated by %.2e)",
                  ps.max_violation);
    result->backend_status += msg;
  }
}

// NLopt's SLSQP keeps its iteration state in a per-call struct
// (slsqpb_state) and each object owns its nlopt_opt: instances may run
// concurrently.
class SlsqpSolver final : public NlpSolver {
 public:
  std::string name() const override { return "slsqp"; }
  bool SupportsConcurrentInstances() const override { return true; }
  OptionTable option_table() const override {
    return {
        OptionSpec::Double("ftol_rel", 0.0,
                           "NLopt relative objective tolerance (0 = NlpOptions "
                           "optimality_tolerance)")
            .AtLeast(0),
        OptionSpec::Double("xtol_rel", 0.0,
                           "NLopt relative step tolerance (0 = NlpOptions "
                           "optimality_tolerance)")
            .AtLeast(0),
        OptionSpec::Double("ftol_abs", 0.0,
                           "NLopt absolute objective tolerance (0 = off)")
            .AtLeast(0),
        OptionSpec::Int("maxeval_per_iteration", 3,
                        "NLopt maxeval = this * max_iterations (NLopt counts "
                        "evaluations, not SLSQP iterations)")
            .AtLeast(1),
        OptionSpec::Double("polish_active_tol", 1e-7,
                           "rows within this of their bound join the "
                           "active-set Newton polish")
            .AtLeast(0),
        OptionSpec::Int("polish_max_iterations", 20,
                        "Gauss-Newton steps of the feasibility polish")
            .AtLeast(0),
    };
  }

 private:
  void ApplyBackendOptions(const OptionValues& values) override {
    SlsqpImpl::Settings& s = impl_.settings;
    s.ftol_rel = values.GetDouble("ftol_rel");
    s.xtol_rel = values.GetDouble("xtol_rel");
    s.ftol_abs = values.GetDouble("ftol_abs");
    s.maxeval_per_iteration =
        static_cast<int>(values.GetInt("maxeval_per_iteration"));
    s.polish_active_tol = values.GetDouble("polish_active_tol");
    s.polish_max_iterations =
        static_cast<int>(values.GetInt("polish_max_iterations"));
  }
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override {
    SlsqpImpl& s = impl_;
    s.Prepare(problem, x0, options);
    const SlsqpImpl::Outcome outcome = s.Optimize(result);
    if (outcome == SlsqpImpl::Outcome::kNonFinite || !result->x.allFinite()) {
      result->status = NlpStatus::kNumericalFailure;
      result->backend_status += " (non-finite function value)";
      return;
    }
    if (outcome == SlsqpImpl::Outcome::kMaxEval) {
      result->status = NlpStatus::kIterationLimit;
      return;
    }
    s.PolishAndClassify(options, outcome, result);
  }

  SlsqpImpl impl_;
};

}  // namespace

std::unique_ptr<NlpSolver> MakeSlsqpSolver() {
  return std::make_unique<SlsqpSolver>();
}

}  // namespace quasiroll
