// Terrain z = h(x, y) behind one interface, with derivatives up to third order.
//
// The contact kinematics (model.md §1.2, §5) uses h, its gradient and Hessian
// at every right-hand-side evaluation; third derivatives enter derivatives of
// the terrain forms (A_g, K_g, tau_g) used by Jacobians. All implementations
// must be C^2 at least (C^3 where stated) so that the curvature form K_g is
// continuous along a path.
#pragma once

#include <limits>
#include <memory>
#include <string>

namespace quasiroll {

// h and its partial derivatives at one point.
struct TerrainJet {
  double h = 0.0;
  double hx = 0.0, hy = 0.0;
  double hxx = 0.0, hxy = 0.0, hyy = 0.0;
  double hxxx = 0.0, hxxy = 0.0, hxyy = 0.0, hyyy = 0.0;
};

class Terrain {
 public:
  virtual ~Terrain() = default;
  // All derivatives up to third order at (x, y). For (x, y) outside the
  // domain (heightmaps only) the result is unspecified: check Contains().
  virtual TerrainJet Evaluate(double x, double y) const = 0;
  // h and its derivatives up to second order, bit for bit those of
  // Evaluate() (what the contact kinematics and the gap search use); the
  // third-order members are unspecified. Terrains whose third derivatives
  // cost extra override it (gaussians).
  virtual TerrainJet EvaluateSecondOrder(double x, double y) const {
    return Evaluate(x, y);
  }
  virtual double Height(double x, double y) const { return Evaluate(x, y).h; }
  // False outside a bounded domain (heightmap); true everywhere otherwise.
  virtual bool Contains(double /*x*/, double /*y*/) const { return true; }
  // An upper bound on the spectral norm of the Hessian of h over the whole
  // plane [1/m] (+inf: none known). It bounds the terrain's curvature form:
  // ||K_g||_2 <= ||hess h||_2 (model.md §3.2), so wheel states whose own
  // curvature exceeds it pass the relative-curvature test without a
  // terrain evaluation (core/limit_events.h).
  virtual double HessianNormBound() const {
    return std::numeric_limits<double>::infinity();
  }
  // One-line human-readable description, e.g. "incline beta=10deg gamma=0deg".
  virtual std::string Describe() const = 0;
};

}  // namespace quasiroll
