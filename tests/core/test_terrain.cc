// Terrain implementations: analytic derivatives vs finite differences,
// heightmap spline properties, CSV parsing, deterministic random bumps.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/terrains.h"

namespace quasiroll {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// The ten jet entries addressed by (order in x, order in y).
double Get(const TerrainJet& j, int p, int q) {
  using J = TerrainJet;
  // kEntry[p][q] = d^(p+q) h / dx^p dy^q; p + q <= 3.
  static constexpr double J::*kEntry[4][4] = {
      {&J::h, &J::hy, &J::hyy, &J::hyyy},
      {&J::hx, &J::hxy, &J::hxyy, nullptr},
      {&J::hxx, &J::hxxy, nullptr, nullptr},
      {&J::hxxx, nullptr, nullptr, nullptr}};
  if (p < 0 || q < 0 || p + q > 3) {
    ADD_FAILURE() << "bad derivative index " << p << "," << q;
    return 0.0;
  }
  return j.*kEntry[p][q];
}

struct FdCase {
  std::string name;
  std::shared_ptr<const Terrain> terrain;
  double step;  // finite-difference step d [m]
  // Upper bound of |any partial derivative of order n| near the test points.
  std::function<double(int)> bound;
  std::vector<std::array<double, 2>> points;
};

// Every analytic derivative of order n = 1..3 is compared with the central
// difference (g(. + d) - g(. - d)) / 2d of an analytic derivative g of order
// n - 1 (in x and, where possible, in y). Error model of a central difference:
//   |D_d g - g'| <= d^2 / 6 * M_{n+2} + 2 eps M_{n-1} / d,
// truncation (M_{n+2} bounds the derivatives two orders above the checked one)
// plus rounding (each evaluation of g carries ~eps * M_{n-1}). The tolerance
// is 4x that bound plus an absolute floor of 1e-13 for exactly-zero entries.
void CheckDerivatives(const FdCase& c) {
  SCOPED_TRACE(c.name);
  const double d = c.step;
  for (const auto& pt : c.points) {
    const double x = pt[0], y = pt[1];
    SCOPED_TRACE("at (" + std::to_string(x) + ", " + std::to_string(y) + ")");
    const TerrainJet j0 = c.terrain->Evaluate(x, y);
    const TerrainJet jxp = c.terrain->Evaluate(x + d, y);
    const TerrainJet jxm = c.terrain->Evaluate(x - d, y);
    const TerrainJet jyp = c.terrain->Evaluate(x, y + d);
    const TerrainJet jym = c.terrain->Evaluate(x, y - d);
    EXPECT_DOUBLE_EQ(j0.h, c.terrain->Height(x, y));
    for (int n = 1; n <= 3; ++n) {
      const double tol = 4.0 * (d * d / 6.0 * c.bound(n + 2) +
                                2.0 * kEps * c.bound(n - 1) / d) +
                         1e-13;
      for (int p = 0; p <= n; ++p) {
        const int q = n - p;
        const double analytic = Get(j0, p, q);
        if (p >= 1) {  // differentiate the (p-1, q) entry in x
          const double fd = (Get(jxp, p - 1, q) - Get(jxm, p - 1, q)) / (2 * d);
          EXPECT_NEAR(analytic, fd, tol)
              << "d^" << p << "x d^" << q << "y via x";
        }
        if (q >= 1) {  // differentiate the (p, q-1) entry in y
          const double fd = (Get(jyp, p, q - 1) - Get(jym, p, q - 1)) / (2 * d);
          EXPECT_NEAR(analytic, fd, tol)
              << "d^" << p << "x d^" << q << "y via y";
        }
      }
    }
  }
}

const std::vector<std::array<double, 2>> kPoints = {{0.0, 0.0},  {0.37, -0.21},
                                                    {-1.3, 0.8}, {1.1, 1.7},
                                                    {2.2, -0.9}, {0.05, 0.55}};

// R1 terrain of model.md §9.3 (also tested against paper.yaml).
std::vector<GaussianBump> SomeBumps() {
  return {{0.0360, -0.2292, -1.1830, 0.2857},
          {-0.0285, 1.3952, 0.3497, 0.3293},
          {0.0231, 0.2323, -0.1855, 0.3764},
          {0.0376, 0.9101, -0.4398, 0.3412},
          {-0.0237, -0.1266, 0.7844, 0.4492}};
}

TEST(TerrainTest, PlaneDerivatives) {
  auto t = std::make_shared<PlaneTerrain>(0.3);
  EXPECT_EQ(t->Height(5.0, -2.0), 0.3);
  EXPECT_TRUE(t->Contains(1e9, -1e9));
  EXPECT_FALSE(t->Describe().empty());
  CheckDerivatives(
      {"plane", t, 1e-3, [](int n) { return n == 0 ? 3.0 : 0.0; }, kPoints});
}

TEST(TerrainTest, InclineFormulaAndDerivatives) {
  const double beta = 10.0 * std::numbers::pi / 180.0;
  const double gamma = 0.7;
  auto t = std::make_shared<InclineTerrain>(beta, gamma, 0.1);
  const double x = 0.4, y = -1.2;
  EXPECT_NEAR(
      t->Height(x, y),
      0.1 + std::tan(beta) * (std::cos(gamma) * x + std::sin(gamma) * y),
      1e-15);
  const TerrainJet j = t->Evaluate(x, y);
  EXPECT_NEAR(std::hypot(j.hx, j.hy), std::tan(beta), 1e-15);
  EXPECT_NEAR(std::atan2(j.hy, j.hx), gamma, 1e-15);
  // 10deg rising along +x.
  InclineTerrain up(beta, 0.0);
  EXPECT_NEAR(up.Height(1.0, 5.0), std::tan(beta), 1e-15);
  EXPECT_FALSE(up.Describe().empty());
  CheckDerivatives({"incline", t, 1e-3,
                    [](int n) { return n == 0   ? 2.0
                                       : n == 1 ? 0.2
                                                : 0.0; },
                    kPoints});
  EXPECT_THROW(InclineTerrain(std::numbers::pi / 2, 0.0), SceneError);
}

TEST(TerrainTest, GaussianDerivatives) {
  auto t = std::make_shared<GaussianTerrain>(SomeBumps());
  double amp = 0.0, smin = 1e9;
  for (const auto& b : t->bumps()) {
    amp += std::abs(b.amplitude);
    smin = std::min(smin, b.sigma);
  }
  // |d^n exp(-t^2/2)/dt^n| <= 10 for n <= 5; per bump |d^n g| <= 10 A / s^n.
  auto bound = [=](int n) { return 10.0 * amp / std::pow(smin, n); };
  std::vector<std::array<double, 2>> pts = kPoints;
  pts.push_back({0.9101, -0.4398});  // a bump centre
  CheckDerivatives({"gaussians", t, 1e-4, bound, pts});
  // Height() agrees with the formula.
  double h = 0.0;
  for (const auto& b : SomeBumps()) {
    h += b.amplitude *
         std::exp(-(std::pow(0.3 - b.x, 2) + std::pow(-0.2 - b.y, 2)) /
                  (2 * b.sigma * b.sigma));
  }
  EXPECT_NEAR(t->Height(0.3, -0.2), h, 1e-16);
}

// The kinematics evaluates the gaussians through EvaluateSecondOrder():
// h and its first and second derivatives must be those of Evaluate() bit
// for bit (simulation results do not depend on which one is called).
// EvaluateSecondOrder works in blocks of 32 bumps: counts on both sides.
TEST(TerrainTest, GaussianSecondOrderEqualsEvaluateBitForBit) {
  for (const int count : {1, 30, 32, 33, 70}) {
    const GaussianTerrain t = GaussianTerrain::Random(
        11, count, {-0.04, 0.04}, {0.2, 0.45}, {-0.5, 2.5}, {-1.2, 1.0});
    for (int a = 0; a < 40; ++a) {
      for (int b = 0; b < 40; ++b) {
        const double x = -1.0 + 0.0937 * a, y = -1.7 + 0.0891 * b;
        const TerrainJet full = t.Evaluate(x, y);
        const TerrainJet second = t.EvaluateSecondOrder(x, y);
        for (double TerrainJet::*m :
             {&TerrainJet::h, &TerrainJet::hx, &TerrainJet::hy,
              &TerrainJet::hxx, &TerrainJet::hxy, &TerrainJet::hyy}) {
          ASSERT_EQ(std::memcmp(&(full.*m), &(second.*m), sizeof(double)), 0)
              << count << " bumps, at (" << x << ", " << y << ")";
        }
      }
    }
  }
}

TEST(TerrainTest, GaussianRejectsBadSigma) {
  EXPECT_THROW(GaussianTerrain({{0.1, 0.0, 0.0, 0.0}}), SceneError);
  EXPECT_THROW(GaussianTerrain({{0.1, 0.0, 0.0, -1.0}}), SceneError);
  EXPECT_THROW(GaussianTerrain({{std::nan(""), 0.0, 0.0, 1.0}}), SceneError);
}

TEST(TerrainTest, SinusoidDerivatives) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<SinusoidComponent> comps = {{0.03, 0.9, 1.4, 0.3, -0.2},
                                          {0.01, 0.5, inf, 1.0, 0.0}};
  auto t = std::make_shared<SinusoidTerrain>(comps, 0.02);
  auto bound = [](int n) {
    const double k = 2 * std::numbers::pi / 0.5;  // largest wavenumber
    return 0.04 * std::pow(k, n) + (n == 0 ? 0.02 : 0.0);
  };
  CheckDerivatives({"sinusoid", t, 1e-5, bound, kPoints});
  // Formula and the "inf = constant" convention.
  const double x = 0.3, y = -0.7;
  const double expected = 0.02 +
                          0.03 *
                              std::cos(2 * std::numbers::pi * x / 0.9 + 0.3) *
                              std::cos(2 * std::numbers::pi * y / 1.4 - 0.2) +
                          0.01 * std::cos(2 * std::numbers::pi * x / 0.5 + 1.0);
  EXPECT_NEAR(t->Height(x, y), expected, 1e-16);
  SinusoidTerrain corrugation({{0.05, 1.0, inf, 0.0, 0.0}});
  EXPECT_EQ(corrugation.Evaluate(0.2, 3.0).hy, 0.0);
  EXPECT_EQ(corrugation.Height(0.2, 3.0), corrugation.Height(0.2, -7.0));
  EXPECT_THROW(SinusoidTerrain({{0.05, -1.0, inf, 0.0, 0.0}}), SceneError);
}

// ------------------------------------------------------------ heightmap ----

double Smooth(double x, double y) {
  return 0.05 * std::sin(1.3 * x + 0.2) * std::cos(0.9 * y) + 0.02 * x * y;
}

// Non-uniform grid on [-2, 3] x [-1.5, 2].
std::vector<double> Grid(double lo, double hi, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / (n - 1);
    v[i] = lo + (hi - lo) * (s + 0.04 * std::sin(3.0 * s * std::numbers::pi));
  }
  return v;
}

HeightmapTerrain MakeMap(const std::function<double(double, double)>& f, int nx,
                         int ny) {
  const std::vector<double> xs = Grid(-2.0, 3.0, nx), ys = Grid(-1.5, 2.0, ny);
  std::vector<double> z;
  for (double y : ys) {
    for (double x : xs) z.push_back(f(x, y));
  }
  return HeightmapTerrain(xs, ys, z);
}

TEST(HeightmapTest, DerivativesMatchFiniteDifferences) {
  auto t = std::make_shared<HeightmapTerrain>(MakeMap(Smooth, 41, 37));
  // The spline follows `Smooth`, whose n-th derivatives are <= 0.05 * 1.3^n +
  // 0.02 (n <= 2); a factor 10 covers the interpolant's own variation.
  auto bound = [](int n) { return 10.0 * (0.05 * std::pow(1.3, n) + 0.1); };
  // Points away from the knots by more than the step.
  std::vector<std::array<double, 2>> pts;
  const auto& xs = t->xs();
  const auto& ys = t->ys();
  for (int k : {3, 10, 17, 25, 33}) {
    pts.push_back({0.5 * (xs[k] + xs[k + 1]), 0.37 * ys[k] + 0.63 * ys[k + 1]});
  }
  CheckDerivatives({"heightmap", t, 1e-5, bound, pts});
  // Close to the underlying function (interpolation error O(h^4)).
  EXPECT_NEAR(t->Height(0.123, -0.456), Smooth(0.123, -0.456), 1e-5);
}

TEST(HeightmapTest, ReproducesBicubicPolynomialsExactly) {
  // Not-a-knot splines are exact for cubics; the tensor product is exact for
  // any sum of x^a y^b with a, b <= 3.
  auto p = [](double x, double y) {
    return 0.3 + 0.5 * x - 0.2 * y + 0.7 * x * x * x - 0.4 * x * x * y +
           0.25 * x * y * y * y - 0.1 * y * y * y +
           0.05 * x * x * x * y * y * y;
  };
  const HeightmapTerrain t = MakeMap(p, 8, 6);
  for (const auto& pt : {std::array<double, 2>{-1.9, -1.4},
                         {0.3, 0.2},
                         {2.99, 1.99},
                         {1.234, -0.777},
                         {-0.5, 1.5}}) {
    const double x = pt[0], y = pt[1];
    const TerrainJet j = t.Evaluate(x, y);
    const double x2 = x * x, y2 = y * y;
    EXPECT_NEAR(j.h, p(x, y), 1e-11);
    EXPECT_NEAR(
        j.hx, 0.5 + 2.1 * x2 - 0.8 * x * y + 0.25 * y2 * y + 0.15 * x2 * y2 * y,
        1e-10);
    EXPECT_NEAR(j.hy,
                -0.2 - 0.4 * x2 + 0.75 * x * y2 - 0.3 * y2 + 0.15 * x2 * x * y2,
                1e-10);
    EXPECT_NEAR(j.hxx, 4.2 * x - 0.8 * y + 0.3 * x * y2 * y, 1e-9);
    EXPECT_NEAR(j.hxy, -0.8 * x + 0.75 * y2 + 0.45 * x2 * y2, 1e-9);
    EXPECT_NEAR(j.hyy, 1.5 * x * y - 0.6 * y + 0.3 * x2 * x * y, 1e-9);
    EXPECT_NEAR(j.hxxx, 4.2 + 0.3 * y2 * y, 1e-8);
    EXPECT_NEAR(j.hxxy, -0.8 + 0.9 * x * y2, 1e-8);
    EXPECT_NEAR(j.hxyy, 1.5 * y + 0.9 * x2 * y, 1e-8);
    EXPECT_NEAR(j.hyyy, 1.5 * x - 0.6 + 0.3 * x2 * x, 1e-8);
  }
}

TEST(HeightmapTest, IsC2AcrossCellBoundaries) {
  const HeightmapTerrain t = MakeMap(Smooth, 12, 10);
  const double delta = 1e-9;
  // h and its first and second derivatives are continuous; with delta = 1e-9
  // the change across the knot is <= 2 delta * |third derivative| ~ 1e-9.
  auto check = [&](const TerrainJet& a, const TerrainJet& b) {
    for (int n = 0; n <= 2; ++n) {
      for (int p = 0; p <= n; ++p) {
        EXPECT_NEAR(Get(a, p, n - p), Get(b, p, n - p), 1e-7)
            << "order (" << p << "," << n - p << ")";
      }
    }
  };
  for (std::size_t i = 1; i + 1 < t.xs().size(); ++i) {
    const double x = t.xs()[i];
    check(t.Evaluate(x - delta, 0.3), t.Evaluate(x + delta, 0.3));
  }
  for (std::size_t j = 1; j + 1 < t.ys().size(); ++j) {
    const double y = t.ys()[j];
    check(t.Evaluate(-0.7, y - delta), t.Evaluate(-0.7, y + delta));
  }
}

TEST(HeightmapTest, DomainAndValidation) {
  const HeightmapTerrain t = MakeMap(Smooth, 6, 5);
  EXPECT_TRUE(t.Contains(-2.0, -1.5));
  EXPECT_TRUE(t.Contains(3.0, 2.0));
  EXPECT_TRUE(t.Contains(0.0, 0.0));
  EXPECT_FALSE(t.Contains(3.01, 0.0));
  EXPECT_FALSE(t.Contains(0.0, -1.51));
  EXPECT_FALSE(t.Describe().empty());
  // Grid values are reproduced at the knots.
  EXPECT_NEAR(t.Height(t.xs()[2], t.ys()[3]), Smooth(t.xs()[2], t.ys()[3]),
              1e-15);

  const std::vector<double> g4 = {0, 1, 2, 3};
  const std::vector<double> z16(16, 0.0);
  EXPECT_NO_THROW(HeightmapTerrain(g4, g4, z16));
  EXPECT_THROW(HeightmapTerrain({0, 1, 2}, g4, std::vector<double>(12, 0.0)),
               SceneError);
  EXPECT_THROW(HeightmapTerrain({0, 2, 1, 3}, g4, z16), SceneError);
  EXPECT_THROW(HeightmapTerrain(g4, g4, std::vector<double>(15, 0.0)),
               SceneError);
  std::vector<double> bad = z16;
  bad[5] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(HeightmapTerrain(g4, g4, bad), SceneError);
}

class CsvTest : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& text) {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("quasiroll_test_terrain_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    dirs_.push_back(dir);
    const auto path = dir / name;
    std::ofstream(path) << text;
    return path.string();
  }
  void TearDown() override {
    for (const auto& d : dirs_) std::filesystem::remove_all(d);
  }
  // Expects FromCsv to throw a SceneError whose message contains every needle.
  void ExpectCsvError(const std::string& text,
                      const std::vector<std::string>& needles) {
    const std::string path = Write("bad.csv", text);
    try {
      HeightmapTerrain::FromCsv(path);
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const SceneError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      for (const auto& n : needles) {
        EXPECT_NE(msg.find(n), std::string::npos)
            << "'" << n << "' not in: " << msg;
      }
    }
  }
  std::vector<std::filesystem::path> dirs_;
};

TEST_F(CsvTest, RoundTripMatchesGridConstructor) {
  const std::vector<double> xs = Grid(-2.0, 3.0, 9), ys = Grid(-1.5, 2.0, 7);
  std::string csv = "# smooth test surface\n y\\x ";
  std::vector<double> z;
  for (double x : xs) {
    char buf[64];
    std::snprintf(buf, sizeof buf, ",%.17g", x);
    csv += buf;
  }
  csv += "\n\n";
  for (double y : ys) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", y);
    csv += buf;
    for (double x : xs) {
      std::snprintf(buf, sizeof buf, ", %.17g", Smooth(x, y));
      csv += buf;
      z.push_back(Smooth(x, y));
    }
    csv += "\r\n";
  }
  const HeightmapTerrain a = HeightmapTerrain::FromCsv(Write("ok.csv", csv));
  const HeightmapTerrain b(xs, ys, z);
  ASSERT_EQ(a.xs().size(), 9u);
  ASSERT_EQ(a.ys().size(), 7u);
  for (const auto& pt : kPoints) {
    if (!b.Contains(pt[0], pt[1])) continue;
    const TerrainJet ja = a.Evaluate(pt[0], pt[1]),
                     jb = b.Evaluate(pt[0], pt[1]);
    for (int n = 0; n <= 3; ++n) {
      for (int p = 0; p <= n; ++p)
        EXPECT_EQ(Get(ja, p, n - p), Get(jb, p, n - p));
    }
  }
}

TEST_F(CsvTest, Errors) {
  const std::string ok_rows = "0,1,2,3,4\n1,1,2,3,4\n2,1,2,3,4\n3,1,2,3,4\n";
  ExpectCsvError(",0,1,0.5,3\n" + ok_rows,
                 {":1:4", "x must be strictly increasing", "got 0.5 after 1"});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,2,3,4\n1,1,2,3,4\n3,1,2,3,4\n",
                 {":4:1", "y must be strictly increasing", "got 1 after 1"});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,,3,4\n2,1,2,3,4\n3,1,2,3,4\n",
                 {":3:3", "missing value"});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,2,3,4\n2,1,2,3,\n3,1,2,3,4\n",
                 {":4:5", "missing value"});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,abc,3,4\n2,1,2,3,4\n3,1,2,3,4\n",
                 {":3:3", "not a number", "\"abc\""});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,nan,3,4\n2,1,2,3,4\n3,1,2,3,4\n",
                 {":3:3", "must be finite", "nan"});
  ExpectCsvError(",0,1,2,3\n0,1,2,3,4\n1,1,2,3\n2,1,2,3,4\n3,1,2,3,4\n",
                 {":3:", "expected 5 cells", "got 4"});
  ExpectCsvError(",0,1,2\n0,1,2,3\n1,1,2,3\n2,1,2,3\n3,1,2,3\n",
                 {"at least 4x4", "got 3x4"});
  ExpectCsvError("", {"at least 4x4", "got 0x0"});
  try {
    HeightmapTerrain::FromCsv("/nonexistent/dir/map.csv");
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/map.csv"),
              std::string::npos);
  }
}

// ----------------------------------------------------------- random bumps ---

TEST(RandomGaussianTest, DeterministicAndWithinRanges) {
  const Interval amp{-0.04, 0.03}, sig{0.2, 0.45}, xr{-0.5, 2.5}, yr{-1.2, 1.0};
  const GaussianTerrain a = GaussianTerrain::Random(42, 30, amp, sig, xr, yr);
  const GaussianTerrain b = GaussianTerrain::Random(42, 30, amp, sig, xr, yr);
  const GaussianTerrain c = GaussianTerrain::Random(43, 30, amp, sig, xr, yr);
  ASSERT_EQ(a.bumps().size(), 30u);
  ASSERT_EQ(c.bumps().size(), 30u);
  int differing = 0;
  for (std::size_t k = 0; k < 30; ++k) {
    const GaussianBump& p = a.bumps()[k];
    EXPECT_EQ(p.amplitude, b.bumps()[k].amplitude);
    EXPECT_EQ(p.x, b.bumps()[k].x);
    EXPECT_EQ(p.y, b.bumps()[k].y);
    EXPECT_EQ(p.sigma, b.bumps()[k].sigma);
    if (p.amplitude != c.bumps()[k].amplitude || p.x != c.bumps()[k].x)
      ++differing;
    for (const GaussianBump& q : {p, c.bumps()[k]}) {
      const std::pair<double, Interval> drawn[] = {
          {q.amplitude, amp}, {q.sigma, sig}, {q.x, xr}, {q.y, yr}};
      for (const auto& [value, range] : drawn) {
        EXPECT_GE(value, range.lo);
        EXPECT_LT(value, range.hi);
      }
    }
  }
  EXPECT_GT(differing, 25);
  // Values are spread over the range, not collapsed.
  double xmin = 1e9, xmax = -1e9;
  for (const auto& p : a.bumps()) {
    xmin = std::min(xmin, p.x);
    xmax = std::max(xmax, p.x);
  }
  EXPECT_GT(xmax - xmin, 1.0);
  // A prefix property: the first bumps do not depend on the count.
  const GaussianTerrain d = GaussianTerrain::Random(42, 5, amp, sig, xr, yr);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(d.bumps()[k].x, a.bumps()[k].x);
  // Degenerate range gives the constant.
  const GaussianTerrain e =
      GaussianTerrain::Random(7, 3, {0.01, 0.01}, {0.3, 0.3}, {1, 1}, {2, 2});
  for (const auto& p : e.bumps()) {
    EXPECT_EQ(p.amplitude, 0.01);
    EXPECT_EQ(p.sigma, 0.3);
  }
}

TEST(RandomGaussianTest, RejectsBadArguments) {
  const Interval amp{-0.04, 0.04}, sig{0.2, 0.4}, r{-1, 1};
  EXPECT_THROW(GaussianTerrain::Random(1, 0, amp, sig, r, r), SceneError);
  EXPECT_THROW(GaussianTerrain::Random(1, 3, {0.1, -0.1}, sig, r, r),
               SceneError);
  EXPECT_THROW(GaussianTerrain::Random(1, 3, amp, {0.0, 0.4}, r, r),
               SceneError);
  EXPECT_THROW(GaussianTerrain::Random(1, 3, amp, sig, {2, 1}, r), SceneError);
}

TEST(TerrainFactoryTest, BuildsEveryType) {
  TerrainSpec s;
  EXPECT_NE(dynamic_cast<const PlaneTerrain*>(MakeTerrain(s).get()), nullptr);
  s.type = TerrainSpec::Type::kIncline;
  s.slope_rad = 0.1;
  EXPECT_NE(dynamic_cast<const InclineTerrain*>(MakeTerrain(s).get()), nullptr);
  s.type = TerrainSpec::Type::kGaussians;
  s.bumps = SomeBumps();
  EXPECT_NE(dynamic_cast<const GaussianTerrain*>(MakeTerrain(s).get()),
            nullptr);
  s.random =
      TerrainSpec::Random{3, 4, {-0.01, 0.01}, {0.2, 0.3}, {0, 1}, {0, 1}};
  auto g = MakeTerrain(s);
  EXPECT_EQ(dynamic_cast<const GaussianTerrain&>(*g).bumps().size(), 4u);
  s.type = TerrainSpec::Type::kSinusoid;
  s.components = {{0.01, 1.0, 2.0, 0.0, 0.0}};
  EXPECT_NE(dynamic_cast<const SinusoidTerrain*>(MakeTerrain(s).get()),
            nullptr);
  s.type = TerrainSpec::Type::kHeightmap;
  s.file = "/nonexistent.csv";
  EXPECT_THROW(MakeTerrain(s), SceneError);
  for (const char* name :
       {"plane", "incline", "gaussians", "sinusoid", "heightmap"}) {
    ASSERT_TRUE(TerrainTypeFromString(name).has_value());
    EXPECT_STREQ(ToString(*TerrainTypeFromString(name)), name);
  }
  EXPECT_FALSE(TerrainTypeFromString("mountain").has_value());
}

}  // namespace
}  // namespace quasiroll
