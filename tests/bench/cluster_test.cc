// Sweeps beyond one process (docs/cluster.md): --shard parsing, the
// cost-balanced partition, shards + merge reproducing a --jobs 1 run, resume
// per shard, and merge's refusals (commit, suite, missing runs).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "quasiroll/bench/cluster/merge.h"
#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/shard.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_reader.h"
#include "quasiroll/core/dae.h"
#include "test_support.h"
#include "tiny_suite_fixture.h"

namespace quasiroll::bench {
namespace {

namespace fs = std::filesystem;

// runs.csv without the timing and host columns.
std::vector<std::vector<std::string>> WithoutTimingAndHost(const fs::path& p) {
  auto rows = ParseCsv(ReadAll(p));
  const auto& skip = TimingAndHostColumns();
  std::vector<std::size_t> keep;
  for (std::size_t k = 0; k < rows[0].size(); ++k)
    if (std::find(skip.begin(), skip.end(), rows[0][k]) == skip.end())
      keep.push_back(k);
  for (auto& r : rows) {
    std::vector<std::string> kept;
    for (std::size_t k : keep) kept.push_back(k < r.size() ? r[k] : "<none>");
    r = kept;
  }
  return rows;
}

// meta.json members without the invocation keys.
std::vector<std::pair<std::string, std::string>> WithoutInvocation(
    const fs::path& p) {
  std::vector<std::pair<std::string, std::string>> members;
  const JsonValue meta = ParseJson(ReadAll(p), p.string());
  for (const auto& [k, v] : meta.members()) members.emplace_back(k, v.raw());
  const auto& skip = InvocationMetaKeys();
  std::erase_if(members, [&](const auto& m) {
    return std::find(skip.begin(), skip.end(), m.first) != skip.end();
  });
  return members;
}

TEST(Shard, ParsesIOverNAndRejectsEverythingElseNamingTheFlag) {
  EXPECT_EQ(ParseShard("0/1"), std::make_pair(0, 1));
  EXPECT_EQ(ParseShard("3/4"), std::make_pair(3, 4));
  EXPECT_EQ(ParseShard("999/1000"), std::make_pair(999, 1000));
  for (const char* bad : {"4/4", "1/0", "0/0", "-1/4", "a/4", "1", "/4", "1/",
                          "1/4/5", " 1/4", "1/4 ", "1.0/4", "0/10000000"}) {
    try {
      ParseShard(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("--shard"), std::string::npos);
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << bad;
    }
  }
}

TEST(Shard, PartitionIsBalancedWithinOneRunAndKeepsReferencesTogether) {
  // Costs spanning 1000x, five reference groups interleaved in grid order.
  std::vector<double> costs;
  std::vector<std::string> keys;
  for (int k = 0; k < 200; ++k) {
    costs.push_back(k % 17 == 0 ? 100.0 : 0.1 + (k * 37 % 11));
    keys.push_back("ref" + std::to_string(k % 5));
  }
  const double total = std::accumulate(costs.begin(), costs.end(), 0.0);
  const double biggest = *std::max_element(costs.begin(), costs.end());
  for (int n : {1, 2, 3, 7, 16}) {
    const std::vector<int> shard = AssignShards(costs, keys, n);
    EXPECT_EQ(shard, AssignShards(costs, keys, n));  // deterministic
    std::vector<double> load(n, 0.0);
    std::map<std::string, std::set<int>> shards_of_key;
    for (std::size_t k = 0; k < costs.size(); ++k) {
      ASSERT_GE(shard[k], 0);
      ASSERT_LT(shard[k], n);
      load[shard[k]] += costs[k];
      shards_of_key[keys[k]].insert(shard[k]);
    }
    for (int s = 0; s < n; ++s)
      EXPECT_LE(std::abs(load[s] - total / n), biggest) << n << " " << s;
    // A reference group spans consecutive shards only, and the number of
    // (group, shard) pairs is at most groups + shards - 1.
    std::size_t pairs = 0;
    for (const auto& [key, set] : shards_of_key) {
      EXPECT_EQ(*set.rbegin() - *set.begin() + 1, static_cast<int>(set.size()))
          << key;
      pairs += set.size();
    }
    EXPECT_LE(pairs, shards_of_key.size() + n - 1);
  }
}

TEST(Shard, CostGrowsWithStepsRepeatsAndCoupling) {
  RunSpec r;
  r.nlp = "newton";
  r.dae = "rk-projection";
  r.dt = 0.05;
  r.t_end = 20;
  r.tol = 1e-8;
  const double base = EstimatedRunCost(r);
  EXPECT_GT(base, 0);
  RunSpec finer = r;
  finer.dt = 0.025;
  EXPECT_GT(EstimatedRunCost(finer), base);
  RunSpec twice = r;
  twice.repeats = 2;
  EXPECT_DOUBLE_EQ(EstimatedRunCost(twice), 2 * base);
  RunSpec coupled = r;
  coupled.coupling = Coupling::kCoupled;
  EXPECT_GT(EstimatedRunCost(coupled), base);
  RunSpec ipopt = r;
  ipopt.nlp = "ipopt";
  EXPECT_GT(EstimatedRunCost(ipopt), base);
  RunSpec plugin = r;  // an unmeasured backend still gets a finite cost
  plugin.nlp = "my-plugin";
  EXPECT_GT(EstimatedRunCost(plugin), 0);
}

TEST(Atlas, EveryMethodOnEveryStabilityAxisWithTwentySeeds) {
  const Suite atlas =
      LoadSuite(std::string(QUASIROLL_SOURCE_DIR) + "/bench/suites/atlas.yaml");
  EXPECT_GE(atlas.runs.size(), 2000u);
  const std::set<std::string> groups(atlas.groups.begin(), atlas.groups.end());
  EXPECT_EQ(groups,
            (std::set<std::string>{"stability_dt", "stability_sigma_dt",
                                   "stability_tol", "stability_mu",
                                   "stability_roughness", "stability_seed"}));
  std::map<std::string, std::set<std::string>> methods;  // group -> methods
  std::set<std::uint64_t> seeds;
  for (const RunSpec& r : atlas.runs) {
    methods[r.group].insert(r.nlp + "/" + r.dae + "/" + ToString(r.coupling));
    if (r.group == "stability_seed" && r.seed) seeds.insert(*r.seed);
  }
  // Every registered integrator (a new one must join the atlas), except on
  // the sigma axis: sigma only exists for rk-baumgarte and ida's index-1 form.
  const std::size_t integrators = IntegratorRegistry::Names().size();
  EXPECT_GE(integrators, 4u);
  for (const auto& [group, set] : methods) {
    const std::size_t daes = group == "stability_sigma_dt" ? 2 : integrators;
    EXPECT_EQ(set.size(), 4 * daes * 2) << group;
    for (const char* nlp : {"newton", "ipopt", "slsqp", "ceres"})
      for (const char* c : {"zoh", "coupled"})
        EXPECT_TRUE(set.count(std::string(nlp) + "/rk-baumgarte/" + c))
            << group << " " << nlp << " " << c;
  }
  EXPECT_GE(seeds.size(), 20u);
}

class ShardMerge : public TinySuiteTest<ShardMerge> {
 protected:
  static void SetUpTestSuite() {
    PrepareTinySuite("quasiroll_cluster_test_",
                     "  wp:\n"
                     "    nlp: [newton, ceres]\n"
                     "    dae: [rk-projection, ida]\n"
                     "    coupling: [zoh, coupled]\n"
                     "    dt: 0.1\n"
                     "  mu:\n"  // four more references
                     "    scenes: [paper]\n"
                     "    mu: [0.3, 0.45, 0.8, 1.0]\n"
                     "  unstable:\n"  // a failure row
                     "    scenes: [paper]\n"
                     "    dae: rk-baumgarte\n"
                     "    sigma: 200\n"
                     "  rough:\n"  // an error row (no initial configuration)
                     "    scenes: [paper]\n"
                     "    roughness: 100\n");
    RunSuite(suite_, Options("j1", 1));
    // Three shards sharing one directory.
    for (int i = 0; i < kShards; ++i) {
      HarnessOptions s = Options("shared");
      s.shard_index = i;
      s.shard_count = kShards;
      shard_summaries_.push_back(RunSuite(suite_, s));
    }
  }
  static HarnessOptions Options(const std::string& sub, int jobs = 2) {
    return TinySuiteTest::Options(sub, jobs);
  }
  static MergeOptions Merge(std::vector<std::string> inputs,
                            const std::string& out) {
    MergeOptions m;
    for (auto& in : inputs) m.inputs.push_back((root_ / in).string());
    m.out = (root_ / out).string();
    m.log = nullptr;
    return m;
  }
  static void ExpectSameAsJobsOne(const std::string& sub) {
    EXPECT_EQ(WithoutTimingAndHost(root_ / "j1" / "runs.csv"),
              WithoutTimingAndHost(root_ / sub / "runs.csv"));
    EXPECT_EQ(WithoutInvocation(root_ / "j1" / "meta.json"),
              WithoutInvocation(root_ / sub / "meta.json"));
    for (const RunSpec& r : suite_.runs)
      for (const char* files : {"trajectories", "checkpoints", "switches"})
        EXPECT_EQ(ReadAll(root_ / "j1" / files / (r.run_id + ".csv")),
                  ReadAll(root_ / sub / files / (r.run_id + ".csv")))
            << files << "/" << r.run_id;
    for (const auto& e : fs::directory_iterator(root_ / "j1" / "terrains"))
      EXPECT_TRUE(fs::exists(root_ / sub / "terrains" / e.path().filename()));
    for (const auto& e : fs::directory_iterator(root_ / "j1" / "references"))
      EXPECT_TRUE(fs::exists(root_ / sub / "references" / e.path().filename()));
  }

  static constexpr int kShards = 3;
  static std::vector<HarnessSummary> shard_summaries_;
};
std::vector<HarnessSummary> ShardMerge::shard_summaries_;

TEST_F(ShardMerge, ShardsCoverTheSuiteOnceAndWriteUnderShards) {
  int selected = 0;
  for (const HarnessSummary& s : shard_summaries_) {
    EXPECT_EQ(s.total, static_cast<int>(suite_.runs.size()));
    EXPECT_GT(s.selected, 0);
    selected += s.selected;
  }
  EXPECT_EQ(selected, static_cast<int>(suite_.runs.size()));
  std::set<std::string> ids;
  for (int i = 0; i < kShards; ++i) {
    const fs::path d = root_ / "shared" / "shards" /
                       (std::to_string(i) + "-of-" + std::to_string(kShards));
    const auto rows = ParseCsv(ReadAll(d / "runs.csv"));
    for (std::size_t k = 1; k < rows.size(); ++k)
      EXPECT_TRUE(ids.insert(rows[k][0]).second) << rows[k][0];
    const std::string meta = ReadAll(d / "meta.json");
    EXPECT_NE(meta.find("\"shard\":{\"index\":" + std::to_string(i) +
                        ",\"count\":3}"),
              std::string::npos);
    EXPECT_NE(meta.find("\"complete\":true"), std::string::npos);
  }
  EXPECT_EQ(ids.size(), suite_.runs.size());
  EXPECT_FALSE(fs::exists(root_ / "shared" / "runs.csv"));
}

TEST_F(ShardMerge, MergeInPlaceEqualsJobsOne) {
  const MergeSummary s = MergeOutputs(Merge({"shared"}, "shared"));
  EXPECT_EQ(s.runs, static_cast<int>(suite_.runs.size()));
  EXPECT_EQ(s.metas, kShards);
  EXPECT_EQ(s.duplicates, 0);
  EXPECT_EQ(s.failures, 2);
  ExpectSameAsJobsOne("shared");
  const JsonValue meta = ParseJson(ReadAll(root_ / "shared" / "meta.json"));
  std::map<std::string, std::string> keys;
  for (const auto& [k, v] : meta.members()) keys.emplace(k, v.raw());
  EXPECT_EQ(keys.count("shard"), 0u);  // only inside merge.inputs
  ASSERT_EQ(keys.count("merge"), 1u);
  EXPECT_EQ(keys["complete"], "true");
  EXPECT_EQ(keys["runs_selected"], std::to_string(suite_.runs.size()));
  EXPECT_EQ(keys["failures"], "2");
  EXPECT_NE(keys["merge"].find("shards/2-of-3/meta.json\""), std::string::npos)
      << keys["merge"];
}

TEST_F(ShardMerge, SeparateShardDirectoriesMergeAndDuplicatesAreRemoved) {
  // Each shard copied to a directory of its own (as from separate nodes'
  // local disks), plus the shared directory again: every row twice.
  for (int i = 0; i < kShards; ++i) {
    HarnessOptions s = Options("node" + std::to_string(i));
    s.shard_index = i;
    s.shard_count = kShards;
    RunSuite(suite_, s);
  }
  const MergeSummary s =
      MergeOutputs(Merge({"node0", "node1", "node2", "shared"}, "merged"));
  EXPECT_EQ(s.runs, static_cast<int>(suite_.runs.size()));
  EXPECT_EQ(s.duplicates, static_cast<int>(suite_.runs.size()));
  EXPECT_EQ(s.differing, 0);
  ExpectSameAsJobsOne("merged");
}

TEST_F(ShardMerge, ResumeWorksPerShard) {
  const fs::path dir = root_ / "resume";
  fs::remove_all(dir);
  fs::copy(root_ / "shared", dir, fs::copy_options::recursive);
  const auto rows = ParseCsv(ReadAll(dir / "shards" / "1-of-3" / "runs.csv"));
  ASSERT_GE(rows.size(), 3u);
  fs::remove(dir / "runs" / (rows[1][0] + ".csv"));
  fs::remove(dir / "trajectories" / (rows[2][0] + ".csv"));
  HarnessOptions o = Options("resume");
  o.shard_index = 1;
  o.shard_count = kShards;
  o.resume = true;
  const HarnessSummary s = RunSuite(suite_, o);
  EXPECT_EQ(s.executed, 2);
  EXPECT_EQ(s.resumed, static_cast<int>(rows.size()) - 1 - 2);
  MergeOutputs(Merge({"resume"}, "resume"));
  ExpectSameAsJobsOne("resume");
}

TEST_F(ShardMerge, MergeRefusesMismatchedCommitSuiteAndMissingRuns) {
  const fs::path dir = root_ / "bad";
  auto fresh = [&] {
    fs::remove_all(dir);
    fs::copy(root_ / "shared", dir, fs::copy_options::recursive);
    fs::remove(dir / "meta.json");
  };
  auto error_of = [&](const MergeOptions& m) -> std::string {
    try {
      MergeOutputs(m);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "(no error)";
  };
  fresh();
  {
    const fs::path meta = dir / "shards" / "2-of-3" / "meta.json";
    std::string text = ReadAll(meta);
    const auto at = text.find("\"commit\":\"") + 10;
    text.insert(at, "other");
    std::ofstream(meta, std::ios::binary) << text;
    const std::string e = error_of(Merge({"bad"}, "bad_out"));
    EXPECT_NE(e.find("disagree on commit"), std::string::npos) << e;
    EXPECT_NE(e.find("2-of-3/meta.json has \"other"), std::string::npos) << e;
  }
  fresh();
  {
    fs::remove(dir / "runs" / (suite_.runs[3].run_id + ".csv"));
    const std::string e = error_of(Merge({"bad"}, "bad_out"));
    EXPECT_NE(e.find("1 of " + std::to_string(suite_.runs.size())),
              std::string::npos)
        << e;
    EXPECT_NE(e.find(suite_.runs[3].run_id), std::string::npos) << e;
  }
  fresh();
  {
    const fs::path other = root_ / "other.yaml";
    std::ofstream(other) << ReadAll(suite_path_) << "# edited\n";
    MergeOptions m = Merge({"bad"}, "bad_out");
    m.suite = other.string();
    const std::string e = error_of(m);
    EXPECT_NE(e.find("suite_hash"), std::string::npos) << e;
  }
  EXPECT_NE(error_of(Merge({"nonexistent"}, "bad_out")).find("nonexistent"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(root_ / "bad_out" / "runs.csv"));
}

TEST_F(ShardMerge, CliExitCodes) {
  const std::string suite = " --suite " + suite_path_ + " --out " +
                            (root_ / "cli").string() + " --progress none";
  for (const char* bad : {"3/3", "1/0", "x", "-1/2"})
    EXPECT_EQ(RunCli("bench" + suite + " --shard " + bad), 2) << bad;
  EXPECT_FALSE(fs::exists(root_ / "cli"));  // rejected before running
  EXPECT_EQ(RunCli("merge " + (root_ / "nonexistent").string() + " --out " +
                   (root_ / "cli").string()),
            2);
  // --plan: the selected runs and their costs, nothing run or written.
  const fs::path plan = root_ / "plan.csv";
  EXPECT_EQ(std::system((std::string(QUASIROLL_CLI_PATH) + " bench" + suite +
                         " --plan --shard 1/3 > " + plan.string())
                            .c_str()),
            0);
  const auto rows = ParseCsv(ReadAll(plan));
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows[0][0], "run_id");
  EXPECT_EQ(rows[0][9], "estimated_cost_s");
  const auto shard1 =
      ParseCsv(ReadAll(root_ / "shared" / "shards" / "1-of-3" / "runs.csv"));
  ASSERT_EQ(rows.size(), shard1.size());
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k][0], shard1[k][0]);  // the runs shard 1 ran
    EXPECT_GT(std::stod(rows[k][9]), 0);
  }
  EXPECT_FALSE(fs::exists(root_ / "cli"));
  EXPECT_EQ(RunCli("bench" + suite + " --shard 0/40 --filter unstable"), 0);
  EXPECT_EQ(RunCli("merge " + (root_ / "cli").string() + " --out " +
                   (root_ / "cli").string()),
            2);  // one run of the filtered selection in 40 shards: missing
}

}  // namespace
}  // namespace quasiroll::bench
