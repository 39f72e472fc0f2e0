#include "quasiroll/core/dae.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/registry.h"

namespace quasiroll {

const char* ToString(IntegratorStatus status) {
  switch (status) {
    case IntegratorStatus::kSuccess:
      return "success";
    case IntegratorStatus::kStepSizeTooSmall:
      return "step_size_too_small";
    case IntegratorStatus::kConvergenceFailure:
      return "convergence_failure";
    case IntegratorStatus::kConstraintFailure:
      return "constraint_failure";
    case IntegratorStatus::kEvent:
      return "event";
    case IntegratorStatus::kInvalidInput:
      return "invalid_input";
    case IntegratorStatus::kRhsFailure:
      return "rhs_failure";
    case IntegratorStatus::kNotRun:
      return "not_run";
  }
  return "unknown";
}

namespace {
std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}
}  // namespace

bool IntegratorOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(std::isfinite(step) && step >= 0))
    return fail("step: must be finite and >= 0, got " + Num(step));
  if (!(std::isfinite(rtol) && rtol > 0))
    return fail("rtol: must be finite and > 0, got " + Num(rtol));
  if (!(std::isfinite(atol) && atol > 0))
    return fail("atol: must be finite and > 0, got " + Num(atol));
  if (!(std::isfinite(min_step) && min_step >= 0))
    return fail("min_step: must be finite and >= 0, got " + Num(min_step));
  if (max_steps < 1)
    return fail("max_steps: must be >= 1, got " + std::to_string(max_steps));
  return true;
}

void Integrator::SetBackendOptions(const GivenOptions& given) {
  OptionValues values =
      ResolveOptions(option_table(), given, "integrator '" + name() + "'");
  ApplyBackendOptions(values);
  backend_options_ = std::move(values);
}

const OptionValues& Integrator::backend_options() {
  if (!backend_options_) SetBackendOptions({});
  return *backend_options_;
}

// The end state of a successful call enters result->step_drift_max (inside
// Integrate's try: an ode whose Constraints throws is reported like any
// other exception of the ode).
void Integrator::RecordEndDrift(const ConstrainedOde& ode,
                                const Eigen::Ref<const Eigen::VectorXd>& y,
                                IntegratorResult* result) {
  const int m = ode.num_constraints();
  if (m == 0 || !y.allFinite() ||
      (result->status != IntegratorStatus::kSuccess &&
       result->status != IntegratorStatus::kEvent))
    return;
  if (end_constraints_.size() != m) end_constraints_.resize(m);
  ode.Constraints(y, end_constraints_);
  result->step_drift_max = std::fmax(
      result->step_drift_max, end_constraints_.lpNorm<Eigen::Infinity>());
}

IntegratorStatus Integrator::Integrate(ConstrainedOde& ode, double t0,
                                       double t1, Eigen::Ref<Eigen::VectorXd> y,
                                       const IntegratorOptions& options,
                                       IntegratorResult* result) {
  if (result == nullptr)
    throw std::invalid_argument(
        "Integrator::Integrate: result must not be null");
  std::string why;
  if (!options.IsValid(&why))
    throw std::invalid_argument("Integrator::Integrate(" + name() +
                                "): invalid options: " + why);
  const int n = ode.state_size(), m = ode.num_constraints();
  if (n <= 0)
    throw std::invalid_argument(
        "Integrator::Integrate: state_size must be > 0, got " +
        std::to_string(n));
  if (m < 0)
    throw std::invalid_argument(
        "Integrator::Integrate: num_constraints must be >= 0, got " +
        std::to_string(m));
  if (ode.num_roots() < 0)
    throw std::invalid_argument(
        "Integrator::Integrate: num_roots must be >= 0, got " +
        std::to_string(ode.num_roots()));
  if (y.size() != n) {
    std::ostringstream os;
    os << "Integrator::Integrate: y has size " << y.size()
       << ", problem has state_size " << n;
    throw std::invalid_argument(os.str());
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(y(i))) {
      std::ostringstream os;
      os << "Integrator::Integrate: y[" << i << "] is not finite (" << y(i)
         << ")";
      throw std::invalid_argument(os.str());
    }
  }
  if (!(std::isfinite(t0) && std::isfinite(t1) && t1 > t0)) {
    std::ostringstream os;
    os << "Integrator::Integrate: need finite t1 > t0, got t0 = " << t0
       << ", t1 = " << t1;
    throw std::invalid_argument(os.str());
  }

  result->status = IntegratorStatus::kNotRun;
  result->t_reached = t0;
  result->root_index = -1;
  result->message.clear();

  if (!backend_options_) SetBackendOptions({});  // the table's defaults
  const auto start = std::chrono::steady_clock::now();
  try {
    ode.MakeConsistent(t0, y);
    DoIntegrate(ode, t0, t1, y, options, result);
    RecordEndDrift(ode, y, result);
  } catch (const std::invalid_argument&) {
    throw;  // misuse detected by the backend (e.g. negative weights)
  } catch (const std::exception& e) {
    // Numerics / third-party failures are reported, not propagated.
    result->status = IntegratorStatus::kConvergenceFailure;
    result->message = std::string("exception: ") + e.what();
  }
  result->wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();

  if ((result->status == IntegratorStatus::kSuccess ||
       result->status == IntegratorStatus::kEvent) &&
      !y.allFinite()) {
    result->status = IntegratorStatus::kConvergenceFailure;
    result->message += " [non-finite state]";
  }
  return result->status;
}

template <>
Registry<Integrator>& BackendRegistry<Integrator>::Instance() {
  static Registry<Integrator> registry("integrator backend");
  return registry;
}
template class BackendRegistry<Integrator>;

}  // namespace quasiroll
