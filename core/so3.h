// SO(3) helpers (header-only, fixed-size, no allocation).
//   Skew(a) b = a x b,  Vee(Skew(a)) = a,
//   Rx, Ry, Rz: elementary rotations (model.md §0 notation),
//   roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)  (model.md §3).
#pragma once

#include <Eigen/Dense>
#include <cmath>

namespace quasiroll {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;

inline Mat3 Skew(const Vec3& a) {
  Mat3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

inline Vec3 Vee(const Mat3& s) { return Vec3(s(2, 1), s(0, 2), s(1, 0)); }

inline Mat3 Rx(double t) {
  const double c = std::cos(t), s = std::sin(t);
  Mat3 r;
  r << 1, 0, 0, 0, c, -s, 0, s, c;
  return r;
}

inline Mat3 Ry(double t) {
  const double c = std::cos(t), s = std::sin(t);
  Mat3 r;
  r << c, 0, s, 0, 1, 0, -s, 0, c;
  return r;
}

inline Mat3 Rz(double t) {
  const double c = std::cos(t), s = std::sin(t);
  Mat3 r;
  r << c, -s, 0, s, c, 0, 0, 0, 1;
  return r;
}

inline Mat3 RotationFromRpy(double roll, double pitch, double yaw) {
  return Rz(yaw) * Ry(pitch) * Rx(roll);
}

// Inverse of RotationFromRpy for |pitch| < pi/2: returns (roll, pitch, yaw).
inline Vec3 RpyFromRotation(const Mat3& r) {
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return Vec3(roll, pitch, yaw);
}

// Rotation error e_R(Ra, Rb) = vee((Q - Q^T)/2), Q = Ra Rb^T (model.md §6):
// sin(angle) * axis of Q; zero iff Ra = Rb for angles < pi.
inline Vec3 RotationError(const Mat3& ra, const Mat3& rb) {
  const Mat3 q = ra * rb.transpose();
  return 0.5 * Vee(q - q.transpose());
}

}  // namespace quasiroll
