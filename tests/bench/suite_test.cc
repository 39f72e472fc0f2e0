// Suite loading: grid expansion, defaults, run ids, and rejection of bad
// suites with the entry path and value in the message.
#include "quasiroll/bench/harness/suite.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "quasiroll/core/dae.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::bench {
namespace {

const std::string kScenes = std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes";

Suite Load(const std::string& text) {
  return LoadSuiteFromString(text, "test.yaml", kScenes);
}

// Expects a SceneError whose message contains every fragment.
void ExpectRejected(const std::string& text,
                    std::initializer_list<std::string> fragments) {
  try {
    Load(text);
    ADD_FAILURE() << "suite accepted:\n" << text;
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    for (const std::string& f : fragments)
      EXPECT_NE(msg.find(f), std::string::npos)
          << "'" << f << "' not in: " << msg;
  }
}

const char* kBase = R"(
scenes:
  - {file: paper.yaml, overrides: {time: {t_end: 2}}}
  - {name: flat5, file: flat.yaml, overrides: {time: {t_end: 5}, mu: 0.8}}
)";

TEST(BenchSuite, ExpandsTheGridInOrderWithDefaults) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  wp:
    scenes: [paper]
    nlp: [newton, ceres]
    dae: [rk-projection, ida]
    coupling: [zoh, coupled]
    dt: [0.1, 0.05]
  sweep:
    mu: [0.3, 0.5]
)");
  ASSERT_EQ(s.scenes.size(), 2u);
  EXPECT_EQ(s.scenes[0].name, "paper");
  EXPECT_EQ(s.scenes[1].name, "flat5");
  EXPECT_EQ(s.scenes[1].scene.mu, 0.8);
  ASSERT_EQ(s.runs.size(), 16u + 4u);
  // Innermost axis is dt.
  EXPECT_EQ(s.runs[0].dt, 0.1);
  EXPECT_EQ(s.runs[1].dt, 0.05);
  EXPECT_EQ(s.runs[0].nlp, "newton");
  EXPECT_EQ(s.runs[15].nlp, "ceres");
  EXPECT_EQ(s.runs[15].dae, "ida");
  EXPECT_EQ(s.runs[15].coupling, Coupling::kCoupled);
  // Defaults of the sweep group: scene dt, scene epsilon, newton +
  // rk-projection + zoh, every scene.
  const RunSpec& r = s.runs[16];
  EXPECT_EQ(r.group, "sweep");
  EXPECT_EQ(r.scene, "paper");
  EXPECT_EQ(r.mu, 0.3);
  EXPECT_EQ(r.dt, 0.05);
  EXPECT_EQ(r.t_end, 2);
  EXPECT_EQ(r.eps, 1e-8);
  EXPECT_EQ(r.nlp, "newton");
  EXPECT_EQ(r.dae, "rk-projection");
  EXPECT_EQ(s.runs[18].scene, "flat5");
  EXPECT_EQ(s.runs[18].t_end, 5);
  std::set<std::string> ids;
  for (const RunSpec& run : s.runs) {
    EXPECT_TRUE(ids.insert(run.run_id).second) << run.run_id;
    for (char c : run.run_id)
      EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(c)) || c == '-' ||
                  c == '_' || c == '.')
          << run.run_id;
  }
  EXPECT_EQ(s.runs[16].run_id.rfind("sweep-paper-newton-rk-projection-zoh-", 0),
            0u)
      << s.runs[16].run_id;
}

TEST(BenchSuite, RunIdsAreDeterministic) {
  const std::string text =
      std::string(kBase) + "groups:\n  g:\n    dt: [0.1, 0.05]\n";
  const Suite a = Load(text), b = Load(text);
  ASSERT_EQ(a.runs.size(), b.runs.size());
  for (std::size_t i = 0; i < a.runs.size(); ++i)
    EXPECT_EQ(a.runs[i].run_id, b.runs[i].run_id);
}

TEST(BenchSuite, SceneFieldsAreGenericAxes) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  g:
    scenes: [paper]
    dt: [0.1, 0.05]
    scene_fields:
      mass: [5, 10]
      initial.yaw: 0.3
      joint_rates: [[0, 0.6, 0, 0.6, 0, 0.6], [0, 0.3, 0, 0.3, 0, 0.3]]
)");
  // dt x mass x yaw x joint_rates, the generic axes innermost in file order.
  ASSERT_EQ(s.runs.size(), 2u * 2u * 1u * 2u);
  EXPECT_EQ(s.runs[0].dt, 0.1);
  EXPECT_EQ(s.runs[4].dt, 0.05);
  ASSERT_EQ(s.runs[3].scene_fields.size(), 3u);
  EXPECT_EQ(s.runs[3].scene_fields[0].first, "mass");
  EXPECT_EQ(s.runs[3].scene_fields[0].second, "10");
  EXPECT_EQ(s.runs[3].scene_fields[1].first, "initial.yaw");
  EXPECT_EQ(s.runs[1].scene_fields[2].second, "[0, 0.3, 0, 0.3, 0, 0.3]");
  const Scene scene = RunScene(s, s.runs[3]);
  EXPECT_EQ(scene.mass, 10.0);
  EXPECT_EQ(scene.yaw0, 0.3);
  EXPECT_EQ(scene.joint_rates[1], 0.3);
  EXPECT_EQ(RunScene(s, s.runs[0]).mass, 5.0);
  // The swept fields are part of the key, hence of the run id, and only
  // appended: a group without them keeps the fixed grid's key.
  EXPECT_NE(s.runs[0].key.find(";scene.mass=5;scene.initial.yaw=0.3;"),
            std::string::npos)
      << s.runs[0].key;
  std::set<std::string> ids;
  for (const RunSpec& r : s.runs) EXPECT_TRUE(ids.insert(r.run_id).second);
  // The reference scene carries them too (they change the motion).
  EXPECT_EQ(ReferenceScene(s, s.runs[3]).mass, 10.0);
}

TEST(BenchSuite, RejectsBadSceneFieldAxes) {
  const std::string base = std::string(kBase) + "groups:\n  g:\n";
  ExpectRejected(base + "    scene_fields: {mu: [0.2, 0.3]}\n",
                 {"groups.g.scene_fields.mu", "use the group key mu",
                  "allowed:", "got \"mu\""});
  ExpectRejected(base + "    scene_fields: {terrain.height: 1}\n",
                 {"groups.g.scene_fields.terrain.height", "seed / roughness"});
  ExpectRejected(base + "    scene_fields: {mass: [5, -1]}\n",
                 {"groups.g.scene_fields.mass[1]", "mass", "> 0", "-1"});
  ExpectRejected(base + "    scene_fields: {mass: [5, 5]}\n",
                 {"groups.g.scene_fields.mass[1]", "duplicate"});
  ExpectRejected(base + "    scene_fields: {robot.tube_radius: 0.09}\n",
                 {"groups.g.scene_fields.robot.tube_radius",
                  "must be < robot.major_radius"});
  ExpectRejected(base + "    scene_fields: {mass: []}\n",
                 {"groups.g.scene_fields.mass", "empty grid axis"});
  ExpectRejected(base + "    scene_fields: []\n",
                 {"groups.g.scene_fields", "non-empty mapping"});
}

TEST(BenchSuite, BackendOptionsAreAxes) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  g:
    scenes: [paper]
    nlp: [ipopt, ipopt-mumps]
    dae: [rk-projection]
    rk_method: dp54
    nlp_options: {mu_strategy: [monotone, adaptive], acceptable_iter: 5}
    dae_options: {projection_tolerance: [1.0e-12, 1.0e-10]}
)");
  // nlp x mu_strategy x acceptable_iter x projection_tolerance.
  ASSERT_EQ(s.runs.size(), 2u * 2u * 1u * 2u);
  const RunSpec& r = s.runs[3];
  EXPECT_EQ(r.nlp, "ipopt");
  EXPECT_EQ(r.nlp_options.at("mu_strategy"), "adaptive");
  EXPECT_EQ(r.nlp_options.at("acceptable_iter"), "5");
  EXPECT_EQ(r.dae_options.at("projection_tolerance"), "1.0e-10");
  // The shorthand group key reaches the integrator option of that name.
  EXPECT_EQ(r.dae_options.at("rk_method"), "dp54");
  // sigma / dae_index are not rk-projection options: not passed.
  EXPECT_EQ(r.dae_options.count("baumgarte_sigma"), 0u);
  EXPECT_EQ(r.dae_options.count("dae_index"), 0u);
  const SimulationOptions o = ResolveRun(s, r).options;
  EXPECT_EQ(o.nlp_options, r.nlp_options);
  EXPECT_EQ(o.dae_options, r.dae_options);
  // Explicit options are appended to the key (names in order).
  EXPECT_NE(r.key.find(";nlp_options.acceptable_iter=5;nlp_options.mu_"
                       "strategy=adaptive;dae_options.projection_tolerance="
                       "1.0e-10"),
            std::string::npos)
      << r.key;
  std::set<std::string> ids;
  for (const RunSpec& run : s.runs) EXPECT_TRUE(ids.insert(run.run_id).second);
}

TEST(BenchSuite, ShorthandsReachOnlyIntegratorsThatHaveTheOption) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  g:
    scenes: [paper]
    dae: [rk-baumgarte, rk-projection, ida]
    sigma: 20
    dae_index: 1
)");
  ASSERT_EQ(s.runs.size(), 3u);
  EXPECT_EQ(s.runs[0].dae_options.at("baumgarte_sigma"), "20");
  EXPECT_EQ(s.runs[0].dae_options.at("rk_method"), "rk4");
  EXPECT_EQ(s.runs[0].dae_options.count("dae_index"), 0u);
  EXPECT_EQ(s.runs[1].dae_options.count("baumgarte_sigma"), 0u);
  if (IntegratorRegistry::Has("ida")) {
    EXPECT_EQ(s.runs[2].dae_options.at("dae_index"), "1");
    EXPECT_EQ(s.runs[2].dae_options.at("baumgarte_sigma"), "20");
    EXPECT_EQ(s.runs[2].dae_options.count("rk_method"), 0u);
  }
  // An explicit integrator option with a shorthand sets its column too.
  const Suite e = Load(std::string(kBase) + R"(
groups:
  g:
    scenes: [paper]
    dae: [rk-baumgarte]
    dae_options: {baumgarte_sigma: [10, 40]}
)");
  ASSERT_EQ(e.runs.size(), 2u);
  EXPECT_EQ(e.runs[1].sigma, 40.0);
  EXPECT_EQ(e.runs[1].dae_options.at("baumgarte_sigma"), "40");
}

TEST(BenchSuite, RejectsUnknownAndIllTypedBackendOptions) {
  const std::string base = std::string(kBase) + "groups:\n  g:\n";
  ExpectRejected(base +
                     "    nlp: [newton]\n    nlp_options: {mu_strategy: "
                     "adaptive}\n",
                 {"groups.g.nlp_options.mu_strategy", "NLP backend 'newton'",
                  "known: ", "rank_pivot_ratio"});
  // Known to one backend of the group but not to the other.
  ExpectRejected(
      base +
          "    dae: [rk-projection, rk-baumgarte]\n"
          "    dae_options: {baumgarte_sigma: 5}\n",
      {"groups.g.dae_options.baumgarte_sigma", "integrator 'rk-projection'"});
  ExpectRejected(
      base +
          "    dae: [rk-projection]\n"
          "    dae_options: {rk_method: [rk4, euler]}\n",
      {"groups.g.dae_options.rk_method[1]", "rk4|dp54|bs32", "\"euler\""});
  ExpectRejected(base +
                     "    dae: [rk-projection]\n"
                     "    dae_options: {max_projection_iterations: 2.5}\n",
                 {"groups.g.dae_options.max_projection_iterations",
                  "expected an integer", "\"2.5\""});
  ExpectRejected(base +
                     "    dae: [rk-projection]\n"
                     "    dae_options: {projection_tolerance: -1}\n",
                 {"groups.g.dae_options.projection_tolerance", "(0, inf)"});
  ExpectRejected(base +
                     "    dae: [rk-projection]\n    rk_method: dp54\n"
                     "    dae_options: {rk_method: bs32}\n",
                 {"groups.g.dae_options.rk_method", "given twice"});
  ExpectRejected(base + "    nlp_options: []\n",
                 {"groups.g.nlp_options", "non-empty mapping"});
}

TEST(BenchSuite, ToleranceLadderSetsRtolAtolAndNlpTolerance) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  tol:
    scenes: [paper]
    dae: [ida]
    tol: [1.0e-4, 1.0e-6]
    atol_ratio: 0.1
    nlp_tol: 1.0e-10
)");
  ASSERT_EQ(s.runs.size(), 2u);
  const SimulationOptions o = ResolveRun(s, s.runs[1]).options;
  EXPECT_EQ(o.integrator.rtol, 1e-6);
  EXPECT_DOUBLE_EQ(o.integrator.atol, 1e-7);
  EXPECT_EQ(o.quasi_static.residual_tolerance, 1e-10);
}

TEST(BenchSuite, SeedAndRoughnessSweepsChangeTheTerrain) {
  const Suite s = Load(R"(
scenes:
  - name: rnd
    file: flat.yaml
    overrides:
      time: {t_end: 1}
      terrain: {type: gaussians, random: {seed: 7, count: 5}}
groups:
  g:
    seed: [1, 2]
    roughness: [1, 0.5]
)");
  ASSERT_EQ(s.runs.size(), 4u);
  EXPECT_EQ(*s.runs[0].seed, 1u);
  const TerrainSpec a = SweptTerrain(s.scenes[0], 1, 1.0);
  const TerrainSpec b = SweptTerrain(s.scenes[0], 1, 0.5);
  ASSERT_TRUE(a.random.has_value());
  EXPECT_EQ(a.random->seed, 1u);
  ASSERT_FALSE(b.random.has_value());
  const auto bumps =
      GaussianTerrain::Random(1, 5, a.random->amplitude, a.random->sigma,
                              a.random->x, a.random->y)
          .bumps();
  ASSERT_EQ(b.bumps.size(), 5u);
  for (int i = 0; i < 5; ++i)
    EXPECT_EQ(b.bumps[i].amplitude, 0.5 * bumps[i].amplitude);
  EXPECT_NE(SceneCanonicalText(ReferenceScene(s, s.runs[0]), a, ""),
            SceneCanonicalText(ReferenceScene(s, s.runs[1]), b, ""));
  EXPECT_EQ(TerrainId(s.runs[1], s.scenes[0]), "rnd_s1_r0.5");
}

TEST(BenchSuite, RejectsUnknownBackend) {
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    nlp: [newton, foo]\n",
                 {"groups.g.nlp[1]", "\"foo\"", "newton"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dae: rk5\n",
                 {"groups.g.dae", "\"rk5\""});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    rk_method: [rk45]\n",
                 {"groups.g.rk_method[0]", "\"rk45\""});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    coupling: [full]\n",
                 {"groups.g.coupling[0]", "\"full\""});
}

TEST(BenchSuite, RejectsEmptyGrids) {
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dt: []\n",
                 {"groups.g.dt", "empty"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    nlp: []\n",
                 {"groups.g.nlp", "empty"});
  ExpectRejected(std::string(kBase) + "groups: {}\n", {"groups", "non-empty"});
  ExpectRejected("scenes: []\ngroups:\n  g: {}\n", {"scenes", "non-empty"});
}

// Verdict bounds (docs/harness.md): defaults, suite level, group override;
// the run key (and id) changes only for non-default bounds.
TEST(BenchSuite, BoundsAtSuiteAndGroupLevel) {
  const Suite plain =
      Load(std::string(kBase) + "groups:\n  g: {scenes: [paper]}\n");
  EXPECT_EQ(plain.runs[0].bounds.drift, 1e-3);
  EXPECT_EQ(plain.runs[0].bounds.gap, 1e-3);
  EXPECT_EQ(plain.runs[0].key.find("bounds"), std::string::npos);
  const Suite s = Load(std::string(kBase) +
                       "bounds: {drift: 1.0e-6}\n"
                       "groups:\n"
                       "  g: {scenes: [paper]}\n"
                       "  h: {scenes: [paper], bounds: {gap: 2.0e-4}}\n");
  EXPECT_EQ(s.runs[0].bounds.drift, 1e-6);
  EXPECT_EQ(s.runs[0].bounds.gap, 1e-3);
  EXPECT_EQ(s.runs[1].bounds.drift, 1e-6);  // suite's, group adds gap
  EXPECT_EQ(s.runs[1].bounds.gap, 2e-4);
  EXPECT_NE(s.runs[0].key.find("bounds=1e-06,0.001"), std::string::npos)
      << s.runs[0].key;
  EXPECT_NE(s.runs[0].run_id.substr(s.runs[0].run_id.size() - 8),
            plain.runs[0].run_id.substr(plain.runs[0].run_id.size() - 8));
  ExpectRejected(std::string(kBase) + "bounds: {drift: 0}\ngroups: {g: {}}\n",
                 {"bounds.drift", "0"});
  ExpectRejected(std::string(kBase) + "groups:\n  g: {bounds: {drift2: 1}}\n",
                 {"groups.g.bounds.drift2", "unknown key"});
  ExpectRejected(std::string(kBase) + "groups:\n  g: {bounds: 1}\n",
                 {"groups.g.bounds", "mapping"});
}

// Checkpoint spacing (docs/harness.md, Errors at checkpoints): default
// 0.3125 s, suite level, group override; the run key (and id) changes only
// for a non-default value.
TEST(BenchSuite, CheckpointIntervalAtSuiteAndGroupLevel) {
  const Suite plain =
      Load(std::string(kBase) + "groups:\n  g: {scenes: [paper]}\n");
  EXPECT_EQ(plain.runs[0].checkpoint_interval, 0.3125);
  EXPECT_EQ(plain.runs[0].key.find("checkpoint"), std::string::npos);
  const Suite s = Load(std::string(kBase) +
                       "checkpoint_interval: 0.5\n"
                       "groups:\n"
                       "  g: {scenes: [paper]}\n"
                       "  h: {scenes: [paper], checkpoint_interval: 0.25}\n");
  EXPECT_EQ(s.runs[0].checkpoint_interval, 0.5);
  EXPECT_EQ(s.runs[1].checkpoint_interval, 0.25);
  EXPECT_NE(s.runs[0].key.find(";checkpoint_interval=0.5"), std::string::npos)
      << s.runs[0].key;
  EXPECT_NE(s.runs[0].run_id.substr(s.runs[0].run_id.size() - 8),
            plain.runs[0].run_id.substr(plain.runs[0].run_id.size() - 8));
  ExpectRejected(
      std::string(kBase) + "checkpoint_interval: 0\ngroups: {g: {}}\n",
      {"checkpoint_interval", "0"});
  ExpectRejected(
      std::string(kBase) + "groups:\n  g: {checkpoint_interval: -1.0}\n",
      {"groups.g.checkpoint_interval", "-1"});
}

TEST(BenchSuite, RejectsUnknownKeys) {
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dtt: [0.1]\n",
                 {"groups.g.dtt", "unknown key"});
  ExpectRejected(std::string(kBase) + "group:\n  g: {}\n",
                 {"group", "unknown key"});
  ExpectRejected(R"(
scenes:
  - {file: paper.yaml, overrides: {mass2: 3}}
groups: {g: {}}
)",
                 {"scenes[0].overrides.mass2", "unknown key"});
}

TEST(BenchSuite, RejectsBadNumbers) {
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dt: [0.1, -0.05]\n",
                 {"groups.g.dt[1]", "-0.05"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dt: 0\n",
                 {"groups.g.dt", "0"});
  ExpectRejected(
      std::string(kBase) + "groups:\n  g:\n    scenes: [paper]\n    dt: [5]\n",
      {"groups.g.dt[0]", "t_end", "5"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    mu: [0.5, .nan]\n",
                 {"groups.g.mu[1]"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    tol: [\"1e-6\"]\n",
                 {"groups.g.tol[0]", "\"1e-6\""});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    dt: [0.1, 0.1]\n",
                 {"groups.g.dt[1]", "duplicate"});
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    repeats: 0\n",
                 {"groups.g.repeats", "0"});
}

TEST(BenchSuite, RejectsSweepsThatDoNotApply) {
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    seed: [3]\n",
                 {"groups.g.seed", "random", "3"});
  ExpectRejected(std::string(kBase) +
                     "groups:\n  g:\n    scenes: [flat5]\n    roughness: 2\n",
                 {"groups.g.roughness", "flat5", "2"});
}

TEST(BenchSuite, RejectsBadScenes) {
  ExpectRejected("scenes:\n  - {file: nope.yaml}\ngroups: {g: {}}\n",
                 {"scenes[0].file", "nope.yaml"});
  ExpectRejected(
      std::string(kBase) + "groups:\n  g:\n    scenes: [paper, hill]\n",
      {"groups.g.scenes[1]", "\"hill\""});
  ExpectRejected(
      "scenes:\n  - {file: paper.yaml}\n  - {file: paper.yaml}\ngroups: {g: "
      "{}}\n",
      {"scenes[1].name", "duplicate", "paper"});
  ExpectRejected(
      "scenes:\n  - {name: 'a b', file: paper.yaml}\ngroups: {g: {}}\n",
      {"scenes[0].name", "a b"});
  ExpectRejected(R"(
scenes:
  - {file: paper.yaml, overrides: {mu: -1}}
groups: {g: {}}
)",
                 {"scenes[0].overrides.mu", "-1"});
}

// bench/suites/stability.yaml (issue 14): one group per axis, named
// stability_<axis>, each with every NLP x DAE x coupling and at least three
// axis values; the default suite's stability groups use the same names.
TEST(BenchSuite, StabilitySuiteCoversEveryMethodOnEveryAxis) {
  const Suite s = LoadSuite(std::string(QUASIROLL_SOURCE_DIR) +
                            "/bench/suites/stability.yaml");
  const std::vector<std::string> axes = {"dt", "sigma_dt",  "tol",
                                         "mu", "roughness", "seed"};
  ASSERT_EQ(s.groups.size(), axes.size());
  for (const std::string& axis : axes) {
    const std::string group = "stability_" + axis;
    std::set<std::string> methods, values;
    for (const RunSpec& r : s.runs) {
      if (r.group != group) continue;
      methods.insert(r.nlp + "/" + r.dae + "/" + ToString(r.coupling));
      const std::string v =
          axis == "dt"         ? Num(r.dt)
          : axis == "sigma_dt" ? Num(r.sigma * r.dt)
          : axis == "tol"      ? Num(r.tol)
          : axis == "mu"       ? Num(r.mu)
          : axis == "roughness"
              ? Num(r.roughness)
              : (r.seed ? std::to_string(*r.seed) : std::string("-"));
      values.insert(v);
    }
    // Every registered integrator: a new one must join the stability suite.
    for (const char* nlp : {"newton", "ipopt", "slsqp", "ceres"})
      for (const std::string& dae : IntegratorRegistry::Names())
        for (const char* coupling : {"zoh", "coupled"})
          EXPECT_EQ(
              methods.count(std::string(nlp) + "/" + dae + "/" + coupling), 1u)
              << group << " lacks " << nlp << "/" << dae << "/" << coupling;
    EXPECT_GE(values.size(), 3u) << group;
  }
  const Suite d = LoadSuite(std::string(QUASIROLL_SOURCE_DIR) +
                            "/bench/suites/default.yaml");
  for (const std::string& g : d.groups) {
    if (g.rfind("stability", 0) != 0) continue;
    bool named = false;
    for (const std::string& axis : axes) named |= g == "stability_" + axis;
    EXPECT_TRUE(named) << "default.yaml group " << g;
  }
}

TEST(BenchSuite, ExclusiveGroupsAreTimedAloneAndKeyed) {
  const Suite s = Load(std::string(kBase) + R"(
groups:
  shared:
    scenes: [paper]
    repeats: 5
  alone:
    scenes: [paper]
    repeats: 5
    exclusive: true
  explicit_false:
    scenes: [paper]
    repeats: 5
    exclusive: false
)");
  ASSERT_EQ(s.runs.size(), 3u);
  EXPECT_FALSE(s.runs[0].exclusive);
  EXPECT_TRUE(s.runs[1].exclusive);
  EXPECT_FALSE(s.runs[2].exclusive);
  // Only an exclusive run's key says so: the keys (and run ids) of suites
  // without the key stay what they were.
  EXPECT_EQ(s.runs[0].key.find("exclusive"), std::string::npos);
  EXPECT_NE(s.runs[1].key.find(";exclusive=1"), std::string::npos);
  EXPECT_EQ(s.runs[2].key.find("exclusive"), std::string::npos);
  ExpectRejected(std::string(kBase) + "groups:\n  g:\n    exclusive: 2\n",
                 {"groups.g.exclusive", "2"});
}

// The main job's report shows every stability axis for every method: the
// default suite carries the stability suite's groups verbatim (same runs,
// same keys, on scenes of the same definition).
TEST(BenchSuite, DefaultSuiteCarriesTheStabilitySuitesGroups) {
  const std::string dir = std::string(QUASIROLL_SOURCE_DIR) + "/bench/suites/";
  const Suite d = LoadSuite(dir + "default.yaml");
  const Suite st = LoadSuite(dir + "stability.yaml");
  auto runs_of = [](const Suite& s) {
    std::vector<std::string> keys;
    for (const RunSpec& r : s.runs) {
      if (r.group.rfind("stability_", 0) != 0) continue;
      const SuiteScene& sc = s.scenes[r.scene_index];
      keys.push_back(r.key + "|" +
                     SceneCanonicalText(RunScene(s, r),
                                        SweptTerrain(sc, r.seed, r.roughness),
                                        sc.heightmap_digest));
    }
    return keys;
  };
  const std::vector<std::string> in_default = runs_of(d);
  EXPECT_EQ(in_default.size(), st.runs.size());
  EXPECT_EQ(in_default, runs_of(st));
}

// Work-precision on four problems, every group timed alone with >= 5
// repeats (issue 21 item 7).
TEST(BenchSuite, DefaultWorkPrecisionGroupsAreTimedAlone) {
  const Suite d = LoadSuite(std::string(QUASIROLL_SOURCE_DIR) +
                            "/bench/suites/default.yaml");
  std::set<std::string> problems;
  for (const RunSpec& r : d.runs) {
    if (r.group.rfind("work_precision", 0) != 0) continue;
    EXPECT_TRUE(r.exclusive) << r.run_id;
    EXPECT_GE(r.repeats, 5) << r.run_id;
    problems.insert(r.scene + "/" + Num(r.roughness));
  }
  EXPECT_GE(problems.size(), 4u);
}

TEST(BenchSuite, ShippedSuitesLoad) {
  for (const char* name : {"smoke", "default", "analytic", "stability"}) {
    const std::string path =
        std::string(QUASIROLL_SOURCE_DIR) + "/bench/suites/" + name + ".yaml";
    EXPECT_NO_THROW({
      const Suite s = LoadSuite(path);
      EXPECT_FALSE(s.runs.empty()) << name;
    }) << name;
  }
}

}  // namespace
}  // namespace quasiroll::bench
