#include "quasiroll/core/surface_forms.h"

#include <cmath>

namespace quasiroll {

SurfaceForms TorusForms(double major_radius, double tube_radius, double u,
                        double v) {
  const double su = std::sin(u), cu = std::cos(u);
  const double sv = std::sin(v), cv = std::cos(v);
  const double rho = major_radius + tube_radius * cv;
  SurfaceForms f;
  f.point = Vec3(rho * cu, rho * su, tube_radius * sv);
  f.frame.col(0) = Vec3(-su, cu, 0.0);
  f.frame.col(1) = Vec3(-sv * cu, -sv * su, cv);
  f.frame.col(2) = Vec3(cv * cu, cv * su, sv);
  f.A << rho, 0.0, 0.0, tube_radius;
  f.K = TorusCurvatures(major_radius, tube_radius, cv).asDiagonal();
  f.tau << sv, 0.0;
  return f;
}

SurfaceForms TerrainForms(const TerrainJet& jet, double x, double y) {
  const double hx = jet.hx, hy = jet.hy;
  const double l2 = 1.0 + hx * hx;
  const double l = std::sqrt(l2);
  const double w = std::sqrt(l2 + hy * hy);
  SurfaceForms f;
  f.point = Vec3(x, y, jet.h);
  f.frame.col(0) = Vec3(1.0, 0.0, hx) / l;
  f.frame.col(1) = Vec3(-hx * hy, l2, hy) / (w * l);
  f.frame.col(2) = Vec3(-hx, -hy, 1.0) / w;
  f.A << l, hx * hy / l, 0.0, w / l;
  Mat2 second;
  second << jet.hxx, jet.hxy, jet.hxy, jet.hyy;
  second /= w;
  const Mat2 a_inv = f.A.inverse();
  f.K = -a_inv.transpose() * second * a_inv;
  f.tau << jet.hxx, jet.hxy;
  f.tau *= hy / (w * l2);
  return f;
}

}  // namespace quasiroll
