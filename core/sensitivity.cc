#include "quasiroll/core/sensitivity.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace quasiroll {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEpsMach = std::numeric_limits<double>::epsilon();
}  // namespace

const std::array<const char*, 21>& StateNames() {
  static const std::array<const char*, 21> names = {
      "u_w1", "v_w1", "x_g1",   "y_g1",   "psi1",   "u_w2",   "v_w2",
      "x_g2", "y_g2", "psi2",   "u_w3",   "v_w3",   "x_g3",   "y_g3",
      "psi3", "phi1", "alpha1", "delta2", "alpha2", "delta3", "alpha3"};
  return names;
}

const std::array<const char*, 6>& JointNames() {
  static const std::array<const char*, 6> names = {
      "phi1", "alpha1", "delta2", "alpha2", "delta3", "alpha3"};
  return names;
}

const char* ToString(SensitivityStatus status) {
  static constexpr const char* kNames[] = {"OK", "SINGULAR", "NOT_SQUARE",
                                           "NOT_COMPUTED"};
  return kNames[static_cast<int>(status)];
}

bool SensitivityOptions::IsValid(std::string* why) const {
  auto check = [&](double v, const char* name) {
    if (std::isfinite(v) && v >= 0) return true;
    if (why) {
      std::ostringstream os;
      os << name << ": must be finite and >= 0, got " << v;
      *why = os.str();
    }
    return false;
  };
  return check(activity_tolerance, "activity_tolerance") &&
         check(singular_rcond, "singular_rcond");
}

std::string OneSidedName(const QuasiStaticSensitivities& sens, int item) {
  const int m = sens.num_constraints;
  std::ostringstream os;
  if (item < m) {
    const int wheel = item - (m - 3) + 1;  // I2 are the last three rows
    os << "I2 wheel " << wheel << " (friction cone, row " << item << ")";
  } else {
    const int wheel = (item - m - sens.num_motion) / 3 + 1;
    os << "I1 wheel " << wheel << " (f_n >= 0, variable " << item - m << ")";
  }
  return os.str();
}

std::vector<SensitivityEntry> SensitivityEntries(
    const QuasiStaticSensitivities& sens) {
  using P = SensitivityParameter;
  const Eigen::MatrixXd outputs[4] = {sens.twist, sens.joint_rates, sens.forces,
                                      sens.multipliers};
  const char* output_names[4] = {"twist", "joint_rates", "forces",
                                 "multipliers"};
  struct Input {
    const char* name;
    int first, count;
  };
  const Input inputs[4] = {{"state", P::kState, P::kNumState},
                           {"mu", P::kMu, 1},
                           {"eps", P::kEpsilon, 1},
                           {"rates", P::kRates, 6}};
  std::vector<SensitivityEntry> entries;
  for (int o = 0; o < 4; ++o) {
    for (const Input& in : inputs) {
      entries.push_back({std::string("d") + output_names[o] + "_d" + in.name,
                         outputs[o].middleCols(in.first, in.count),
                         in.count == 1});
    }
  }
  return entries;
}

SensitivityAnalyzer::SensitivityAnalyzer(const SensitivityOptions& options)
    : options_(options) {
  std::string why;
  if (!options_.IsValid(&why))
    throw std::invalid_argument("SensitivityAnalyzer: " + why);
}

double SensitivityAnalyzer::Scale(int k) const {
  if (k == SensitivityParameter::kMu) return std::abs(nominal_.mu);
  if (k == SensitivityParameter::kEpsilon) return std::abs(nominal_.epsilon);
  if (k >= SensitivityParameter::kRates)
    return std::max(1.0, std::abs(nominal_.joint_rates[static_cast<size_t>(
                             k - SensitivityParameter::kRates)]));
  return 1.0;  // Theta: angles [rad] and chart lengths [m] of order 1
}

void PerturbParameter(const QuasiStaticParameters& nominal, int k, double delta,
                      QuasiStaticProblem* problem, Configuration* theta) {
  problem->set_mu(nominal.mu);
  problem->set_epsilon(nominal.epsilon);
  problem->set_joint_rates(nominal.joint_rates);
  if (k < SensitivityParameter::kMu) {
    (*theta)(k) += delta;
  } else if (k == SensitivityParameter::kMu) {
    problem->set_mu(nominal.mu + delta);
  } else if (k == SensitivityParameter::kEpsilon) {
    problem->set_epsilon(nominal.epsilon + delta);
  } else {
    std::array<double, 6> rates = nominal.joint_rates;
    rates[static_cast<size_t>(k - SensitivityParameter::kRates)] += delta;
    problem->set_joint_rates(rates);
  }
}

void SensitivityAnalyzer::SetParameter(int k, double delta) {
  Configuration theta = theta_;
  PerturbParameter(nominal_, k, delta, &*work_, &theta);
  if (k < SensitivityParameter::kMu) work_->SetConfiguration(theta);
}

void SensitivityAnalyzer::Restore(int k) {
  // Theta: every perturbation starts from theta_, so the configuration is
  // restored once, after the last state column (Compute), not per column.
  if (k >= SensitivityParameter::kMu) SetParameter(k, 0.0);
}

SensitivityAnalyzer::Outputs SensitivityAnalyzer::OutputsAt(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  const QuasiStaticProblem& p = *work_;
  Outputs y;
  const Vec12 w = p.JointSpaceVelocity(z);
  y.head<12>() = w;
  const int nm = p.num_motion();
  for (int i = 0; i < 3; ++i) {
    const Vec3 f = p.F0() * z.segment<3>(nm + 3 * i);
    y.segment<3>(12 + 3 * i) = p.chains()[i].R_GCW * Vec3(f(0), f(1), -f(2));
  }
  return y;
}

void SensitivityAnalyzer::LagrangianGradient(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    Eigen::Ref<Eigen::VectorXd> grad) {
  work_->ObjectiveGradient(z, grad);
  work_->ConstraintJacobian(z, jac_);
  grad.noalias() += jac_.transpose() * lambda_;
}

void SensitivityAnalyzer::ParameterDerivatives(int k, Vec* dc, Outputs* dy) {
  const double h = std::cbrt(kEpsMach) * Scale(k);
  const int m = work_->num_constraints();
  SetParameter(k, h);
  const Eigen::Matrix<double, 9, 1> vel_plus =
      work_->ContactLinearVelocities(z_);
  work_->ConstraintsAtVelocities(z_, vel0_, g_);
  Vec g_plus = g_;
  const Outputs y_plus = OutputsAt(z_);
  SetParameter(k, -h);
  const Eigen::Matrix<double, 9, 1> vel_minus =
      work_->ContactLinearVelocities(z_);
  work_->ConstraintsAtVelocities(z_, vel0_, g_);
  const Outputs y_minus = OutputsAt(z_);
  Restore(k);
  const Eigen::Matrix<double, 9, 1> dvel = (vel_plus - vel_minus) / (2 * h);
  dc->resize(m);
  *dc = (g_plus - g_) / (2 * h);
  dc->noalias() += dg_dvel_ * dvel;
  *dy = (y_plus - y_minus) / (2 * h);
}

bool SensitivityAnalyzer::FindActiveSet(const QuasiStaticProblem& problem,
                                        QuasiStaticSensitivities* out) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  out->one_sided = false;
  out->num_one_sided = 0;
  out->min_inequality_slack = kInf;
  auto consider = [&](double slack, int item) {
    out->min_inequality_slack = std::min(out->min_inequality_slack, slack);
    if (slack <= options_.activity_tolerance) {
      out->one_sided = true;
      out->one_sided_items[static_cast<size_t>(out->num_one_sided++)] = item;
    }
  };
  int num_eq = 0;
  for (int i = 0; i < m; ++i) {
    if (g_lb_(i) == g_ub_(i)) {
      ++num_eq;
      continue;
    }
    if (std::isfinite(g_lb_(i))) consider(g_(i) - g_lb_(i), i);
    if (std::isfinite(g_ub_(i))) consider(g_ub_(i) - g_(i), i);
  }
  for (int j = 0; j < n; ++j) {
    if (std::isfinite(x_lb_(j))) consider(z_(j) - x_lb_(j), m + j);
    if (std::isfinite(x_ub_(j))) consider(x_ub_(j) - z_(j), m + j);
  }
  return num_eq == n;
}

void SensitivityAnalyzer::TangentDifference(int k, const Vec& dz, double t,
                                            Vec* d) {
  SetParameter(k, t);
  zt_ = z_ + t * dz;
  LagrangianGradient(zt_, grad_);
  *d = grad_;
  SetParameter(k, -t);
  zt_ = z_ - t * dz;
  LagrangianGradient(zt_, grad_);
  Restore(k);
  *d = (*d - grad_) / (2 * t);
}

SensitivityStatus SensitivityAnalyzer::Compute(
    const QuasiStaticProblem& problem,
    const Eigen::Ref<const Eigen::VectorXd>& z, QuasiStaticSensitivities* out) {
  const int n = problem.num_variables(), m = problem.num_constraints();
  if (z.size() != n || !z.allFinite()) {
    std::ostringstream os;
    os << "SensitivityAnalyzer::Compute: z must be finite of size " << n
       << ", got size " << z.size();
    throw std::invalid_argument(os.str());
  }
  work_.emplace(problem);  // fixed-capacity members: no heap allocation
  jac_.resize(m, n);
  dg_dvel_.resize(m, 9);
  out->num_constraints = m;
  out->num_motion = problem.num_motion();
  nominal_ = problem.parameters();
  theta_ = problem.configuration();
  z_ = z;
  zt_.resize(n);
  g_.resize(m);
  grad_.resize(n);
  x_lb_.resize(n);
  x_ub_.resize(n);
  g_lb_.resize(m);
  g_ub_.resize(m);
  work_->GetBounds(x_lb_, x_ub_, g_lb_, g_ub_);
  work_->Constraints(z_, g_);
  out->status = SensitivityStatus::kNotComputed;
  if (!FindActiveSet(problem, out))
    return out->status = SensitivityStatus::kNotSquare;
  const int ne = problem.num_equalities();  // rows [0, ne) are E
  work_->ConstraintJacobian(z_, jac_);
  jac_eq_ = jac_.topRows(ne);
  lu_.compute(jac_eq_);
  lu_t_.compute(jac_eq_.transpose());  // Eigen 3.3 has no transposed solve
  // Eigen's 1-norm estimate, capped by the pivot ratio of U (the estimate
  // misses an exactly zero pivot, e.g. at z = 0 where dC/ds = 0).
  const auto pivots = lu_.matrixLU().diagonal().cwiseAbs();
  out->rcond = std::min(lu_.rcond(), pivots.minCoeff() / pivots.maxCoeff());
  if (!(out->rcond > options_.singular_rcond))
    return out->status = SensitivityStatus::kSingular;
  // Multipliers: J_E^T l_E = -grad f; inactive inequalities have l = 0.
  work_->ObjectiveGradient(z_, grad_);
  lambda_.setZero(m);
  lambda_.head(ne) = -lu_t_.solve(grad_);
  out->multiplier_values = lambda_;
  work_->ConstraintVelocityJacobian(z_, dg_dvel_);
  vel0_ = work_->ContactLinearVelocities(z_);
  // dy/dz: y is affine in z at fixed p, so columns y(e_j) - y(0) are exact.
  zt_.setZero();
  const Outputs y0 = OutputsAt(zt_);
  dy_dz_.resize(21, n);
  for (int j = 0; j < n; ++j) {
    zt_.setZero();
    zt_(j) = 1.0;
    dy_dz_.col(j) = OutputsAt(zt_) - y0;
  }
  out->multipliers.resize(m, SensitivityParameter::kCount);
  Vec dc, dz, grad_plus, grad_half;
  Outputs dy;
  for (int k = 0; k < SensitivityParameter::kCount; ++k) {
    if (k == SensitivityParameter::kMu) work_->SetConfiguration(theta_);
    ParameterDerivatives(k, &dc, &dy);
    dz = -lu_.solve(dc.head(ne));
    dy.noalias() += dy_dz_ * dz;
    out->twist.col(k) = dy.head<6>();
    out->joint_rates.col(k) = dy.segment<6>(6);
    out->forces.col(k) = dy.tail<9>();
    out->multipliers.col(k).setConstant(
        std::numeric_limits<double>::quiet_NaN());
    if (!options_.multipliers) continue;
    // Multipliers: J_E^T dl_E = -D_t grad_z L along the tangent, Richardson
    // extrapolated from t and t/2 (header).
    const double t = std::cbrt(kEpsMach) * Scale(k);
    TangentDifference(k, dz, t, &grad_plus);
    TangentDifference(k, dz, t / 2, &grad_half);
    grad_plus = (4 * grad_half - grad_plus) / 3;
    out->multipliers.col(k).setZero();
    out->multipliers.col(k).head(ne) = -lu_t_.solve(grad_plus);
  }
  return out->status = SensitivityStatus::kOk;
}

}  // namespace quasiroll
