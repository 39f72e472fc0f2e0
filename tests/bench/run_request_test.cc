// One RunRequest, one set of rules (bench/harness/run_request.h): the CLI and
// the Python module differ only in how they name keys.
#include "quasiroll/bench/harness/run_request.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>

#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll::bench {
namespace {

const std::string kScenes =
    std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes/";

std::string Flag(const std::string& key) {
  if (key == "dae_options") return "--dae-opt";
  std::string f = "--" + key;
  for (char& c : f)
    if (c == '_') c = '-';
  return f;
}
std::string Same(const std::string& key) { return key; }

std::string ErrorOf(const RunRequest& r, const KeyNamer& namer) {
  try {
    ResolveRunRequest(LoadScene(kScenes + "flat.yaml"), r, namer);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(RunRequest, DefaultsComeFromTheSceneAndTheRegistry) {
  const Scene scene = LoadScene(kScenes + "paper.yaml");
  RunRequest r;
  r.mu = 0.3;
  r.nlp_max_iter = 7;
  r.substeps = 4;
  const ResolvedRun run = ResolveRunRequest(scene, r, Flag);
  EXPECT_EQ(run.options.nlp,
            NlpSolverRegistry::WithRole(BackendRole::kDefault));
  EXPECT_EQ(run.options.dae,
            IntegratorRegistry::WithRole(BackendRole::kDefault));
  EXPECT_EQ(run.options.dt, scene.dt);
  EXPECT_EQ(run.options.t_end, scene.t_end);
  EXPECT_EQ(run.options.integrator.step, scene.dt / 4);
  EXPECT_EQ(run.options.quasi_static.max_iterations, 7);
  EXPECT_EQ(run.scene.mu, 0.3);
}

TEST(RunRequest, TimesAreNamedAsTheFrontEndSpellsThem) {
  RunRequest r;
  r.dt = 5;
  r.t_end = 1;
  EXPECT_EQ(ErrorOf(r, Flag),
            "--dt: must be <= the end time 1 s (--t-end), got 5");
  EXPECT_EQ(ErrorOf(r, Same), "dt: must be <= the end time 1 s (t_end), got 5");
  r.dt.reset();
  r.t_end = 0.01;  // flat.yaml's dt is larger
  EXPECT_NE(ErrorOf(r, Flag).find("--t-end: must be >= the hold interval"),
            std::string::npos);
  RunRequest bad;
  bad.nlp_max_iter = 0;
  EXPECT_EQ(ErrorOf(bad, Same),
            "nlp_max_iter: must be an integer in [1, 1000000], got 0");
  RunRequest bad_events;
  bad_events.event_tolerance = 0;
  EXPECT_NE(ErrorOf(bad_events, Flag).find("--event-tolerance: "),
            std::string::npos);
  bad_events.event_tolerance.reset();
  bad_events.event_points = 1001;
  EXPECT_EQ(ErrorOf(bad_events, Same),
            "event_points: must be an integer in [0, 1000], got 1001");
}

// The located-stop settings reach SimulationOptions from every front end,
// and a suite's run key names them only off their defaults.
TEST(RunRequest, EventSettingsReachTheSimulator) {
  RunRequest r;
  r.locate_events = false;
  r.event_points = 7;
  r.event_tolerance = 1e-6;
  r.locate_switches = false;
  const ResolvedRun run =
      ResolveRunRequest(LoadScene(kScenes + "paper.yaml"), r, Same);
  EXPECT_FALSE(run.options.locate_events);
  EXPECT_EQ(run.options.event_points, 7);
  EXPECT_EQ(run.options.event_tolerance, 1e-6);
  EXPECT_FALSE(run.options.locate_switches);
  const Suite suite = LoadSuiteFromString(
      "name: s\nscenes:\n  - {name: paper, file: paper.yaml}\ngroups:\n"
      "  g:\n    locate_events: [true, false]\n    event_tolerance: 1.0e-6\n",
      "<test>", kScenes);
  ASSERT_EQ(suite.runs.size(), 2u);
  const ResolvedRun on = ResolveRun(suite, suite.runs[0]);
  const ResolvedRun off = ResolveRun(suite, suite.runs[1]);
  EXPECT_TRUE(on.options.locate_events);
  EXPECT_FALSE(off.options.locate_events);
  EXPECT_EQ(off.options.event_tolerance, 1e-6);
  EXPECT_EQ(off.options.event_points, SimulationOptions{}.event_points);
  EXPECT_EQ(suite.runs[0].key.find("locate_events"), std::string::npos);
  EXPECT_NE(suite.runs[1].key.find(";locate_events=0"), std::string::npos);
  EXPECT_NE(suite.runs[0].key.find(";event_tolerance=1e-06"), std::string::npos)
      << suite.runs[0].key;
}

TEST(RunRequest, ShorthandsMapOntoIntegratorOptionsOnce) {
  const Scene scene = LoadScene(kScenes + "flat.yaml");
  RunRequest r;
  r.dae = "rk-baumgarte";
  r.sigma = 2;
  r.rk_method = "dp54";
  r.dae_index = 1;  // rk-baumgarte has no dae_index: a note, nothing else
  const ResolvedRun run = ResolveRunRequest(scene, r, Flag);
  EXPECT_EQ(run.options.dae_options.at("baumgarte_sigma"), "2");
  EXPECT_EQ(run.options.dae_options.at("rk_method"), "dp54");
  EXPECT_EQ(run.options.dae_options.count("dae_index"), 0u);
  ASSERT_EQ(run.notes.size(), 1u);
  EXPECT_EQ(run.notes[0],
            "--dae-index does not apply to rk-baumgarte (ignored)");
  // Given twice (shorthand and backend option): an error in every front end.
  r.dae_options["rk_method"] = "rk4";
  EXPECT_EQ(ErrorOf(r, Flag), "--rk-method: also given as --dae-opt rk_method");
  EXPECT_EQ(ErrorOf(r, Same), "rk_method: also given as dae_options rk_method");
}

// A backend whose option is named like a run setting ("substeps") would act
// next to the run's own setting: refused by the request and by suites.
class ShadowingIntegrator final : public Integrator {
 public:
  std::string name() const override { return "shadowing-test"; }
  OptionTable option_table() const override {
    return {OptionSpec::Int("substeps", 1, "clashes with the run setting")};
  }

 private:
  void DoIntegrate(ConstrainedOde&, double, double, Eigen::Ref<Eigen::VectorXd>,
                   const IntegratorOptions&,
                   IntegratorResult* result) override {
    result->status = IntegratorStatus::kConvergenceFailure;
  }
};

TEST(RunRequest, ABackendOptionMayNotShadowARunSetting) {
  RegisterBuiltinIntegrators();
  if (!IntegratorRegistry::Has("shadowing-test"))
    IntegratorRegistry::Register("shadowing-test", "test", [] {
      return std::make_unique<ShadowingIntegrator>();
    });
  RunRequest r;
  r.dae = "shadowing-test";
  EXPECT_NE(ErrorOf(r, Flag).find("--dae-opt: backend 'shadowing-test' "
                                  "declares an option named like the run "
                                  "setting --substeps"),
            std::string::npos);
  try {
    LoadSuiteFromString(
        "name: s\nscenes:\n  - {name: flat, file: flat.yaml}\ngroups:\n  g:\n"
        "    dae: [shadowing-test]\n",
        "<test>", kScenes);
    FAIL() << "a shadowing backend was accepted in a suite";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("groups.g.dae: backend "
                                         "'shadowing-test' declares an option "
                                         "named like the run setting substeps"),
              std::string::npos)
        << e.what();
  }
  // No built-in shadows a run setting.
  for (const std::string& n : IntegratorRegistry::Names()) {
    if (n == "shadowing-test") continue;
    EXPECT_EQ(ShadowedRunSetting(IntegratorRegistry::Create(n)->option_table()),
              "")
        << n;
  }
  RegisterBuiltinNlpSolvers();
  for (const std::string& n : NlpSolverRegistry::Names())
    EXPECT_EQ(ShadowedRunSetting(NlpSolverRegistry::Create(n)->option_table()),
              "")
        << n;
}

// A suite's run is a RunRequest like the CLI's: the same request given by
// hand resolves to the same options (shorthands, explicit options, times).
TEST(RunRequest, ASuiteRunResolvesLikeAnyOtherRequest) {
  const Suite suite = LoadSuiteFromString(
      "name: s\nscenes:\n  - {name: paper, file: paper.yaml}\ngroups:\n"
      "  g:\n    dae: [rk-baumgarte, rk-projection]\n    dt: 0.1\n    t_end: "
      "2\n"
      "    sigma: 7\n    tol: 1.0e-5\n    substeps: 2\n"
      "    nlp_max_iter: 40\n    contact_check: 0\n"
      "    dae_options: {rk_method: dp54}\n",
      "<test>", kScenes);
  ASSERT_EQ(suite.runs.size(), 2u);
  for (const RunSpec& run : suite.runs) {
    RunRequest byhand;
    byhand.dae = run.dae;
    byhand.dt = 0.1;
    byhand.t_end = 2;
    byhand.sigma = 7;
    byhand.tol = 1e-5;
    byhand.atol = 1e-7;  // atol_ratio 1e-2
    byhand.substeps = 2;
    byhand.nlp_max_iter = 40;
    byhand.contact_check = 0;
    byhand.dae_index = 2;
    byhand.dae_options["rk_method"] = "dp54";
    const ResolvedRun expected =
        ResolveRunRequest(LoadScene(kScenes + "paper.yaml"), byhand, Same);
    const ResolvedRun got = ResolveRun(suite, run);
    EXPECT_EQ(got.options.nlp, expected.options.nlp) << run.run_id;
    EXPECT_EQ(got.options.dae_options, expected.options.dae_options)
        << run.run_id;
    EXPECT_EQ(got.options.nlp_options, expected.options.nlp_options);
    EXPECT_EQ(got.options.integrator.step, expected.options.integrator.step);
    EXPECT_EQ(got.options.integrator.rtol, expected.options.integrator.rtol);
    EXPECT_DOUBLE_EQ(got.options.integrator.atol,
                     expected.options.integrator.atol);
    EXPECT_EQ(got.options.quasi_static.max_iterations, 40);
    EXPECT_EQ(got.options.second_contact_check_every, 0);
    EXPECT_EQ(got.options.t_end, 2.0);
    EXPECT_EQ(got.scene.mu, expected.scene.mu);
    EXPECT_EQ(got.scene.epsilon, expected.scene.epsilon);
    // The runs.csv fields carry what ran.
    EXPECT_EQ(run.dae_options, got.options.dae_options);
    EXPECT_EQ(run.rk_method, "dp54");
    EXPECT_EQ(run.dae_options.at("rk_method"), "dp54");
  }
  // The shorthand reached only the integrator that has the option.
  EXPECT_EQ(suite.runs[0].dae_options.at("baumgarte_sigma"), "7");
  EXPECT_EQ(suite.runs[1].dae_options.count("baumgarte_sigma"), 0u);
}

}  // namespace
}  // namespace quasiroll::bench
