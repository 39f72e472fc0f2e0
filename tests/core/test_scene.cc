// Scene loading: the shipped scenes, defaults, and rejected inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/terrains.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll {
namespace {

const std::string kSource = QUASIROLL_SOURCE_DIR;
const std::string kScenes = kSource + "/bench/scenes/";
const std::string kBad = kSource + "/tests/data/bad_scenes/";

// Reference terrain R1, typed in from model.md §9.3:
// {A_k, x_k, y_k, s_k}.
const double kR1[30][4] = {
    {0.0009, 1.0514, -0.5423, 0.3883},  {0.0360, -0.2292, -1.1830, 0.2857},
    {-0.0285, 1.3952, 0.3497, 0.3293},  {0.0359, 1.8854, 0.5278, 0.2512},
    {-0.0151, 1.3616, 0.8054, 0.3025},  {-0.0061, 2.3354, -0.5235, 0.3342},
    {0.0262, -0.4733, -0.6835, 0.2712}, {-0.0073, 1.0915, 0.3344, 0.3766},
    {0.0040, 0.8699, 0.7321, 0.3261},   {-0.0378, -0.4005, 1.1128, 0.3951},
    {0.0203, 1.4523, -0.8387, 0.3808},  {0.0031, 2.1284, -0.0427, 0.3362},
    {-0.0136, 1.2974, 0.9473, 0.4235},  {0.0231, 0.2323, -0.1855, 0.3764},
    {-0.0157, 2.0876, 0.2148, 0.4121},  {-0.0037, 1.0304, -1.1412, 0.3184},
    {-0.0293, 1.0348, 0.4163, 0.3587},  {-0.0078, 1.8097, 1.0058, 0.2893},
    {-0.0237, -0.1266, 0.7844, 0.4492}, {-0.0190, 2.0228, 0.9252, 0.2986},
    {0.0200, 1.5865, 0.3849, 0.3014},   {-0.0176, 1.9187, -0.6107, 0.2646},
    {-0.0012, 0.0132, 0.6444, 0.3016},  {0.0385, 1.9676, -0.6920, 0.4026},
    {0.0369, 0.0122, 0.7951, 0.3896},   {0.0180, -0.3390, -1.0495, 0.2757},
    {0.0033, 2.1367, 0.7812, 0.3252},   {-0.0178, 2.1561, -0.8052, 0.3342},
    {-0.0271, 2.2049, -0.2996, 0.3830}, {0.0376, 0.9101, -0.4398, 0.3412}};

double R1Height(double x, double y) {
  double h = 0.0;
  for (const auto& b : kR1) {
    const double dx = x - b[1], dy = y - b[2];
    h += b[0] * std::exp(-(dx * dx + dy * dy) / (2.0 * b[3] * b[3]));
  }
  return h;
}

void ExpectDefaultRobot(const Scene& s) {
  EXPECT_EQ(s.geometry.a, 0.25);
  EXPECT_EQ(s.geometry.b, 0.25);
  EXPECT_EQ(s.geometry.track, 0.4);
  EXPECT_EQ(s.geometry.z_h, 0.05);
  EXPECT_EQ(s.geometry.major_radius, 0.08);
  EXPECT_EQ(s.geometry.tube_radius, 0.02);
  EXPECT_EQ(s.geometry.camber_offset, 0.0);
  EXPECT_EQ(s.mass, 5.0);
  EXPECT_EQ(s.gravity, 9.8);
}

TEST(SceneTest, PaperSceneIsTheReferenceScene) {
  const Scene s = LoadScene(kScenes + "paper.yaml");
  EXPECT_EQ(s.name, "paper");
  EXPECT_EQ(s.source_path, kScenes + "paper.yaml");
  EXPECT_EQ(s.mode, ActuationMode::kPaper);
  ExpectDefaultRobot(s);
  EXPECT_EQ(s.mu, 0.5);
  EXPECT_EQ(s.dt, 0.05);
  EXPECT_EQ(s.t_end, 20.0);
  EXPECT_EQ(s.epsilon, 1e-8);
  EXPECT_EQ(s.x0, 0.0);
  EXPECT_EQ(s.y0, 0.0);
  EXPECT_EQ(s.yaw0, 0.0);
  EXPECT_EQ(s.joint_angles, (std::array<double, 6>{0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(s.joint_rates, (std::array<double, 6>{0, 0.6, 0, 0.6, 0, 0.6}));
  const auto* g = dynamic_cast<const GaussianTerrain*>(s.terrain.get());
  ASSERT_NE(g, nullptr);
  ASSERT_EQ(g->bumps().size(), 30u);
  for (int k = 0; k < 30; ++k) {
    SCOPED_TRACE("bump " + std::to_string(k + 1));
    EXPECT_EQ(g->bumps()[k].amplitude, kR1[k][0]);
    EXPECT_EQ(g->bumps()[k].x, kR1[k][1]);
    EXPECT_EQ(g->bumps()[k].y, kR1[k][2]);
    EXPECT_EQ(g->bumps()[k].sigma, kR1[k][3]);
  }
  for (const auto& p : {std::array<double, 2>{0, 0},
                        {0.5, 0.1},
                        {1.0, -0.3},
                        {1.7, 0.35},
                        {-0.4, -0.4},
                        {2.0, 0.9}}) {
    EXPECT_NEAR(s.terrain->Height(p[0], p[1]), R1Height(p[0], p[1]), 1e-15);
    EXPECT_NEAR(s.terrain->Evaluate(p[0], p[1]).h, R1Height(p[0], p[1]), 1e-15);
  }
}

TEST(SceneTest, FlatScene) {
  const Scene s = LoadScene(kScenes + "flat.yaml");
  ExpectDefaultRobot(s);
  EXPECT_EQ(s.mode, ActuationMode::kPaper);
  EXPECT_EQ(s.t_end, 20.0);
  EXPECT_EQ(s.yaw0, 0.0);
  const auto* p = dynamic_cast<const PlaneTerrain*>(s.terrain.get());
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->height(), 0.0);
}

TEST(SceneTest, Incline10Scene) {
  const Scene s = LoadScene(kScenes + "incline10.yaml");
  EXPECT_EQ(s.mode, ActuationMode::kPvc);
  EXPECT_EQ(s.mu, 0.5);
  EXPECT_EQ(s.t_end, 10.0);
  EXPECT_EQ(s.yaw0, 0.0);
  const auto* t = dynamic_cast<const InclineTerrain*>(s.terrain.get());
  ASSERT_NE(t, nullptr);
  EXPECT_NEAR(t->beta(), 10.0 * std::numbers::pi / 180.0, 1e-15);
  EXPECT_EQ(t->gamma(), 0.0);
  EXPECT_NEAR(s.terrain->Height(1.0, 0.3),
              std::tan(10.0 * std::numbers::pi / 180.0), 1e-15);
}

TEST(SceneTest, CircleScenesHaveTheConsistentRatesOfO2) {
  const double v = 0.06, phi = 0.5, L = 0.5, rho = 0.1, t = 0.4;
  const double omega = v * std::tan(phi) / L;
  for (const char* name : {"circle.yaml", "circle_pvc.yaml"}) {
    SCOPED_TRACE(name);
    const Scene s = LoadScene(kScenes + name);
    ExpectDefaultRobot(s);
    EXPECT_EQ(s.geometry.rho(), rho);
    EXPECT_EQ(s.geometry.wheelbase(), L);
    EXPECT_EQ(s.joint_angles[0], phi);
    EXPECT_EQ(s.joint_rates[0], 0.0);
    EXPECT_NEAR(s.joint_rates[1], v / (rho * std::cos(phi)), 1e-15);
    EXPECT_EQ(s.joint_rates[2], 0.0);
    EXPECT_NEAR(s.joint_rates[3], (v - omega * t / 2) / rho, 1e-15);
    EXPECT_EQ(s.joint_rates[4], 0.0);
    EXPECT_NEAR(s.joint_rates[5], (v + omega * t / 2) / rho, 1e-15);
    EXPECT_NE(dynamic_cast<const PlaneTerrain*>(s.terrain.get()), nullptr);
  }
  EXPECT_EQ(LoadScene(kScenes + "circle.yaml").mode, ActuationMode::kPaper);
  EXPECT_EQ(LoadScene(kScenes + "circle_pvc.yaml").mode, ActuationMode::kPvc);
}

TEST(SceneTest, CrabPvcScene) {
  const Scene s = LoadScene(kScenes + "crab_pvc.yaml");
  EXPECT_EQ(s.mode, ActuationMode::kPvc);
  EXPECT_EQ(s.joint_angles[0], 0.5);
  EXPECT_EQ(s.joint_rates[3], 0.6);
  EXPECT_EQ(s.joint_rates[5], 0.6);
}

TEST(SceneTest, EmptySceneTakesAllDefaults) {
  const Scene s = LoadSceneFromString("");
  const Scene d;
  EXPECT_EQ(s.name, "unnamed");
  ExpectDefaultRobot(s);
  EXPECT_EQ(s.mu, d.mu);
  EXPECT_EQ(s.epsilon, d.epsilon);
  EXPECT_EQ(s.dt, d.dt);
  EXPECT_EQ(s.t_end, d.t_end);
  EXPECT_EQ(s.mode, d.mode);
  EXPECT_EQ(s.joint_rates, d.joint_rates);
  ASSERT_NE(s.terrain, nullptr);
  EXPECT_EQ(s.terrain->Height(3.0, -4.0), 0.0);
  // The name defaults to the file stem.
  EXPECT_EQ(LoadSceneFromString("mu: 0.3", "/some/dir/my_scene.yaml").name,
            "my_scene");
  EXPECT_EQ(ToString(ActuationMode::kPaper), std::string("paper"));
  EXPECT_EQ(ToString(ActuationMode::kPvc), std::string("pvc"));
}

TEST(SceneTest, EveryTerrainTypeFromYaml) {
  Scene s = LoadSceneFromString(
      "terrain: {type: incline, slope_deg: -5, azimuth_deg: 90, height: 0.1}");
  EXPECT_NEAR(s.terrain->Height(0.0, 1.0),
              0.1 + std::tan(-5 * std::numbers::pi / 180), 1e-15);
  s = LoadSceneFromString(
      "terrain:\n  type: gaussians\n  random: {seed: 12345, count: 7, "
      "amplitude: [-0.01, 0.02], sigma: [0.3, 0.4], x: [0, 1], y: [-1, 0]}\n");
  const auto& g = dynamic_cast<const GaussianTerrain&>(*s.terrain);
  ASSERT_EQ(g.bumps().size(), 7u);
  const GaussianTerrain same = GaussianTerrain::Random(
      12345, 7, {-0.01, 0.02}, {0.3, 0.4}, {0, 1}, {-1, 0});
  for (std::size_t k = 0; k < 7; ++k)
    EXPECT_EQ(g.bumps()[k].y, same.bumps()[k].y);
  s = LoadSceneFromString(
      "terrain: {type: gaussians, random: {seed: 1, count: 3}}");
  EXPECT_EQ(dynamic_cast<const GaussianTerrain&>(*s.terrain).bumps().size(),
            3u);
  s = LoadSceneFromString(
      "terrain: {type: sinusoid, amplitude: 0.02, wavelength_x: 1.5, "
      "wavelength_y: .inf, phase_x: 0.5, height: 0.01}");
  EXPECT_NEAR(s.terrain->Height(0.2, 9.0),
              0.01 + 0.02 * std::cos(2 * std::numbers::pi * 0.2 / 1.5 + 0.5),
              1e-15);
  s = LoadSceneFromString(
      "terrain:\n  type: sinusoid\n  components:\n"
      "    - {amplitude: 0.01, wavelength_x: 1}\n"
      "    - {amplitude: 0.02, wavelength_y: 2, phase_y: 0.1}\n");
  EXPECT_EQ(
      dynamic_cast<const SinusoidTerrain&>(*s.terrain).components().size(), 2u);
  EXPECT_NEAR(s.terrain->Height(0.0, 0.0), 0.01 + 0.02 * std::cos(0.1), 1e-15);
}

TEST(SceneTest, HeightmapPathIsRelativeToTheSceneFile) {
  const Scene s = LoadScene(kBad + "heightmap_ok.yaml");
  EXPECT_EQ(s.name, "small_heightmap");
  const auto* h = dynamic_cast<const HeightmapTerrain*>(s.terrain.get());
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->xs().size(), 5u);
  EXPECT_NEAR(h->Height(0.0, 0.0), 0.04, 1e-15);
  EXPECT_TRUE(h->Contains(s.x0, s.y0));
  // From a string: relative to the origin's directory.
  const Scene t = LoadSceneFromString(
      "terrain: {type: heightmap, file: grid_ok.csv}", kBad + "inline.yaml");
  EXPECT_NE(dynamic_cast<const HeightmapTerrain*>(t.terrain.get()), nullptr);
}

TEST(YamlUtilTest, GenericReaders) {
  using namespace yaml;
  const YAML::Node n = ParseYaml(
      "a: 1.5\nb: [1, 2, 3]\nc: +.inf\nd: '7'\ne: 0x10\nf: [3, 1]\ng: 1e-3\n",
      "t");
  EXPECT_EQ(ReadDouble(n["a"], "a", Bounds::Positive()), 1.5);
  EXPECT_EQ(ReadVector(n["b"], "b", 3), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(ReadDouble(n["g"], "g"), 1e-3);
  EXPECT_TRUE(std::isinf(ReadDouble(n["c"], "c", Bounds{}.AllowInf())));
  EXPECT_THROW(ReadDouble(n["c"], "c"), SceneError);
  EXPECT_THROW(ReadDouble(n["d"], "d"), SceneError);  // quoted
  EXPECT_THROW(ReadDouble(n["e"], "e"), SceneError);  // hex not accepted
  EXPECT_THROW(ReadInterval(n["f"], "f"), SceneError);
  EXPECT_EQ(ReadString(n["d"], "d"), "7");
  EXPECT_THROW(CheckKeys(n, "", {"a", "b"}), SceneError);
  EXPECT_NO_THROW(CheckKeys(n, "", {"a", "b", "c", "d", "e", "f", "g"}));
  EXPECT_EQ(JoinKey("", "x"), "x");
  EXPECT_EQ(JoinKey("a.b", "x"), "a.b.x");
  EXPECT_EQ(JoinIndex("a", 3), "a[3]");
  EXPECT_EQ(FormatNumber(-0.2), "-0.2");
  // Overrides on an existing scene keep everything else.
  Scene s = LoadScene(kScenes + "paper.yaml");
  ReadSceneNode(ParseYaml("mu: 0.2\nmode: pvc\n", "override"), "cases[1]", "",
                &s);
  EXPECT_EQ(s.mu, 0.2);
  EXPECT_EQ(s.mode, ActuationMode::kPvc);
  EXPECT_EQ(dynamic_cast<const GaussianTerrain&>(*s.terrain).bumps().size(),
            30u);
  try {
    ReadSceneNode(ParseYaml("mu: -1", "override"), "cases[1]", "", &s);
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "cases[1].mu: must be > 0, got -1");
  }
}

// ----------------------------------------------------------- bad scenes ----

struct BadCase {
  const char* name;
  std::string yaml;  // scene text; if it ends in ".yaml", a file to load
  std::vector<std::string> needles;  // substrings of the message
};

std::ostream& operator<<(std::ostream& os, const BadCase& c) {
  return os << c.name;
}

class BadSceneTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadSceneTest, ThrowsSceneErrorNamingKeyAndValue) {
  const BadCase& c = GetParam();
  const bool is_file = c.yaml.size() > 5 && c.yaml.ends_with(".yaml");
  try {
    if (is_file) {
      LoadScene(c.yaml);
    } else {
      LoadSceneFromString(c.yaml, "mem.yaml");
    }
    ADD_FAILURE() << "no SceneError for " << c.name;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "multi-line: " << msg;
    for (const std::string& n : c.needles) {
      EXPECT_NE(msg.find(n), std::string::npos)
          << "'" << n << "' not in: " << msg;
    }
  }
}

const std::string kFourBumps =
    "terrain:\n  type: gaussians\n  bumps:\n"
    "    - {amplitude: 0.01, x: 0, y: 0, sigma: 0.3}\n"
    "    - {amplitude: 0.01, x: 1, y: 0, sigma: 0.3}\n"
    "    - {amplitude: 0.01, x: 2, y: 0, sigma: 0.3}\n";

INSTANTIATE_TEST_SUITE_P(
    All, BadSceneTest,
    ::testing::Values(
        BadCase{"missing_file",
                kBad + "does_not_exist.yaml",
                {kBad + "does_not_exist.yaml", "cannot open"}},
        BadCase{"syntax_error_string",
                "mass: [1, 2\nmu: 0.5\n",
                {"mem.yaml:", "YAML syntax error"}},
        BadCase{"syntax_error_file",
                kBad + "syntax_error.yaml",
                {kBad + "syntax_error.yaml:", "YAML syntax error"}},
        BadCase{"unknown_top_key", "mass: 5\nfoo: 1\n", {"foo: unknown key"}},
        BadCase{"unknown_nested_key",
                "robot: {a: 0.25, radius: 0.1}",
                {"robot.radius: unknown key"}},
        BadCase{"unknown_terrain_key",
                "terrain: {type: plane, slope_deg: 3}",
                {"terrain.slope_deg: unknown key"}},
        BadCase{"duplicate_key", "mass: 5\nmass: 6\n", {"mass: duplicate key"}},
        BadCase{"negative_mass", "mass: -5", {"mass: must be > 0, got -5"}},
        BadCase{"mu_negative", "mu: -0.1", {"mu: must be > 0, got -0.1"}},
        BadCase{"mu_zero", "mu: 0", {"mu: must be > 0, got 0"}},
        BadCase{"mu_nan", "mu: .nan", {"mu: must be finite, got nan"}},
        BadCase{"gravity_inf",
                "gravity: .inf",
                {"gravity: must be finite, got inf"}},
        BadCase{"x_minus_inf",
                "initial: {x: -.inf}",
                {"initial.x: must be finite, got -inf"}},
        BadCase{"nan_in_sequence",
                "initial: {joint_angles: [0, 0, .NaN, 0, 0, 0]}",
                {"initial.joint_angles[2]: must be finite, got nan"}},
        BadCase{"epsilon_zero", "epsilon: 0", {"epsilon: must be > 0, got 0"}},
        BadCase{"tube_ge_major",
                "robot: {tube_radius: 0.09}",
                {"robot.tube_radius: must be < robot.major_radius (0.08), got "
                 "0.09"}},
        BadCase{"tube_eq_major",
                "robot: {major_radius: 0.05, tube_radius: 0.05}",
                {"robot.tube_radius: must be < robot.major_radius (0.05), got "
                 "0.05"}},
        BadCase{"zero_track",
                "robot: {track: 0}",
                {"robot.track: must be > 0, got 0"}},
        BadCase{"wrong_type_string",
                "mass: abc",
                {"mass: expected a number, got \"abc\""}},
        BadCase{"wrong_type_quoted",
                "mass: \"5\"",
                {"mass: expected a number, got \"5\""}},
        BadCase{"wrong_type_mapping",
                "robot: 5",
                {"robot: expected a mapping, got \"5\""}},
        BadCase{
            "wrong_type_null", "mass:", {"mass: expected a number, got null"}},
        BadCase{"wrong_type_sequence_for_number",
                "mu: [1]",
                {"mu: expected a number, got a sequence of 1"}},
        BadCase{"joint_rates_length",
                "joint_rates: [0, 0.6, 0, 0.6, 0]",
                {"joint_rates: expected a sequence of 6 numbers, got 5"}},
        BadCase{"joint_rates_scalar",
                "joint_rates: 0.6",
                {"joint_rates: expected a sequence of 6 numbers, got \"0.6\""}},
        BadCase{"bad_mode",
                "mode: fast",
                {"mode: must be one of paper, pvc, got \"fast\""}},
        BadCase{"dt_gt_t_end",
                "time: {t_end: 1, dt: 2}",
                {"time.dt: must be <= time.t_end (1), got 2"}},
        BadCase{"dt_negative",
                "time: {dt: -0.05}",
                {"time.dt: must be > 0, got -0.05"}},
        BadCase{"t_end_zero",
                "time: {t_end: 0}",
                {"time.t_end: must be > 0, got 0"}},
        BadCase{"bad_terrain_type",
                "terrain: {type: mountain}",
                {"terrain.type: must be one of", "got \"mountain\""}},
        BadCase{"terrain_not_mapping",
                "terrain: flat",
                {"terrain: expected a mapping, got \"flat\""}},
        BadCase{
            "bump_sigma_negative",
            kFourBumps + "    - {amplitude: 0.01, x: 3, y: 0, sigma: -0.2}\n",
            {"terrain.bumps[3].sigma: must be > 0, got -0.2"}},
        BadCase{"bump_sigma_zero",
                kFourBumps + "    - {amplitude: 0.01, x: 3, y: 0, sigma: 0}\n",
                {"terrain.bumps[3].sigma: must be > 0, got 0"}},
        BadCase{"bump_missing_key",
                kFourBumps + "    - {amplitude: 0.01, x: 3, y: 0}\n",
                {"terrain.bumps[3].sigma: required key missing"}},
        BadCase{"bump_unknown_key",
                kFourBumps +
                    "    - {amplitude: 0.01, x: 3, y: 0, sigma: 1, z: 0}\n",
                {"terrain.bumps[3].z: unknown key"}},
        BadCase{"gaussians_empty",
                "terrain: {type: gaussians}",
                {"terrain: gaussians needs either 'bumps' or 'random'"}},
        BadCase{"gaussians_both",
                "terrain: {type: gaussians, bumps: [], random: {seed: 1, "
                "count: 2}}",
                {"terrain.random: not allowed together with terrain.bumps"}},
        BadCase{"random_count_zero",
                "terrain: {type: gaussians, random: {seed: 1, count: 0}}",
                {"terrain.random.count: must be in [1, 100000], got 0"}},
        BadCase{"random_count_float",
                "terrain: {type: gaussians, random: {seed: 1, count: 2.5}}",
                {"terrain.random.count: expected an integer, got \"2.5\""}},
        BadCase{"random_seed_negative",
                "terrain: {type: gaussians, random: {seed: -1, count: 2}}",
                {"terrain.random.seed: expected a non-negative integer, got "
                 "\"-1\""}},
        BadCase{"random_range_inverted",
                "terrain: {type: gaussians, random: {seed: 1, count: 2, x: [2, "
                "1]}}",
                {"terrain.random.x: lo must be <= hi, got [2, 1]"}},
        BadCase{"random_sigma_nonpositive",
                "terrain: {type: gaussians, random: {seed: 1, count: 2, sigma: "
                "[0, 1]}}",
                {"terrain.random.sigma[0]: must be > 0, got 0"}},
        BadCase{"incline_too_steep",
                "terrain: {type: incline, slope_deg: 90}",
                {"terrain.slope_deg: must be in (-89, 89), got 90"}},
        BadCase{"sinusoid_bad_wavelength",
                "terrain: {type: sinusoid, amplitude: 0.1, wavelength_x: -2}",
                {"terrain.wavelength_x: must be > 0, got -2"}},
        BadCase{"sinusoid_missing_amplitude",
                "terrain: {type: sinusoid}",
                {"terrain.amplitude: required key missing"}},
        BadCase{"heightmap_no_file",
                "terrain: {type: heightmap}",
                {"terrain.file: required key missing"}},
        BadCase{"heightmap_missing_file",
                kBad + "heightmap_missing_file.yaml",
                {"terrain.file: ", "no_such_grid.csv", "cannot open"}},
        BadCase{"heightmap_nonmonotone",
                kBad + "heightmap_nonmonotone.yaml",
                {"terrain.file: ", "grid_nonmonotone.csv:2:5",
                 "x must be strictly increasing", "got 0.25 after 0.5"}},
        BadCase{"heightmap_hole",
                kBad + "heightmap_hole.yaml",
                {"terrain.file: ", "grid_hole.csv:5:4", "missing value"}},
        BadCase{"heightmap_start_outside",
                kBad + "heightmap_start_outside.yaml",
                {"initial: start (x, y) must lie inside", "got (5, 0)"}},
        BadCase{"two_documents",
                "mass: 5\n---\nmass: 6\n",
                {"mem.yaml", "expected a single YAML document"}},
        BadCase{"root_not_mapping",
                "- 1\n- 2\n",
                {"expected a mapping, got a sequence of 2"}}),
    [](const ::testing::TestParamInfo<BadCase>& info) {
      return std::string(info.param.name);
    });

}  // namespace
}  // namespace quasiroll
