#include "quasiroll/core/kinematics.h"

#include <cstring>
#include <stdexcept>

#include "quasiroll/core/central_difference_internal.h"

namespace quasiroll {

namespace {
const Mat3& M0() {
  static const Mat3 m0 = Rx(-M_PI / 2);
  return m0;
}
}  // namespace

KinematicModel::KinematicModel(const RobotGeometry& geometry,
                               std::shared_ptr<const Terrain> terrain)
    : geometry_(geometry), terrain_(std::move(terrain)) {
  if (!terrain_) throw std::invalid_argument("KinematicModel: null terrain");
  if (!(geometry_.tube_radius > 0 &&
        geometry_.major_radius > geometry_.tube_radius))
    throw std::invalid_argument(
        "KinematicModel: need 0 < tube_radius < major_radius");
  const double zh = geometry_.z_h;
  b_[0] = Vec3(geometry_.a, 0.0, -zh);
  b_[1] = Vec3(-geometry_.b, geometry_.track / 2, -zh);
  b_[2] = Vec3(-geometry_.b, -geometry_.track / 2, -zh);
}

void KinematicModel::Mount(int chain, double q0, double q1, Mat3* R_PW,
                           Vec3* p_PW, std::array<Vec3, 2>* axes,
                           std::array<Vec3, 2>* points) const {
  if (chain == 0) {
    const Mat3 steer = Rz(q0);
    *R_PW = steer * M0() * Rz(q1);
    *p_PW = b_[0];
    (*axes)[0] = Vec3::UnitZ();
    (*axes)[1] = steer.col(1);
    (*points)[0] = b_[0];
    (*points)[1] = b_[0];
  } else {
    const Mat3 camber = Rx(q0);
    *R_PW = camber * M0() * Rz(q1);
    *p_PW = b_[chain] + camber * Vec3(0.0, 0.0, -geometry_.camber_offset);
    (*axes)[0] = Vec3::UnitX();
    (*axes)[1] = camber.col(1);
    (*points)[0] = b_[chain];
    (*points)[1] = *p_PW;
  }
}

namespace {
Eigen::Matrix<double, 7, 1> ChainKey(const Configuration& theta, int chain) {
  Eigen::Matrix<double, 7, 1> key;
  key << theta.segment<5>(ConfigIndex::Eta(chain)),
      theta.segment<2>(ConfigIndex::kTheta + 2 * chain);
  return key;
}
}  // namespace

bool KinematicModel::CachedChain(const Configuration& theta, int chain,
                                 ChainState* s) const {
  const std::array<CacheEntry, kCacheWays>& ways = cache_[chain];
  const int next = cache_next_[chain];
  const Eigen::Matrix<double, 7, 1> key = ChainKey(theta, chain);
  // Bitwise comparison: NaNs never hit, -0.0 vs 0.0 only costs a recompute.
  // Most recent first.
  for (int w = 1; w <= kCacheWays; ++w) {
    const CacheEntry& entry = ways[(next + kCacheWays - w) % kCacheWays];
    if (entry.valid &&
        std::memcmp(key.data(), entry.key.data(), sizeof(double) * 7) == 0) {
      *s = entry.state;
      return true;
    }
  }
  return false;
}

void KinematicModel::EvaluateChain(const Configuration& theta, int chain,
                                   ChainState* s) const {
  if (CachedChain(theta, chain, s)) return;
  const int e = ConfigIndex::Eta(chain);
  const int j = ConfigIndex::kTheta + 2 * chain;
  std::array<CacheEntry, kCacheWays>& ways = cache_[chain];
  int& next = cache_next_[chain];
  const Eigen::Matrix<double, 7, 1> key = ChainKey(theta, chain);
  CacheEntry& entry = ways[next];
  next = (next + 1) % kCacheWays;
  const double u = theta(e), v = theta(e + 1), xg = theta(e + 2),
               yg = theta(e + 3), psi = theta(e + 4);
  s->wheel = TorusForms(geometry_.major_radius, geometry_.tube_radius, u, v);
  s->ground = TerrainForms(terrain_->EvaluateSecondOrder(xg, yg), xg, yg);
  s->r_psi = ContactRotation2(psi);
  s->R_GCW = s->ground.frame * ContactRotation(psi);
  s->R_GW = s->R_GCW * s->wheel.frame.transpose();
  s->p_W = s->ground.point - s->R_GW * s->wheel.point;
  Mat3 R_PW;
  Vec3 p_PW;
  std::array<Vec3, 2> axes, points;
  Mount(chain, theta(j), theta(j + 1), &R_PW, &p_PW, &axes, &points);
  s->R = s->R_GW * R_PW.transpose();
  s->p = s->p_W - s->R * p_PW;
  s->p_c = s->ground.point;
  for (int k = 0; k < 2; ++k) {
    s->axis[k] = s->R * axes[k];
    s->point[k] = s->p + s->R * points[k];
  }
  entry.key = key;
  entry.state = *s;
  entry.valid = true;
}

void KinematicModel::PlatformPose(const Configuration& theta, Mat3* R,
                                  Vec3* p) const {
  ChainState s;
  EvaluateChain(theta, 0, &s);
  *R = s.R;
  *p = s.p;
}

void KinematicModel::ContactVelocities(const ChainState& s, int chain,
                                       ContactVelocityMap* L) const {
  // World-frame map first, then rotate both halves into {C_W}. Only the
  // 8 columns of the platform and of this chain's joints are non-zero; each
  // column of a product is computed on its own, so rotating those 8 gives
  // the 6 x 12 product's values.
  Eigen::Matrix<double, 6, 8> m = Eigen::Matrix<double, 6, 8>::Zero();
  m.block<3, 3>(0, 0) = s.R;
  m.block<3, 3>(0, 3) = -Skew(s.p_c - s.p) * s.R;
  m.block<3, 3>(3, 3) = s.R;
  for (int k = 0; k < 2; ++k) {
    m.block<3, 1>(0, 6 + k) = s.axis[k].cross(s.p_c - s.point[k]);
    m.block<3, 1>(3, 6 + k) = s.axis[k];
  }
  Eigen::Matrix<double, 6, 8> rotated;
  rotated.topRows<3>().noalias() = s.R_GCW.transpose() * m.topRows<3>();
  rotated.bottomRows<3>().noalias() = s.R_GCW.transpose() * m.bottomRows<3>();
  L->setZero();
  L->leftCols<6>() = rotated.leftCols<6>();
  L->middleCols<2>(6 + 2 * chain) = rotated.rightCols<2>();
}

Vec6 KinematicModel::ContactTwist(const ChainState& s, int chain,
                                  const Vec12& w) const {
  const double q0 = w(6 + 2 * chain), q1 = w(7 + 2 * chain);
  const Vec3 w_platform = s.R * w.segment<3>(3);
  const Vec3 v_world = s.R * w.head<3>() + w_platform.cross(s.p_c - s.p) +
                       q0 * s.axis[0].cross(s.p_c - s.point[0]) +
                       q1 * s.axis[1].cross(s.p_c - s.point[1]);
  const Vec3 w_world = w_platform + q0 * s.axis[0] + q1 * s.axis[1];
  Vec6 twist;
  twist.head<3>().noalias() = s.R_GCW.transpose() * v_world;
  twist.tail<3>().noalias() = s.R_GCW.transpose() * w_world;
  return twist;
}

bool KinematicModel::ContactRates(const ChainState& s, const Vec6& twist,
                                  EtaRates* eta_rates) const {
  const Vec2 vt = twist.head<2>();
  const Vec2 q(-twist(4), twist(3));  // (-w_y, w_x)
  const Mat2 kg = s.r_psi * s.ground.K * s.r_psi;
  const Mat2 k = s.wheel.K + kg;
  const double det = k.determinant();
  if (!(std::abs(det) > 1e-12 * k.squaredNorm()) || !std::isfinite(det))
    return false;
  const Mat2 k_inv = k.inverse();
  const Vec2 aw_rate = s.wheel.A.inverse() * (k_inv * (q - kg * vt));
  const Vec2 ag_rate =
      s.ground.A.inverse() * (s.r_psi * (k_inv * (q + s.wheel.K * vt)));
  eta_rates->head<2>() = aw_rate;
  eta_rates->segment<2>(2) = ag_rate;
  (*eta_rates)(4) =
      twist(5) + s.wheel.tau.dot(aw_rate) + s.ground.tau.dot(ag_rate);
  return true;
}

Vec6 KinematicModel::PlatformVelocity(const ChainState& s,
                                      const EtaRates& eta_rates, double q0_rate,
                                      double q1_rate) const {
  const Vec2 aw_rate = eta_rates.head<2>();
  const Vec2 ag_rate = eta_rates.segment<2>(2);
  const Vec2 a_w = s.wheel.A * aw_rate;
  const Vec2 b = s.r_psi * (s.ground.A * ag_rate);
  const Vec2 vt = b - a_w;
  const Mat2 kg = s.r_psi * s.ground.K * s.r_psi;
  const Vec2 wy_minus_wx = -(s.wheel.K * a_w + kg * b);  // (w_y, -w_x)
  const double wz =
      eta_rates(4) - s.wheel.tau.dot(aw_rate) - s.ground.tau.dot(ag_rate);
  const Vec3 w_wheel = s.R_GCW * Vec3(-wy_minus_wx(1), wy_minus_wx(0), wz);
  const Vec3 v_c = s.R_GCW * Vec3(vt(0), vt(1), 0.0);
  const Vec3 w_p = w_wheel - q0_rate * s.axis[0] - q1_rate * s.axis[1];
  const Vec3 v_p = v_c - w_p.cross(s.p_c - s.p) -
                   q0_rate * s.axis[0].cross(s.p_c - s.point[0]) -
                   q1_rate * s.axis[1].cross(s.p_c - s.point[1]);
  Vec6 out;
  out << v_p, w_p;
  return out;
}

bool KinematicModel::ChainRates(const Configuration& theta, int chain,
                                const Vec12& w, EtaRates* rates) const {
  ChainState s;
  EvaluateChain(theta, chain, &s);
  return ContactRates(s, ContactTwist(s, chain, w), rates);
}

bool KinematicModel::Rhs(const Configuration& theta, const Vec12& w,
                         Configuration* theta_dot) const {
  for (int i = 0; i < kNumWheels; ++i) {
    EtaRates rates;
    if (!ChainRates(theta, i, w, &rates)) return false;
    theta_dot->segment<5>(ConfigIndex::Eta(i)) = rates;
  }
  theta_dot->tail<6>() = w.tail<6>();
  return true;
}

bool KinematicModel::RhsStateDerivative(const Configuration& theta,
                                        const Vec12& w,
                                        RhsStateJacobian* dfdtheta) const {
  dfdtheta->setZero();
  for (int i = 0; i < kNumWheels; ++i) {
    const int e = ConfigIndex::Eta(i), j = ConfigIndex::kTheta + 2 * i;
    const int columns[7] = {e, e + 1, e + 2, e + 3, e + 4, j, j + 1};
    const auto rates = [this, i, &w](const Configuration& at, EtaRates* r) {
      return ChainRates(at, i, w, r);
    };
    for (int k : columns) {
      EtaRates column;
      if (!internal::CentralDifference(theta, k, rates, &column)) return false;
      dfdtheta->block<5, 1>(e, k) = column;
    }
  }
  return true;
}

bool KinematicModel::RhsTwistDerivative(const Configuration& theta,
                                        RhsTwistJacobian* dfdw) const {
  Configuration column;
  for (int j = 0; j < 12; ++j) {
    if (!Rhs(theta, Vec12::Unit(j), &column)) return false;
    dfdw->col(j) = column;
  }
  return true;
}

void KinematicModel::Constraints(const Configuration& theta,
                                 LoopClosure* h) const {
  std::array<ChainState, 3> s;
  for (int i = 0; i < 3; ++i) EvaluateChain(theta, i, &s[i]);
  for (int k = 1; k < 3; ++k) {
    const int row = 6 * (k - 1);
    h->segment<3>(row) = s[0].p - s[k].p;
    h->segment<3>(row + 3) = RotationError(s[0].R, s[k].R);
  }
}

void KinematicModel::ConstraintJacobian(const Configuration& theta,
                                        LoopClosureJacobian* jac) const {
  // G_i: 6 x 7 map (eta_i rates, joint rates of chain i) -> (v_P, w_P).
  std::array<ChainState, 3> s;
  std::array<Eigen::Matrix<double, 6, 7>, 3> g;
  for (int i = 0; i < 3; ++i) {
    EvaluateChain(theta, i, &s[i]);
    for (int c = 0; c < 5; ++c) {
      g[i].col(c) = PlatformVelocity(s[i], EtaRates::Unit(c), 0.0, 0.0);
    }
    g[i].col(5) = PlatformVelocity(s[i], EtaRates::Zero(), 1.0, 0.0);
    g[i].col(6) = PlatformVelocity(s[i], EtaRates::Zero(), 0.0, 1.0);
  }
  jac->setZero();
  for (int k = 1; k < 3; ++k) {
    const int row = 6 * (k - 1);
    // d/dt vee(skew(Q)) with Q = R0 Rk^T, Qdot = [w0]x Q - Q [wk]x.
    const Mat3 q = s[0].R * s[k].R.transpose();
    Mat3 m_a, m_b;
    for (int j = 0; j < 3; ++j) {
      const Mat3 e = Skew(Vec3::Unit(j));
      const Mat3 qa = e * q;
      const Mat3 qb = -q * e;
      m_a.col(j) = 0.5 * Vee(qa - qa.transpose());
      m_b.col(j) = 0.5 * Vee(qb - qb.transpose());
    }
    for (int side = 0; side < 2; ++side) {
      const int chain = side == 0 ? 0 : k;
      const double sign = side == 0 ? 1.0 : -1.0;
      const Mat3& m_rot = side == 0 ? m_a : m_b;
      Eigen::Matrix<double, 6, 7> block;
      block.topRows<3>() = sign * g[chain].topRows<3>();
      block.bottomRows<3>() = m_rot * g[chain].bottomRows<3>();
      jac->block<6, 5>(row, ConfigIndex::Eta(chain)) = block.leftCols<5>();
      jac->block<6, 2>(row, ConfigIndex::kTheta + 2 * chain) =
          block.rightCols<2>();
    }
  }
}

Configuration KinematicModel::CorrectionWeights() const {
  Configuration d = Configuration::Zero();
  const double rho = geometry_.rho(), r = geometry_.tube_radius;
  for (int i = 0; i < 3; ++i) {
    d(ConfigIndex::U(i)) = 1.0 / (rho * rho);
    d(ConfigIndex::V(i)) = 1.0 / (r * r);
    d(ConfigIndex::Xg(i)) = 1.0;
    d(ConfigIndex::Yg(i)) = 1.0;
    d(ConfigIndex::Psi(i)) = 1.0 / (rho * rho);
  }
  return d;
}

}  // namespace quasiroll
