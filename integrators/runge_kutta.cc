#include "quasiroll/integrators/runge_kutta.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace quasiroll::integrators_internal {
namespace {

// An explicit tableau from the rows 2..s of A below the diagonal (row i has
// i - 1 entries), the weights b (for an FSAL pair: empty, b is then the last
// row of A), the nodes c and the embedded weights b_hat (empty: none).
ButcherTableau Explicit(int order, int embedded_order,
                        const std::vector<std::vector<double>>& lower,
                        const std::vector<double>& b,
                        const std::vector<double>& c,
                        const std::vector<double>& b_hat) {
  ButcherTableau t;
  t.stages = static_cast<int>(c.size());
  t.order = order;
  t.embedded_order = embedded_order;
  t.fsal = b.empty();
  t.a = Eigen::MatrixXd::Zero(t.stages, t.stages);
  for (int i = 1; i < t.stages; ++i)
    for (int j = 0; j < i; ++j)
      t.a(i, j) =
          lower[static_cast<std::size_t>(i - 1)][static_cast<std::size_t>(j)];
  if (t.fsal)
    t.b = t.a.row(t.stages - 1).transpose();
  else
    t.b = Eigen::Map<const Eigen::VectorXd>(b.data(), t.stages);
  t.c = Eigen::Map<const Eigen::VectorXd>(c.data(), t.stages);
  t.b_hat = Eigen::Map<const Eigen::VectorXd>(
      b_hat.data(), static_cast<Eigen::Index>(b_hat.size()));
  return t;
}

ButcherTableau MakeRk4() {
  return Explicit(4, 0, {{0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}},
                  {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6}, {0.0, 0.5, 0.5, 1.0},
                  {});
}

// Dormand & Prince (1980), "A family of embedded Runge-Kutta formulae".
ButcherTableau MakeDormandPrince54() {
  return Explicit(
      5, 4,
      {{1.0 / 5},
       {3.0 / 40, 9.0 / 40},
       {44.0 / 45, -56.0 / 15, 32.0 / 9},
       {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729},
       {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176,
        -5103.0 / 18656},
       {35.0 / 384, 0.0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}},
      {}, {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0},
      {5179.0 / 57600, 0.0, 7571.0 / 16695, 393.0 / 640, -92097.0 / 339200,
       187.0 / 2100, 1.0 / 40});
}

// Bogacki & Shampine (1989), "A 3(2) pair of Runge-Kutta formulas".
ButcherTableau MakeBogackiShampine32() {
  return Explicit(
      3, 2, {{1.0 / 2}, {0.0, 3.0 / 4}, {2.0 / 9, 1.0 / 3, 4.0 / 9}}, {},
      {0.0, 1.0 / 2, 3.0 / 4, 1.0}, {7.0 / 24, 1.0 / 4, 1.0 / 3, 1.0 / 8});
}

}  // namespace

const char* ToString(RkMethod method) {
  switch (method) {
    case RkMethod::kRk4:
      return "rk4";
    case RkMethod::kDormandPrince54:
      return "dp54";
    case RkMethod::kBogackiShampine32:
      return "bs32";
  }
  return "unknown";
}

RkMethod RkMethodFromString(const std::string& name) {
  if (name == "rk4") return RkMethod::kRk4;
  if (name == "dp54" || name == "dopri5") return RkMethod::kDormandPrince54;
  if (name == "bs32") return RkMethod::kBogackiShampine32;
  throw std::invalid_argument("unknown Runge-Kutta method '" + name +
                              "' (known: rk4, dp54, bs32)");
}

OptionTable RkOptionTable(OptionTable own) {
  const OptionTable shared = {
      OptionSpec::Choice("rk_method", "rk4", {"rk4", "dp54", "bs32"},
                         "RK scheme: classic RK4 (fixed step) or the "
                         "embedded pairs DP5(4), BS3(2) (adaptive)"),
      OptionSpec::Double("safety", 0.9,
                         "step controller safety factor: h_new = h * safety "
                         "* err^(-1/(q+1))")
          .GreaterThan(0)
          .AtMost(1),
      OptionSpec::Double("max_growth", 5.0,
                         "largest step increase factor after an accepted "
                         "step")
          .AtLeast(1),
      OptionSpec::Double("max_shrink", 0.2,
                         "smallest step decrease factor after an error-test "
                         "failure")
          .GreaterThan(0)
          .AtMost(1),
      OptionSpec::Double("stage_failure_shrink", 0.25,
                         "step factor after a trial step whose constraint "
                         "correction failed (singular J D J^T at a stage) or "
                         "whose stage's right-hand side failed recoverably "
                         "(a coupled solve that missed its tolerance)")
          .GreaterThan(0)
          .LessThan(1),
  };
  own.insert(own.end(), shared.begin(), shared.end());
  return own;
}

RkSettings RkSettingsFrom(const OptionValues& values) {
  RkSettings s;
  s.method = RkMethodFromString(values.GetString("rk_method"));
  s.safety = values.GetDouble("safety");
  s.max_growth = values.GetDouble("max_growth");
  s.max_shrink = values.GetDouble("max_shrink");
  s.stage_failure_shrink = values.GetDouble("stage_failure_shrink");
  return s;
}

const ButcherTableau& Tableau(RkMethod method) {
  static const ButcherTableau rk4 = MakeRk4();
  static const ButcherTableau dp54 = MakeDormandPrince54();
  static const ButcherTableau bs32 = MakeBogackiShampine32();
  switch (method) {
    case RkMethod::kRk4:
      return rk4;
    case RkMethod::kDormandPrince54:
      return dp54;
    case RkMethod::kBogackiShampine32:
      return bs32;
  }
  return rk4;
}

void RungeKuttaDriver::Resize(int n, int stages, int roots) {
  if (k_.rows() != n || k_.cols() != stages) k_.resize(n, stages);
  if (y_.size() != n) {
    y_.resize(n);
    y_stage_.resize(n);
    y_new_.resize(n);
    err_.resize(n);
    y_hi_.resize(n);
  }
  if (g_old_.size() != roots) {
    g_old_.resize(roots);
    g_new_.resize(roots);
    g_trial_.resize(roots);
    g_lo_.resize(roots);
    g_hi_.resize(roots);
  }
}

IntegratorStatus RungeKuttaDriver::Step(RkSystem& system,
                                        const ButcherTableau& tab, double t,
                                        double h, IntegratorResult* result) {
  const int s = tab.stages;
  for (int i = 1; i < s; ++i) {
    y_stage_ = y_;
    for (int j = 0; j < i; ++j) {
      const double aij = tab.a(i, j);
      if (aij != 0.0) y_stage_.noalias() += (h * aij) * k_.col(j);
    }
    const IntegratorStatus status =
        system.Field(t + tab.c(i) * h, y_stage_, k_.col(i), result);
    if (status != IntegratorStatus::kSuccess) return status;
  }
  if (tab.fsal) {
    y_new_ = y_stage_;  // last stage is evaluated at y_new (a.row(s-1) == b)
  } else {
    y_new_ = y_;
    for (int j = 0; j < s; ++j)
      if (tab.b(j) != 0.0) y_new_.noalias() += (h * tab.b(j)) * k_.col(j);
  }
  if (tab.embedded_order > 0) {
    err_.setZero();
    for (int j = 0; j < s; ++j) {
      const double e = tab.b(j) - tab.b_hat(j);
      if (e != 0.0) err_.noalias() += (h * e) * k_.col(j);
    }
  }
  return IntegratorStatus::kSuccess;
}

bool RungeKuttaDriver::Fired(int i, const Eigen::VectorXd& g) const {
  const double g0 = g_old_(i), g1 = g(i);
  if (g0 == 0.0 || std::isnan(g1)) return false;
  return g1 == 0.0 || ((g1 > 0.0) != (g0 > 0.0));
}

IntegratorStatus RungeKuttaDriver::LocateRoot(
    RkSystem& system, ConstrainedOde& ode, const ButcherTableau& tab, double t,
    double h, IntegratorResult* result, double* t_root, int* index) {
  const int nr = static_cast<int>(g_old_.size());
  double lo = 0.0, hi = 1.0;
  g_lo_ = g_old_;
  g_hi_ = g_new_;
  y_hi_ = y_new_;
  // Root time tolerance as in SUNDIALS: 100 * unit roundoff * (|t| + |h|).
  const double theta_tol = 100.0 * std::numeric_limits<double>::epsilon() *
                           (std::abs(t) + std::abs(h)) / std::abs(h);
  // Illinois modification of regula falsi: alpha weights g_lo against g_hi;
  // when the same end is replaced twice in a row the retained end's value is
  // halved, which restores superlinear convergence.
  double alpha = 1.0;
  int last_side = 0;  // 1: lo replaced, 2: hi replaced
  auto earliest = [&](double weight, double* frac_out) {
    int best = -1;
    double best_frac = -1.0;
    for (int i = 0; i < nr; ++i) {
      if (!Fired(i, g_hi_)) continue;
      const double denom = g_hi_(i) - weight * g_lo_(i);
      const double frac = denom == 0.0 ? 0.0 : g_hi_(i) / denom;
      if (frac > best_frac) {
        best_frac = frac;
        best = i;
      }
    }
    *frac_out = std::clamp(best_frac, 0.0, 1.0);
    return best;
  };
  for (int iter = 0; iter < 200 && hi - lo > theta_tol; ++iter) {
    double frac = 0.0;
    earliest(alpha, &frac);
    double theta = hi - (hi - lo) * frac;
    // Keep the trial strictly inside the bracket, half a tolerance from ends.
    const double margin = std::min(0.5 * theta_tol, 0.25 * (hi - lo));
    theta = std::clamp(theta, lo + margin, hi - margin);

    // Re-step from y_ (state at t); k_.col(0) = f(t, y_) is still valid.
    IntegratorStatus status = Step(system, tab, t, theta * h, result);
    if (status != IntegratorStatus::kSuccess) return status;
    bool moved = false;
    status = system.PostStep(t + theta * h, y_new_, result, &moved);
    if (status != IntegratorStatus::kSuccess) return status;
    ode.Roots(t + theta * h, y_new_, g_trial_);
    if (AnyFired(g_trial_)) {
      hi = theta;
      g_hi_ = g_trial_;
      y_hi_ = y_new_;
      alpha = last_side == 2 ? 0.5 * alpha : 1.0;
      last_side = 2;
    } else {
      lo = theta;
      g_lo_ = g_trial_;
      alpha = last_side == 1 ? 2.0 * alpha : 1.0;
      last_side = 1;
    }
  }
  double frac = 0.0;
  *index = earliest(1.0, &frac);
  *t_root = t + hi * h;
  y_new_ = y_hi_;
  return IntegratorStatus::kSuccess;
}

double RungeKuttaDriver::WeightedNorm(
    const Eigen::Ref<const Eigen::VectorXd>& v,
    const Eigen::Ref<const Eigen::VectorXd>& y,
    const IntegratorOptions& options) const {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const double e = v(i) / (options.atol + options.rtol * std::abs(y(i)));
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(v.size()));
}

double RungeKuttaDriver::InitialStep(RkSystem& system,
                                     const ButcherTableau& tab, double t0,
                                     double span,
                                     const IntegratorOptions& options,
                                     IntegratorResult* result) {
  const double d0 = WeightedNorm(y_, y_, options);
  const double d1 = WeightedNorm(k_.col(0), y_, options);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min(h0, span);
  // One explicit Euler step to estimate the second derivative. If the field
  // cannot be evaluated there, h0 alone is the (cautious) answer.
  y_stage_ = y_ + h0 * k_.col(0);
  if (system.Field(t0 + h0, y_stage_, k_.col(1), result) !=
      IntegratorStatus::kSuccess) {
    result->message.clear();  // a probe, not a failure of this call
    return h0;
  }
  err_ = k_.col(1) - k_.col(0);
  const double d2 = WeightedNorm(err_, y_, options) / h0;
  const double dmax = std::max(d1, d2);
  const double h1 = dmax <= 1e-15
                        ? std::max(1e-6, 1e-3 * h0)
                        : std::pow(0.01 / dmax, 1.0 / (tab.order + 1));
  return std::min({100.0 * h0, h1, span});
}

bool RungeKuttaDriver::PlanSteps(const ButcherTableau& tab,
                                 const IntegratorOptions& options, RunState* s,
                                 IntegratorResult* result) const {
  s->adaptive = tab.embedded_order > 0;
  s->fixed_steps = 1;
  s->h = s->span;
  if (!s->adaptive) {
    if (options.step > 0.0 && options.step < s->span) {
      // Relative slack so that e.g. 0.05 / 0.01 = 5.000000000000001 gives 5.
      const double ratio = s->span / options.step * (1.0 - 1e-10);
      if (ratio >= static_cast<double>(options.max_steps)) {
        std::ostringstream os;
        os << "RK4 needs " << std::ceil(ratio) << " steps of " << options.step
           << " > max_steps = " << options.max_steps;
        result->message = os.str();
        return false;
      }
      s->fixed_steps = std::max(1, static_cast<int>(std::ceil(ratio)));
    }
  } else if (options.step > 0.0) {
    s->h = std::min(options.step, s->span);
  }
  s->exponent =
      s->adaptive ? -1.0 / (std::min(tab.order, tab.embedded_order) + 1) : 0.0;
  return true;
}

bool RungeKuttaDriver::NextTrial(const IntegratorOptions& options,
                                 const RunState& s, double* t_new,
                                 double* h_try,
                                 IntegratorResult* result) const {
  if (!s.adaptive) {
    *t_new = s.accepted + 1 == s.fixed_steps
                 ? s.t1
                 : s.t0 + (s.accepted + 1) * options.step;
    *h_try = *t_new - s.t;
    return true;
  }
  if (s.accepted >= options.max_steps) {
    std::ostringstream os;
    os << "max_steps = " << options.max_steps << " reached at t = " << s.t;
    result->message = os.str();
    return false;
  }
  if (s.h < options.min_step && s.h < s.t1 - s.t) {
    std::ostringstream os;
    os << "step size " << s.h << " < min_step = " << options.min_step
       << " at t = " << s.t;
    result->message = os.str();
    return false;
  }
  if (s.h >= s.t1 - s.t) {
    *h_try = s.t1 - s.t;
    *t_new = s.t1;
  } else {
    *h_try = s.h;
    *t_new = s.t + s.h;
  }
  return true;
}

bool RungeKuttaDriver::RetrySmaller(double h_try, IntegratorStatus failure,
                                    bool rhs_failure_recoverable,
                                    const IntegratorOptions& options,
                                    const RkSettings& settings, RunState* s,
                                    IntegratorResult* result) const {
  const bool retry =
      failure == IntegratorStatus::kConstraintFailure ||
      (failure == IntegratorStatus::kRhsFailure && rhs_failure_recoverable);
  if (!s->adaptive || !retry) return false;
  const double h_new = h_try * settings.stage_failure_shrink;
  if (h_new < options.min_step) {
    std::ostringstream os;
    os << result->message
       << " (step rejected and shrunk below min_step = " << options.min_step
       << " at t = " << s->t << ")";
    result->message = os.str();
    return false;
  }
  ++result->rejected_steps;
  result->message.clear();  // handled: the step is retried
  s->h = h_new;
  s->last_rejected = true;
  return true;
}

RungeKuttaDriver::ErrorTest RungeKuttaDriver::TestErrorAndAdapt(
    double h_try, double t_new, const IntegratorOptions& options,
    const RkSettings& settings, RunState* s, IntegratorResult* result) const {
  const int n = static_cast<int>(y_.size());
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double scale =
        options.atol +
        options.rtol * std::max(std::abs(y_(i)), std::abs(y_new_(i)));
    const double e = err_(i) / scale;
    sum += e * e;
  }
  const double err = std::sqrt(sum / n);
  if (!(err <= 1.0)) {
    ++result->rejected_steps;
    const double factor =
        std::isfinite(err)
            ? std::max(settings.max_shrink,
                       settings.safety * std::pow(err, s->exponent))
            : settings.max_shrink;
    s->h = h_try * factor;
    s->last_rejected = true;
    if (s->h < options.min_step) {
      std::ostringstream os;
      os << "step size " << s->h << " < min_step = " << options.min_step
         << " at t = " << s->t << " (error norm " << err << ")";
      result->message = os.str();
      return ErrorTest::kStepTooSmall;
    }
    return ErrorTest::kRejected;
  }
  double factor = err > 0.0
                      ? std::clamp(settings.safety * std::pow(err, s->exponent),
                                   settings.max_shrink, settings.max_growth)
                      : settings.max_growth;
  if (s->last_rejected) factor = std::min(1.0, factor);
  s->last_rejected = false;
  if (t_new != s->t1) s->h = h_try * factor;
  return ErrorTest::kAccepted;
}

bool RungeKuttaDriver::AnyFired(const Eigen::VectorXd& g) const {
  bool fired = false;
  const int nr = static_cast<int>(g_old_.size());
  for (int i = 0; i < nr && !fired; ++i) fired = Fired(i, g);
  return fired;
}

void RungeKuttaDriver::Run(RkSystem& system, ConstrainedOde& ode, double t0,
                           double t1, Eigen::Ref<Eigen::VectorXd> y,
                           const IntegratorOptions& options,
                           const RkSettings& settings,
                           IntegratorResult* result) {
  const ButcherTableau& tab = Tableau(settings.method);
  const int n = static_cast<int>(y.size());
  const int nr = ode.num_roots();
  Resize(n, tab.stages, nr);
  y_ = y;
  RunState s;
  s.t0 = t0;
  s.t1 = t1;
  s.t = t0;
  s.span = t1 - t0;
  auto finish = [&](IntegratorStatus status) {
    y = y_;
    result->status = status;
    result->t_reached = s.t;
  };
  if (!PlanSteps(tab, options, &s, result))
    return finish(IntegratorStatus::kStepSizeTooSmall);

  if (nr > 0) ode.Roots(s.t, y_, g_old_);
  IntegratorStatus status = system.Field(s.t, y_, k_.col(0), result);
  if (status != IntegratorStatus::kSuccess) return finish(status);
  if (s.adaptive && !(options.step > 0.0))
    s.h = InitialStep(system, tab, t0, s.span, options, result);

  while (true) {
    double t_new = 0.0, h_try = 0.0;
    if (!NextTrial(options, s, &t_new, &h_try, result))
      return finish(IntegratorStatus::kStepSizeTooSmall);

    // A trial step whose correction failed (J D J^T singular at a stage, a
    // projection that did not converge) or whose stage hit a recoverable Rhs
    // failure is rejected and retried smaller unless that falls below
    // min_step (then the failure stands).
    status = Step(system, tab, s.t, h_try, result);
    if (status != IntegratorStatus::kSuccess) {
      if (RetrySmaller(h_try, status, ode.RhsFailureIsRecoverable(), options,
                       settings, &s, result))
        continue;
      return finish(status);
    }
    if (s.adaptive) {
      const ErrorTest test =
          TestErrorAndAdapt(h_try, t_new, options, settings, &s, result);
      if (test == ErrorTest::kRejected) continue;
      if (test == ErrorTest::kStepTooSmall)
        return finish(IntegratorStatus::kStepSizeTooSmall);
    }
    bool moved = false;
    status = system.PostStep(t_new, y_new_, result, &moved);
    if (status != IntegratorStatus::kSuccess) {
      if (RetrySmaller(h_try, status, /*rhs_failure_recoverable=*/false,
                       options, settings, &s, result))
        continue;
      return finish(status);
    }

    if (nr > 0) {
      ode.Roots(t_new, y_new_, g_new_);
      if (AnyFired(g_new_)) {
        double t_root = t_new;
        int index = -1;
        status =
            LocateRoot(system, ode, tab, s.t, h_try, result, &t_root, &index);
        if (status != IntegratorStatus::kSuccess) return finish(status);
        ++result->steps;
        y_.swap(y_new_);
        s.t = t_root >= t_new ? t_new : t_root;
        result->root_index = index;
        return finish(IntegratorStatus::kEvent);
      }
      g_old_.swap(g_new_);
    }

    ++s.accepted;
    ++result->steps;
    y_.swap(y_new_);
    s.t = t_new;
    if (s.t == t1) break;
    if (tab.fsal && !moved) {
      k_.col(0) = k_.col(tab.stages - 1);
    } else {
      status = system.Field(s.t, y_, k_.col(0), result);
      if (status != IntegratorStatus::kSuccess) return finish(status);
    }
  }
  finish(IntegratorStatus::kSuccess);
}

IntegratorStatus EvaluateRhs(ConstrainedOde& ode, double t,
                             const Eigen::Ref<const Eigen::VectorXd>& y,
                             Eigen::Ref<Eigen::VectorXd> f,
                             IntegratorResult* result) {
  ++result->rhs_evaluations;
  if (ode.Rhs(t, y, f)) return IntegratorStatus::kSuccess;
  std::ostringstream os;
  os << "Rhs returned false at t = " << t;
  result->message = os.str();
  return IntegratorStatus::kRhsFailure;
}

}  // namespace quasiroll::integrators_internal
