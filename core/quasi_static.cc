#include "quasiroll/core/quasi_static.h"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "quasiroll/core/initial_configuration.h"

namespace quasiroll {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

QuasiStaticParameters QuasiStaticParameters::FromScene(const Scene& scene) {
  QuasiStaticParameters p;
  p.mass = scene.mass;
  p.gravity = scene.gravity;
  p.mu = scene.mu;
  p.epsilon = scene.epsilon;
  p.mode = scene.mode;
  p.joint_rates = scene.joint_rates;
  return p;
}

bool QuasiStaticParameters::IsValid(std::string* why) const {
  auto positive = [&](double v, const char* name) {
    if (std::isfinite(v) && v > 0) return true;
    if (why) {
      std::ostringstream os;
      os << name << ": must be finite and > 0, got " << v;
      *why = os.str();
    }
    return false;
  };
  if (!positive(mass, "mass") || !positive(gravity, "gravity") ||
      !positive(mu, "mu") || !positive(epsilon, "epsilon"))
    return false;
  for (int j = 0; j < 6; ++j) {
    if (!std::isfinite(joint_rates[j])) {
      if (why) *why = "joint_rates[" + std::to_string(j) + "]: must be finite";
      return false;
    }
  }
  return true;
}

bool QuasiStaticOptions::IsValid(std::string* why) const {
  if (!(residual_tolerance > 0 && std::isfinite(residual_tolerance))) {
    if (why) *why = "residual_tolerance: must be finite and > 0";
    return false;
  }
  if (max_iterations < 1) {
    if (why) *why = "max_iterations: must be >= 1";
    return false;
  }
  if (stall_iterations < 0) {
    if (why)
      *why = "stall_iterations: must be >= 0, got " +
             std::to_string(stall_iterations);
    return false;
  }
  return true;
}

const char* ToString(QuasiStaticStatus status) {
  switch (status) {
    case QuasiStaticStatus::kOk:
      return "OK";
    case QuasiStaticStatus::kLiftOff:
      return "LIFT_OFF";
    case QuasiStaticStatus::kInfeasibleFriction:
      return "INFEASIBLE_FRICTION";
    case QuasiStaticStatus::kDegenerateContact:
      return "DEGENERATE_CONTACT";
    case QuasiStaticStatus::kSingular:
      return "SINGULAR";
    case QuasiStaticStatus::kSolverFailure:
      return "SOLVER_FAILURE";
  }
  return "UNKNOWN";
}

QuasiStaticProblem::QuasiStaticProblem(const KinematicModel& model,
                                       const QuasiStaticParameters& params)
    : model_(model), params_(params) {
  std::string why;
  if (!params_.IsValid(&why))
    throw std::invalid_argument("QuasiStaticProblem: " + why);
  if (params_.mode == ActuationMode::kPvc) {
    num_passive_ = 3;
    passive_ = {1, 2, 4};  // alpha1, delta2, delta3
  }
  const RobotGeometry& g = model_.geometry();
  rho_ = g.rho();
  l0_ = g.wheelbase();
  f0_ = params_.mass * params_.gravity;
  double max_rate = 0.0;
  for (double r : params_.joint_rates)
    max_rate = std::max(max_rate, std::abs(r));
  v0_ = std::max(rho_ * max_rate, 0.01);

  const int nm = num_motion();
  w_from_m_.setZero(12, nm);
  w_from_m_.block<3, 3>(0, 0) = v0_ * Mat3::Identity();
  w_from_m_.block<3, 3>(3, 3) = (v0_ / l0_) * Mat3::Identity();
  w_fixed_.setZero();
  for (int j = 0; j < 6; ++j) w_fixed_(6 + j) = params_.joint_rates[j];
  for (int k = 0; k < num_passive_; ++k) {
    w_from_m_(6 + passive_[k], 6 + k) = v0_ / rho_;
    w_fixed_(6 + passive_[k]) = 0.0;
  }
  vel_m_.setZero(9, nm);
  statics_f_.setZero(6 + num_passive_, 9);
  statics_0_.setZero(6 + num_passive_);
}

void QuasiStaticProblem::SetConfiguration(const Configuration& theta) {
  theta_ = theta;
  const int nm = num_motion();
  statics_f_.setZero();
  for (int i = 0; i < 3; ++i) {
    model_.EvaluateChain(theta, i, &chains_[i]);
    model_.ContactVelocities(chains_[i], i, &L_[i]);
    const auto lv = L_[i].topRows<3>();
    vel_m_.block(3 * i, 0, 3, nm).noalias() = lv.lazyProduct(w_from_m_);
    vel_0_.segment<3>(3 * i).noalias() = lv * w_fixed_;
    // f~ = F0 diag(1, 1, -1) fhat; rows scaled by 1/F0 (forces) and
    // 1/(F0 L0) (moments, passive torques).
    for (int c = 0; c < 3; ++c) {
      const double sign = c == 2 ? -1.0 : 1.0;
      for (int r = 0; r < 6; ++r) {
        statics_f_(r, 3 * i + c) = sign * lv(c, r) / (r < 3 ? 1.0 : l0_);
      }
      for (int k = 0; k < num_passive_; ++k) {
        statics_f_(6 + k, 3 * i + c) = sign * lv(c, 6 + passive_[k]) / l0_;
      }
    }
  }
  statics_0_.setZero();
  // R^T m g_vec / F0 = -R^T e_z.
  statics_0_.head<3>() = -chains_[0].R.row(2).transpose();
}

void QuasiStaticProblem::GetBounds(Eigen::Ref<Eigen::VectorXd> x_lb,
                                   Eigen::Ref<Eigen::VectorXd> x_ub,
                                   Eigen::Ref<Eigen::VectorXd> g_lb,
                                   Eigen::Ref<Eigen::VectorXd> g_ub) const {
  x_lb.setConstant(-kInf);
  x_ub.setConstant(kInf);
  const int nm = num_motion();
  for (int i = 0; i < 3; ++i) x_lb(nm + 3 * i + 2) = 0.0;  // I1
  const int ne = num_equalities();
  g_lb.setZero();
  g_ub.setZero();
  g_ub.tail(3).setConstant(kInf);  // I2
  (void)ne;
}

double QuasiStaticProblem::Objective(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  const int nm = num_motion();
  double j = 0.0;
  for (int i = 0; i < 3; ++i) j += z.segment<2>(nm + 3 * i).squaredNorm();
  return 0.5 * j;
}

void QuasiStaticProblem::ObjectiveGradient(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    Eigen::Ref<Eigen::VectorXd> grad) const {
  const int nm = num_motion();
  grad.setZero();
  for (int i = 0; i < 3; ++i)
    grad.segment<2>(nm + 3 * i) = z.segment<2>(nm + 3 * i);
}

// The two small products of every constraint evaluation (the Newton line
// search evaluates the constraints ~10 times per iteration) written out in
// the summation order of Eigen's column-major gemv, which they replace bit
// for bit: per row c = sum over the columns in order of a_ij x_j, starting
// from 0, added to the destination's previous value (0 for an assignment).
Eigen::Matrix<double, 9, 1> QuasiStaticProblem::ContactLinearVelocities(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  const int nm = num_motion();
  double c[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int j = 0; j < nm; ++j) {
    const double zj = z(j);
    for (int i = 0; i < 9; ++i) c[i] += vel_m_(i, j) * zj;
  }
  Eigen::Matrix<double, 9, 1> vel;
  for (int i = 0; i < 9; ++i) vel(i) = vel_0_(i) + c[i];
  return vel;
}

QuasiStaticProblem::ConstraintTerms QuasiStaticProblem::Terms(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    const Eigen::Matrix<double, 9, 1>& vel) const {
  const int nm = num_motion();
  return {nm,
          6 + num_passive_,
          z.segment<9>(nm),
          vel,
          1.0 / v0_,
          params_.mu,
          params_.epsilon * params_.epsilon};
}

Mat2 QuasiStaticProblem::SlipDerivative(const Vec2& s, const Vec2& ft,
                                        double fn, double mu, double eps2) {
  const double sigma = std::sqrt(s.squaredNorm() + eps2);
  return ft * s.transpose() / sigma + mu * fn * Mat2::Identity();
}

void QuasiStaticProblem::Constraints(const Eigen::Ref<const Eigen::VectorXd>& z,
                                     Eigen::Ref<Eigen::VectorXd> g) const {
  ConstraintsAtVelocities(z, ContactLinearVelocities(z), g);
}

void QuasiStaticProblem::ConstraintsAtVelocities(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    const Eigen::Matrix<double, 9, 1>& velocities,
    Eigen::Ref<Eigen::VectorXd> g) const {
  const auto [nm, ns, f, vel, inv_v0, mu, eps2] = Terms(z, velocities);
  for (int i = 0; i < 3; ++i) g(i) = vel(3 * i + 2) * inv_v0;  // E1
  // E2, E3: statics_f_ f (as ContactLinearVelocities) + statics_0_.
  double c[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int j = 0; j < 9; ++j) {
    const double fj = f(j);
    for (int r = 0; r < ns; ++r) c[r] += statics_f_(r, j) * fj;
  }
  for (int r = 0; r < ns; ++r) g(3 + r) = (0.0 + c[r]) + statics_0_(r);
  const int c0 = 3 + ns;
  for (int i = 0; i < 3; ++i) {  // C
    const Vec2 s = vel.segment<2>(3 * i);
    const double sigma = std::sqrt(s.squaredNorm() + eps2);
    g.segment<2>(c0 + 2 * i) =
        (sigma * f.segment<2>(3 * i) + mu * f(3 * i + 2) * s) * inv_v0;
  }
  for (int i = 0; i < 3; ++i) {  // I2
    g(c0 + 6 + i) = mu * mu * f(3 * i + 2) * f(3 * i + 2) -
                    f.segment<2>(3 * i).squaredNorm();
  }
}

void QuasiStaticProblem::ConstraintJacobian(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    Eigen::Ref<Eigen::MatrixXd> jac) const {
  const auto [nm, ns, f, vel, inv_v0, mu, eps2] =
      Terms(z, ContactLinearVelocities(z));
  jac.setZero();
  for (int i = 0; i < 3; ++i)
    jac.row(i).head(nm) = vel_m_.row(3 * i + 2) * inv_v0;
  jac.block(3, nm, ns, 9) = statics_f_;
  const int c0 = 3 + ns;
  for (int i = 0; i < 3; ++i) {
    const Vec2 s = vel.segment<2>(3 * i);
    const Vec2 ft = f.segment<2>(3 * i);
    const double fn = f(3 * i + 2);
    const double sigma = std::sqrt(s.squaredNorm() + eps2);
    const Mat2 dcds = SlipDerivative(s, ft, fn, mu, eps2);
    jac.block(c0 + 2 * i, 0, 2, nm).noalias() =
        inv_v0 * dcds * vel_m_.block(3 * i, 0, 2, nm);
    jac.block<2, 2>(c0 + 2 * i, nm + 3 * i) = sigma * inv_v0 * Mat2::Identity();
    jac.block<2, 1>(c0 + 2 * i, nm + 3 * i + 2) = mu * inv_v0 * s;
    jac.block<1, 2>(c0 + 6 + i, nm + 3 * i) = -2.0 * ft.transpose();
    jac(c0 + 6 + i, nm + 3 * i + 2) = 2.0 * mu * mu * fn;
  }
}

void QuasiStaticProblem::ConstraintVelocityJacobian(
    const Eigen::Ref<const Eigen::VectorXd>& z,
    Eigen::Ref<Eigen::MatrixXd> dg_dvel) const {
  const auto [nm, ns, f, vel, inv_v0, mu, eps2] =
      Terms(z, ContactLinearVelocities(z));
  dg_dvel.setZero();
  const int c0 = 3 + ns;
  for (int i = 0; i < 3; ++i) {
    dg_dvel(i, 3 * i + 2) = inv_v0;  // E1
    dg_dvel.block<2, 2>(c0 + 2 * i, 3 * i) =
        inv_v0 * SlipDerivative(vel.segment<2>(3 * i), f.segment<2>(3 * i),
                                f(3 * i + 2), mu, eps2);
  }
}

void QuasiStaticProblem::set_joint_rates(const std::array<double, 6>& rates) {
  params_.joint_rates = rates;
  for (int j = 0; j < 6; ++j) w_fixed_(6 + j) = rates[j];
  for (int k = 0; k < num_passive_; ++k) w_fixed_(6 + passive_[k]) = 0.0;
  for (int i = 0; i < 3; ++i)
    vel_0_.segment<3>(3 * i).noalias() = L_[i].topRows<3>() * w_fixed_;
}

void QuasiStaticProblem::ColdStartGuess(Eigen::Ref<Eigen::VectorXd> z) const {
  const int nm = num_motion();
  const Eigen::MatrixXd s = statics_f_;
  z.segment<9>(nm) =
      s.completeOrthogonalDecomposition().solve(-Eigen::VectorXd(statics_0_));
  const Eigen::MatrixXd a = vel_m_ / v0_;
  z.head(nm) = a.colPivHouseholderQr().solve(-Eigen::VectorXd(vel_0_ / v0_));
  // Normal forces must start feasible (I1).
  for (int i = 0; i < 3; ++i) {
    double& fn = z(nm + 3 * i + 2);
    fn = std::max(fn, 1e-3);
  }
}

Vec12 QuasiStaticProblem::JointSpaceVelocity(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  Vec12 w = w_fixed_;
  w.noalias() += w_from_m_ * z.head(num_motion());
  return w;
}

double QuasiStaticProblem::EqualityResidual(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxRows, 1> g(num_constraints());
  Constraints(z, g);
  return g.head(num_equalities()).lpNorm<Eigen::Infinity>();
}

double QuasiStaticProblem::ConditionNumber(
    const Eigen::Ref<const Eigen::VectorXd>& z) const {
  Eigen::MatrixXd jac(num_constraints(), num_variables());
  ConstraintJacobian(z, jac);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(jac.topRows(num_equalities()));
  const auto& sv = svd.singularValues();
  return sv(sv.size() - 1) > 0 ? sv(0) / sv(sv.size() - 1) : kInf;
}

bool QuasiStaticProblem::StaticsFullRank() const {
  Eigen::FullPivLU<Eigen::MatrixXd> lu(statics_f_);
  lu.setThreshold(1e-10);
  return lu.rank() == statics_f_.rows();
}

namespace {

// min over y of the smoothed max_i g_i(y), g_i = |T_i f(y)| - t f_n,i(y),
// f(y) = fp + N y (model.md §7.7 feasibility test for mu_min). Returns true
// as soon as a y with max_i g_i(y) <= 0 (exact, unsmoothed) is found: that
// force satisfies every cone |f_t| <= t f_n, a certificate of feasibility.
bool ConesFeasible(const Eigen::Matrix<double, 9, 1>& fp,
                   const Eigen::Matrix<double, 9, 3>& null, double t,
                   Eigen::Vector3d* y) {
  auto exact_max = [&](const Eigen::Vector3d& yy) {
    const Eigen::Matrix<double, 9, 1> f = fp + null * yy;
    double worst = -kInf;
    for (int i = 0; i < 3; ++i)
      worst = std::max(worst, f.segment<2>(3 * i).norm() - t * f(3 * i + 2));
    return worst;
  };
  if (exact_max(*y) <= 0) return true;
  for (double kappa = 10.0; kappa <= 1e10; kappa *= 10.0) {
    const double delta = std::min(1e-3, 1.0 / kappa);
    auto smoothed = [&](const Eigen::Vector3d& yy, Eigen::Vector3d* grad,
                        Eigen::Matrix3d* hess) {
      const Eigen::Matrix<double, 9, 1> f = fp + null * yy;
      double gi[3];
      Eigen::Vector3d dg[3];
      Eigen::Matrix3d hg[3];
      for (int i = 0; i < 3; ++i) {
        const Vec2 a = f.segment<2>(3 * i);
        const Eigen::Matrix<double, 2, 3> am = null.middleRows<2>(3 * i);
        const Eigen::RowVector3d cn = null.row(3 * i + 2);
        const double q = std::sqrt(a.squaredNorm() + delta * delta);
        gi[i] = q - t * f(3 * i + 2);
        dg[i] = am.transpose() * a / q - t * cn.transpose();
        if (hess)
          hg[i] = am.transpose() *
                  (Mat2::Identity() - a * a.transpose() / (q * q)) * am / q;
      }
      const double gmax = std::max({gi[0], gi[1], gi[2]});
      double sum = 0.0, p[3];
      for (int i = 0; i < 3; ++i)
        sum += p[i] = std::exp(kappa * (gi[i] - gmax));
      for (double& pi : p) pi /= sum;
      if (grad) {
        *grad = p[0] * dg[0] + p[1] * dg[1] + p[2] * dg[2];
        if (hess) {
          hess->setZero();
          for (int i = 0; i < 3; ++i)
            *hess += p[i] * (hg[i] + kappa * dg[i] * dg[i].transpose());
          *hess -= kappa * (*grad) * grad->transpose();
        }
      }
      return gmax + std::log(sum) / kappa;
    };
    for (int it = 0; it < 60; ++it) {
      Eigen::Vector3d grad;
      Eigen::Matrix3d hess;
      const double phi = smoothed(*y, &grad, &hess);
      if (grad.norm() < 1e-14) break;
      Eigen::LDLT<Eigen::Matrix3d> ldlt(hess +
                                        1e-14 * Eigen::Matrix3d::Identity());
      Eigen::Vector3d step = -ldlt.solve(grad);
      if (!step.allFinite() || grad.dot(step) >= 0) step = -grad;
      double alpha = 1.0;
      bool moved = false;
      for (int ls = 0; ls < 50; ++ls, alpha *= 0.5) {
        const Eigen::Vector3d trial = *y + alpha * step;
        if (smoothed(trial, nullptr, nullptr) <=
            phi + 1e-4 * alpha * grad.dot(step)) {
          *y = trial;
          moved = true;
          break;
        }
      }
      if (exact_max(*y) <= 0) return true;
      if (!moved) break;
    }
  }
  return exact_max(*y) <= 0;
}

}  // namespace

double QuasiStaticProblem::MinimumFriction(int* critical,
                                           double* min_normal_force,
                                           double relative_tolerance) const {
  auto ratio_of = [&](const Eigen::Matrix<double, 9, 1>& f, int* arg) {
    double worst = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double r = f.segment<2>(3 * i).norm() / f(3 * i + 2);
      if (r > worst || *arg < 0) {
        worst = r;
        *arg = i;
      }
    }
    return worst;
  };
  int arg = -1;
  if (num_passive_ == 3) {
    // pvc: statically determinate, f* = -S^{-1} s_b.
    Eigen::FullPivLU<Eigen::MatrixXd> lu(statics_f_);
    if (!lu.isInvertible()) {
      if (critical) *critical = -1;
      return kNaN;
    }
    const Eigen::Matrix<double, 9, 1> f =
        lu.solve(-Eigen::VectorXd(statics_0_));
    double fn_min = kInf;
    int fn_arg = 0;
    for (int i = 0; i < 3; ++i) {
      if (f(3 * i + 2) < fn_min) {
        fn_min = f(3 * i + 2);
        fn_arg = i;
      }
    }
    if (min_normal_force) *min_normal_force = fn_min * f0_;
    if (fn_min <= 0) {
      if (critical) *critical = fn_arg;
      return kInf;
    }
    const double r = ratio_of(f, &arg);
    if (critical) *critical = arg;
    return r;
  }
  // paper: f = fp + N y with S fp = -s_b, S N = 0.
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 9>> svd(
      Eigen::Matrix<double, 6, 9>(statics_f_),
      Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> fp =
      svd.solve(Eigen::Matrix<double, 6, 1>(-statics_0_));
  const Eigen::Matrix<double, 9, 3> null = svd.matrixV().rightCols<3>();
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  const double t_max = 1e6;
  if (!ConesFeasible(fp, null, t_max, &y)) {
    // No admissible force even with (practically) unlimited friction.
    const Eigen::Matrix<double, 9, 1> f = fp + null * y;
    int fn_arg = 0;
    for (int i = 1; i < 3; ++i)
      if (f(3 * i + 2) < f(3 * fn_arg + 2)) fn_arg = i;
    if (critical) *critical = fn_arg;
    if (min_normal_force) *min_normal_force = f(3 * fn_arg + 2) * f0_;
    return kInf;
  }
  Eigen::Matrix<double, 9, 1> best = fp + null * y;
  double hi = ratio_of(best, &arg), lo = 0.0;
  Eigen::Vector3d y_try = y;
  while (hi - lo > relative_tolerance * std::max(1.0, hi)) {
    const double mid = 0.5 * (lo + hi);
    y_try = y;
    if (ConesFeasible(fp, null, mid, &y_try)) {
      y = y_try;
      best = fp + null * y;
      int a = -1;
      hi = std::min(mid, ratio_of(best, &a));
    } else {
      lo = mid;
    }
  }
  arg = -1;
  ratio_of(best, &arg);
  if (critical) *critical = arg;
  if (min_normal_force)
    *min_normal_force = f0_ * std::min({best(2), best(5), best(8)});
  return hi;
}

// ---------------------------------------------------------------------------

QuasiStaticSolver::QuasiStaticSolver(const KinematicModel& model,
                                     const QuasiStaticParameters& params,
                                     std::unique_ptr<NlpSolver> nlp,
                                     const QuasiStaticOptions& options)
    : model_(model),
      problem_(model, params),
      nlp_(std::move(nlp)),
      options_(options) {
  if (!nlp_) throw std::invalid_argument("QuasiStaticSolver: null NLP solver");
  std::string why;
  if (!options_.IsValid(&why))
    throw std::invalid_argument("QuasiStaticSolver: " + why);
  nlp_options_.feasibility_tolerance = options_.residual_tolerance;
  nlp_options_.optimality_tolerance = 1e-10;
  nlp_options_.max_iterations = options_.max_iterations;
  warm_z_.setZero(problem_.num_variables());
  z0_.setZero(problem_.num_variables());
  z_homotopy_.setZero(problem_.num_variables());
}

bool QuasiStaticSolver::TrySolve(const Eigen::VectorXd& z0,
                                 QuasiStaticSolution* out) {
  const NlpStatus status = nlp_->Solve(problem_, z0, nlp_options_, &result_);
  out->nlp_status = status;
  out->nlp_iterations += result_.iterations;
  out->nlp_iterations_native += result_.native_iterations;
  out->nlp_solves += 1;
  stalled_ = stalled_ || result_.stalled;
  if (!result_.x.allFinite()) return false;
  out->residual = problem_.EqualityResidual(result_.x);
  const int nm = problem_.num_motion();
  for (int i = 0; i < 3; ++i)
    if (!(result_.x(nm + 3 * i + 2) >= 0)) return false;
  return status == NlpStatus::kConverged &&
         out->residual <= options_.residual_tolerance;
}

QuasiStaticStatus QuasiStaticSolver::Solve(const Configuration& theta,
                                           QuasiStaticSolution* out) {
  const auto start = std::chrono::steady_clock::now();
  out->nlp_iterations = 0;
  out->nlp_iterations_native = 0;
  out->nlp_solves = 0;
  out->message.clear();
  out->mu_min = kNaN;
  out->kkt_residual = kNaN;
  out->condition_number = kNaN;
  out->critical_contact = -1;
  if (!theta.allFinite())
    throw std::invalid_argument(
        "QuasiStaticSolver::Solve: non-finite configuration");
  problem_.SetConfiguration(theta);

  const ValidityReport validity = CheckValidity(model_, theta, false);
  bool ok = false;
  if (!validity.ok()) {
    out->status = QuasiStaticStatus::kDegenerateContact;
    out->message = validity.Describe();
    for (int i = 0; i < 3; ++i)
      if (validity.contact[i] != ContactValidity::kValid) {
        out->critical_contact = i;
        break;
      }
  } else {
    if (have_warm_ && have_previous_ && options_.extrapolate_warm_start) {
      z0_ = 2.0 * warm_z_ - previous_z_;  // linear predictor along the path
      const int nm = problem_.num_motion();
      for (int i = 0; i < 3; ++i)
        z0_(nm + 3 * i + 2) = std::max(z0_(nm + 3 * i + 2), 0.0);
    } else if (have_warm_) {
      z0_ = warm_z_;
    } else {
      problem_.ColdStartGuess(z0_);
    }
    // result_ still holds the previous solve's multipliers: backends that use
    // them (Ipopt) start from the previous primal-dual point.
    nlp_options_.warm_start_multipliers =
        have_warm_ && options_.warm_start_multipliers;
    stalled_ = false;
    nlp_options_.stall_iterations = options_.stall_iterations;
    ok = TrySolve(z0_, out);
    nlp_options_.warm_start_multipliers = false;
    if (!ok && options_.homotopy) ok = HomotopyAndColdStart(out);
    if (!ok && stalled_) {
      // The same attempts without the stall watch: a stalled Newton can
      // still converge where the homotopy does not (paper scene, a probe at
      // t = 2.907 s, 4 ms after wheel 1 starts to slide).
      nlp_options_.stall_iterations = 0;
      ok = TrySolve(z0_, out);
      if (!ok && options_.homotopy) ok = HomotopyAndColdStart(out);
    }
    if (ok) {
      out->status = QuasiStaticStatus::kOk;
      out->z = result_.x;
      out->kkt_residual = result_.kkt_residual;
      if (have_warm_) {
        previous_z_ = warm_z_;
        have_previous_ = true;
      }
      warm_z_ = result_.x;
      have_warm_ = true;
      FillOutputs(out);
      if (options_.diagnostics) {
        out->mu_min = problem_.MinimumFriction(nullptr, &out->min_normal_force);
        out->condition_number = problem_.ConditionNumber(out->z);
      }
    } else if (options_.classify_failures) {
      Classify(out);
    } else {
      out->z = result_.x;
      out->status = QuasiStaticStatus::kSolverFailure;
      out->message = "unclassified";  // short: no allocation (SSO)
    }
  }
  out->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return out->status;
}

bool QuasiStaticSolver::Refine(double tolerance, QuasiStaticSolution* out) {
  if (out->status != QuasiStaticStatus::kOk ||
      !(tolerance < options_.residual_tolerance))
    return false;
  const double saved = options_.residual_tolerance;
  const NlpStatus nlp_status = out->nlp_status;
  const double residual = out->residual;
  options_.residual_tolerance = tolerance;
  nlp_options_.feasibility_tolerance = tolerance;
  z0_ = out->z;
  const bool ok = TrySolve(z0_, out);
  options_.residual_tolerance = saved;
  nlp_options_.feasibility_tolerance = saved;
  if (!ok) {
    out->nlp_status = nlp_status;
    out->residual = residual;
    return false;
  }
  out->z = result_.x;
  out->kkt_residual = result_.kkt_residual;
  warm_z_ = result_.x;
  FillOutputs(out);
  return true;
}

bool QuasiStaticSolver::HomotopyAndColdStart(QuasiStaticSolution* out) {
  // Epsilon homotopy from a well-conditioned creep law down to epsilon.
  const double eps = problem_.parameters().epsilon;
  problem_.ColdStartGuess(z_homotopy_);
  for (double e = problem_.v0() * 1e-2; e > eps; e *= 0.1) {
    problem_.set_epsilon(e);
    if (TrySolve(z_homotopy_, out)) z_homotopy_ = result_.x;
  }
  problem_.set_epsilon(eps);
  if (TrySolve(z_homotopy_, out)) return true;
  problem_.ColdStartGuess(z_homotopy_);
  return TrySolve(z_homotopy_, out);
}

void QuasiStaticSolver::Classify(QuasiStaticSolution* out) {
  out->z = result_.x;
  if (!problem_.StaticsFullRank()) {
    out->status = QuasiStaticStatus::kSingular;
    out->message = "statics rows (E2, E3) are rank deficient";
    return;
  }
  int critical = -1;
  double fn_min = kNaN;
  const double mu_min = problem_.MinimumFriction(&critical, &fn_min);
  out->mu_min = mu_min;
  out->critical_contact = critical;
  out->min_normal_force = fn_min;
  std::ostringstream os;
  const double mu = problem_.parameters().mu;
  if (std::isnan(mu_min)) {
    out->status = QuasiStaticStatus::kSingular;
    os << "statics matrix is singular";
  } else if (std::isinf(mu_min)) {
    out->status = QuasiStaticStatus::kLiftOff;
    os << "no contact forces with f_n >= 0 balance the load; wheel "
       << critical + 1 << " would have to pull (min normal force " << fn_min
       << " N)";
  } else if (mu <= mu_min) {
    out->status = QuasiStaticStatus::kInfeasibleFriction;
    os << "mu = " << mu << " <= mu_min = " << mu_min << " (wheel "
       << critical + 1 << " saturates)";
  } else {
    out->status = QuasiStaticStatus::kSolverFailure;
    os << "no converged solution (NLP " << ToString(out->nlp_status)
       << ", scaled residual " << out->residual << ") although mu = " << mu
       << " > mu_min = " << mu_min;
  }
  out->message = os.str();
}

void QuasiStaticSolver::FillOutputs(QuasiStaticSolution* out) const {
  const QuasiStaticProblem& p = problem_;
  const Eigen::VectorXd& z = out->z;
  const Vec12 w = p.JointSpaceVelocity(z);
  out->twist = w.head<6>();
  for (int j = 0; j < 6; ++j) out->joint_rates[j] = w(6 + j);
  const double mu = p.parameters().mu;
  const int nm = p.num_motion();
  double gap = 0.0;
  std::array<Vec3, 3> forces;
  for (int i = 0; i < 3; ++i) {
    const ChainState& s = p.chains()[i];
    ContactVelocityMap L;
    model_.ContactVelocities(s, i, &L);
    const Vec3 vel = L.topRows<3>() * w;
    const Vec3 f = p.F0() * z.segment<3>(nm + 3 * i);
    const Vec3 force = s.R_GCW * Vec3(f(0), f(1), -f(2));
    forces[i] = force;
    const Vec3 n = s.ground.frame.col(2);
    const Vec3 lon = s.axis[1].cross(n).normalized();
    ContactOutput& c = out->contacts[i];
    c.point = s.p_c;
    c.normal_force = force.dot(n);
    c.traction = Vec2(force.dot(lon), force.dot(n.cross(lon)));
    c.force_world = force;
    c.slip = vel.head<2>();
    c.normal_velocity = vel(2);
    c.friction_use = f.head<2>().norm() / (mu * f(2));
    gap += c.slip.dot(f.head<2>()) + mu * f(2) * c.slip.norm();
  }
  out->gap = gap;
  // Actuator torque = -(torque of the contact force about the joint axis).
  for (int j = 0; j < 6; ++j) {
    bool passive = false;
    for (int k = 0; k < p.num_passive(); ++k)
      passive |= p.passive_joints()[k] == j;
    if (passive) {
      out->actuator_torques[j] = kNaN;
      continue;
    }
    const ChainState& s = p.chains()[j / 2];
    const int k = j % 2;
    out->actuator_torques[j] =
        -s.axis[k].dot((s.p_c - s.point[k]).cross(forces[j / 2]));
  }
}

}  // namespace quasiroll
