#include "quasiroll/integrators/runge_kutta.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace quasiroll::integrators_internal {
namespace {

ButcherTableau MakeRk4() {
  ButcherTableau t;
  t.stages = 4;
  t.order = 4;
  t.a = Eigen::MatrixXd::Zero(4, 4);
  t.a(1, 0) = 0.5;
  t.a(2, 1) = 0.5;
  t.a(3, 2) = 1.0;
  t.b = Eigen::Vector4d(1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6);
  t.c = Eigen::Vector4d(0.0, 0.5, 0.5, 1.0);
  return t;
}

// Dormand & Prince (1980), "A family of embedded Runge-Kutta formulae".
ButcherTableau MakeDormandPrince54() {
  ButcherTableau t;
  t.stages = 7;
  t.order = 5;
  t.embedded_order = 4;
  t.fsal = true;
  t.a = Eigen::MatrixXd::Zero(7, 7);
  t.a(1, 0) = 1.0 / 5;
  t.a(2, 0) = 3.0 / 40;
  t.a(2, 1) = 9.0 / 40;
  t.a(3, 0) = 44.0 / 45;
  t.a(3, 1) = -56.0 / 15;
  t.a(3, 2) = 32.0 / 9;
  t.a(4, 0) = 19372.0 / 6561;
  t.a(4, 1) = -25360.0 / 2187;
  t.a(4, 2) = 64448.0 / 6561;
  t.a(4, 3) = -212.0 / 729;
  t.a(5, 0) = 9017.0 / 3168;
  t.a(5, 1) = -355.0 / 33;
  t.a(5, 2) = 46732.0 / 5247;
  t.a(5, 3) = 49.0 / 176;
  t.a(5, 4) = -5103.0 / 18656;
  t.a(6, 0) = 35.0 / 384;
  t.a(6, 2) = 500.0 / 1113;
  t.a(6, 3) = 125.0 / 192;
  t.a(6, 4) = -2187.0 / 6784;
  t.a(6, 5) = 11.0 / 84;
  t.b = t.a.row(6).transpose();
  t.b_hat.resize(7);
  t.b_hat << 5179.0 / 57600, 0.0, 7571.0 / 16695, 393.0 / 640,
      -92097.0 / 339200, 187.0 / 2100, 1.0 / 40;
  t.c.resize(7);
  t.c << 0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0;
  return t;
}

// Bogacki & Shampine (1989), "A 3(2) pair of Runge-Kutta formulas".
ButcherTableau MakeBogackiShampine32() {
  ButcherTableau t;
  t.stages = 4;
  t.order = 3;
  t.embedded_order = 2;
  t.fsal = true;
  t.a = Eigen::MatrixXd::Zero(4, 4);
  t.a(1, 0) = 1.0 / 2;
  t.a(2, 1) = 3.0 / 4;
  t.a(3, 0) = 2.0 / 9;
  t.a(3, 1) = 1.0 / 3;
  t.a(3, 2) = 4.0 / 9;
  t.b = t.a.row(3).transpose();
  t.b_hat = Eigen::Vector4d(7.0 / 24, 1.0 / 4, 1.0 / 3, 1.0 / 8);
  t.c = Eigen::Vector4d(0.0, 1.0 / 2, 3.0 / 4, 1.0);
  return t;
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

OptionTable RkOptionTable() {
  return {
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
                         "correction failed (singular J D J^T at a stage)")
          .GreaterThan(0)
          .LessThan(1),
  };
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
    bool fired = false;
    for (int i = 0; i < nr && !fired; ++i) fired = Fired(i, g_trial_);
    if (fired) {
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
  double t = t0;
  auto finish = [&](IntegratorStatus status) {
    y = y_;
    result->status = status;
    result->t_reached = t;
  };

  const bool adaptive = tab.embedded_order > 0;
  int accepted = 0;
  bool last_rejected = false;
  const double span = t1 - t0;
  int fixed_steps = 1;
  double h = span;
  if (!adaptive) {
    if (options.step > 0.0 && options.step < span) {
      // Relative slack so that e.g. 0.05 / 0.01 = 5.000000000000001 gives 5.
      const double ratio = span / options.step * (1.0 - 1e-10);
      if (ratio >= static_cast<double>(options.max_steps)) {
        std::ostringstream os;
        os << "RK4 needs " << std::ceil(ratio) << " steps of " << options.step
           << " > max_steps = " << options.max_steps;
        result->message = os.str();
        finish(IntegratorStatus::kStepSizeTooSmall);
        return;
      }
      fixed_steps = std::max(1, static_cast<int>(std::ceil(ratio)));
    }
  } else if (options.step > 0.0) {
    h = std::min(options.step, span);
  }
  const double exponent =
      adaptive ? -1.0 / (std::min(tab.order, tab.embedded_order) + 1) : 0.0;

  if (nr > 0) ode.Roots(t, y_, g_old_);
  IntegratorStatus status = system.Field(t, y_, k_.col(0), result);
  if (status != IntegratorStatus::kSuccess) return finish(status);
  if (adaptive && !(options.step > 0.0))
    h = InitialStep(system, tab, t0, span, options, result);

  // An adaptive trial step whose correction failed (J D J^T singular at a
  // stage, a projection that did not converge): reject it and retry smaller.
  // Returns false when the step would fall below min_step (then the failure
  // stands).
  auto retry_smaller = [&](double h_try, IntegratorStatus failure) {
    if (!adaptive || failure != IntegratorStatus::kConstraintFailure)
      return false;
    const double h_new = h_try * settings.stage_failure_shrink;
    if (h_new < options.min_step) {
      std::ostringstream os;
      os << result->message
         << " (step rejected and shrunk below min_step = " << options.min_step
         << " at t = " << t << ")";
      result->message = os.str();
      return false;
    }
    ++result->rejected_steps;
    result->message.clear();  // handled: the step is retried
    h = h_new;
    last_rejected = true;
    return true;
  };

  while (true) {
    double t_new = 0.0, h_try = 0.0;
    if (!adaptive) {
      t_new =
          accepted + 1 == fixed_steps ? t1 : t0 + (accepted + 1) * options.step;
      h_try = t_new - t;
    } else {
      if (accepted >= options.max_steps) {
        std::ostringstream os;
        os << "max_steps = " << options.max_steps << " reached at t = " << t;
        result->message = os.str();
        return finish(IntegratorStatus::kStepSizeTooSmall);
      }
      if (h < options.min_step && h < t1 - t) {
        std::ostringstream os;
        os << "step size " << h << " < min_step = " << options.min_step
           << " at t = " << t;
        result->message = os.str();
        return finish(IntegratorStatus::kStepSizeTooSmall);
      }
      if (h >= t1 - t) {
        h_try = t1 - t;
        t_new = t1;
      } else {
        h_try = h;
        t_new = t + h;
      }
    }

    status = Step(system, tab, t, h_try, result);
    if (status != IntegratorStatus::kSuccess) {
      if (retry_smaller(h_try, status)) continue;
      return finish(status);
    }

    if (adaptive) {
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
                           settings.safety * std::pow(err, exponent))
                : settings.max_shrink;
        h = h_try * factor;
        last_rejected = true;
        if (h < options.min_step) {
          std::ostringstream os;
          os << "step size " << h << " < min_step = " << options.min_step
             << " at t = " << t << " (error norm " << err << ")";
          result->message = os.str();
          return finish(IntegratorStatus::kStepSizeTooSmall);
        }
        continue;
      }
      double factor =
          err > 0.0 ? std::clamp(settings.safety * std::pow(err, exponent),
                                 settings.max_shrink, settings.max_growth)
                    : settings.max_growth;
      if (last_rejected) factor = std::min(1.0, factor);
      last_rejected = false;
      if (t_new != t1) h = h_try * factor;
    }

    bool moved = false;
    status = system.PostStep(t_new, y_new_, result, &moved);
    if (status != IntegratorStatus::kSuccess) {
      if (retry_smaller(h_try, status)) continue;
      return finish(status);
    }

    if (nr > 0) {
      ode.Roots(t_new, y_new_, g_new_);
      bool fired = false;
      for (int i = 0; i < nr && !fired; ++i) fired = Fired(i, g_new_);
      if (fired) {
        double t_root = t_new;
        int index = -1;
        status =
            LocateRoot(system, ode, tab, t, h_try, result, &t_root, &index);
        if (status != IntegratorStatus::kSuccess) return finish(status);
        ++result->steps;
        y_.swap(y_new_);
        t = t_root >= t_new ? t_new : t_root;
        result->root_index = index;
        return finish(IntegratorStatus::kEvent);
      }
      g_old_.swap(g_new_);
    }

    ++accepted;
    ++result->steps;
    y_.swap(y_new_);
    t = t_new;
    if (t == t1) break;
    if (tab.fsal && !moved) {
      k_.col(0) = k_.col(tab.stages - 1);
    } else {
      status = system.Field(t, y_, k_.col(0), result);
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
