// A method's identity (docs/harness.md, "Method identity"): backends,
// coupling and the non-default backend options, the same text for the
// same run whichever front end resolved it.
#include "quasiroll/bench/harness/method_id.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "quasiroll/bench/harness/run_request.h"
#include "quasiroll/bench/harness/suite.h"

namespace quasiroll::bench {
namespace {

const std::string kScenes = std::string(QUASIROLL_SOURCE_DIR) + "/bench/scenes";

Suite Load(const std::string& groups) {
  return LoadSuiteFromString(
      "scenes:\n  - {file: paper.yaml, overrides: {time: {t_end: 1}}}\n"
      "groups:\n" +
          groups,
      "test.yaml", kScenes);
}

TEST(MethodId, DefaultsAreOmitted) {
  EXPECT_EQ(MethodId("newton", {}, "rk-projection", {}, Coupling::kZoh),
            "newton/rk-projection/zoh");
  // Given at their defaults, in any spelling: still the default method.
  EXPECT_EQ(
      MethodId("newton", {{"armijo", "0.0002"}}, "rk-projection",
               {{"rk_method", "rk4"}, {"projection_tolerance", "1.0e-12"}},
               Coupling::kCoupled),
      "newton/rk-projection/coupled");
}

TEST(MethodId, NonDefaultsAreSortedAndFormattedAlike) {
  const GivenOptions dae = {{"rk_method", "dp54"},
                            {"projection_tolerance", "1.0e-10"},
                            {"max_projection_iterations", "20"}};
  const std::string id = MethodId("newton", {{"armijo", "1e-3"}},
                                  "rk-projection", dae, Coupling::kCoupled);
  EXPECT_EQ(id,
            "newton[armijo=0.001]/rk-projection[max_projection_iterations=20,"
            "projection_tolerance=1e-10,rk_method=dp54]/coupled");
  // Stable: another spelling of the same values, the same text.
  EXPECT_EQ(MethodId("newton", {{"armijo", "0.0010"}}, "rk-projection",
                     {{"rk_method", "dp54"},
                      {"projection_tolerance", "1e-10"},
                      {"max_projection_iterations", "20"}},
                     Coupling::kCoupled),
            id);
  EXPECT_EQ(NonDefaultOptions({}, {}, "none"), "");
}

TEST(MethodId, BadOptionsAndUnknownBackends) {
  EXPECT_THROW(MethodId("newton", {{"no_such_option", "1"}}, "rk-projection",
                        {}, Coupling::kZoh),
               std::invalid_argument);
  EXPECT_THROW(MethodId("newton", {}, "rk-projection", {{"rk_method", "x"}},
                        Coupling::kZoh),
               std::invalid_argument);
  // No table to compare with (a plugin not loaded): every given option.
  EXPECT_EQ(MethodId("not-registered", {{"b", "2"}, {"a", "1"}},
                     "rk-projection", {}, Coupling::kZoh),
            "not-registered[a=1,b=2]/rk-projection/zoh");
}

TEST(MethodId, SuiteRunsDifferingInABackendOptionAreDifferentMethods) {
  const Suite s = Load(
      "  g:\n"
      "    dae: [rk-projection]\n"
      "    dae_options: {projection_tolerance: [1.0e-12, 1.0e-10]}\n"
      "  rk:\n"
      "    dae: [rk-projection]\n"
      "    rk_method: [rk4, dp54]\n"
      "  sigma:\n"
      "    dae: [rk-baumgarte, rk-projection]\n"
      "    sigma: 20\n");
  ASSERT_EQ(s.runs.size(), 6u);
  EXPECT_EQ(MethodId(s.runs[0]), "newton/rk-projection/zoh");
  EXPECT_EQ(MethodId(s.runs[1]),
            "newton/rk-projection[projection_tolerance=1e-10]/zoh");
  EXPECT_EQ(MethodId(s.runs[2]), "newton/rk-projection/zoh");
  EXPECT_EQ(MethodId(s.runs[3]), "newton/rk-projection[rk_method=dp54]/zoh");
  // The shorthand names the integrator option it stands for; an integrator
  // without that option ran its default method.
  EXPECT_EQ(MethodId(s.runs[4]), "newton/rk-baumgarte[baumgarte_sigma=20]/zoh");
  EXPECT_EQ(MethodId(s.runs[5]), "newton/rk-projection/zoh");
}

TEST(MethodId, SuiteAndRunRequestAgree) {
  const Suite s = Load(
      "  g:\n"
      "    dae: [rk-projection]\n"
      "    coupling: coupled\n"
      "    rk_method: dp54\n");
  ASSERT_EQ(s.runs.size(), 1u);
  RunRequest request;
  request.nlp = "newton";
  request.dae = "rk-projection";
  request.coupling = Coupling::kCoupled;
  request.rk_method = "dp54";
  const ResolvedRun resolved = ResolveRunRequest(
      s.scenes[0].scene, request, [](const std::string& k) { return k; });
  const SimulationOptions& o = resolved.options;
  EXPECT_EQ(MethodId(o.nlp, o.nlp_options, o.dae, o.dae_options, o.coupling),
            MethodId(s.runs[0]));
  EXPECT_EQ(MethodId(s.runs[0]),
            "newton/rk-projection[rk_method=dp54]/coupled");
}

}  // namespace
}  // namespace quasiroll::bench
