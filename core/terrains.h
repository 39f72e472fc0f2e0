// Concrete terrains z = h(x, y). Every implementation evaluates h and all of
// its partial derivatives up to third order analytically (no finite
// differences). See model.md §1.2 for the formulas of plane, incline and
// sum-of-Gaussians terrains; docs/scenes.md for how scenes select them.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/core/terrain.h"

namespace quasiroll {

// h = height everywhere.
class PlaneTerrain final : public Terrain {
 public:
  explicit PlaneTerrain(double height = 0.0);
  TerrainJet Evaluate(double x, double y) const override;
  double HessianNormBound() const override { return 0.0; }
  std::string Describe() const override;
  double height() const { return height_; }

 private:
  double height_;
};

// h = height + tan(beta) (cos(gamma) x + sin(gamma) y): a plane whose steepest
// ascent points along azimuth gamma (measured from +x towards +y) with slope
// angle beta. Requires |beta| < pi/2.
class InclineTerrain final : public Terrain {
 public:
  InclineTerrain(double beta_rad, double gamma_rad, double height = 0.0);
  TerrainJet Evaluate(double x, double y) const override;
  double HessianNormBound() const override { return 0.0; }
  std::string Describe() const override;
  double beta() const { return beta_; }
  double gamma() const { return gamma_; }

 private:
  double beta_, gamma_, height_;
  double gx_, gy_;  // constant gradient
};

struct GaussianBump {
  double amplitude = 0.0;   // A_k [m] (negative = dip)
  double x = 0.0, y = 0.0;  // centre [m]
  double sigma = 1.0;       // s_k [m], > 0
};

// Closed interval [lo, hi] used by the random generators.
struct Interval {
  double lo = 0.0, hi = 0.0;
};

// h = sum_k A_k exp(-((x - x_k)^2 + (y - y_k)^2) / (2 s_k^2)).
class GaussianTerrain final : public Terrain {
 public:
  // Throws SceneError if a sigma is not > 0 or a value is non-finite.
  explicit GaussianTerrain(std::vector<GaussianBump> bumps);

  // `count` bumps drawn from a platform-independent generator: std::mt19937_64
  // seeded with `seed`; each draw u = (engine() >> 11) * 2^-53 in [0, 1) is
  // mapped to lo + (hi - lo) u. Per bump the draws are taken in the order
  // amplitude, x, y, sigma. Throws SceneError for count < 1, lo > hi, a
  // non-finite bound or sigma.lo <= 0.
  static GaussianTerrain Random(std::uint64_t seed, int count,
                                Interval amplitude, Interval sigma, Interval x,
                                Interval y);

  TerrainJet Evaluate(double x, double y) const override;
  TerrainJet EvaluateSecondOrder(double x, double y) const override;
  double Height(double x, double y) const override;
  std::string Describe() const override;
  // sum_k |A_k| / s_k^2: a bump's Hessian is g_k (d d^T / s^4 - I / s^2)
  // (d the offset from its centre), whose eigenvalues
  // g_k (|d|^2 / s^2 - 1) / s^2 and -g_k / s^2 are at most |A_k| / s_k^2 in
  // size (|u - 1| e^(-u/2) <= 1 for u >= 0).
  double HessianNormBound() const override { return hessian_norm_bound_; }
  const std::vector<GaussianBump>& bumps() const { return bumps_; }

 private:
  std::vector<GaussianBump> bumps_;
  std::vector<double> inv_var_;  // 1 / sigma_k^2, precomputed
  // The bumps' fields as arrays (EvaluateSecondOrder's vectorised passes).
  std::vector<double> amplitude_, center_x_, center_y_;
  double hessian_norm_bound_ = 0.0;
};

// One separable cosine product:
//   A cos(2 pi x / lambda_x + phase_x) * cos(2 pi y / lambda_y + phase_y).
// A wavelength of +infinity means "constant in that direction" (the factor is
// then cos(phase)). Wavelengths must be > 0 (or +inf).
struct SinusoidComponent {
  double amplitude = 0.0;                                         // [m]
  double wavelength_x = std::numeric_limits<double>::infinity();  // [m]
  double wavelength_y = std::numeric_limits<double>::infinity();  // [m]
  double phase_x = 0.0;                                           // [rad]
  double phase_y = 0.0;                                           // [rad]
};

// h = height + sum_k component_k(x, y) (see SinusoidComponent). Example: a
// corrugation along x is {A, lambda, inf, 0, 0}; an egg-crate is
// {A, lambda, lambda, 0, 0}.
class SinusoidTerrain final : public Terrain {
 public:
  explicit SinusoidTerrain(std::vector<SinusoidComponent> components,
                           double height = 0.0);
  TerrainJet Evaluate(double x, double y) const override;
  std::string Describe() const override;
  // sum_k |A_k| (kx_k^2 + ky_k^2), k = 2 pi / wavelength: the Frobenius
  // norm of a component's Hessian.
  double HessianNormBound() const override;
  const std::vector<SinusoidComponent>& components() const {
    return components_;
  }

 private:
  std::vector<SinusoidComponent> components_;
  double height_;
};

// Tabulated terrain on a rectilinear grid, interpolated by the tensor-product
// not-a-knot cubic spline (de Boor's bicubic spline): C^2 everywhere on the
// grid, a bicubic polynomial in every cell (so third derivatives are
// piecewise polynomial and may jump across cell boundaries), and exact for any
// polynomial of degree <= 3 in x times degree <= 3 in y.
//
// CSV format (FromCsv): comma-separated; blank lines and lines whose first
// non-blank character is '#' are ignored; cells are trimmed of blanks.
//   first row : <anything or empty>, x_0, x_1, ..., x_{nx-1}
//   other rows: y_j, z(x_0, y_j), z(x_1, y_j), ..., z(x_{nx-1}, y_j)
// x and y strictly increasing, every cell a finite number, nx, ny >= 4, every
// row of the same length. Rows/columns in messages are 1-based and count the
// physical lines/cells of the file.
//
// Outside [x_0, x_{nx-1}] x [y_0, y_{ny-1}] Contains() is false and
// Evaluate() extrapolates the nearest boundary cell's polynomial.
class HeightmapTerrain final : public Terrain {
 public:
  // z is row-major by y: z[j * xs.size() + i] = h(xs[i], ys[j]). Throws
  // SceneError (naming the offending index and value) for sizes < 4, a size
  // mismatch, non-increasing coordinates or non-finite values.
  HeightmapTerrain(std::vector<double> xs, std::vector<double> ys,
                   std::vector<double> z, std::string label = "grid");
  // Throws SceneError "<path>: ..." for a missing/unreadable file and
  // "<path>:<row>:<col>: <problem>, got <value>" for a bad cell.
  static HeightmapTerrain FromCsv(const std::string& path);

  TerrainJet Evaluate(double x, double y) const override;
  bool Contains(double x, double y) const override;
  std::string Describe() const override;

  const std::vector<double>& xs() const { return xs_; }
  const std::vector<double>& ys() const { return ys_; }
  double x_min() const { return xs_.front(); }
  double x_max() const { return xs_.back(); }
  double y_min() const { return ys_.front(); }
  double y_max() const { return ys_.back(); }

 private:
  std::vector<double> xs_, ys_;
  // 16 coefficients per cell (i, j): c[a][b] of u^a v^b with
  // u = (x - x_i)/dx_i, v = (y - y_j)/dy_j; cell index j * (nx-1) + i.
  std::vector<double> coeffs_;
  std::string label_;
};

// Everything needed to build any terrain; filled by the scene loader (and by
// code that wants to describe a terrain as data).
struct TerrainSpec {
  enum class Type { kPlane, kIncline, kGaussians, kSinusoid, kHeightmap };
  Type type = Type::kPlane;
  double height = 0.0;       // plane, incline, sinusoid offset [m]
  double slope_rad = 0.0;    // incline beta
  double azimuth_rad = 0.0;  // incline gamma
  // gaussians: explicit bumps, or (if `random` is set) generated ones.
  std::vector<GaussianBump> bumps;
  struct Random {
    std::uint64_t seed = 0;
    int count = 0;
    Interval amplitude, sigma, x, y;
  };
  std::optional<Random> random;
  std::vector<SinusoidComponent> components;  // sinusoid
  std::string file;  // heightmap CSV path (used as given)
};

const char* ToString(TerrainSpec::Type type);
// Parses "plane" | "incline" | "gaussians" | "sinusoid" | "heightmap".
std::optional<TerrainSpec::Type> TerrainTypeFromString(const std::string& s);

// Builds the terrain; throws SceneError on invalid parameters.
std::shared_ptr<const Terrain> MakeTerrain(const TerrainSpec& spec);

}  // namespace quasiroll
