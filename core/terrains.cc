#include "quasiroll/core/terrains.h"

#include <Eigen/Dense>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <system_error>
#include <utility>

#include "quasiroll/core/scene.h"

namespace quasiroll {
namespace {

// Shortest round-trip representation ("0.1", "nan", "-inf").
std::string Num(double v) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

double Deg(double rad) { return rad * 180.0 / std::numbers::pi; }

// Throws SceneError "<what>: must be finite, got <v>" unless v is finite.
void RequireFinite(const std::string& what, double v) {
  if (!std::isfinite(v))
    throw SceneError(what + ": must be finite, got " + Num(v));
}

}  // namespace

// ---------------------------------------------------------------- plane ----

PlaneTerrain::PlaneTerrain(double height) : height_(height) {
  RequireFinite("plane height", height);
}

TerrainJet PlaneTerrain::Evaluate(double, double) const {
  TerrainJet j;
  j.h = height_;
  return j;
}

std::string PlaneTerrain::Describe() const { return "plane z=" + Num(height_); }

// -------------------------------------------------------------- incline ----

InclineTerrain::InclineTerrain(double beta_rad, double gamma_rad, double height)
    : beta_(beta_rad), gamma_(gamma_rad), height_(height) {
  if (!std::isfinite(beta_rad) ||
      !(std::abs(beta_rad) < std::numbers::pi / 2)) {
    throw SceneError("incline beta: must be finite with |beta| < pi/2, got " +
                     Num(beta_rad));
  }
  RequireFinite("incline gamma", gamma_rad);
  RequireFinite("incline height", height);
  const double t = std::tan(beta_rad);
  gx_ = t * std::cos(gamma_rad);
  gy_ = t * std::sin(gamma_rad);
}

TerrainJet InclineTerrain::Evaluate(double x, double y) const {
  TerrainJet j;
  j.h = height_ + gx_ * x + gy_ * y;
  j.hx = gx_;
  j.hy = gy_;
  return j;
}

std::string InclineTerrain::Describe() const {
  std::string s = "incline beta=" + Num(Deg(beta_)) +
                  "deg gamma=" + Num(Deg(gamma_)) + "deg";
  if (height_ != 0.0) s += " height=" + Num(height_);
  return s;
}

// ------------------------------------------------------------ gaussians ----

GaussianTerrain::GaussianTerrain(std::vector<GaussianBump> bumps)
    : bumps_(std::move(bumps)) {
  for (std::size_t k = 0; k < bumps_.size(); ++k) {
    const GaussianBump& b = bumps_[k];
    const std::string p = "bumps[" + std::to_string(k) + "].";
    RequireFinite(p + "amplitude", b.amplitude);
    RequireFinite(p + "x", b.x);
    RequireFinite(p + "y", b.y);
    if (!(b.sigma > 0.0) || !std::isfinite(b.sigma)) {
      throw SceneError(p + "sigma: must be > 0 and finite, got " +
                       Num(b.sigma));
    }
    inv_var_.push_back(1.0 / (b.sigma * b.sigma));
    hessian_norm_bound_ += std::abs(b.amplitude) * inv_var_.back();
    amplitude_.push_back(b.amplitude);
    center_x_.push_back(b.x);
    center_y_.push_back(b.y);
  }
}

GaussianTerrain GaussianTerrain::Random(std::uint64_t seed, int count,
                                        Interval amplitude, Interval sigma,
                                        Interval x, Interval y) {
  if (count < 1) {
    throw SceneError("random.count: must be >= 1, got " +
                     std::to_string(count));
  }
  const std::pair<const char*, Interval> ranges[] = {
      {"amplitude", amplitude}, {"sigma", sigma}, {"x", x}, {"y", y}};
  for (const auto& [name, r] : ranges) {
    if (!std::isfinite(r.lo) || !std::isfinite(r.hi)) {
      throw SceneError(std::string("random.") + name +
                       ": bounds must be finite, got [" + Num(r.lo) + ", " +
                       Num(r.hi) + "]");
    }
    if (r.lo > r.hi) {
      throw SceneError(std::string("random.") + name +
                       ": lo must be <= hi, got [" + Num(r.lo) + ", " +
                       Num(r.hi) + "]");
    }
  }
  if (!(sigma.lo > 0.0)) {
    throw SceneError("random.sigma: lo must be > 0, got " + Num(sigma.lo));
  }
  std::mt19937_64 engine(seed);
  // 53 random mantissa bits -> u in [0, 1), exactly representable; identical
  // on every platform because mt19937_64's output sequence is specified.
  auto draw = [&engine](const Interval& r) {
    const double u = static_cast<double>(engine() >> 11) * 0x1.0p-53;
    return r.lo + (r.hi - r.lo) * u;
  };
  std::vector<GaussianBump> bumps(static_cast<std::size_t>(count));
  for (GaussianBump& b : bumps) {
    b.amplitude = draw(amplitude);
    b.x = draw(x);
    b.y = draw(y);
    b.sigma = draw(sigma);
  }
  return GaussianTerrain(std::move(bumps));
}

namespace {
// One bump's first and second derivative terms (g = its height term).
// Evaluate and EvaluateSecondOrder sum these in the same order, so their
// first six entries are bit-identical.
struct BumpTerms {
  double hx, hy, hxx, hxy, hyy;
};
inline BumpTerms SecondOrderTerms(double q, double dx, double dy, double g) {
  const double q2 = q * q;
  return {-q * dx * g, -q * dy * g, (q2 * dx * dx - q) * g, q2 * dx * dy * g,
          (q2 * dy * dy - q) * g};
}

// One bump's terms up to second order, added to *j.
inline void AddSecondOrder(double q, double dx, double dy, double g,
                           TerrainJet* j) {
  const BumpTerms t = SecondOrderTerms(q, dx, dy, g);
  j->h += g;
  j->hx += t.hx;
  j->hy += t.hy;
  j->hxx += t.hxx;
  j->hxy += t.hxy;
  j->hyy += t.hyy;
}
}  // namespace

TerrainJet GaussianTerrain::Evaluate(double x, double y) const {
  TerrainJet j;
  for (std::size_t k = 0; k < bumps_.size(); ++k) {
    const GaussianBump& b = bumps_[k];
    const double dx = x - b.x, dy = y - b.y;
    const double q = inv_var_[k];
    const double g = b.amplitude * std::exp(-0.5 * q * (dx * dx + dy * dy));
    AddSecondOrder(q, dx, dy, g, &j);
    const double q2 = q * q, q3 = q2 * q;
    j.hxxx += (3.0 * q2 * dx - q3 * dx * dx * dx) * g;
    j.hxxy += (q2 * dy - q3 * dx * dx * dy) * g;
    j.hxyy += (q2 * dx - q3 * dx * dy * dy) * g;
    j.hyyy += (3.0 * q2 * dy - q3 * dy * dy * dy) * g;
  }
  return j;
}

// Evaluate()'s sums without the third-order ones, in three passes over
// blocks of bumps so that the per-bump arithmetic vectorises: the exponents,
// the exp calls, then each bump's terms (SecondOrderTerms, as
// AddSecondOrder), summed in bump order. The sums keep their order,
// so the result is bit-identical to Evaluate()'s first six entries
// (tested); the terrain jet is ~25% of a paper-scene run's instructions.
TerrainJet GaussianTerrain::EvaluateSecondOrder(double x, double y) const {
  constexpr std::size_t kBlock = 32;
  alignas(16) double dx[kBlock], dy[kBlock], g[kBlock], hx[kBlock], hy[kBlock],
      hxx[kBlock], hxy[kBlock], hyy[kBlock];
  TerrainJet j;
  const std::size_t n = bumps_.size();
  for (std::size_t k0 = 0; k0 < n; k0 += kBlock) {
    const std::size_t m = std::min(kBlock, n - k0);
    const double* bx = &center_x_[k0];
    const double* by = &center_y_[k0];
    const double* q = &inv_var_[k0];
    const double* amp = &amplitude_[k0];
    for (std::size_t k = 0; k < m; ++k) {
      dx[k] = x - bx[k];
      dy[k] = y - by[k];
      g[k] = -0.5 * q[k] * (dx[k] * dx[k] + dy[k] * dy[k]);
    }
    for (std::size_t k = 0; k < m; ++k) g[k] = amp[k] * std::exp(g[k]);
    for (std::size_t k = 0; k < m; ++k) {  // arrays per term: vectorises
      const BumpTerms t = SecondOrderTerms(q[k], dx[k], dy[k], g[k]);
      hx[k] = t.hx;
      hy[k] = t.hy;
      hxx[k] = t.hxx;
      hxy[k] = t.hxy;
      hyy[k] = t.hyy;
    }
    for (std::size_t k = 0; k < m; ++k) {
      j.h += g[k];
      j.hx += hx[k];
      j.hy += hy[k];
      j.hxx += hxx[k];
      j.hxy += hxy[k];
      j.hyy += hyy[k];
    }
  }
  return j;
}

double GaussianTerrain::Height(double x, double y) const {
  double h = 0.0;
  for (std::size_t k = 0; k < bumps_.size(); ++k) {
    const GaussianBump& b = bumps_[k];
    const double dx = x - b.x, dy = y - b.y;
    const double q = inv_var_[k];
    h += b.amplitude *
         std::exp(-0.5 * q * (dx * dx + dy * dy));  // as Evaluate()
  }
  return h;
}

std::string GaussianTerrain::Describe() const {
  return "gaussians n=" + std::to_string(bumps_.size());
}

// ------------------------------------------------------------- sinusoid ----

SinusoidTerrain::SinusoidTerrain(std::vector<SinusoidComponent> components,
                                 double height)
    : components_(std::move(components)), height_(height) {
  RequireFinite("sinusoid height", height);
  for (std::size_t k = 0; k < components_.size(); ++k) {
    const SinusoidComponent& c = components_[k];
    const std::string p = "components[" + std::to_string(k) + "].";
    RequireFinite(p + "amplitude", c.amplitude);
    if (!(c.wavelength_x > 0.0)) {
      throw SceneError(p + "wavelength_x: must be > 0 (or .inf), got " +
                       Num(c.wavelength_x));
    }
    if (!(c.wavelength_y > 0.0)) {
      throw SceneError(p + "wavelength_y: must be > 0 (or .inf), got " +
                       Num(c.wavelength_y));
    }
    RequireFinite(p + "phase_x", c.phase_x);
    RequireFinite(p + "phase_y", c.phase_y);
  }
}

TerrainJet SinusoidTerrain::Evaluate(double x, double y) const {
  TerrainJet j;
  j.h = height_;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  for (const SinusoidComponent& c : components_) {
    // 2 pi / inf = 0: the factor is the constant cos(phase).
    const double kx = kTwoPi / c.wavelength_x, ky = kTwoPi / c.wavelength_y;
    const double ax = kx * x + c.phase_x, ay = ky * y + c.phase_y;
    const double cx = std::cos(ax), sx = std::sin(ax);
    const double cy = std::cos(ay), sy = std::sin(ay);
    // d^n/dx^n of cos(kx x + phase): cos, -k sin, -k^2 cos, k^3 sin.
    const double X[4] = {cx, -kx * sx, -kx * kx * cx, kx * kx * kx * sx};
    const double Y[4] = {cy, -ky * sy, -ky * ky * cy, ky * ky * ky * sy};
    const double A = c.amplitude;
    j.h += A * X[0] * Y[0];
    j.hx += A * X[1] * Y[0];
    j.hy += A * X[0] * Y[1];
    j.hxx += A * X[2] * Y[0];
    j.hxy += A * X[1] * Y[1];
    j.hyy += A * X[0] * Y[2];
    j.hxxx += A * X[3] * Y[0];
    j.hxxy += A * X[2] * Y[1];
    j.hxyy += A * X[1] * Y[2];
    j.hyyy += A * X[0] * Y[3];
  }
  return j;
}

double SinusoidTerrain::HessianNormBound() const {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double bound = 0.0;
  for (const SinusoidComponent& c : components_) {
    const double kx = kTwoPi / c.wavelength_x, ky = kTwoPi / c.wavelength_y;
    bound += std::abs(c.amplitude) * (kx * kx + ky * ky);
  }
  return bound;
}

std::string SinusoidTerrain::Describe() const {
  std::string s = "sinusoid n=" + std::to_string(components_.size());
  if (components_.size() == 1) {
    const SinusoidComponent& c = components_[0];
    s += " A=" + Num(c.amplitude) + " lx=" + Num(c.wavelength_x) +
         " ly=" + Num(c.wavelength_y);
  }
  if (height_ != 0.0) s += " height=" + Num(height_);
  return s;
}

// ------------------------------------------------------------ heightmap ----
namespace {

// Knot derivatives of the not-a-knot cubic spline through (t_i, values(i, k))
// for every column k. Same linear system as scipy's CubicSpline(bc_type=
// 'not-a-knot'); solved densely with partial pivoting (the end rows are not
// diagonally dominant). n >= 4.
Eigen::MatrixXd NotAKnotSlopes(const std::vector<double>& t,
                               const Eigen::MatrixXd& values) {
  const int n = static_cast<int>(t.size());
  std::vector<double> dx(n - 1);
  for (int i = 0; i + 1 < n; ++i) dx[i] = t[i + 1] - t[i];
  Eigen::MatrixXd slope(n - 1, values.cols());
  for (int i = 0; i + 1 < n; ++i) {
    slope.row(i) = (values.row(i + 1) - values.row(i)) / dx[i];
  }
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd B(n, values.cols());
  {
    const double d = t[2] - t[0];
    A(0, 0) = dx[1];
    A(0, 1) = d;
    B.row(0) = ((dx[0] + 2.0 * d) * dx[1] * slope.row(0) +
                dx[0] * dx[0] * slope.row(1)) /
               d;
  }
  for (int i = 1; i + 1 < n; ++i) {
    A(i, i - 1) = dx[i];
    A(i, i) = 2.0 * (dx[i - 1] + dx[i]);
    A(i, i + 1) = dx[i - 1];
    B.row(i) = 3.0 * (dx[i] * slope.row(i - 1) + dx[i - 1] * slope.row(i));
  }
  {
    const double d = t[n - 1] - t[n - 3];
    A(n - 1, n - 2) = d;
    A(n - 1, n - 1) = dx[n - 3];
    B.row(n - 1) = (dx[n - 2] * dx[n - 2] * slope.row(n - 3) +
                    (2.0 * d + dx[n - 2]) * dx[n - 3] * slope.row(n - 2)) /
                   d;
  }
  return A.partialPivLu().solve(B);
}

void CheckAxis(const std::vector<double>& v, const std::string& label,
               const char* name) {
  if (v.size() < 4) {
    throw SceneError(label + ": " + name +
                     " needs at least 4 grid points, got " +
                     std::to_string(v.size()));
  }
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw SceneError(label + ": " + name + "[" + std::to_string(i) +
                       "] must be finite, got " + Num(v[i]));
    }
    if (i > 0 && !(v[i] > v[i - 1])) {
      throw SceneError(label + ": " + name + "[" + std::to_string(i) +
                       "] must be strictly increasing, got " + Num(v[i]) +
                       " after " + Num(v[i - 1]));
    }
  }
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// Index of the cell containing t (clamped to the boundary cells).
int FindCell(const std::vector<double>& knots, double t) {
  const auto it = std::upper_bound(knots.begin(), knots.end(), t);
  int i = static_cast<int>(it - knots.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(knots.size()) - 2);
}

}  // namespace

HeightmapTerrain::HeightmapTerrain(std::vector<double> xs,
                                   std::vector<double> ys,
                                   std::vector<double> z, std::string label)
    : xs_(std::move(xs)), ys_(std::move(ys)), label_(std::move(label)) {
  CheckAxis(xs_, label_, "x");
  CheckAxis(ys_, label_, "y");
  const int nx = static_cast<int>(xs_.size()),
            ny = static_cast<int>(ys_.size());
  if (z.size() != xs_.size() * ys_.size()) {
    throw SceneError(label_ + ": expected " + std::to_string(nx) + "x" +
                     std::to_string(ny) + " = " + std::to_string(nx * ny) +
                     " heights, got " + std::to_string(z.size()));
  }
  // Z(i, j) = h(x_i, y_j).
  Eigen::MatrixXd Z(nx, ny);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double v = z[static_cast<std::size_t>(j) * nx + i];
      if (!std::isfinite(v)) {
        throw SceneError(label_ + ": z at (x[" + std::to_string(i) + "], y[" +
                         std::to_string(j) + "]) must be finite, got " +
                         Num(v));
      }
      Z(i, j) = v;
    }
  }
  const Eigen::MatrixXd Fx = NotAKnotSlopes(xs_, Z);  // nx x ny
  const Eigen::MatrixXd Fy =
      NotAKnotSlopes(ys_, Z.transpose()).transpose();  // nx x ny
  const Eigen::MatrixXd Fxy =
      NotAKnotSlopes(ys_, Fx.transpose()).transpose();  // nx x ny

  // Cubic Hermite on [0, 1]: coefficients of u^a from (p0, p1, d0, d1).
  Eigen::Matrix4d M;
  M << 1, 0, 0, 0,    //
      0, 0, 1, 0,     //
      -3, 3, -2, -1,  //
      2, -2, 1, 1;
  coeffs_.resize(static_cast<std::size_t>(nx - 1) * (ny - 1) * 16);
  for (int j = 0; j + 1 < ny; ++j) {
    const double hy = ys_[j + 1] - ys_[j];
    for (int i = 0; i + 1 < nx; ++i) {
      const double hx = xs_[i + 1] - xs_[i];
      Eigen::Matrix4d G;
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          G(a, b) = Z(i + a, j + b);
          G(a, 2 + b) = hy * Fy(i + a, j + b);
          G(2 + a, b) = hx * Fx(i + a, j + b);
          G(2 + a, 2 + b) = hx * hy * Fxy(i + a, j + b);
        }
      }
      const Eigen::Matrix4d C = M * G * M.transpose();
      // Finite but huge heights (1e308) overflow the slopes and coefficients
      // (found by tests/fuzz/fuzz_scene); the sum of 16 terms must stay finite.
      if (!(C.cwiseAbs().maxCoeff() <= 1e300)) {
        throw SceneError(label_ + ": heights too large for a spline near (x[" +
                         std::to_string(i) + "], y[" + std::to_string(j) +
                         "]), coefficient " + Num(C.cwiseAbs().maxCoeff()));
      }
      double* c = &coeffs_[(static_cast<std::size_t>(j) * (nx - 1) + i) * 16];
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) c[a * 4 + b] = C(a, b);
      }
    }
  }
}

HeightmapTerrain HeightmapTerrain::FromCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open heightmap file");
  std::vector<double> xs, ys, z;
  std::string line;
  int row = 0;
  bool header_done = false;
  std::size_t ncells = 0;
  while (std::getline(in, line)) {
    ++row;
    const std::string t = Trim(line);
    if (t.empty() || t[0] == '#') continue;
    std::vector<std::string> cells;
    {
      std::stringstream ss(line);
      std::string cell;
      while (std::getline(ss, cell, ',')) cells.push_back(Trim(cell));
      if (!line.empty() && Trim(line).back() == ',') cells.push_back("");
    }
    const std::string where = path + ":" + std::to_string(row) + ":";
    if (!header_done) {
      ncells = cells.size();
    } else if (cells.size() != ncells) {
      throw SceneError(where + " expected " + std::to_string(ncells) +
                       " cells like the header row, got " +
                       std::to_string(cells.size()));
    }
    for (std::size_t c = header_done ? 0 : 1; c < cells.size(); ++c) {
      const std::string loc = where + std::to_string(c + 1);
      const std::string& s = cells[c];
      if (s.empty()) throw SceneError(loc + ": missing value, got \"\"");
      const char* first = s.data();
      const char* last = s.data() + s.size();
      if (*first == '+') ++first;
      double v = 0.0;
      const auto res = std::from_chars(first, last, v);
      if (res.ec != std::errc() || res.ptr != last) {
        throw SceneError(loc + ": not a number, got \"" + s + "\"");
      }
      RequireFinite(loc, v);
      if (!header_done) {
        if (!xs.empty() && !(v > xs.back())) {
          throw SceneError(loc + ": x must be strictly increasing, got " +
                           Num(v) + " after " + Num(xs.back()));
        }
        xs.push_back(v);
      } else if (c == 0) {
        if (!ys.empty() && !(v > ys.back())) {
          throw SceneError(loc + ": y must be strictly increasing, got " +
                           Num(v) + " after " + Num(ys.back()));
        }
        ys.push_back(v);
      } else {
        z.push_back(v);
      }
    }
    header_done = true;
  }
  if (xs.size() < 4 || ys.size() < 4) {
    throw SceneError(
        path + ": grid must have at least 4x4 points (x by y), got " +
        std::to_string(xs.size()) + "x" + std::to_string(ys.size()));
  }
  return HeightmapTerrain(std::move(xs), std::move(ys), std::move(z), path);
}

TerrainJet HeightmapTerrain::Evaluate(double x, double y) const {
  const int i = FindCell(xs_, x), j = FindCell(ys_, y);
  const int nx = static_cast<int>(xs_.size());
  const double hx = xs_[i + 1] - xs_[i], hy = ys_[j + 1] - ys_[j];
  const double u = (x - xs_[i]) / hx, v = (y - ys_[j]) / hy;
  const double* c = &coeffs_[(static_cast<std::size_t>(j) * (nx - 1) + i) * 16];
  // D[n][a] = d^n/du^n u^a.
  const double U[4][4] = {{1, u, u * u, u * u * u},
                          {0, 1, 2 * u, 3 * u * u},
                          {0, 0, 2, 6 * u},
                          {0, 0, 0, 6}};
  const double V[4][4] = {{1, v, v * v, v * v * v},
                          {0, 1, 2 * v, 3 * v * v},
                          {0, 0, 2, 6 * v},
                          {0, 0, 0, 6}};
  auto d = [&](int p, int q) {
    double s = 0.0;
    for (int a = p; a < 4; ++a) {
      double t = 0.0;
      for (int b = q; b < 4; ++b) t += c[a * 4 + b] * V[q][b];
      s += U[p][a] * t;
    }
    return s / (std::pow(hx, p) * std::pow(hy, q));
  };
  TerrainJet jet;
  jet.h = d(0, 0);
  jet.hx = d(1, 0);
  jet.hy = d(0, 1);
  jet.hxx = d(2, 0);
  jet.hxy = d(1, 1);
  jet.hyy = d(0, 2);
  jet.hxxx = d(3, 0);
  jet.hxxy = d(2, 1);
  jet.hxyy = d(1, 2);
  jet.hyyy = d(0, 3);
  return jet;
}

bool HeightmapTerrain::Contains(double x, double y) const {
  return x >= xs_.front() && x <= xs_.back() && y >= ys_.front() &&
         y <= ys_.back();
}

std::string HeightmapTerrain::Describe() const {
  return "heightmap " + label_ + " (" + std::to_string(xs_.size()) + "x" +
         std::to_string(ys_.size()) + ", x in [" + Num(x_min()) + ", " +
         Num(x_max()) + "], y in [" + Num(y_min()) + ", " + Num(y_max()) + "])";
}

// -------------------------------------------------------------- factory ----

const char* ToString(TerrainSpec::Type type) {
  switch (type) {
    case TerrainSpec::Type::kPlane:
      return "plane";
    case TerrainSpec::Type::kIncline:
      return "incline";
    case TerrainSpec::Type::kGaussians:
      return "gaussians";
    case TerrainSpec::Type::kSinusoid:
      return "sinusoid";
    case TerrainSpec::Type::kHeightmap:
      return "heightmap";
  }
  return "?";
}

std::optional<TerrainSpec::Type> TerrainTypeFromString(const std::string& s) {
  for (auto t : {TerrainSpec::Type::kPlane, TerrainSpec::Type::kIncline,
                 TerrainSpec::Type::kGaussians, TerrainSpec::Type::kSinusoid,
                 TerrainSpec::Type::kHeightmap}) {
    if (s == ToString(t)) return t;
  }
  return std::nullopt;
}

std::shared_ptr<const Terrain> MakeTerrain(const TerrainSpec& spec) {
  switch (spec.type) {
    case TerrainSpec::Type::kPlane:
      return std::make_shared<PlaneTerrain>(spec.height);
    case TerrainSpec::Type::kIncline:
      return std::make_shared<InclineTerrain>(spec.slope_rad, spec.azimuth_rad,
                                              spec.height);
    case TerrainSpec::Type::kGaussians:
      if (spec.random) {
        const TerrainSpec::Random& r = *spec.random;
        return std::make_shared<GaussianTerrain>(GaussianTerrain::Random(
            r.seed, r.count, r.amplitude, r.sigma, r.x, r.y));
      }
      return std::make_shared<GaussianTerrain>(spec.bumps);
    case TerrainSpec::Type::kSinusoid:
      return std::make_shared<SinusoidTerrain>(spec.components, spec.height);
    case TerrainSpec::Type::kHeightmap:
      return std::make_shared<HeightmapTerrain>(
          HeightmapTerrain::FromCsv(spec.file));
  }
  throw SceneError("terrain.type: unknown terrain type");
}

}  // namespace quasiroll
