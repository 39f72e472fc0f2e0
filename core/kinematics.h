// Kinematics of the three-wheeled robot on a terrain (model.md §2, §4–§6).
//
// Configuration Theta in R^21 (model.md §2): per chain i = 0, 1, 2 the
// contact coordinates eta_i = (u_w, v_w, x_g, y_g, psi) at 5i..5i+4, then the
// joint angles theta = (phi1, alpha1, delta2, alpha2, delta3, alpha3)
// at 15..20. The platform pose is not a state: each chain gives one by forward
// kinematics from its contact coordinates ("ground side"); H(Theta) = 0 says
// they agree.
//
// Chain i, ground side (model.md §2):
//   R_GCW = R_GCG(x_g, y_g) R_psi,   R_GW = R_GCW R_WCW(u, v)^T,
//   p_W = c_g(x_g, y_g) - R_GW c_w(u, v),
//   R^(i) = R_GW R_PWi(theta_i)^T,   p^(i) = p_W - R^(i) p_PWi(theta_i).
// Wheel mounts in {P} (model.md §1.5), M0 = Rx(-pi/2):
//   T_PW1 = (Rz(phi1) M0 Rz(alpha1), b1),
//   T_PWi = (Rx(delta_i) M0 Rz(alpha_i), b_i + Rx(delta_i) e_i), i = 2, 3,
//   e_i = (0, 0, -camber_offset): wheel centre below the camber axis.
//
// Contact velocity map (model.md §4, replaces the paper's eqs. (8)-(9)):
//   [v; w]_i = L_i [V^B; thetadot],
//   L_i = blkdiag(R_GCW^T, R_GCW^T) [[R, -[p_c - p]x R, a_j x (p_c - o_j)],
//                                    [0,  R,            a_j          ]].
// Montana's contact kinematics, general chart (model.md §5; paper eq. (13)):
//   K = K_w + r_psi K_g r_psi,
//   alphadot_w = A_w^{-1} K^{-1} ((-w_y, w_x) - r_psi K_g r_psi v_t),
//   alphadot_g = A_g^{-1} r_psi K^{-1} ((-w_y, w_x) + K_w v_t),
//   psidot     = w_z + tau_w alphadot_w + tau_g alphadot_g.
// Loop closure (model.md §6; paper eq. (14)):
//   H = [p1 - p2; e_R(R1, R2); p1 - p3; e_R(R1, R3)] in R^12,
// and its exact Jacobian J = dH/dTheta built from the inverse contact map.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/so3.h"
#include "quasiroll/core/surface_forms.h"
#include "quasiroll/core/terrain.h"

namespace quasiroll {

constexpr int kConfigSize = 21;
constexpr int kNumConstraints = 12;
constexpr int kNumJoints = 6;
constexpr int kNumWheels = 3;

using Configuration = Eigen::Matrix<double, kConfigSize, 1>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using LoopClosure = Eigen::Matrix<double, kNumConstraints, 1>;
using LoopClosureJacobian = Eigen::Matrix<double, kNumConstraints, kConfigSize>;
using ContactVelocityMap = Eigen::Matrix<double, 6, 12>;
// dF/dTheta and dF/dw of Theta' = F(Theta, w) (KinematicModel::Rhs).
using RhsStateJacobian = Eigen::Matrix<double, kConfigSize, kConfigSize>;
using RhsTwistJacobian = Eigen::Matrix<double, kConfigSize, 12>;

// Named indices into Theta.
struct ConfigIndex {
  static constexpr int Eta(int chain) { return 5 * chain; }
  static constexpr int U(int chain) { return 5 * chain + 0; }
  static constexpr int V(int chain) { return 5 * chain + 1; }
  static constexpr int Xg(int chain) { return 5 * chain + 2; }
  static constexpr int Yg(int chain) { return 5 * chain + 3; }
  static constexpr int Psi(int chain) { return 5 * chain + 4; }
  static constexpr int kTheta = 15;
  // Joint k (0 = steer/camber, 1 = spin) of chain i, as index into theta.
  static constexpr int Joint(int chain, int k) { return 2 * chain + k; }
  static constexpr int kPhi1 = 15, kAlpha1 = 16, kDelta2 = 17, kAlpha2 = 18,
                       kDelta3 = 19, kAlpha3 = 20;
};

// Everything about chain i at one configuration, in world coordinates.
struct ChainState {
  SurfaceForms wheel;   // torus forms at (u, v), wheel frame
  SurfaceForms ground;  // terrain forms at (x_g, y_g), world frame
  Mat2 r_psi;
  Mat3 R_GCW;                 // wheel contact frame in world
  Mat3 R_GW;                  // wheel frame in world
  Vec3 p_W;                   // wheel centre
  Mat3 R;                     // platform rotation through this chain
  Vec3 p;                     // platform COM through this chain
  Vec3 p_c;                   // contact point
  std::array<Vec3, 2> axis;   // world joint axes (steer/camber, spin)
  std::array<Vec3, 2> point;  // world points on them
};

// Contact-coordinate rates of one chain: (u, v, x_g, y_g, psi) rates.
using EtaRates = Eigen::Matrix<double, 5, 1>;

class KinematicModel {
 public:
  KinematicModel(const RobotGeometry& geometry,
                 std::shared_ptr<const Terrain> terrain);

  const RobotGeometry& geometry() const { return geometry_; }
  const Terrain& terrain() const { return *terrain_; }
  std::shared_ptr<const Terrain> terrain_ptr() const { return terrain_; }

  // Wheel pose in {P} for chain i and its two joint angles, with joint axes
  // and points in {P}.
  void Mount(int chain, double q0, double q1, Mat3* R_PW, Vec3* p_PW,
             std::array<Vec3, 2>* axes, std::array<Vec3, 2>* points) const;

  // Evaluates chain i. The last kCacheWays evaluations of each chain are
  // cached (keyed bitwise on its 7 inputs eta_i, theta_i): integrators
  // evaluate H, J and F at the same state several times, and the simulator
  // returns to an interval's start state (the dense output's slope) after
  // the RK stages and the projection (5-6 states) have been evaluated.
  // Because of this cache a KinematicModel must not be used from several
  // threads at once; use one per thread.
  void EvaluateChain(const Configuration& theta, int chain,
                     ChainState* out) const;
  // The cached evaluation of chain i at theta if there is one (true, *out
  // set, bit for bit EvaluateChain's), else false; never evaluates, so a
  // caller that only needs part of a chain (the limit indicators' curvature
  // at an interval's end, where the projection just evaluated the chains)
  // neither pays for the rest nor evicts the integrator's states.
  bool CachedChain(const Configuration& theta, int chain,
                   ChainState* out) const;

  // Platform pose reported for Theta: chain 1's.
  void PlatformPose(const Configuration& theta, Mat3* R, Vec3* p) const;

  // L_i of model.md §4 (6 x 12; columns of other chains' joints are zero).
  void ContactVelocities(const ChainState& chain_state, int chain,
                         ContactVelocityMap* L) const;
  // L_i w without forming L_i (the right-hand side's kernel): the contact
  // point's world velocity R V + (R W) x (p_c - p) + sum_k qdot_k a_k x
  // (p_c - o_k) and the wheel's world angular velocity R W + sum_k qdot_k
  // a_k, both rotated into {C_W}. Equal to L_i w up to round-off.
  Vec6 ContactTwist(const ChainState& chain_state, int chain,
                    const Vec12& w) const;

  // Montana (model.md §5): relative twist (v, w) in {C_W} -> eta rates.
  // Returns false if K is singular (relative curvature lost).
  bool ContactRates(const ChainState& s, const Vec6& twist,
                    EtaRates* eta_rates) const;

  // Inverse map (model.md §5): eta rates and the chain's joint rates ->
  // platform velocity in world (v_P, w_P) implied by that chain.
  Vec6 PlatformVelocity(const ChainState& s, const EtaRates& eta_rates,
                        double q0_rate, double q1_rate) const;

  // Theta' = F(Theta, w), w = (V^B, thetadot) (model.md §8.1). Returns false
  // if a contact lost relative curvature.
  bool Rhs(const Configuration& theta, const Vec12& w,
           Configuration* theta_dot) const;
  // dF/dTheta at fixed w (model.md §8.9, §7.9), for the implicit
  // integrators' Newton matrix (the simulator's RobotOde::RhsJacobian) and
  // the step derivative's g_Y (StepSensitivity): central differences
  // (core/central_difference_internal.h: the step and why) of one chain's
  // rates per column. eta_i' depends only on chain i's seven inputs (eta_i
  // and its two joint angles) and theta' = w_theta not on Theta at all, so
  // every other entry is exactly zero: 42 chain evaluations instead of 42
  // right-hand sides. Returns false if a contact lost relative curvature at
  // a differenced state (*dfdtheta then partly written).
  bool RhsStateDerivative(const Configuration& theta, const Vec12& w,
                          RhsStateJacobian* dfdtheta) const;
  // dF/dw at theta, exact: F is linear in w (twist L_i w, Montana's rates
  // linear in the twist, theta' = w_theta), so column j is F(theta, e_j):
  // 12 right-hand sides. Returns false as Rhs.
  bool RhsTwistDerivative(const Configuration& theta,
                          RhsTwistJacobian* dfdw) const;

  void Constraints(const Configuration& theta, LoopClosure* h) const;
  void ConstraintJacobian(const Configuration& theta,
                          LoopClosureJacobian* jac) const;

  // Correction weights D of model.md §8.3: 1/rho^2 for u, 1/r^2 for v, 1 for
  // x_g, y_g, 1/rho^2 for psi, 0 for the joints.
  Configuration CorrectionWeights() const;

 private:
  // eta_i' = Montana_i(L_i w) at theta (model.md §8.1): Rhs's rows of
  // chain i. Returns false if K is singular.
  bool ChainRates(const Configuration& theta, int chain, const Vec12& w,
                  EtaRates* rates) const;

  RobotGeometry geometry_;
  std::shared_ptr<const Terrain> terrain_;
  std::array<Vec3, 3> b_;  // joint points b_i in {P}

  struct CacheEntry {
    Eigen::Matrix<double, 7, 1> key;
    ChainState state;
    bool valid = false;
  };
  static constexpr int kCacheWays = 8;
  // Per chain, filled round-robin; cache_next_ is the slot written next.
  mutable std::array<std::array<CacheEntry, kCacheWays>, 3> cache_;
  mutable std::array<int, 3> cache_next_ = {0, 0, 0};
};

}  // namespace quasiroll
