// Contact geometry of the two surfaces in contact: the torus wheel and the
// terrain graph z = h(x, y), with the general-chart forms of model.md §1.2/§1.4
// (model.md §1.2, §1.3; Montana 1988 generalised to non-orthogonal charts):
//
//   metric       A   = E^T Dc                     (E = [x y], Dc = [c_u c_v])
//   curvature    K   = E^T Dn A^{-1} = -A^{-T} II A^{-1},  II_jk = c_jk . n
//   connection   tau = y^T Dx                     (1 x 2)
//
// Torus (major radius R, tube r, chart (u, v), v = 0 on the tread crown):
//   c_w = ((R + r cos v) cos u, (R + r cos v) sin u, r sin v),
//   A_w = diag(R + r cos v, r), K_w = diag(cos v/(R + r cos v), 1/r),
//   tau_w = [sin v, 0].
// Terrain, graph chart c_g = (x, y, h), w = sqrt(1 + hx^2 + hy^2),
// l = sqrt(1 + hx^2):
//   n_g = (-hx, -hy, 1)/w,  x_g = (1, 0, hx)/l,  y_g = n_g x x_g,
//   A_g = [[l, hx hy/l], [0, w/l]],  II_g = Hess(h)/w,
//   tau_g = hy/(w l^2) [hxx, hxy].
#pragma once

#include <Eigen/Core>

#include "quasiroll/core/so3.h"
#include "quasiroll/core/terrain.h"

namespace quasiroll {

struct SurfaceForms {
  Vec3 point;  // c(u, v) in the surface's own frame (world for the terrain)
  Mat3 frame;  // columns x, y, n (orthonormal, right-handed)
  Mat2 A;      // metric form
  Mat2 K;      // curvature form (symmetric)
  Eigen::RowVector2d tau;  // connection form
};

// The torus's principal curvatures at tube angle v (cos_v = cos v), the
// diagonal of TorusForms().K: along the rolling circle and around the tube.
inline Vec2 TorusCurvatures(double major_radius, double tube_radius,
                            double cos_v) {
  return Vec2(cos_v / (major_radius + tube_radius * cos_v), 1.0 / tube_radius);
}

SurfaceForms TorusForms(double major_radius, double tube_radius, double u,
                        double v);

SurfaceForms TerrainForms(const TerrainJet& jet, double x, double y);

// Montana's contact-frame rotation R_{C_G,C_W} (model.md §1.6) and its 2x2
// tangent block r_psi (symmetric and its own inverse).
inline Mat3 ContactRotation(double psi) {
  const double c = std::cos(psi), s = std::sin(psi);
  Mat3 r;
  r << c, -s, 0, -s, -c, 0, 0, 0, -1;
  return r;
}

inline Mat2 ContactRotation2(double psi) {
  const double c = std::cos(psi), s = std::sin(psi);
  Mat2 r;
  r << c, -s, -s, -c;
  return r;
}

}  // namespace quasiroll
