// The traversability atlas (bench/atlas): analytic thresholds on the 10°
// incline, the heading dependence, causes for poses where the robot cannot
// stand, and outputs that do not depend on --jobs or on an interruption.
#include "quasiroll/bench/atlas/atlas.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "quasiroll/bench/atlas/edge.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_reader.h"
#include "test_support.h"

namespace quasiroll::bench {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;

AtlasSpec InclineSpec(int headings) {
  AtlasSpec spec;
  spec.scene_path = kScenes + "incline10.yaml";
  spec.scene = LoadScene(spec.scene_path);
  spec.headings = headings;
  return spec;
}

// Thresholds on a 10° incline (docs/model.md §7.7 and oracle O3-num): paper
// mode tan 10° in every heading (every joint actuated: the platform can hold
// any heading with the friction of a block on the slope); pvc 0.318914 uphill
// (heading 0 = up the slope of incline10.yaml) and 0.394378 downhill. The
// 1e-6 bound is that of the oracle's six digits; mu_min itself is computed to
// a relative 1e-11 (QuasiStaticProblem::MinimumFriction) at a contact
// configuration solved to 1e-10 (model.md §3.1).
TEST(TraversabilityAtlas, InclineThresholdsAreAnalytic) {
  const AtlasSpec spec = InclineSpec(8);
  const double tan10 = std::tan(10.0 * kPi / 180.0);
  for (std::int64_t i = 0; i < spec.CellCount(); ++i) {
    const AtlasCell cell = CellAt(spec, i);
    const AtlasRow row = EvaluateAtlasCell(spec, cell);
    ASSERT_EQ(row.status, "ok") << i << ": " << row.detail;
    EXPECT_DOUBLE_EQ(row.margin, spec.scene.mu - row.mu_min);
    if (cell.mode == ActuationMode::kPaper) {
      EXPECT_NEAR(row.mu_min, tan10, 1e-9) << "heading " << cell.heading;
    } else if (cell.heading == 0.0) {
      EXPECT_NEAR(row.mu_min, 0.318914, 1e-6);
    } else if (std::abs(cell.heading - kPi) < 1e-12) {
      EXPECT_NEAR(row.mu_min, 0.394378, 1e-6);
    }
  }
}

// pvc: heading h and -h are mirror images across the fall line (wheels 2 and
// 3 swap), so mu_min agrees and the critical wheel swaps 2 <-> 3; and the
// robot across the slope needs more friction than along it.
TEST(TraversabilityAtlas, PvcHeadingDependenceIsMirrorSymmetric) {
  AtlasSpec spec = InclineSpec(16);
  spec.modes = {ActuationMode::kPvc};
  std::vector<AtlasRow> rows;
  for (std::int64_t i = 0; i < spec.CellCount(); ++i)
    rows.push_back(EvaluateAtlasCell(spec, CellAt(spec, i)));
  for (int h = 1; h < 16; ++h) {
    const AtlasRow &a = rows[h], &b = rows[16 - h];
    EXPECT_NEAR(a.mu_min, b.mu_min, 1e-9 * a.mu_min) << h;
    // At h = 8 (straight down) wheels 2 and 3 tie.
    if (a.critical_wheel > 1 && h != 8) {
      EXPECT_EQ(a.critical_wheel + b.critical_wheel, 5) << h;
    }
  }
  EXPECT_GT(rows[4].mu_min, rows[0].mu_min);  // across vs up the slope
  EXPECT_GT(rows[4].mu_min, rows[8].mu_min);  // across vs down
}

// R1 (paper.yaml), 3 x 2 positions, both modes.
AtlasSpec SmallR1Spec(int headings) {
  AtlasSpec spec;
  spec.scene_path = kScenes + "paper.yaml";
  spec.scene = LoadScene(spec.scene_path);
  spec.x = {-0.5, 1.5, 3};
  spec.y = {-0.5, 0.5, 2};
  spec.headings = headings;
  return spec;
}

std::string WithoutWallTime(const fs::path& csv) {
  std::istringstream in(ReadAll(csv));
  std::string line, out;
  while (std::getline(in, line)) out += line.substr(0, line.rfind(',')) + "\n";
  return out;
}

// Same atlas.csv (but for wall times) with one or two threads, and after an
// interruption that left only part of the rows (resume computes the rest).
TEST(TraversabilityAtlas, OutputDoesNotDependOnJobsOrInterruption) {
  const fs::path root = FreshTempDir("quasiroll_atlas_test_");
  AtlasSpec spec = SmallR1Spec(3);
  AtlasOptions one;
  one.out_dir = (root / "one").string();
  AtlasOptions two = one;
  two.out_dir = (root / "two").string();
  two.jobs = 2;
  const AtlasSummary s1 = RunAtlas(spec, one);
  RunAtlas(spec, two);
  EXPECT_EQ(s1.cells, 36);
  // meta.json is JSON with the grid's key and the provenance.
  const JsonValue meta = ParseJson(ReadAll(root / "one" / "meta.json"));
  ASSERT_NE(meta.Find("key"), nullptr);
  EXPECT_EQ(meta.Find("key")->str(), CanonicalAtlasKey(spec));
  ASSERT_NE(meta.Find("library_versions"), nullptr);
  EXPECT_TRUE(meta.Find("library_versions")->is_object());
  EXPECT_EQ(meta.Find("cells")->number(), 36);
  EXPECT_EQ(WithoutWallTime(root / "one" / "atlas.csv"),
            WithoutWallTime(root / "two" / "atlas.csv"));
  // Keep the header and the first 10 rows, and tear the 11th mid-line.
  std::istringstream in(ReadAll(root / "two" / "atlas.csv"));
  std::string line, cut;
  for (int k = 0; k < 11 && std::getline(in, line); ++k) cut += line + "\n";
  std::getline(in, line);
  cut += line.substr(0, line.size() / 2);
  std::ofstream(root / "two" / "atlas.csv") << cut;
  two.resume = true;
  const AtlasSummary resumed = RunAtlas(spec, two);
  EXPECT_EQ(resumed.reused, 10);
  EXPECT_EQ(resumed.computed, 26);
  EXPECT_EQ(WithoutWallTime(root / "one" / "atlas.csv"),
            WithoutWallTime(root / "two" / "atlas.csv"));
  // Another grid in the same directory is refused, naming the file.
  spec.headings = 4;
  try {
    RunAtlas(spec, two);
    ADD_FAILURE() << "resume over another grid was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("atlas.csv"), std::string::npos);
  }
  fs::remove_all(root);
}

// --shard I/N: contiguous ranges that cover every cell exactly once, sizes
// differing by at most one, also where cells * index exceeds 64 bits.
TEST(AtlasShards, CellRangesCoverEveryCellOnceBalancedByCount) {
  for (std::int64_t cells :
       {std::int64_t{0}, std::int64_t{1}, std::int64_t{7}, std::int64_t{240},
        std::int64_t{131072}, std::int64_t{2000000000000000}}) {
    for (int count : {1, 2, 3, 7, 1000, 1000000}) {
      std::int64_t expected_begin = 0, smallest = cells, largest = 0;
      for (int i = 0; i < count; ++i) {
        const AtlasCellRange r = ShardCells(cells, i, count);
        ASSERT_EQ(r.begin, expected_begin) << cells << " " << i << "/" << count;
        ASSERT_LE(r.begin, r.end);
        smallest = std::min(smallest, r.end - r.begin);
        largest = std::max(largest, r.end - r.begin);
        expected_begin = r.end;
      }
      EXPECT_EQ(expected_begin, cells) << count;
      EXPECT_LE(largest - smallest, 1) << cells << " in " << count;
    }
  }
  EXPECT_EQ(AtlasShardDir("out", 2, 16), "out/shards/2-of-16");
}

// Shards write only their cells under OUT/shards/I-of-N; their rows,
// finished together (what quasiroll merge does), are the one-process atlas;
// a cell without a row is named.
TEST(AtlasShards, ShardRowsFinishToTheOneProcessAtlas) {
  const fs::path root = FreshTempDir("quasiroll_atlas_shards_");
  const AtlasSpec spec = SmallR1Spec(2);  // 24 cells: 3 shards of 8
  AtlasOptions whole;
  whole.out_dir = (root / "whole").string();
  RunAtlas(spec, whole);
  std::map<std::int64_t, std::string> rows;
  for (int i = 0; i < 3; ++i) {
    AtlasOptions shard;
    shard.out_dir = (root / "sharded").string();
    shard.shard_index = i;
    shard.shard_count = 3;
    const AtlasSummary s = RunAtlas(spec, shard);
    EXPECT_EQ(s.cells, 8);
    const fs::path dir = AtlasShardDir(shard.out_dir, i, 3);
    const JsonValue meta = ParseJson(ReadAll(dir / "meta.json"));
    EXPECT_EQ(meta.Find("shard")->Find("first_cell")->number(), 8 * i);
    EXPECT_EQ(SpecFromAtlasMeta(meta, "meta.json").CellCount(), 24);
    for (const auto& [index, row] : ReadFinishedAtlasRows(spec, dir.string()))
      EXPECT_TRUE(rows.emplace(index, row).second) << "cell " << index;
  }
  EXPECT_FALSE(fs::exists(root / "sharded" / "atlas.csv"));
  const std::map<std::int64_t, std::string> all = rows;
  rows.erase(5);
  rows.erase(17);
  try {
    FinishAtlasOutput(spec, (root / "merged").string(), rows, {}, {});
    ADD_FAILURE() << "missing cells accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(
        std::string(e.what()).find("2 of 24 cells have no row (first: 5)"),
        std::string::npos)
        << e.what();
  }
  fs::create_directories(root / "merged");
  FinishAtlasOutput(spec, (root / "merged").string(), all, {}, {});
  EXPECT_EQ(WithoutWallTime(root / "whole" / "atlas.csv"),
            WithoutWallTime(root / "merged" / "atlas.csv"));
  fs::remove_all(root);
}

// A partial file whose last line was torn by a kill: the next row starts on
// a line of its own (appended to the fragment, "3" + "5,..." would read as
// cell 35), and a row whose position columns are not its cell's is ignored.
TEST(AtlasShards, TornPartialLinesAreNeverReadAsRows) {
  const fs::path root = FreshTempDir("quasiroll_atlas_torn_");
  const AtlasSpec spec = SmallR1Spec(2);
  BeginAtlasOutput(spec, root.string(), false, {});
  const std::string row0 =
      AtlasCsvRow(EvaluateAtlasCell(spec, CellAt(spec, 0)));
  const std::string row5 =
      AtlasCsvRow(EvaluateAtlasCell(spec, CellAt(spec, 5)));
  const fs::path partial = root / "atlas.partial.csv";
  std::ofstream(partial) << row0 << "\n"
                         << "1";
  {
    AtlasPartialFile file(partial.string());
    file.Append(row5);
  }
  EXPECT_EQ(ReadAll(partial), row0 + "\n" + row5 + "\n");
  // A glued line: cell 1's index in front of cell 5's row.
  std::ofstream(root / "atlas.partial.rank-1.csv") << "1" << row5 << "\n";
  const auto rows = ReadFinishedAtlasRows(spec, root.string());
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows.at(0), row0);
  EXPECT_EQ(rows.at(5), row5);
  // Without --resume an earlier run's rows are removed, not reused.
  BeginAtlasOutput(spec, root.string(), false, {});
  EXPECT_TRUE(ReadFinishedAtlasRows(spec, root.string()).empty());
  fs::remove_all(root);
}

// DIR/spike.yaml: a narrow 5 cm spike under the front wheel (x = a =
// 0.25 m) at x = 0, which leaves no consistent contact; its path.
std::string WriteSpikeScene(const fs::path& dir) {
  const std::string scene = (dir / "spike.yaml").string();
  std::ofstream(scene)
      << "name: spike\nmode: paper\nmu: 0.5\n"
         "initial: {x: 0, y: 0, yaw: 0, joint_angles: [0, 0, 0, 0, 0, 0]}\n"
         "terrain: {type: gaussians, bumps: [{amplitude: 0.05, x: 0.27, y: 0, "
         "sigma: 0.01}]}\n";
  return scene;
}

// A pose where the robot cannot stand is a row with its cause.
TEST(TraversabilityAtlas, PoseWithoutContactIsARowWithItsCause) {
  const fs::path root = FreshTempDir("quasiroll_atlas_cause_");
  const std::string scene = WriteSpikeScene(root);
  AtlasSpec spec;
  spec.scene_path = scene;
  spec.scene = LoadScene(scene);
  spec.x = {0.0, 2.0, 2};
  spec.headings = 1;
  spec.modes = {ActuationMode::kPaper};
  const AtlasRow spike = EvaluateAtlasCell(spec, CellAt(spec, 0));
  EXPECT_EQ(spike.status, "no_contact");
  EXPECT_FALSE(spike.detail.empty());
  EXPECT_TRUE(std::isnan(spike.mu_min));
  const AtlasRow clear = EvaluateAtlasCell(spec, CellAt(spec, 1));
  EXPECT_EQ(clear.status, "ok") << clear.detail;
  fs::remove_all(root);
}

// The modes of a pose share its placement (EvaluateAtlasCells): every row,
// a failed placement's included, is the row of the cell evaluated alone but
// for wall_s, whatever cells are grouped (a pose's modes split or not).
TEST(TraversabilityAtlas, PosesSharedAcrossModesGiveTheRowsOfSingleCells) {
  const fs::path root = FreshTempDir("quasiroll_atlas_shared_");
  const std::string scene = WriteSpikeScene(root);
  for (const AtlasSpec& spec : {SmallR1Spec(2), [&] {
                                  AtlasSpec s = SmallR1Spec(2);
                                  s.scene_path = scene;
                                  s.scene = LoadScene(scene);
                                  s.x = {0.0, 2.0, 2};
                                  s.y = {0.0, 0.0, 1};
                                  return s;
                                }()}) {
    std::vector<std::int64_t> cells;
    for (std::int64_t i = 0; i < spec.CellCount(); ++i)
      if (i % 5 != 2) cells.push_back(i);  // some poses with one mode only
    const std::vector<AtlasRow> rows = EvaluateAtlasCells(spec, cells);
    ASSERT_EQ(rows.size(), cells.size());
    std::set<std::string> statuses;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      AtlasRow alone = EvaluateAtlasCell(spec, CellAt(spec, cells[k]));
      alone.wall_s = rows[k].wall_s;
      EXPECT_EQ(AtlasCsvRow(rows[k]), AtlasCsvRow(alone)) << cells[k];
      statuses.insert(rows[k].status);
    }
    EXPECT_TRUE(statuses.count("ok"));
    if (spec.scene_path == scene) {
      EXPECT_TRUE(statuses.count("no_contact"));
    }
  }
  fs::remove_all(root);
}

// The shipped atlas specs load (scene path relative to the spec file).
TEST(TraversabilityAtlas, ShippedSpecsLoad) {
  const std::string dir = std::string(QUASIROLL_SOURCE_DIR) + "/bench/atlases/";
  const AtlasSpec r1 = LoadAtlasSpec(dir + "r1.yaml");
  EXPECT_EQ(r1.CellCount(), 64 * 64 * 16 * 2);
  EXPECT_EQ(r1.edge_cells, 32);
  EXPECT_EQ(r1.scene.name, LoadScene(kScenes + "paper.yaml").name);
  EXPECT_EQ(LoadAtlasSpec(dir + "r1_small.yaml").CellCount(), 24 * 18 * 8 * 2);
  const AtlasSpec fine = LoadAtlasSpec(dir + "r1_fine.yaml");
  EXPECT_EQ(fine.CellCount(), std::int64_t{256} * 256 * 64 * 2);
  // The same area as the default atlas, 4x finer in x, y and heading.
  EXPECT_EQ(fine.x.lo, r1.x.lo);
  EXPECT_EQ(fine.y.hi, r1.y.hi);
}

TEST(TraversabilityAtlas, InvalidGridNamesTheKey) {
  AtlasSpec spec = InclineSpec(0);
  try {
    spec.Validate();
    ADD_FAILURE() << "headings 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "headings: must be in [1, 100000], got 0");
  }
  spec.headings = 1;
  spec.x = {1.0, 0.0, 2};
  EXPECT_THROW(spec.Validate(), std::invalid_argument);
}

// Every backend at mu = mu_min (1 + d) on the 10° incline, heading up and
// across, both modes: converges above the edge, is classified infeasible
// below it. A claim of convergence below the edge would be counted.
TEST(EdgeReliability, EveryBackendFindsTheEdgeOnTheIncline) {
  AtlasSpec spec = InclineSpec(4);
  EXPECT_EQ(ChooseEdgeCells({0, 1, 2, 3, 4, 5, 6, 7}, 4),
            (std::vector<std::int64_t>{0, 2, 4, 6}));
  // Cells 0-3: paper and pvc heading up the slope, then across it.
  const std::vector<EdgeRow> rows =
      RunEdgeStudy(spec, {0, 1, 2, 3}, EdgeOptions{});
  ASSERT_EQ(rows.size(), 4 * 5 * NlpSolverRegistry::Names().size());
  for (const EdgeRow& r : rows)
    EXPECT_EQ(r.verdict, "correct")
        << r.backend << " cell " << r.cell << " d " << r.offset << ": "
        << r.qs_status << " / " << r.nlp_status;
}

TEST(EdgeReliability, VerdictsCountWrongClaimsAndFalseInfeasibility) {
  using Q = QuasiStaticStatus;
  EXPECT_STREQ(EdgeVerdict(1e-3, Q::kOk, NlpStatus::kConverged), "correct");
  EXPECT_STREQ(EdgeVerdict(-1e-3, Q::kOk, NlpStatus::kConverged),
               "wrong_claim");
  EXPECT_STREQ(EdgeVerdict(1e-3, Q::kSolverFailure, NlpStatus::kInfeasible),
               "false_infeasibility");
  EXPECT_STREQ(EdgeVerdict(1e-3, Q::kSolverFailure, NlpStatus::kIterationLimit),
               "failure");
  EXPECT_STREQ(
      EdgeVerdict(-1e-2, Q::kInfeasibleFriction, NlpStatus::kInfeasible),
      "correct");
  EXPECT_STREQ(EdgeVerdict(-1e-2, Q::kSolverFailure, NlpStatus::kNotRun),
               "failure");
}

}  // namespace
}  // namespace quasiroll::bench
