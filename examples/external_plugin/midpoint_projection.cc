#include "midpoint_projection.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace example {

using quasiroll::ConstrainedOde;
using quasiroll::IntegratorOptions;
using quasiroll::IntegratorResult;
using quasiroll::IntegratorStatus;

quasiroll::OptionTable MidpointProjectionIntegrator::option_table() const {
  quasiroll::OptionTable table = quasiroll::ProjectionSettings::Options();
  table.push_back(
      quasiroll::OptionSpec::Int("midpoint_steps", 1,
                                 "midpoint steps per IntegratorOptions::step")
          .AtLeast(1)
          .AtMost(1000));
  return table;
}

void MidpointProjectionIntegrator::ApplyBackendOptions(
    const quasiroll::OptionValues& values) {
  projection_settings_ = quasiroll::ProjectionSettings::From(values);
  substeps_ = static_cast<int>(values.GetInt("midpoint_steps"));
}

IntegratorStatus MidpointProjectionIntegrator::Project(
    ConstrainedOde& ode, Eigen::VectorXd& y,
    const IntegratorOptions& /*options*/, IntegratorResult* result) {
  bool moved = false;
  const IntegratorStatus status =
      projection_.Project(ode, y, projection_settings_, result, &moved);
  if (status != IntegratorStatus::kSuccess)
    result->message = projection_.message();
  return status;
}

IntegratorStatus MidpointProjectionIntegrator::Step(
    ConstrainedOde& ode, double t, double h, const Eigen::VectorXd& y,
    Eigen::VectorXd& out, const IntegratorOptions& options,
    IntegratorResult* result) {
  auto rhs = [&](double tt, const Eigen::VectorXd& yy) {
    ++result->rhs_evaluations;
    if (ode.Rhs(tt, yy, k_)) return true;
    std::ostringstream os;
    os << "Rhs returned false at t = " << tt;
    result->message = os.str();
    return false;
  };
  if (!rhs(t, y)) return IntegratorStatus::kRhsFailure;
  y_mid_ = y + 0.5 * h * k_;
  if (!rhs(t + 0.5 * h, y_mid_)) return IntegratorStatus::kRhsFailure;
  out = y + h * k_;
  if (!out.allFinite()) {
    result->message = "non-finite state after a step";
    return IntegratorStatus::kConvergenceFailure;
  }
  return Project(ode, out, options, result);
}

int MidpointProjectionIntegrator::Fired(const Eigen::VectorXd& g) const {
  for (Eigen::Index i = 0; i < g.size(); ++i)
    if ((g_old_(i) < 0 && g(i) >= 0) || (g_old_(i) > 0 && g(i) <= 0))
      return static_cast<int>(i);
  return -1;
}

void MidpointProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                               double t1,
                                               Eigen::Ref<Eigen::VectorXd> y,
                                               const IntegratorOptions& options,
                                               IntegratorResult* result) {
  const int n = ode.state_size(), nr = ode.num_roots();
  for (Eigen::VectorXd* v : {&y0_, &y1_, &y_mid_, &y_hi_, &k_}) v->resize(n);
  g_old_.resize(nr);
  g_new_.resize(nr);
  // Loads D; throws std::invalid_argument on a broken problem (misuse).
  projection_.Begin(ode);

  auto finish = [&](IntegratorStatus status, double t) {
    result->status = status;
    result->t_reached = t;
    y = y0_;
  };
  y0_ = y;
  IntegratorStatus status = Project(ode, y0_, options, result);
  if (status != IntegratorStatus::kSuccess) {
    result->message = "initial state: " + result->message;
    return finish(status, t0);
  }

  const double h_nominal =
      (options.step > 0 ? options.step : t1 - t0) / substeps_;
  const double ratio = (t1 - t0) / h_nominal;
  if (!(ratio < static_cast<double>(options.max_steps))) {
    result->message =
        "needs more than max_steps = " + std::to_string(options.max_steps) +
        " steps";
    return finish(IntegratorStatus::kStepSizeTooSmall, t0);
  }
  const long steps = std::max(1L, static_cast<long>(std::ceil(ratio - 1e-9)));
  if (nr > 0) ode.Roots(t0, y0_, g_old_);

  double t = t0;
  for (long k = 1; k <= steps; ++k) {
    const double t_next =
        k == steps ? t1 : t0 + static_cast<double>(k) * h_nominal;
    const double h = t_next - t;
    status = Step(ode, t, h, y0_, y1_, options, result);
    if (status != IntegratorStatus::kSuccess) return finish(status, t);
    if (nr > 0) {
      ode.Roots(t_next, y1_, g_new_);
      if (Fired(g_new_) >= 0) {
        // Bisection on the step fraction: root in (lo, hi], y_hi_ at hi.
        double lo = 0.0, hi = 1.0;
        y_hi_ = y1_;
        while ((hi - lo) * h > 1e-12 * std::max(1.0, std::abs(t))) {
          const double mid = 0.5 * (lo + hi);
          status = Step(ode, t, mid * h, y0_, y1_, options, result);
          if (status != IntegratorStatus::kSuccess) return finish(status, t);
          ode.Roots(t + mid * h, y1_, g_new_);
          if (Fired(g_new_) >= 0) {
            hi = mid;
            y_hi_ = y1_;
          } else {
            lo = mid;
          }
        }
        ode.Roots(t + hi * h, y_hi_, g_new_);
        result->root_index = Fired(g_new_);
        ++result->steps;
        y0_ = y_hi_;
        return finish(IntegratorStatus::kEvent, t + hi * h);
      }
      g_old_ = g_new_;
    }
    y0_.swap(y1_);
    t = t_next;
    ++result->steps;
  }
  finish(IntegratorStatus::kSuccess, t1);
}

}  // namespace example
