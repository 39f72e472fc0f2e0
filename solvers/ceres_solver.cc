#include "quasiroll/solvers/ceres_solver.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "quasiroll/core/nlp_polish.h"

namespace quasiroll {
namespace {

struct CeresImpl {
  struct Settings {
    double rho_init = 10.0, rho_growth = 10.0, rho_max = 1e8;
    double rho_grow_unless = 0.25;
    double polish_threshold = 1e-7;
    double infeasible_threshold = 1e-6;
    int polish_max_iterations = 20;
    ceres::TrustRegionStrategyType trust_region = ceres::LEVENBERG_MARQUARDT;
    ceres::LinearSolverType linear_solver = ceres::DENSE_QR;
    ceres::LineSearchDirectionType direction = ceres::BFGS;
  } settings;

  // ---- problem classification (refreshed every solve, no allocation when
  // sizes repeat) -----------------------------------------------------------
  const NlpProblem* problem = nullptr;
  NlpBounds b;
  int n = 0, m = 0;
  std::vector<int> eq_rows, side_rows, fixed_vars, lb_vars, ub_vars;
  std::vector<double> side_sign;  // +1: h = g - g_ub, -1: h = g_lb - g
  Eigen::VectorXd g, grad, w, gx;
  Eigen::MatrixXd jac;
  int f_evals = 0, g_evals = 0, j_evals = 0;

  int NumResiduals() const {
    return static_cast<int>(eq_rows.size() + side_rows.size() +
                            fixed_vars.size());
  }
  double SideValue(size_t k) const {
    const int i = side_rows[k];
    return side_sign[k] > 0 ? g(i) - b.g_ub(i) : b.g_lb(i) - g(i);
  }

  // ---- phase 1: feasibility least squares ----------------------------------
  class FeasibilityCost final : public ceres::CostFunction {
   public:
    FeasibilityCost(CeresImpl* s, int num_residuals, int n) : s_(s) {
      set_num_residuals(num_residuals);
      mutable_parameter_block_sizes()->push_back(n);
    }
    bool Evaluate(double const* const* parameters, double* residuals,
                  double** jacobians) const override {
      return s_->EvalFeasibility(parameters[0], residuals,
                                 jacobians != nullptr ? jacobians[0] : nullptr);
    }

   private:
    CeresImpl* s_;
  };

  class StopWhenFeasible final : public ceres::IterationCallback {
   public:
    double threshold = 0.0;  // on |r|_2 = sqrt(2 cost)
    ceres::CallbackReturnType operator()(
        const ceres::IterationSummary& it) override {
      return std::sqrt(2.0 * it.cost) <= threshold
                 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                 : ceres::SOLVER_CONTINUE;
    }
  };

  bool EvalFeasibility(const double* xp, double* r, double* jr) {
    Eigen::Map<const Eigen::VectorXd> x(xp, n);
    problem->Constraints(x, g);
    ++g_evals;
    int k = 0;
    for (int i : eq_rows) r[k++] = g(i) - b.g_lb(i);
    for (size_t s = 0; s < side_rows.size(); ++s)
      r[k++] = std::max(0.0, SideValue(s));
    for (int j : fixed_vars) r[k++] = x(j) - b.x_lb(j);
    for (int q = 0; q < k; ++q)
      if (!std::isfinite(r[q])) return false;
    if (jr == nullptr) return true;
    problem->ConstraintJacobian(x, jac);
    ++j_evals;
    if (!jac.allFinite()) return false;
    Eigen::Map<
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
        J(jr, k, n);
    int row = 0;
    for (int i : eq_rows) J.row(row++) = jac.row(i);
    for (size_t s = 0; s < side_rows.size(); ++s, ++row) {
      if (r[row] > 0.0)
        J.row(row) = side_sign[s] * jac.row(side_rows[s]);
      else
        J.row(row).setZero();
    }
    for (int j : fixed_vars) {
      J.row(row).setZero();
      J(row++, j) = 1.0;
    }
    return true;
  }

  std::unique_ptr<FeasibilityCost> cost;
  std::unique_ptr<ceres::Problem> ls;
  Eigen::VectorXd xp;  // Ceres parameter block (pointer must stay stable)
  std::vector<char> ls_key, key;
  StopWhenFeasible stop_cb;

  // ---- phase 2: augmented Lagrangian ---------------------------------------
  class AlFunction final : public ceres::FirstOrderFunction {
   public:
    AlFunction(CeresImpl* s, int n) : s_(s), n_(n) {}
    bool Evaluate(const double* x, double* cost,
                  double* gradient) const override {
      return s_->EvalAl(x, cost, gradient);
    }
    int NumParameters() const override { return n_; }

   private:
    CeresImpl* s_;
    int n_;
  };

  Eigen::VectorXd lam_eq, mu_side, lam_fix, mu_lb, mu_ub;
  double rho = 10.0;

  bool EvalAl(const double* xp_al, double* cost_out, double* gradient) {
    Eigen::Map<const Eigen::VectorXd> x(xp_al, n);
    const double f = problem->Objective(x);
    ++f_evals;
    problem->Constraints(x, g);
    ++g_evals;
    if (!std::isfinite(f) || !g.allFinite()) return false;
    double phi = f;
    w.setZero();
    gx.setZero();
    for (size_t k = 0; k < eq_rows.size(); ++k) {
      const int i = eq_rows[k];
      const double c = g(i) - b.g_lb(i);
      phi += lam_eq(k) * c + 0.5 * rho * c * c;
      w(i) += lam_eq(k) + rho * c;
    }
    auto ineq = [&](double mu,
                    double h) {  // PHR term, returns max(0, mu + rho h)
      const double t = std::max(0.0, mu + rho * h);
      phi += (t * t - mu * mu) / (2.0 * rho);
      return t;
    };
    for (size_t k = 0; k < side_rows.size(); ++k)
      w(side_rows[k]) += side_sign[k] * ineq(mu_side(k), SideValue(k));
    for (size_t k = 0; k < fixed_vars.size(); ++k) {
      const int j = fixed_vars[k];
      const double c = x(j) - b.x_lb(j);
      phi += lam_fix(k) * c + 0.5 * rho * c * c;
      gx(j) += lam_fix(k) + rho * c;
    }
    for (size_t k = 0; k < lb_vars.size(); ++k) {
      const int j = lb_vars[k];
      gx(j) -= ineq(mu_lb(k), b.x_lb(j) - x(j));
    }
    for (size_t k = 0; k < ub_vars.size(); ++k) {
      const int j = ub_vars[k];
      gx(j) += ineq(mu_ub(k), x(j) - b.x_ub(j));
    }
    *cost_out = phi;
    if (!std::isfinite(phi)) return false;
    if (gradient != nullptr) {
      problem->ObjectiveGradient(x, grad);
      problem->ConstraintJacobian(x, jac);
      ++j_evals;
      Eigen::Map<Eigen::VectorXd> gout(gradient, n);
      gout = grad + gx;
      gout.noalias() += jac.transpose() * w;
      if (!gout.allFinite()) return false;
    }
    return true;
  }

  std::unique_ptr<ceres::GradientProblem> gp;
  int gp_n = -1;
  Eigen::VectorXd xa;

  void Classify(const NlpProblem& p) {
    problem = &p;
    b.Load(p);
    n = p.num_variables();
    m = p.num_constraints();
    ClassifyRows(b, &eq_rows, &side_rows, &side_sign);
    fixed_vars.clear();
    lb_vars.clear();
    ub_vars.clear();
    key.clear();
    for (int j = 0; j < n; ++j) {
      if (b.x_lb(j) == b.x_ub(j)) {
        fixed_vars.push_back(j);
        key.push_back('f');
        continue;
      }
      if (std::isfinite(b.x_lb(j))) lb_vars.push_back(j);
      if (std::isfinite(b.x_ub(j))) ub_vars.push_back(j);
      key.push_back(static_cast<char>('0' + std::isfinite(b.x_lb(j)) +
                                      2 * std::isfinite(b.x_ub(j))));
    }
    key.push_back('|');
    const int nres = NumResiduals();
    for (int shift = 0; shift < 32; shift += 8)
      key.push_back(static_cast<char>((nres >> shift) & 0xff));
    g.resize(m);
    w.resize(m);
    gx.resize(n);
    grad.resize(n);
    jac.resize(m, n);
    f_evals = g_evals = j_evals = 0;
  }

  // (Re)builds the persistent least-squares problem if the structure changed.
  void PrepareLeastSquares() {
    if (ls && key == ls_key) return;
    ls.reset();
    cost.reset();
    xp.resize(n);
    cost = std::make_unique<FeasibilityCost>(this, NumResiduals(), n);
    ceres::Problem::Options po;
    // The cost function is a member of this object.
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ls = std::make_unique<ceres::Problem>(po);
    ls->AddResidualBlock(cost.get(), nullptr, xp.data());
    ls_key = key;
  }

  // ---- DoSolve()'s phases (defined below) ---------------------------------
  // Per-solve counts. native: LM steps (both kinds) + BFGS iterations +
  // polish steps; comparable (core/nlp.h): accepted iterates, i.e.
  // successful LM steps, BFGS iterations (each ends with an accepted
  // line-search point) and polish steps that moved x.
  int iterations = 0, accepted = 0;
  // Sets the status and copies the counts into `result`.
  void Finish(NlpStatus status, NlpResult* result) const;
  // The active-set polish of *x, its steps and evaluations counted.
  PolishStats Polish(double active_tol, double feas_tol, Eigen::VectorXd* x);
  // Phase 1 on result->x; true when it settled the status (square systems,
  // infeasibility, failure), false to go on with phase 2.
  bool FeasibilityPhase(const NlpOptions& options, NlpResult* result);
  ceres::Solver::Options FeasibilityOptions(const NlpOptions& options);
  // Phase 2 from result->x, polish and multipliers included.
  void AugmentedLagrangianPhase(const NlpOptions& options, NlpResult* result);
  // lam / mu zero, or seeded from result.multipliers (warm start).
  void InitMultipliers(const NlpOptions& options, const NlpResult& result);
  ceres::GradientProblemSolver::Options InnerOptions(const NlpOptions& options,
                                                     double grad_scale) const;
  // The outer iterations' progress.
  struct AlState {
    int outer = 0;
    double viol = std::numeric_limits<double>::infinity();
    bool converged = false, polished = false;
    ceres::GradientProblemSolver::Summary inner;  // the last inner solve
  };
  // False when a failure status was set.
  bool AugmentedLagrangianLoop(const ceres::GradientProblemSolver::Options& go,
                               const NlpOptions& options, AlState* al,
                               NlpResult* result);
  // Multiplier updates at x (g = g(x)); returns the feasibility /
  // complementarity measure V.
  double UpdateMultipliers(const Eigen::VectorXd& x);
  void StoreMultipliers(NlpResult* result) const;
};

const char* TerminationName(ceres::TerminationType t) {
  switch (t) {
    case ceres::CONVERGENCE:
      return "CONVERGENCE";
    case ceres::NO_CONVERGENCE:
      return "NO_CONVERGENCE";
    case ceres::FAILURE:
      return "FAILURE";
    case ceres::USER_SUCCESS:
      return "USER_SUCCESS";
    case ceres::USER_FAILURE:
      return "USER_FAILURE";
  }
  return "UNKNOWN";
}

void CeresImpl::Finish(NlpStatus status, NlpResult* result) const {
  result->status = status;
  result->iterations = accepted;
  result->native_iterations = iterations;
  result->objective_evaluations = f_evals;
  result->constraint_evaluations = g_evals;
  result->jacobian_evaluations = j_evals;
}

PolishStats CeresImpl::Polish(double active_tol, double feas_tol,
                              Eigen::VectorXd* x) {
  const PolishStats ps = PolishActiveConstraints(
      *problem, b, active_tol, feas_tol, settings.polish_max_iterations, x);
  accepted += ps.accepted_steps;
  iterations += ps.iterations;
  g_evals += ps.constraint_evaluations;
  j_evals += ps.jacobian_evaluations;
  return ps;
}

ceres::Solver::Options CeresImpl::FeasibilityOptions(
    const NlpOptions& options) {
  ceres::Solver::Options o;
  o.minimizer_type = ceres::TRUST_REGION;
  o.trust_region_strategy_type = settings.trust_region;
  o.linear_solver_type = settings.linear_solver;
  o.max_num_iterations = options.max_iterations;
  // Round-off, not Ceres' tolerances, should end a zero-residual solve; the
  // callback stops as soon as every residual is below the tolerance.
  o.function_tolerance = 1e-16;
  o.gradient_tolerance = 1e-16;
  o.parameter_tolerance = 1e-16;
  o.num_threads = 1;
  o.logging_type =
      options.verbosity > 0 ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  o.minimizer_progress_to_stdout = options.verbosity > 0;
  stop_cb.threshold = 0.5 * options.feasibility_tolerance;
  o.callbacks.push_back(&stop_cb);
  return o;
}

bool CeresImpl::FeasibilityPhase(const NlpOptions& options, NlpResult* result) {
  const double feas_tol = options.feasibility_tolerance;
  const bool square = static_cast<int>(eq_rows.size()) == n;
  char msg[256];
  Eigen::VectorXd& x = result->x;
  PrepareLeastSquares();
  xp = x;
  for (int j : lb_vars) ls->SetParameterLowerBound(xp.data(), j, b.x_lb(j));
  for (int j : ub_vars) ls->SetParameterUpperBound(xp.data(), j, b.x_ub(j));
  const ceres::Solver::Options o = FeasibilityOptions(options);
  std::string why;
  if (!o.IsValid(&why)) {
    result->backend_status = "invalid Ceres options: " + why;
    Finish(NlpStatus::kNumericalFailure, result);
    return true;
  }
  ceres::Solver::Summary summary;
  ceres::Solve(o, ls.get(), &summary);
  // Entry 0 of summary.iterations is the starting point; every later entry
  // is one trust-region step, successful (accepted) or not.
  for (const ceres::IterationSummary& it : summary.iterations) {
    if (it.iteration == 0) continue;
    ++iterations;
    accepted += it.step_is_successful;
  }
  x = xp;
  g.resize(m);
  problem->Constraints(x, g);
  ++g_evals;
  const double viol = MaxConstraintViolation(x, g, b);
  std::snprintf(msg, sizeof msg, "LM %s after %d iterations, violation %.2e",
                TerminationName(summary.termination_type), iterations, viol);
  result->backend_status = msg;
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(viol)) {
    result->backend_status += ": " + summary.message;
    Finish(NlpStatus::kNumericalFailure, result);
    return true;
  }
  if (viol <= feas_tol) {
    if (!square) return false;
    Finish(NlpStatus::kConverged, result);  // isolated root: f is moot
    return true;
  }
  if (summary.termination_type == ceres::CONVERGENCE &&
      viol >= settings.infeasible_threshold) {
    result->backend_status += " (minimum of the violation > 0)";
    Finish(NlpStatus::kInfeasible, result);
    return true;
  }
  if (!square) return false;
  // LM's cost-decrease test can stall on ill-conditioned roots (cond
  // ~1e7-1e8); finish with affine-invariant Newton steps from nearby.
  // active_tol = 0: the root is isolated, so a variable merely close to a
  // bound must stay free (freezing it drops a column of a square J).
  if (viol <= settings.infeasible_threshold) {
    const PolishStats ps = Polish(/*active_tol=*/0.0, feas_tol, &x);
    std::snprintf(msg, sizeof msg, "; polish -> violation %.2e",
                  ps.max_violation);
    result->backend_status += msg;
    if (ps.success) {
      Finish(NlpStatus::kConverged, result);
      return true;
    }
  }
  Finish(summary.termination_type == ceres::NO_CONVERGENCE
             ? NlpStatus::kIterationLimit
             : NlpStatus::kNumericalFailure,
         result);
  return true;
}

void CeresImpl::InitMultipliers(const NlpOptions& options,
                                const NlpResult& result) {
  const size_t n_eq = eq_rows.size(), n_side = side_rows.size();
  lam_eq.setZero(static_cast<Eigen::Index>(n_eq));
  mu_side.setZero(static_cast<Eigen::Index>(n_side));
  lam_fix.setZero(static_cast<Eigen::Index>(fixed_vars.size()));
  mu_lb.setZero(static_cast<Eigen::Index>(lb_vars.size()));
  mu_ub.setZero(static_cast<Eigen::Index>(ub_vars.size()));
  if (!options.warm_start_multipliers || result.multipliers.size() != m ||
      !result.multipliers.allFinite())
    return;
  const Eigen::VectorXd& lam = result.multipliers;
  for (size_t k = 0; k < n_eq; ++k) lam_eq(k) = lam(eq_rows[k]);
  for (size_t k = 0; k < n_side; ++k)
    mu_side(k) = std::max(0.0, side_sign[k] * lam(side_rows[k]));
  // Box multipliers from the reduced gradient r = grad f + J^T lambda:
  // r = z_L - z_U at a KKT point.
  problem->ObjectiveGradient(result.x, grad);
  problem->ConstraintJacobian(result.x, jac);
  ++j_evals;
  gx = grad;
  gx.noalias() += jac.transpose() * lam;
  if (gx.allFinite()) {
    for (size_t k = 0; k < fixed_vars.size(); ++k)
      lam_fix(k) = -gx(fixed_vars[k]);
    for (size_t k = 0; k < lb_vars.size(); ++k)
      mu_lb(k) = std::max(0.0, gx(lb_vars[k]));
    for (size_t k = 0; k < ub_vars.size(); ++k)
      mu_ub(k) = std::max(0.0, -gx(ub_vars[k]));
  }
}

ceres::GradientProblemSolver::Options CeresImpl::InnerOptions(
    const NlpOptions& options, double grad_scale) const {
  ceres::GradientProblemSolver::Options go;
  go.line_search_direction_type = settings.direction;
  go.line_search_type = ceres::WOLFE;
  go.max_num_iterations = options.max_iterations;
  go.function_tolerance = 1e-16;
  go.parameter_tolerance = 1e-16;
  go.gradient_tolerance = options.optimality_tolerance * grad_scale;
  go.logging_type =
      options.verbosity > 0 ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  go.minimizer_progress_to_stdout = options.verbosity > 0;
  return go;
}

double CeresImpl::UpdateMultipliers(const Eigen::VectorXd& x) {
  double v = 0.0;
  for (size_t k = 0; k < eq_rows.size(); ++k) {
    const double c = g(eq_rows[k]) - b.g_lb(eq_rows[k]);
    v = std::max(v, std::abs(c));
    lam_eq(k) += rho * c;
  }
  auto upd = [&](double& mu, double h) {
    v = std::max(v, std::abs(std::min(-h, mu / rho)));
    mu = std::max(0.0, mu + rho * h);
  };
  for (size_t k = 0; k < side_rows.size(); ++k) upd(mu_side(k), SideValue(k));
  for (size_t k = 0; k < fixed_vars.size(); ++k) {
    const int j = fixed_vars[k];
    const double c = x(j) - b.x_lb(j);
    v = std::max(v, std::abs(c));
    lam_fix(k) += rho * c;
  }
  for (size_t k = 0; k < lb_vars.size(); ++k)
    upd(mu_lb(k), b.x_lb(lb_vars[k]) - x(lb_vars[k]));
  for (size_t k = 0; k < ub_vars.size(); ++k)
    upd(mu_ub(k), x(ub_vars[k]) - b.x_ub(ub_vars[k]));
  return v;
}

bool CeresImpl::AugmentedLagrangianLoop(
    const ceres::GradientProblemSolver::Options& go, const NlpOptions& options,
    AlState* al, NlpResult* result) {
  const double feas_tol = options.feasibility_tolerance;
  Eigen::VectorXd& x = result->x;
  // V below which the answer is finished by an active-set Newton polish: the
  // AL error bound |x - x*| <= C |lambda - lambda*| / rho ~ C V makes further
  // outer iterations pointless once V is this small.
  const double polish_v = std::max(feas_tol, settings.polish_threshold);
  double v_prev = std::numeric_limits<double>::infinity();
  ceres::GradientProblemSolver::Summary& gs = al->inner;
  for (; al->outer < options.max_iterations && !al->converged; ++al->outer) {
    ceres::Solve(go, *gp, xa.data(), &gs);
    if (!gs.iterations.empty()) {
      iterations += static_cast<int>(gs.iterations.size()) - 1;
      accepted += static_cast<int>(gs.iterations.size()) - 1;
    }
    if (gs.termination_type == ceres::FAILURE && gs.iterations.size() <= 1 &&
        !std::isfinite(gs.final_cost)) {
      result->backend_status += "; AL inner solve failed: " + gs.message;
      x = xa;
      Finish(NlpStatus::kNumericalFailure, result);
      return false;
    }
    x = xa;
    problem->Constraints(x, g);
    ++g_evals;
    if (!g.allFinite()) {
      Finish(NlpStatus::kNumericalFailure, result);
      result->backend_status += "; non-finite constraints in the AL loop";
      return false;
    }
    al->viol = MaxConstraintViolation(x, g, b);
    // Feasibility / complementarity measure and multiplier updates.
    const double v = UpdateMultipliers(x);
    // KKT: the inner gradient is grad_x L at the updated multipliers.
    const double inner_grad = gs.iterations.empty()
                                  ? std::numeric_limits<double>::infinity()
                                  : gs.iterations.back().gradient_max_norm;
    const bool stationary = inner_grad <= 100.0 * go.gradient_tolerance ||
                            gs.termination_type == ceres::CONVERGENCE;
    al->converged = al->viol <= feas_tol && v <= feas_tol && stationary;
    if (!al->converged && stationary && v <= polish_v) {
      // Close enough that the active set is settled: finish feasibility with
      // a Newton polish instead of driving rho up against round-off.
      xa = x;
      const PolishStats ps =
          Polish(/*active_tol=*/settings.polish_threshold, feas_tol, &xa);
      if (ps.success) {
        x = xa;
        al->viol = ps.max_violation;
        al->converged = true;
        al->polished = true;
      } else {
        xa = x;
      }
    }
    if (options.verbosity > 0)
      std::printf(
          "ceres AL outer %3d: inner %-14s %4zu it, |grad L| %.2e, "
          "violation %.2e, V %.2e, rho %.0e\n",
          al->outer, TerminationName(gs.termination_type),
          gs.iterations.empty() ? size_t{0} : gs.iterations.size() - 1,
          inner_grad, al->viol, v, rho);
    if (v > settings.rho_grow_unless * v_prev)
      rho = std::min(settings.rho_growth * rho, settings.rho_max);
    v_prev = v;
  }
  return true;
}

void CeresImpl::StoreMultipliers(NlpResult* result) const {
  // Ipopt's convention: lambda = mu_upper - mu_lower.
  if (result->multipliers.size() != m) result->multipliers.resize(m);
  result->multipliers.setZero();
  for (size_t k = 0; k < eq_rows.size(); ++k)
    result->multipliers(eq_rows[k]) = lam_eq(k);
  for (size_t k = 0; k < side_rows.size(); ++k)
    result->multipliers(side_rows[k]) += side_sign[k] * mu_side(k);
  result->has_multipliers = true;
}

void CeresImpl::AugmentedLagrangianPhase(const NlpOptions& options,
                                         NlpResult* result) {
  const double feas_tol = options.feasibility_tolerance;
  Eigen::VectorXd& x = result->x;
  InitMultipliers(options, *result);
  rho = settings.rho_init;
  if (!gp || gp_n != n) {
    gp = std::make_unique<ceres::GradientProblem>(new AlFunction(this, n));
    gp_n = n;
  }
  xa = x;
  problem->ObjectiveGradient(x, grad);
  const double grad_scale =
      grad.allFinite() ? std::max(1.0, grad.lpNorm<Eigen::Infinity>()) : 1.0;
  const ceres::GradientProblemSolver::Options go =
      InnerOptions(options, grad_scale);
  std::string why;
  if (!go.IsValid(&why)) {
    result->backend_status = "invalid Ceres options: " + why;
    Finish(NlpStatus::kNumericalFailure, result);
    return;
  }

  AlState al;
  if (!AugmentedLagrangianLoop(go, options, &al, result)) return;
  char msg[256];
  std::snprintf(
      msg, sizeof msg,
      "; AL %d outer iterations, rho %.0e, violation %.2e%s, last inner %s",
      al.outer, rho, al.viol, al.polished ? " (polished)" : "",
      TerminationName(al.inner.termination_type));
  result->backend_status += msg;
  NlpStatus status =
      al.converged ? NlpStatus::kConverged : NlpStatus::kIterationLimit;
  if (!al.converged && al.viol > feas_tol &&
      al.viol <= settings.infeasible_threshold) {
    const PolishStats ps =
        Polish(/*active_tol=*/settings.polish_threshold, feas_tol, &x);
    std::snprintf(msg, sizeof msg, "; polish -> violation %.2e",
                  ps.max_violation);
    result->backend_status += msg;
    if (ps.success) status = NlpStatus::kConverged;
  }
  StoreMultipliers(result);
  Finish(status, result);
}

// Ceres keeps all solver state in its Problem/Solver objects: instances may
// run concurrently.
class CeresNlpSolver final : public NlpSolver {
 public:
  std::string name() const override { return "ceres"; }
  bool SupportsConcurrentInstances() const override { return true; }
  OptionTable option_table() const override {
    return {
        OptionSpec::Double("rho_init", 10.0,
                           "initial augmented-Lagrangian penalty rho")
            .GreaterThan(0),
        OptionSpec::Double("rho_growth", 10.0,
                           "rho <- rho_growth * rho when V did not drop enough")
            .GreaterThan(1),
        OptionSpec::Double("rho_max", 1e8, "largest penalty rho")
            .GreaterThan(0),
        OptionSpec::Double("rho_grow_unless", 0.25,
                           "rho grows unless V <= rho_grow_unless * V_previous")
            .GreaterThan(0)
            .LessThan(1),
        OptionSpec::Double("polish_threshold", 1e-7,
                           "V below which the AL loop hands over to the "
                           "active-set Newton polish (or feasibility_tolerance "
                           "if larger); also the polish's active-row tolerance")
            .GreaterThan(0),
        OptionSpec::Double("infeasible_threshold", 1e-6,
                           "phase 1: violation at Ceres CONVERGENCE from which "
                           "the problem counts as infeasible")
            .GreaterThan(0),
        OptionSpec::Int("polish_max_iterations", 20,
                        "Gauss-Newton steps of the feasibility polish")
            .AtLeast(0),
        OptionSpec::Choice("trust_region_strategy", "levenberg_marquardt",
                           {"levenberg_marquardt", "dogleg"},
                           "phase 1 trust-region strategy "
                           "(Solver::Options::trust_region_strategy_type)"),
        OptionSpec::Choice("linear_solver", "dense_qr",
                           {"dense_qr", "dense_normal_cholesky"},
                           "phase 1 linear solver "
                           "(Solver::Options::linear_solver_type)"),
        OptionSpec::Choice(
            "line_search_direction", "bfgs", {"bfgs", "lbfgs"},
            "phase 2 inner solves' direction "
            "(GradientProblemSolver line_search_direction_type)"),
    };
  }

 private:
  void ApplyBackendOptions(const OptionValues& values) override {
    CeresImpl::Settings& s = impl_.settings;
    s.rho_init = values.GetDouble("rho_init");
    s.rho_growth = values.GetDouble("rho_growth");
    s.rho_max = values.GetDouble("rho_max");
    s.rho_grow_unless = values.GetDouble("rho_grow_unless");
    s.polish_threshold = values.GetDouble("polish_threshold");
    s.infeasible_threshold = values.GetDouble("infeasible_threshold");
    s.polish_max_iterations =
        static_cast<int>(values.GetInt("polish_max_iterations"));
    s.trust_region = values.GetString("trust_region_strategy") == "dogleg"
                         ? ceres::DOGLEG
                         : ceres::LEVENBERG_MARQUARDT;
    s.linear_solver = values.GetString("linear_solver") == "dense_qr"
                          ? ceres::DENSE_QR
                          : ceres::DENSE_NORMAL_CHOLESKY;
    s.direction = values.GetString("line_search_direction") == "lbfgs"
                      ? ceres::LBFGS
                      : ceres::BFGS;
  }
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override {
    CeresImpl& s = impl_;
    s.Classify(problem);
    for (int j = 0; j < s.n; ++j)
      result->x(j) = std::clamp(x0(j), s.b.x_lb(j), s.b.x_ub(j));
    s.iterations = s.accepted = 0;
    // Phase 1 settles square systems (and failures); phase 2 the others.
    if (s.NumResiduals() > 0 && s.FeasibilityPhase(options, result)) return;
    s.AugmentedLagrangianPhase(options, result);
  }

  CeresImpl impl_;
};

}  // namespace

std::unique_ptr<NlpSolver> MakeCeresNlpSolver() {
  return std::make_unique<CeresNlpSolver>();
}

}  // namespace quasiroll
