// Run ids of existing suites never change: users --resume old output
// directories and the report keys on run ids. tests/data/suites/frozen/ holds
// copies of the shipped suites as they were when the grid expansion became a
// generic Cartesian product (default, smoke, analytic, report_fixture), and
// <suite>.runs the expansion recorded then with the nested-loop expander:
// one line per run, "<run_id> <key> <scene text>" separated by tabs, in grid
// order, where <scene text> is SceneCanonicalText of the scene the run
// simulates. Every later expander must reproduce these files exactly.
//
// To record them again (only for a deliberate, documented change of run ids):
//   QUASIROLL_WRITE_GOLDEN=1 build/tests/bench/bench_suite_golden_test
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/suite.h"

namespace quasiroll::bench {
namespace {

const std::string kDir =
    std::string(QUASIROLL_SOURCE_DIR) + "/tests/data/suites/frozen/";

std::string Expand(const std::string& name) {
  const Suite suite = LoadSuite(kDir + name + ".yaml");
  std::ostringstream os;
  for (const RunSpec& r : suite.runs) {
    const SuiteScene& sc = suite.scenes[r.scene_index];
    const Scene scene = RunScene(suite, r);
    os << r.run_id << '\t' << r.key << '\t'
       << SceneCanonicalText(scene, SweptTerrain(sc, r.seed, r.roughness),
                             sc.heightmap_digest)
       << '\n';
  }
  return os.str();
}

class FrozenSuiteTest : public ::testing::TestWithParam<std::string> {};

TEST_P(FrozenSuiteTest, ExpansionIsUnchanged) {
  const std::string name = GetParam();
  const std::string got = Expand(name);
  const std::string golden_path = kDir + name + ".runs";
  if (std::getenv("QUASIROLL_WRITE_GOLDEN") != nullptr) {
    std::ofstream(golden_path, std::ios::binary) << got;
    GTEST_SKIP() << "wrote " << golden_path;
  }
  std::ifstream in(golden_path, std::ios::binary);
  ASSERT_TRUE(in) << "missing " << golden_path;
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string want = ss.str();
  // Line by line, so that a failure names the first run that differs.
  std::istringstream gs(got), ws(want);
  std::string g, w;
  int line = 0;
  while (true) {
    const bool more_g = static_cast<bool>(std::getline(gs, g));
    const bool more_w = static_cast<bool>(std::getline(ws, w));
    ++line;
    if (!more_g && !more_w) break;
    ASSERT_EQ(more_g, more_w)
        << name << ": number of runs changed at line " << line;
    ASSERT_EQ(g, w) << name << ": run " << line << " changed";
  }
}

INSTANTIATE_TEST_SUITE_P(Shipped, FrozenSuiteTest,
                         ::testing::Values("default", "smoke", "analytic",
                                           "report_fixture"));

}  // namespace
}  // namespace quasiroll::bench
