// References: detection of the analytic cases (model.md §9.1: O1, O2, O3),
// agreement of the numerical reference with the closed forms, and the disk
// cache.
#include "quasiroll/bench/harness/reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "quasiroll/bench/harness/metrics.h"
#include "quasiroll/bench/harness/reference_retry.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll::bench {
namespace {

namespace fs = std::filesystem;
const std::string kScenes =
    std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/";

struct Loaded {
  Scene scene;
  TerrainSpec terrain;
};

Loaded LoadWithSpec(const std::string& file, double t_end) {
  Loaded l;
  l.scene = LoadScene(kScenes + file);
  l.scene.t_end = t_end;
  const YAML::Node root = yaml::LoadYamlFile(kScenes + file);
  if (root["terrain"])
    l.terrain = yaml::ReadTerrainSpec(root["terrain"], "terrain", kScenes);
  return l;
}

TEST(BenchReference, DetectsTheAnalyticCases) {
  EXPECT_EQ(DetectAnalyticCase(LoadWithSpec("flat.yaml", 1).scene,
                               LoadWithSpec("flat.yaml", 1).terrain),
            AnalyticCase::kFlatStraight);
  for (const char* f : {"circle.yaml", "circle_pvc.yaml"}) {
    const Loaded l = LoadWithSpec(f, 1);
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain), AnalyticCase::kCircle)
        << f;
  }
  {
    const Loaded l = LoadWithSpec("incline10.yaml", 1);
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain), AnalyticCase::kIncline);
  }
  std::string why;
  {
    const Loaded l = LoadWithSpec("paper.yaml", 1);
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain, &why),
              AnalyticCase::kNone);
  }
  {
    // O2b crab: pvc with equal rear rates at phi1 != 0 is not a circle.
    const Loaded l = LoadWithSpec("crab_pvc.yaml", 1);
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain, &why),
              AnalyticCase::kNone);
    EXPECT_NE(why.find("O2"), std::string::npos) << why;
  }
  {
    // Incline below the pvc friction threshold (0.318914 uphill): no oracle.
    Loaded l = LoadWithSpec("incline10.yaml", 1);
    l.scene.mu = 0.3;
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain, &why),
              AnalyticCase::kNone);
    l.scene.mu = 0.32;
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain), AnalyticCase::kIncline);
    // Oblique heading: not covered.
    l.scene.yaw0 = 0.3;
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain, &why),
              AnalyticCase::kNone);
  }
  {
    // Flat with unequal rates (would turn and slip): no oracle.
    Loaded l = LoadWithSpec("flat.yaml", 1);
    l.scene.joint_rates[3] = 0.5;
    EXPECT_EQ(DetectAnalyticCase(l.scene, l.terrain), AnalyticCase::kNone);
  }
}

TEST(BenchReference, ClosedFormsMatchTheOracleNumbers) {
  {
    const Loaded l = LoadWithSpec("flat.yaml", 20);
    const AnalyticSolution a(l.scene, l.terrain, AnalyticCase::kFlatStraight);
    const TrajectorySample s = a.Sample(10);
    EXPECT_NEAR(s.position.x(), 0.6, 1e-15);  // 0.06 m/s
    EXPECT_NEAR(s.position.z(), 0.15, 1e-15);
    EXPECT_NEAR(s.contacts[0].normal_force, 24.5, 1e-12);
    EXPECT_NEAR(s.contacts[1].normal_force, 12.25, 1e-12);
  }
  {
    const Loaded l = LoadWithSpec("circle.yaml", 20);
    const AnalyticSolution a(l.scene, l.terrain, AnalyticCase::kCircle);
    // COM on a circle of radius 0.948774 m, yaw rate 0.065556 rad/s.
    const Vec3 c0 = a.Sample(0).position, c1 = a.Sample(7).position,
               c2 = a.Sample(19).position;
    const double radius =
        std::sqrt(std::pow(0.5 / std::tan(0.5), 2) + 0.25 * 0.25);
    EXPECT_NEAR(radius, 0.948774, 1e-6);
    // The centre is equidistant from all three samples.
    const Vec3 centre(-0.25 * 0 + 0.0, 0.5 / std::tan(0.5), 0.15);  // ICR
    const Vec3 icr =
        Vec3(0, 0, 0) + Vec3(-0.25, 0, 0) + Vec3(0, 0.5 / std::tan(0.5), 0);
    for (const Vec3& c : {c0, c1, c2})
      EXPECT_NEAR(std::hypot(c.x() - icr.x(), c.y() - icr.y()), radius, 1e-12);
    EXPECT_NEAR(centre.y(), icr.y(), 0);
    EXPECT_NEAR(a.Sample(10).rpy(2), 10 * 0.06555629878125485, 1e-12);
  }
  {
    const Loaded l = LoadWithSpec("incline10.yaml", 10);
    const AnalyticSolution a(l.scene, l.terrain, AnalyticCase::kIncline);
    const TrajectorySample s = a.Sample(0);
    EXPECT_NEAR(s.position.z(), 0.15231399178286176, 1e-12);
    EXPECT_NEAR(s.rpy(1), -10 * std::numbers::pi / 180, 1e-12);
    double sum = 0;
    for (const auto& c : s.contacts) sum += c.normal_force;
    EXPECT_NEAR(sum, 48.2556, 1e-4);                         // O3-num
    EXPECT_NEAR(s.contacts[0].normal_force, 21.5752, 1e-4);  // up
    // Distance along the slope after 10 s: 0.6 m less the creep of the
    // driven wheels (q = 4.255 / (0.5 * 13.340), |s| = 1e-8 q / sqrt(1 - q^2)
    // = 8.28e-9 m/s).
    EXPECT_NEAR((a.Sample(10).position - s.position).norm(), 0.6 - 8.28e-8,
                1e-10);
  }
}

// Numerical reference (coupled, rk-projection, RK4 at dt/16) against the
// closed form over the same output grid.
AccuracyMetrics Agreement(const std::string& file, double t_end,
                          std::string* kind, void (*modify)(Scene*) = nullptr) {
  Loaded l = LoadWithSpec(file, t_end);
  if (modify) modify(&l.scene);
  const AnalyticCase ac = DetectAnalyticCase(l.scene, l.terrain);
  EXPECT_NE(ac, AnalyticCase::kNone) << file;
  const SimulationResult num =
      ComputeNumericalReference(l.scene, ReferenceSettings{}, kind);
  EXPECT_EQ(num.status, "success") << num.stop_reason;
  const AnalyticSolution a(l.scene, l.terrain, ac);
  std::vector<TrajectorySample> exact;
  for (const TrajectorySample& s : num.samples) exact.push_back(a.Sample(s.t));
  return CompareTrajectories(num.samples, exact, true);
}

// Tolerances. The numerical reference integrates a smooth ODE with RK4 at
// h = 3.125 ms: the local truncation error ~ (omega h)^5 R with
// omega <= 0.07 rad/s is far below 1e-15 m, so what remains is the
// quasi-static solve (scaled residual <= 1e-12, i.e. velocity errors of
// ~1e-12 * v0 = 6e-14 m/s, integrated over <= 20 s: ~1e-12 m), the
// projection tolerance (1e-12) and rounding accumulated over ~6400 steps
// (~1e-13 m). We allow 1e-9 m / 1e-9 rad, three orders of magnitude above
// these estimates yet six below the error of the cheapest method in the
// suites (~1e-5 m). Normal forces: the NLP solution at residual 1e-12 of
// F0 = 49 N gives ~1e-10 N; we allow 1e-8 N. Slip: the regularised law
// gives creep <= eps = 1e-8 m/s on these oracles; we allow 1e-9 m/s.
constexpr double kPosTol = 1e-9, kRotTol = 1e-9, kForceTol = 1e-8,
                 kSlipTol = 1e-9;

TEST(BenchReference, NumericalAgreesWithAnalyticFlat) {
  std::string kind;
  const AccuracyMetrics m = Agreement("flat.yaml", 10, &kind);
  RecordProperty("pos_max", std::to_string(m.pos_max));
  std::printf("flat: pos_max %.3e rot_max %.3e force_rms %.3e slip %.3e\n",
              m.pos_max, m.rot_max, m.force_rms, m.slip_rms);
  EXPECT_LT(m.pos_max, kPosTol);
  EXPECT_LT(m.rot_max, kRotTol);
  EXPECT_LT(m.force_rms, kForceTol);
  EXPECT_LT(m.slip_rms, kSlipTol);
}

TEST(BenchReference, NumericalAgreesWithAnalyticCircle) {
  for (const char* f : {"circle.yaml", "circle_pvc.yaml"}) {
    std::string kind;
    const AccuracyMetrics m = Agreement(f, 10, &kind);
    std::printf("%s: pos_max %.3e rot_max %.3e force_rms %.3e slip %.3e\n", f,
                m.pos_max, m.rot_max, m.force_rms, m.slip_rms);
    EXPECT_LT(m.pos_max, kPosTol) << f;
    EXPECT_LT(m.rot_max, kRotTol) << f;
    EXPECT_LT(m.force_rms, kForceTol) << f;
    EXPECT_LT(m.slip_rms, kSlipTol) << f;
  }
}

TEST(BenchReference, NumericalAgreesWithAnalyticIncline) {
  // pvc uphill (the shipped scene), pvc downhill, paper mode uphill/downhill.
  using Modifier = void (*)(Scene*);
  const std::pair<const char*, Modifier> cases[] = {
      {"pvc up", nullptr},
      {"pvc down", [](Scene* s) { s->yaw0 = std::numbers::pi; }},
      {"paper up", [](Scene* s) { s->mode = ActuationMode::kPaper; }},
      {"paper down",
       [](Scene* s) {
         s->mode = ActuationMode::kPaper;
         s->yaw0 = -std::numbers::pi;
       }},
  };
  for (const auto& [name, modify] : cases) {
    std::string kind;
    const AccuracyMetrics m = Agreement("incline10.yaml", 10, &kind, modify);
    std::printf(
        "incline %s: pos_max %.3e rot_max %.3e force_rms %.3e slip %.3e\n",
        name, m.pos_max, m.rot_max, m.force_rms, m.slip_rms);
    EXPECT_LT(m.pos_max, kPosTol) << name;
    EXPECT_LT(m.rot_max, kRotTol) << name;
    EXPECT_LT(m.force_rms, kForceTol) << name;
    EXPECT_LT(m.slip_rms, kSlipTol) << name;
  }
}

TEST(BenchReference, CacheRoundTripIsExact) {
  const fs::path dir =
      fs::temp_directory_path() / "quasiroll_reference_cache_test";
  fs::remove_all(dir);
  Loaded l = LoadWithSpec("paper.yaml", 0.5);
  const ReferenceSettings settings;
  const Reference a = LoadOrComputeReference(dir.string(), l.scene, l.terrain,
                                             "", settings, "paper");
  EXPECT_EQ(a.kind, "numerical");
  EXPECT_TRUE(fs::exists(dir / "references" / (a.hash + ".csv")));
  EXPECT_TRUE(fs::exists(dir / "references" / (a.hash + ".json")));
  const Reference b = LoadOrComputeReference(dir.string(), l.scene, l.terrain,
                                             "", settings, "paper");
  ASSERT_EQ(a.samples.size(), b.samples.size());
  ASSERT_EQ(a.samples.size(), 41u);  // 0.5 s at dt/4 = 0.0125 s
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].t, b.samples[i].t);
    EXPECT_EQ(a.samples[i].position, b.samples[i].position);
    EXPECT_EQ(a.samples[i].contacts[2].normal_force,
              b.samples[i].contacts[2].normal_force);
  }
  EXPECT_EQ(a.status, b.status);
  // A cache written under other stop rules (reference_retry.h) is
  // recomputed; one under the current rules is read as it is.
  const fs::path json = dir / "references" / (a.hash + ".json");
  auto rewrite = [&](const std::string& from, const std::string& to) {
    std::ifstream in(json);
    std::stringstream text;
    text << in.rdbuf();
    std::string t = text.str();
    const std::size_t at = t.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    std::ofstream(json) << t;
  };
  rewrite("\"status\":\"success\"", "\"status\":\"EDITED\"");
  EXPECT_EQ(LoadOrComputeReference(dir.string(), l.scene, l.terrain, "",
                                   settings, "paper")
                .status,
            "EDITED");
  rewrite("\"stop_rules\":" + std::to_string(kReferenceStopRules),
          "\"stop_rules\":1");
  EXPECT_EQ(LoadOrComputeReference(dir.string(), l.scene, l.terrain, "",
                                   settings, "paper")
                .status,
            "success");
  // A different scene parameter is a different key.
  l.scene.mu = 0.3;
  EXPECT_NE(ReferenceKey(l.scene, l.terrain, "", settings), a.key);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace quasiroll::bench
