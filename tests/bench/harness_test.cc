// End-to-end: a tiny suite through the harness (runs.csv with one row per
// grid point, failure and error rows, --jobs invariance, --resume, --filter)
// and the CLI's exit codes.
#include "quasiroll/bench/harness/harness.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "quasiroll/bench/harness/method_id.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/csv.h"
#include "test_support.h"
#include "tiny_suite_fixture.h"

namespace quasiroll::bench {
namespace {

namespace fs = std::filesystem;

std::string HostName() {
  char host[256] = {0};
  ::gethostname(host, sizeof(host) - 1);
  return host;
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
};

Table ReadTable(const fs::path& p) {
  const auto raw = ParseCsv(ReadAll(p));
  Table t;
  if (raw.empty()) return t;
  t.header = raw[0];
  for (std::size_t i = 1; i < raw.size(); ++i) {
    EXPECT_EQ(raw[i].size(), t.header.size()) << "row " << i;
    std::map<std::string, std::string> m;
    for (std::size_t k = 0; k < t.header.size() && k < raw[i].size(); ++k)
      m[t.header[k]] = raw[i][k];
    t.rows.push_back(m);
  }
  return t;
}

// A tab-separated table with a header line (bench/io/runs_columns.tsv).
Table ReadTsv(const fs::path& p) {
  std::istringstream in(ReadAll(p));
  Table t;
  std::string line;
  const auto split = [](const std::string& l) {
    std::vector<std::string> f;
    std::istringstream ls(l);
    for (std::string x; std::getline(ls, x, '\t');) f.push_back(x);
    return f;
  };
  if (std::getline(in, line)) t.header = split(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> f = split(line);
    EXPECT_EQ(f.size(), t.header.size()) << line;
    std::map<std::string, std::string> m;
    for (std::size_t k = 0; k < t.header.size() && k < f.size(); ++k)
      m[t.header[k]] = f[k];
    t.rows.push_back(m);
  }
  return t;
}

// Whether a runs.csv value has a schema type; empty means not applicable.
bool HasType(const std::string& v, const std::string& type) {
  if (v.empty() || type == "string") return true;
  if (type == "json") return v.front() == '{' && v.back() == '}';
  std::size_t used = 0;
  try {
    if (type == "int") std::stoll(v, &used);
    if (type == "double") std::stod(v, &used);
  } catch (const std::exception&) {
    return v == "nan" && type == "double";
  }
  return used == v.size();
}

// runs.csv without the timing columns (wall_s, wall_s_median, ...,
// wall_per_sim_s).
std::string WithoutTiming(const fs::path& p) {
  const auto raw = ParseCsv(ReadAll(p));
  std::vector<bool> timing(raw[0].size(), false);
  for (std::size_t k = 0; k < raw[0].size(); ++k)
    timing[k] = raw[0][k].rfind("wall_", 0) == 0;
  std::string out;
  for (const auto& r : raw) {
    for (std::size_t k = 0; k < r.size(); ++k)
      if (!timing[k]) out += r[k] + "\x1f";
    out += "\n";
  }
  return out;
}

// Exclusive tasks (group key `exclusive`) never overlap another task, even
// with --jobs 4; the shared ones do run concurrently (so the check can
// fail); every task runs once. Each task sleeps 20 ms so that overlaps
// would happen if the scheduler allowed them.
TEST(ScheduleTasks, ExclusiveTasksRunAloneAfterTheSharedOnes) {
  const int n = 12;
  std::vector<int> classes(n, 0);
  std::vector<bool> alone(n, false);
  for (int k : {1, 4, 5, 9}) alone[k] = true;
  std::atomic<int> active{0};
  std::mutex mutex;
  std::vector<int> order, active_at_start(n, -1);
  int max_shared = 0;
  ScheduleTasks(classes, alone, 4, [&](int k) {
    const int now = ++active;
    {
      std::lock_guard<std::mutex> lock(mutex);
      order.push_back(k);
      active_at_start[k] = now;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    {
      std::lock_guard<std::mutex> lock(mutex);
      // Still alone at the end: nothing started meanwhile.
      if (alone[k]) {
        EXPECT_EQ(active.load(), 1) << "task " << k;
      }
      max_shared = std::max(max_shared, active.load());
    }
    --active;
  });
  ASSERT_EQ(order.size(), static_cast<std::size_t>(n));
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int k = 0; k < n; ++k) EXPECT_EQ(sorted[k], k);
  for (int k = 0; k < n; ++k) {
    if (alone[k]) {
      EXPECT_EQ(active_at_start[k], 1) << "task " << k;
    }
  }
  // The exclusive tasks come last, in order.
  EXPECT_EQ(std::vector<int>(order.end() - 4, order.end()),
            (std::vector<int>{1, 4, 5, 9}));
  EXPECT_GT(max_shared, 1) << "shared tasks never overlapped";
}

class BenchHarness : public TinySuiteTest<BenchHarness> {
 protected:
  static void SetUpTestSuite() {
    PrepareTinySuite("quasiroll_harness_test_",
                     "  wp:\n"
                     "    nlp: [newton, ceres]\n"
                     "    dae: [rk-projection, rk-baumgarte]\n"
                     "    dt: [0.05, 0.1]\n"
                     "  ip:\n"  // ipopt-mumps runs are serialised (MUMPS)
                     "    scenes: [paper]\n"
                     "    nlp: [ipopt, ipopt-mumps]\n"
                     "    dae: [rk-projection, rk-baumgarte]\n"
                     "    dt: 0.1\n"
                     "  unstable:\n"  // sigma * dt = 10 >> 2.785: blows up
                     "    scenes: [paper]\n"
                     "    dae: rk-baumgarte\n"
                     "    sigma: 200\n"
                     "  rough:\n"  // no initial contact configuration
                     "    scenes: [paper]\n"
                     "    roughness: 100\n");
    summary_j1_ = RunSuite(suite_, Options("j1", 1));
  }

  static inline HarnessSummary summary_j1_;
};

TEST_F(BenchHarness, RunsCsvHasOneRowPerGridPointAndTheDocumentedColumns) {
  ASSERT_EQ(suite_.runs.size(), 16u + 4u + 1u + 1u);
  EXPECT_EQ(summary_j1_.executed, 22);
  const Table t = ReadTable(root_ / "j1" / "runs.csv");
  // The documented columns: the schema file (docs/formats.md's table is
  // generated from it), in order, and every value of its column's type.
  const Table schema = ReadTsv(fs::path(QUASIROLL_SOURCE_DIR) / "bench" / "io" /
                               "runs_columns.tsv");
  std::vector<std::string> names;
  for (const auto& c : schema.rows) names.push_back(c.at("name"));
  EXPECT_EQ(t.header, names);
  EXPECT_EQ(t.header, RunsCsvColumns());
  for (const auto& c : schema.rows)
    for (const auto& r : t.rows)
      EXPECT_TRUE(HasType(r.at(c.at("name")), c.at("type")))
          << r.at("run_id") << " " << c.at("name") << " = '"
          << r.at(c.at("name")) << "' is no " << c.at("type");
  ASSERT_EQ(t.rows.size(), suite_.runs.size());
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    EXPECT_EQ(r.at("run_id"), suite_.runs[i].run_id);  // grid order
    // The method that ran (docs/harness.md, "Method identity").
    EXPECT_EQ(r.at("method"), MethodId(suite_.runs[i]));
    EXPECT_TRUE(
        fs::exists(root_ / "j1" / "trajectories" / (r.at("run_id") + ".csv")));
    EXPECT_TRUE(fs::exists(root_ / "j1" / "runs" / (r.at("run_id") + ".csv")));
    // No wheel changes class in the first 0.5 s (the paper scene's first
    // switch is at 2.903 s): the switches file is its header alone.
    EXPECT_EQ(ReadAll(root_ / "j1" / "switches" / (r.at("run_id") + ".csv")),
              "t,wheel,from,to,located,t_lower,t_upper,kind\n");
    // The machine that executed the row.
    EXPECT_EQ(r.at("host"), HostName()) << r.at("run_id");
    EXPECT_FALSE(r.at("cpu_model").empty()) << r.at("run_id");
    if (r.at("suite_group") == "wp" || r.at("suite_group") == "ip") {
      EXPECT_EQ(r.at("status"), "success")
          << r.at("run_id") << ": " << r.at("stop_reason");
      EXPECT_EQ(r.at("t_reached"), "0.5");
      EXPECT_LT(std::stod(r.at("err_pos_max")), 1e-4) << r.at("run_id");
      // Errors at checkpoints (docs/harness.md): 0.3125 s = 25 reference
      // intervals of 0.0125 s, and the end 0.5 s; their states on file.
      EXPECT_EQ(r.at("checkpoints"), "2") << r.at("run_id");
      const std::string cp =
          ReadAll(root_ / "j1" / "checkpoints" / (r.at("run_id") + ".csv"));
      EXPECT_EQ(std::count(cp.begin(), cp.end(), '\n'), 3) << cp;
      EXPECT_NE(cp.find("\n0.3125,"), std::string::npos) << cp;
      EXPECT_EQ(
          std::stod(r.at("err_pos_max")) >= std::stod(r.at("err_pos_rms")),
          true);
      EXPECT_GT(std::stoi(r.at("nlp_solves")), 0);
      // Comparable count <= native count (docs/harness.md, "Iterations"),
      // equal for newton and ipopt, which count only accepted iterates.
      const long long iters = std::stoll(r.at("nlp_iters"));
      const long long native = std::stoll(r.at("nlp_iters_native"));
      EXPECT_GE(iters, 0) << r.at("run_id");
      EXPECT_LE(iters, native) << r.at("run_id");
      if (r.at("nlp") == "newton" || r.at("nlp").rfind("ipopt", 0) == 0) {
        EXPECT_EQ(iters, native) << r.at("run_id");
      }
      // The options the backends used: every option of their tables, as
      // compact JSON (the rk-projection / newton defaults here).
      if (r.at("dae") == "rk-projection") {
        EXPECT_NE(r.at("dae_options").find("\"projection_tolerance\":1e-12"),
                  std::string::npos)
            << r.at("dae_options");
        EXPECT_NE(r.at("dae_options").find("\"rk_method\":\"rk4\""),
                  std::string::npos)
            << r.at("dae_options");
      }
      if (r.at("nlp") == "newton") {
        EXPECT_NE(r.at("nlp_options").find("\"armijo\":2e-04"),
                  std::string::npos)
            << r.at("nlp_options");
      }
      EXPECT_EQ(r.at("scene_fields"), "");
      // Default options: the method is its backends and coupling.
      EXPECT_EQ(r.at("method"), r.at("nlp") + "/" + r.at("dae") + "/zoh");
      EXPECT_EQ(r.at("ref_kind"),
                r.at("scene") == "flat" ? "analytic:flat" : "numerical");
      EXPECT_EQ(r.at("ref_status"), "success");
    }
  }
  EXPECT_TRUE(fs::exists(root_ / "j1" / "terrains" / "paper.json"));
  EXPECT_TRUE(fs::exists(root_ / "j1" / "terrains" / "flat.json"));
  EXPECT_NE(ReadAll(root_ / "j1" / "terrains" / "flat.json").find("\"plane\""),
            std::string::npos);
  const std::string meta = ReadAll(root_ / "j1" / "meta.json");
  for (const char* k :
       {"\"commit\"", "\"library_versions\"", "\"machine\"", "\"start_time\"",
        "\"end_time\"", "\"hash\"", "\"jobs\":1", "\"complete\":true"})
    EXPECT_NE(meta.find(k), std::string::npos) << k;
}

TEST_F(BenchHarness, FailuresAndErrorsAreRowsAndTheSuiteFinishes) {
  const Table t = ReadTable(root_ / "j1" / "runs.csv");
  const auto& unstable = t.rows[20];
  EXPECT_EQ(unstable.at("suite_group"), "unstable");
  // sigma 200 is not rk-baumgarte's default: another method.
  EXPECT_EQ(unstable.at("method"),
            "newton/rk-baumgarte[baumgarte_sigma=200]/zoh");
  EXPECT_NE(unstable.at("status"), "success");
  EXPECT_FALSE(unstable.at("stop_reason").empty());
  EXPECT_LT(std::stod(unstable.at("t_reached")), 0.5);
  // Accuracy over the time reached only.
  EXPECT_GT(std::stoi(unstable.at("common_samples")), 0);
  EXPECT_EQ(unstable.at("err_final"), "nan");
  const auto& rough = t.rows[21];
  EXPECT_EQ(rough.at("status"), "error");
  EXPECT_NE(rough.at("stop_reason").find("initial"), std::string::npos)
      << rough.at("stop_reason");
  EXPECT_EQ(summary_j1_.failures, 2);
}

TEST_F(BenchHarness, JobsTwoGivesTheSameRunsCsvExceptTiming) {
  const HarnessSummary s = RunSuite(suite_, Options("j2", 2));
  EXPECT_EQ(s.executed, 22);
  EXPECT_EQ(WithoutTiming(root_ / "j1" / "runs.csv"),
            WithoutTiming(root_ / "j2" / "runs.csv"));
  // Trajectories are bit-identical too.
  for (const RunSpec& r : suite_.runs)
    EXPECT_EQ(ReadAll(root_ / "j1" / "trajectories" / (r.run_id + ".csv")),
              ReadAll(root_ / "j2" / "trajectories" / (r.run_id + ".csv")))
        << r.run_id;
}

TEST_F(BenchHarness, ResumeAfterInterruptionGivesTheSameFiles) {
  const fs::path dir = root_ / "resume";
  fs::remove_all(dir);
  fs::copy(root_ / "j1", dir, fs::copy_options::recursive);
  // Simulate an interruption: no runs.csv, three runs not persisted, one
  // trajectory missing.
  fs::remove(dir / "runs.csv");
  for (int i : {0, 7, 18})
    fs::remove(dir / "runs" / (suite_.runs[i].run_id + ".csv"));
  fs::remove(dir / "trajectories" / (suite_.runs[9].run_id + ".csv"));
  HarnessOptions o = Options("resume", 2);
  o.resume = true;
  const HarnessSummary s = RunSuite(suite_, o);
  EXPECT_EQ(s.resumed, 18);
  EXPECT_EQ(s.executed, 4);
  EXPECT_EQ(WithoutTiming(root_ / "j1" / "runs.csv"),
            WithoutTiming(dir / "runs.csv"));
  // Rows taken from disk are reused verbatim (timing included).
  const Table a = ReadTable(root_ / "j1" / "runs.csv"),
              b = ReadTable(dir / "runs.csv");
  for (int i : {1, 2, 8, 16, 19}) EXPECT_EQ(a.rows[i], b.rows[i]);
  for (const RunSpec& r : suite_.runs)
    EXPECT_EQ(ReadAll(root_ / "j1" / "trajectories" / (r.run_id + ".csv")),
              ReadAll(dir / "trajectories" / (r.run_id + ".csv")));
  // Resuming a finished directory runs nothing.
  const HarnessSummary again = RunSuite(suite_, o);
  EXPECT_EQ(again.executed, 0);
  EXPECT_EQ(WithoutTiming(root_ / "j1" / "runs.csv"),
            WithoutTiming(dir / "runs.csv"));
}

TEST_F(BenchHarness, FilterKeepsMatchingRunIds) {
  HarnessOptions o = Options("filter", 2);
  o.filter = "^wp-flat-newton";
  const HarnessSummary s = RunSuite(suite_, o);
  EXPECT_EQ(s.selected, 4);
  const Table t = ReadTable(root_ / "filter" / "runs.csv");
  ASSERT_EQ(t.rows.size(), 4u);
  for (const auto& r : t.rows)
    EXPECT_EQ(r.at("run_id").rfind("wp-flat-newton", 0), 0u);
  o.filter = "([";
  EXPECT_THROW(RunSuite(suite_, o), SceneError);
}

// The tiny suite's verdict columns: every row has them; the fixture's
// successes carry the timing of each repeat and a verified KKT residual; the
// blow-up (sigma h = 10) is numerical, the error row too.
TEST_F(BenchHarness, VerdictColumns) {
  const Table t = ReadTable(root_ / "j1" / "runs.csv");
  for (const auto& r : t.rows) {
    if (r.at("status") == "success") {
      EXPECT_EQ(r.at("cause"), "");
      EXPECT_EQ(r.at("cause_detail"), "");
      EXPECT_EQ(r.at("t_reached_frac"), "1");
      EXPECT_EQ(r.at("wall_s"), r.at("wall_s_min"));
      EXPECT_EQ(r.at("wall_s_all"), r.at("wall_s_min"));  // repeats: 1
      EXPECT_DOUBLE_EQ(std::stod(r.at("wall_per_sim_s")),
                       std::stod(r.at("wall_s_median")) / 0.5);
      EXPECT_LE(std::stod(r.at("kkt_residual")), 1e-9) << r.at("run_id");
      // 0.06 m/s over R1's bumps: inertial loads ~1e-4 of the weight.
      EXPECT_LT(std::stod(r.at("qs_inertia_ratio")), 1e-2) << r.at("run_id");
      if (r.at("ref_kind") == "numerical") {
        // A DP5(4) check reference agrees with the RK4 reference to its
        // O(h^4) error on 0.5 s of R1 (h = 3.125 ms): far below 1e-9 m.
        EXPECT_LT(std::stod(r.at("ref_err_est")), 1e-9) << r.at("run_id");
        EXPECT_GT(std::stod(r.at("ref_mu_min")), 0.0);
        EXPECT_LT(std::stod(r.at("ref_mu_min")), 0.5);  // mu = 0.5 suffices
      } else {
        EXPECT_EQ(r.at("ref_err_est"), "");  // closed form: no check
      }
    }
  }
  const auto& unstable = t.rows[20];
  EXPECT_EQ(unstable.at("cause"), "numerical");
  EXPECT_EQ(unstable.at("cause_detail"), "baumgarte_instability");
  EXPECT_LT(std::stod(unstable.at("t_reached_frac")), 1.0);
  const auto& rough = t.rows[21];
  EXPECT_EQ(rough.at("cause"), "numerical");
  EXPECT_EQ(rough.at("cause_detail"), "error");
}

// The fixtures: rk-baumgarte at dt = 3.2 s (sigma h = 16) meets
// INFEASIBLE_FRICTION at the 3.2 s sample (mu_min ~4) although mu = 0.5
// carries the reference to the end; located inside that interval
// (model.md §8.6), the stop is at ~1.58 s with mu_min = mu: a blow-up,
// classed numerical. pvc on R1 at mu = 0.3
// stops at ~14.3 s where the reference stops too: a friction limit, classed
// physical. Tight bounds turn a finished Baumgarte run (drift ~1e-8) into
// drift_exceeded.
TEST(BenchVerdicts, BlowUpIsNumericalFrictionStopIsPhysical) {
  const fs::path root = FreshTempDir("quasiroll_verdict_test_");
  RunSuiteText(
      root,
      std::string("scenes:\n"
                  "  - {name: paper, file: ") +
          kScenes +
          "paper.yaml, overrides: {time: {t_end: 6.4}}}\n"
          "  - {name: paper_pvc, file: " +
          kScenes +
          "paper.yaml, overrides: {mode: pvc, mu: 0.3, time: {t_end: 15}}}\n"
          "groups:\n"
          "  blowup:\n"
          "    scenes: [paper]\n"
          "    dae: rk-baumgarte\n"
          "    dt: 3.2\n"
          "  friction:\n"
          "    scenes: [paper_pvc]\n"
          "  tight:\n"
          "    scenes: [paper]\n"
          "    dae: rk-baumgarte\n"
          "    dt: 0.2\n"
          "    t_end: 1\n"
          "    repeats: 3\n"
          "    bounds: {drift: 1.0e-12}\n",
      2);
  const Table t = ReadTable(root / "out" / "runs.csv");
  ASSERT_EQ(t.rows.size(), 3u);
  const auto& blowup = t.rows[0];
  EXPECT_EQ(blowup.at("status"), "INFEASIBLE_FRICTION");   // kept as is
  EXPECT_NEAR(std::stod(blowup.at("mu_min")), 0.5, 1e-6);  // located
  EXPECT_EQ(blowup.at("ref_status"), "success");
  EXPECT_EQ(blowup.at("cause"), "numerical");
  EXPECT_EQ(blowup.at("cause_detail"), "baumgarte_instability");
  EXPECT_GT(std::stod(blowup.at("t_reached_frac")), 0.0);
  EXPECT_LT(std::stod(blowup.at("t_reached_frac")), 0.5);  // inside [0, 3.2]
  // The path's friction requirement stays below mu = 0.5: the limit the
  // run meets belongs to states off the path.
  EXPECT_LT(std::stod(blowup.at("ref_mu_min")), 0.5);

  const auto& friction = t.rows[1];
  EXPECT_EQ(friction.at("status"), "INFEASIBLE_FRICTION");
  EXPECT_EQ(friction.at("ref_status"), "INFEASIBLE_FRICTION");
  EXPECT_EQ(friction.at("cause"), "physical");
  EXPECT_EQ(friction.at("cause_detail"), "friction_limit");
  EXPECT_GT(std::stod(friction.at("t_reached")), 14.0);
  EXPECT_GE(std::stod(friction.at("ref_mu_min")), 0.3);  // reached mu
  // Where the zoh run stops against the reference's located stop, 14.2568653
  // s (the coupled location, tests/core/test_switch_events.cc
  // CoupledRunStopsWhereAWheelsFrictionSaturates): the hold's lag, ~1.3 ms.
  const double err_stop_t = std::stod(friction.at("err_stop_t"));
  EXPECT_NEAR(err_stop_t, std::stod(friction.at("t_reached")) - 14.2568653,
              1e-6);
  EXPECT_GT(err_stop_t, 1e-4);
  EXPECT_LT(err_stop_t, 5e-3);
  // The reference's DP5(4) check stops within 1e-5 s of it (its adaptive
  // stages first fail a few µs short of the limit); the blow-up's reference
  // and its check both reach t_end.
  EXPECT_LT(std::abs(std::stod(friction.at("ref_check_t_diff"))), 1e-5);
  EXPECT_EQ(std::stod(blowup.at("ref_check_t_diff")), 0.0);
  EXPECT_EQ(blowup.at("err_stop_t"), "nan");  // numerical: no common limit

  const auto& tight = t.rows[2];
  EXPECT_EQ(tight.at("status"), "drift_exceeded");
  EXPECT_EQ(tight.at("cause"), "numerical");
  EXPECT_EQ(tight.at("cause_detail"), "drift_blowup");
  EXPECT_EQ(tight.at("t_reached_frac"), "1");
  EXPECT_EQ(tight.at("err_stop_t"), "nan");
  EXPECT_NE(tight.at("stop_reason").find("bounds.drift"), std::string::npos);
  // Three repeats: three timings, wall_s their minimum.
  std::vector<double> walls;
  std::stringstream all(tight.at("wall_s_all"));
  for (std::string w; std::getline(all, w, ';');) walls.push_back(std::stod(w));
  ASSERT_EQ(walls.size(), 3u);
  EXPECT_EQ(std::stod(tight.at("wall_s")),
            *std::min_element(walls.begin(), walls.end()));
  EXPECT_EQ(std::stod(tight.at("wall_s_max")),
            *std::max_element(walls.begin(), walls.end()));
  EXPECT_LE(std::stod(tight.at("wall_s_min")),
            std::stod(tight.at("wall_s_median")));
  fs::remove_all(root);
}

TEST_F(BenchHarness, CliExitCodes) {
  const fs::path bad = root_ / "bad.yaml";
  std::ofstream(bad) << "scenes:\n  - {file: " << kScenes
                     << "paper.yaml}\ngroups:\n  g:\n    nlp: [newton, nope]\n";
  EXPECT_EQ(RunCli("bench --suite " + bad.string() + " --out " +
                   (root_ / "bad").string()),
            2);
  EXPECT_FALSE(
      fs::exists(root_ / "bad" / "runs.csv"));  // rejected before running
  EXPECT_EQ(RunCli("bench --suite " + suite_path_ + " --out " +
                   (root_ / "cli").string() +
                   " --jobs 2 --filter unstable --progress lines"),
            0);  // the only run fails, the suite completes
  const Table t = ReadTable(root_ / "cli" / "runs.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_NE(t.rows[0].at("status"), "success");
#ifdef QUASIROLL_REFERENCE_BLAS_DIR
  // The CLI binds BLAS and LAPACK to the reference libraries the build pins
  // (CMakeLists.txt, QUASIROLL_REFERENCE_LAPACK), and says so in meta.json.
  const std::string meta = ReadAll(root_ / "cli" / "meta.json");
  EXPECT_NE(meta.find("\"numerical_libraries\":{\"blas\":\"" +
                      std::string(QUASIROLL_REFERENCE_BLAS_DIR) + "/"),
            std::string::npos)
      << meta;
  EXPECT_NE(meta.find("\"lapack\":\"" +
                      std::string(QUASIROLL_REFERENCE_LAPACK_DIR) + "/"),
            std::string::npos)
      << meta;
#endif
  EXPECT_EQ(RunCli("bench --suite " + suite_path_ + " --out x --filter '(['"),
            2);
  EXPECT_EQ(
      RunCli("bench --suite " + (root_ / "missing.yaml").string() + " --out x"),
      2);
}

}  // namespace
}  // namespace quasiroll::bench
