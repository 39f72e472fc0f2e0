#include "quasiroll/core/step_sensitivity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/central_difference_internal.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/loop_closure_ode.h"

namespace quasiroll {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kN = kConfigSize;
constexpr int kP = SensitivityParameter::kCount;

// Classic RK4 as integrators/runge_kutta.cc builds it (MakeRk4): the only
// nonzero a_ij are a_{i,i-1} = 1/2, 1/2, 1, and b = (1/6, 1/3, 1/3, 1/6),
// spelled as there so that h * a and h * b round alike.
constexpr double kA[4] = {0.0, 0.5, 0.5, 1.0};
constexpr double kB[4] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};

const char* kProjection = "rk-projection";
const char* kBaumgarte = "rk-baumgarte";

// The multipliers' derivatives are not needed (twist and rates only).
SensitivityOptions WithoutMultipliers(SensitivityOptions options) {
  options.multipliers = false;
  return options;
}
}  // namespace

const char* ToString(StepSensitivityStatus status) {
  static constexpr const char* kNames[] = {
      "OK",          "ONE_SIDED",
      "SINGULAR",    "QUASI_STATIC_FAILURE",
      "RHS_FAILURE", "CONSTRAINT_FAILURE",
      "NOT_COMPUTED"};
  return kNames[static_cast<int>(status)];
}

bool StepSensitivityOptions::IsValid(std::string* why) const {
  std::ostringstream os;
  if (!(std::isfinite(dt) && dt > 0))
    os << "dt: must be finite and > 0, got " << dt;
  else if (substeps < 1 || substeps > 100000)
    os << "substeps: must be in [1, 100000], got " << substeps;
  else if (dae != kProjection && dae != kBaumgarte)
    os << "dae: must be " << kProjection << " or " << kBaumgarte
       << " (explicit fixed-step integrators), got '" << dae << "'";
  else if (rk_method != "rk4")
    os << "rk_method: must be rk4 (fixed step; the adaptive pairs have no "
          "step derivative here), got '"
       << rk_method << "'";
  else if (!(std::isfinite(baumgarte_sigma) && baumgarte_sigma >= 0))
    os << "baumgarte_sigma: must be finite and >= 0, got " << baumgarte_sigma;
  else if (!(projection.tolerance > 0) || projection.max_iterations < 1)
    os << "projection: tolerance must be > 0 and max_iterations >= 1, got "
       << projection.tolerance << ", " << projection.max_iterations;
  else if (!std::isfinite(t0))
    os << "t0: must be finite, got " << t0;
  std::string inner;
  if (os.tellp() == 0 && !quasi_static.IsValid(&inner))
    os << "quasi_static." << inner;
  if (os.tellp() == 0 && !sensitivity.IsValid(&inner))
    os << "sensitivity." << inner;
  if (os.tellp() == 0) return true;
  if (why) *why = os.str();
  return false;
}

std::vector<SensitivityEntry> StepSensitivityEntries(
    const StepSensitivityResult& result) {
  using P = SensitivityParameter;
  return {
      {"dstate_next_dstate", result.jacobian.middleCols(P::kState, 21), false},
      {"dstate_next_dmu", result.jacobian.col(P::kMu), true},
      {"dstate_next_deps", result.jacobian.col(P::kEpsilon), true},
      {"dstate_next_drates", result.jacobian.middleCols(P::kRates, 6), false}};
}

// The robot's H, J and D for WeightedProjection (the simulator's RobotOde
// without the right-hand side, which is evaluated here directly).
class StepSensitivity::FieldOde final : public LoopClosureOde {
 public:
  using LoopClosureOde::LoopClosureOde;
};

StepSensitivity::StepSensitivity(const KinematicModel& model,
                                 const QuasiStaticParameters& params,
                                 const StepSensitivityOptions& options)
    : model_(model),
      params_(params),
      options_(options),
      analyzer_(WithoutMultipliers(options.sensitivity)) {
  std::string why;
  if (!options_.IsValid(&why))
    throw std::invalid_argument("StepSensitivity: " + why);
  if (!params_.IsValid(&why))
    throw std::invalid_argument("StepSensitivity: " + why);
  baumgarte_ = options_.dae == kBaumgarte;
  QuasiStaticOptions qs = options_.quasi_static;
  qs.extrapolate_warm_start = false;  // the simulator's coupled setting
  std::unique_ptr<NlpSolver> nlp = NlpSolverRegistry::Create(options_.nlp);
  nlp->SetBackendOptions(options_.nlp_options);
  solver_ =
      std::make_unique<QuasiStaticSolver>(model_, params_, std::move(nlp), qs);
  ode_ = std::make_unique<FieldOde>(model_);
  correction_.Begin(*ode_);
  yv_.resize(kN);
  fv_.resize(kN);
}

StepSensitivity::~StepSensitivity() = default;

void StepSensitivity::Fail(StepSensitivityStatus status,
                           const std::string& message,
                           StepSensitivityResult* out) const {
  out->status = status;
  out->message = message;
  out->theta_next.setConstant(kNaN);
  out->jacobian.setConstant(kNaN);
}

std::string StepSensitivity::Where() const {
  if (stage_ < 0) return "Theta_k";
  return "stage " + std::to_string(stage_ + 1) + " of step " +
         std::to_string(step_ + 1);
}

bool StepSensitivity::SolveAt(const Configuration& y,
                              StepSensitivityResult* out) {
  const QuasiStaticStatus status = solver_->Solve(y, &sol_);
  ++out->quasi_static_solves;
  if (status != QuasiStaticStatus::kOk) {
    Fail(StepSensitivityStatus::kQuasiStaticFailure,
         Where() + ": " + ToString(status) + ": " + sol_.message, out);
    return false;
  }
  w_ = solver_->problem().JointSpaceVelocity(sol_.z);
  if (!options_.derivatives || have_singular_) return true;
  const SensitivityStatus s =
      analyzer_.Compute(solver_->problem(), sol_.z, &sens_);
  out->min_rcond = std::min(out->min_rcond, sens_.rcond);
  if (s != SensitivityStatus::kOk) {
    // No derivative exists there: the value goes on, the Jacobian is NaN.
    have_singular_ = true;
    std::ostringstream os;
    os << Where() << ": quasi-static sensitivities " << ToString(s)
       << " (rcond " << sens_.rcond << ")";
    out->message = os.str();
    return true;
  }
  for (int a = 0; a < sens_.num_one_sided; ++a)
    out->one_sided.push_back(
        Where() + ": " +
        OneSidedName(sens_, sens_.one_sided_items[static_cast<size_t>(a)]));
  dw_.topRows<6>() = sens_.twist;
  dw_.bottomRows<6>() = sens_.joint_rates;
  return true;
}

bool StepSensitivity::Field(const Configuration& y, const Vec12& w,
                            Configuration* f, StepSensitivityResult* out) {
  ++out->rhs_evaluations;
  if (!model_.Rhs(y, w, f)) {
    std::ostringstream os;
    os << "KinematicModel::Rhs failed (relative curvature lost) at a stage "
          "state";
    Fail(StepSensitivityStatus::kRhsFailure, os.str(), out);
    return false;
  }
  if (!baumgarte_) return true;
  // rk-baumgarte's CorrectedField::Field, operation for operation.
  yv_ = y;
  fv_ = *f;
  ode_->Constraints(yv_, correction_.h());
  if (!correction_.Factorize(*ode_, yv_, &counters_)) {
    Fail(StepSensitivityStatus::kConstraintFailure, correction_.message(), out);
    return false;
  }
  correction_.r().noalias() = correction_.jacobian() * fv_;
  correction_.r() += options_.baumgarte_sigma * correction_.h();
  correction_.SolveMultiplier(correction_.r(), correction_.lambda());
  Eigen::VectorXd& delta = yv_;  // y no longer needed: reuse as delta
  correction_.Lift(correction_.lambda(), delta);
  fv_ -= delta;
  *f = fv_;
  return true;
}

bool StepSensitivity::FieldDerivative(const Configuration& y, const Vec12& w,
                                      const StateJac& s, const ParamJac& dw,
                                      StateJac* dk,
                                      StepSensitivityResult* out) {
  // g_Y at fixed w, kinematics only: F's chain by chain; the Baumgarte
  // field, which couples the chains, column by column with the same step.
  RhsStateJacobian g_y;
  if (baumgarte_) {
    const auto field = [&](const Configuration& at, Configuration* f) {
      return Field(at, w, f, out);
    };
    for (int j = 0; j < kN; ++j) {
      Configuration column;
      if (!internal::CentralDifference(y, j, field, &column)) return false;
      g_y.col(j) = column;
    }
  } else {
    out->rhs_evaluations += 2 * kN;  // one chain's rows each
    if (!model_.RhsStateDerivative(y, w, &g_y)) {
      Fail(StepSensitivityStatus::kRhsFailure,
           "KinematicModel::Rhs failed (relative curvature lost) at a stage "
           "state",
           out);
      return false;
    }
  }
  // g_w exact; the Baumgarte correction is affine in F.
  RhsTwistJacobian g_w;
  out->rhs_evaluations += 12;
  if (!model_.RhsTwistDerivative(y, &g_w)) {
    Fail(StepSensitivityStatus::kRhsFailure,
         "KinematicModel::Rhs failed (relative curvature lost)", out);
    return false;
  }
  if (baumgarte_) {
    Eigen::Matrix<double, kN, kN> p;
    if (!Projector(y, &p, out)) return false;
    g_w = p * g_w;
  }
  dk->noalias() = g_y * s;
  dk->noalias() += g_w * dw;
  return true;
}

bool StepSensitivity::Projector(const Configuration& y,
                                Eigen::Matrix<double, kN, kN>* p,
                                StepSensitivityResult* out) {
  yv_ = y;
  if (!correction_.Factorize(*ode_, yv_, &counters_)) {
    Fail(StepSensitivityStatus::kConstraintFailure, correction_.message(), out);
    return false;
  }
  // P e_j = e_j - D J^T (J D J^T)^{-1} J e_j.
  for (int j = 0; j < kN; ++j) {
    correction_.SolveMultiplier(correction_.jacobian().col(j),
                                correction_.lambda());
    correction_.Lift(correction_.lambda(), fv_);
    p->col(j) = -fv_;
    (*p)(j, j) += 1.0;
  }
  return true;
}

bool StepSensitivity::Project(Configuration* y, StepSensitivityResult* out) {
  yv_ = *y;
  bool moved = false;
  const IntegratorStatus status =
      correction_.Project(*ode_, yv_, options_.projection, &counters_, &moved);
  if (status != IntegratorStatus::kSuccess) {
    Fail(StepSensitivityStatus::kConstraintFailure,
         "projection: " + correction_.message(), out);
    return false;
  }
  *y = yv_;
  return true;
}

bool StepSensitivity::StageTwist(const Configuration& y, const StateJac& s,
                                 StepSensitivityResult* out) {
  if (options_.coupling == Coupling::kZoh) {
    w_ = w_held_;
    dw_ = dw_held_;
    return true;
  }
  if (!SolveAt(y, out)) return false;
  if (!options_.derivatives || have_singular_) return true;
  // dw = W_Theta(Y) S + [0 W_p(Y)]: the stage state carries Theta_k's
  // influence, the parameters act directly too.
  const ParamJac direct = dw_;
  dw_.noalias() = direct.leftCols<kN>() * s;
  dw_.rightCols<kP - kN>() += direct.rightCols<kP - kN>();
  return true;
}

bool StepSensitivity::RkStep(double h, int step, Configuration* y, StateJac* s,
                             StepSensitivityResult* out) {
  const bool derivs = options_.derivatives;
  Configuration k[4], stage;
  StateJac dk[4], s_stage = *s;
  for (int i = 0; i < 4; ++i) {
    stage = *y;
    if (i > 0) stage.noalias() += (h * kA[i]) * k[i - 1];
    if (derivs && !have_singular_) {
      s_stage = *s;
      if (i > 0) s_stage.noalias() += (h * kA[i]) * dk[i - 1];
    }
    stage_ = i;  // names a failure or a one-sided constraint (Where())
    step_ = step;
    if (!StageTwist(stage, s_stage, out)) return false;
    if (!Field(stage, w_, &k[i], out)) return false;
    if (derivs && !have_singular_ &&
        !FieldDerivative(stage, w_, s_stage, dw_, &dk[i], out))
      return false;
  }
  for (int j = 0; j < 4; ++j) {
    y->noalias() += (h * kB[j]) * k[j];
    if (derivs && !have_singular_) s->noalias() += (h * kB[j]) * dk[j];
  }
  if (baumgarte_) return true;
  if (!Project(y, out)) return false;
  if (!derivs || have_singular_) return true;
  Eigen::Matrix<double, kN, kN> p;
  if (!Projector(*y, &p, out)) return false;
  s_stage.noalias() = p * *s;
  *s = s_stage;
  return true;
}

StepSensitivityStatus StepSensitivity::Compute(
    const Eigen::Ref<const Configuration>& theta, StepSensitivityResult* out) {
  if (!theta.allFinite())
    throw std::invalid_argument(
        "StepSensitivity::Compute: theta must be finite");
  *out = StepSensitivityResult{};
  out->min_rcond = std::numeric_limits<double>::infinity();
  solver_->Reset();
  have_singular_ = false;
  const bool derivs = options_.derivatives;
  Configuration y = theta;
  if (options_.coupling == Coupling::kZoh) {
    // The simulator solves at Theta_k as given (before any projection).
    stage_ = -1;
    if (!SolveAt(y, out)) return out->status;
    w_held_ = w_;
    dw_held_ = dw_;
  }
  StateJac s = StateJac::Zero();
  s.leftCols<kN>().setIdentity();
  if (!baumgarte_) {
    if (!Project(&y, out)) return out->status;
    Eigen::Matrix<double, kN, kN> p;
    if (derivs && !Projector(y, &p, out)) return out->status;
    if (derivs) s.leftCols<kN>() = p;
  }
  // Step ends as RungeKuttaDriver::PlanSteps / NextTrial compute them.
  const double t0 = options_.t0, t1 = t0 + options_.dt;
  const double step = options_.dt / options_.substeps;
  int steps = 1;
  if (step < t1 - t0)
    steps = std::max(
        1, static_cast<int>(std::ceil((t1 - t0) / step * (1.0 - 1e-10))));
  double t = t0;
  for (int i = 0; i < steps; ++i) {
    const double t_new = i + 1 == steps ? t1 : t0 + (i + 1) * step;
    if (!RkStep(t_new - t, i, &y, &s, out)) return out->status;
    t = t_new;
  }
  out->theta_next = y;
  LoopClosure h;
  model_.Constraints(y, &h);
  out->drift = h.lpNorm<Eigen::Infinity>();
  if (!derivs || have_singular_) out->jacobian.setConstant(kNaN);
  if (derivs && !have_singular_) out->jacobian = s;
  if (have_singular_) return out->status = StepSensitivityStatus::kSingular;
  if (!out->one_sided.empty()) {
    out->message = "one-sided derivative: " + out->one_sided.front();
    return out->status = StepSensitivityStatus::kOneSided;
  }
  return out->status = StepSensitivityStatus::kOk;
}

StepSensitivityResult ComputeStepSensitivity(
    const Scene& scene, const StepSensitivityOptions& options,
    const Configuration* theta) {
  const KinematicModel model(scene.geometry, scene.terrain);
  const Configuration theta_k =
      theta ? *theta : SolveInitialConfiguration(model, scene);
  StepSensitivity step(model, QuasiStaticParameters::FromScene(scene), options);
  StepSensitivityResult result;
  step.Compute(theta_k, &result);
  return result;
}

}  // namespace quasiroll
