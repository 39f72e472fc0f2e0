// The reference's retry ladder (bench/harness/reference_retry.h): a
// reference whose NLP fails on purpose inside a window of its path is
// retried and continues; a failure that persists through every rung is a
// reference failure, recorded in references/<hash>.json and in the runs'
// reference_stop; a physical stop is not retried.
#include "quasiroll/bench/harness/reference_retry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/reference.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_reader.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/terrains.h"
#include "test_support.h"

namespace quasiroll::bench {
namespace {

// Where the fake backends fail: wheel 1's contact (x_g, y_g) at a distance
// in [lo, hi] from `origin`, i.e. over a stretch of the path.
struct FailureWindow {
  bool active = false;
  double x0 = 0, y0 = 0, lo = 0, hi = 0;
  bool fail_a_tight_only = false;  // a fails only at a tolerance < 1e-10
  bool fail_b = false;             // b fails in the window too
  bool b_throws = false;           // b throws (misuse) in the window
};
FailureWindow g_window;

bool InWindow(const NlpProblem& problem) {
  const auto* qs = dynamic_cast<const QuasiStaticProblem*>(&problem);
  if (!g_window.active || !qs) return false;
  const Configuration& th = qs->configuration();
  const double d = std::hypot(th(ConfigIndex::Xg(0)) - g_window.x0,
                              th(ConfigIndex::Yg(0)) - g_window.y0);
  return d >= g_window.lo && d <= g_window.hi;
}

// Newton, except inside the window, where it gives up (numerical failure)
// when told to.
class WindowNlp final : public NlpSolver {
 public:
  explicit WindowNlp(bool is_b) : is_b_(is_b) {}
  std::string name() const override {
    return is_b_ ? "test-window-b" : "test-window-a";
  }
  bool RequiresSquareSystem() const override { return true; }
  bool SupportsConcurrentInstances() const override { return true; }

 private:
  void DoSolve(const NlpProblem& problem,
               const Eigen::Ref<const Eigen::VectorXd>& x0,
               const NlpOptions& options, NlpResult* result) override {
    const bool fails = is_b_ ? g_window.fail_b
                             : !g_window.fail_a_tight_only ||
                                   options.feasibility_tolerance < 1e-10;
    if (is_b_ && g_window.b_throws && InWindow(problem))
      throw std::invalid_argument("test-window-b: cannot take this problem");
    if (fails && InWindow(problem)) {
      result->x = x0;
      result->status = NlpStatus::kNumericalFailure;
      result->iterations = 0;
      result->backend_status = "failure window (test)";
      return;
    }
    newton_->Solve(problem, x0, options, result);
    result->backend = name();
  }
  bool is_b_;
  std::unique_ptr<NlpSolver> newton_ = NlpSolverRegistry::Create("newton");
};

void RegisterWindowBackends() {
  static std::once_flag once;
  std::call_once(once, [] {
    RegisterBuiltinNlpSolvers();
    RegisterBuiltinIntegrators();
    // a: a family of its own, cost unknown; b: another family, cheaper than
    // any built-in, so SecondReferenceNlp(a) picks it by its BackendInfo.
    NlpSolverRegistry::Register(
        "test-window-a",
        ThreadSafeBackendInfo("newton failing in a window", "test-a"),
        [] { return std::make_unique<WindowNlp>(false); });
    BackendInfo b = ThreadSafeBackendInfo("newton failing on demand", "test-b");
    b.cost_ratio = 0.5;
    NlpSolverRegistry::Register("test-window-b", std::move(b), [] {
      return std::make_unique<WindowNlp>(true);
    });
  });
}

// The paper scene cut to 2 s; reference on the dt/4 = 0.0125 s grid.
Scene PaperScene(double t_end = 2.0) {
  Scene s = LoadScene(kScenes + "paper.yaml");
  s.t_end = t_end;
  return s;
}

ReferenceSettings WindowSettings() {
  ReferenceSettings r;
  r.nlp = "test-window-a";
  r.analytic = false;
  return r;
}

// Puts the window over the middle half of the reference's interval
// [1.0, 1.0125] s of `plain` (a run without failures): every stage of the
// primary step (0.003125 s) and of the smaller ones lands in it.
void SetWindow(const SimulationResult& plain) {
  const Configuration& start = plain.samples.front().theta;
  auto dist = [&](double t) {
    for (const TrajectorySample& s : plain.samples)
      if (std::abs(s.t - t) < 1e-9)
        return std::hypot(
            s.theta(ConfigIndex::Xg(0)) - start(ConfigIndex::Xg(0)),
            s.theta(ConfigIndex::Yg(0)) - start(ConfigIndex::Yg(0)));
    ADD_FAILURE() << "no sample at " << t;
    return 0.0;
  };
  const double d0 = dist(1.0), d1 = dist(1.0125);
  ASSERT_GT(d1, d0);
  g_window = FailureWindow{};
  g_window.active = true;
  g_window.x0 = start(ConfigIndex::Xg(0));
  g_window.y0 = start(ConfigIndex::Yg(0));
  g_window.lo = d0 + 0.25 * (d1 - d0);
  g_window.hi = d0 + 0.75 * (d1 - d0);
}

class ReferenceRetry : public ::testing::Test {
 protected:
  void SetUp() override {
    RegisterWindowBackends();
    g_window = FailureWindow{};
    plain_ = ComputeNumericalReference(PaperScene(), WindowSettings());
    ASSERT_TRUE(plain_.success()) << plain_.stop_reason;
    SetWindow(plain_);
  }
  void TearDown() override { g_window = FailureWindow{}; }

  // The stitched reference agrees with the uninterrupted one: the same
  // times, positions within 1e-9 m (both solve every state to the scaled
  // residual 1e-12 with Newton, so they differ by the solves' round-off,
  // ~1e-12 relative, carried over 2 s).
  void ExpectLikePlain(const SimulationResult& r) const {
    ASSERT_EQ(r.samples.size(), plain_.samples.size());
    double worst = 0;
    for (std::size_t k = 0; k < r.samples.size(); ++k) {
      EXPECT_EQ(r.samples[k].t, plain_.samples[k].t) << k;
      worst = std::max(
          worst, (r.samples[k].position - plain_.samples[k].position).norm());
    }
    EXPECT_LT(worst, 1e-9);
    const auto &c = r.samples.back().contacts,
               &p = plain_.samples.back().contacts;
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(c[i].creep_distance, p[i].creep_distance,
                  1e-6 * p[i].creep_distance + 1e-15);
  }

  SimulationResult plain_;
};

TEST_F(ReferenceRetry, SecondNlpIsChosenByBackendInfo) {
  EXPECT_EQ(SecondReferenceNlp("test-window-a"), "test-window-b");
  // From b: another family than b's, cheapest (cost unknown = last).
  const std::string second = SecondReferenceNlp("test-window-b");
  EXPECT_NE(second, "test-window-b");
  EXPECT_NE(NlpSolverRegistry::Info(second).family, "test-b");
}

TEST_F(ReferenceRetry, WithoutTheLadderTheReferenceStopsInTheWindow) {
  SimulationOptions o;
  o.nlp = "test-window-a";
  o.coupling = Coupling::kCoupled;
  o.dt = 0.0125;
  o.t_end = 2;
  o.dae_options = {{"rk_method", "rk4"}};
  o.integrator.step = 0.003125;
  const SimulationResult r = Simulator(PaperScene(), o).Run();
  EXPECT_EQ(r.status, "SOLVER_FAILURE") << r.stop_reason;
  EXPECT_GT(r.t_reached, 1.0);
  EXPECT_LT(r.t_reached, 1.0125);
}

TEST_F(ReferenceRetry, RescuedByTheSecondNlp) {
  ReferenceRetryLog log;
  std::string method;
  const SimulationResult r =
      ComputeNumericalReference(PaperScene(), WindowSettings(), &method, &log);
  EXPECT_TRUE(r.success()) << r.stop_reason;
  EXPECT_EQ(method, "rk4");
  EXPECT_EQ(log.stop, "end");
  EXPECT_EQ(log.rescues, 1);
  ASSERT_EQ(log.attempts.size(), 5u);
  EXPECT_EQ(log.attempts[0].rung, "primary");
  EXPECT_EQ(log.attempts[0].status, "SOLVER_FAILURE");
  for (int i : {1, 2}) {
    EXPECT_EQ(log.attempts[i].rung, i == 1 ? "step/4" : "step/16");
    EXPECT_EQ(log.attempts[i].status, "SOLVER_FAILURE");
    EXPECT_EQ(log.attempts[i].t_start, 1.0);
    EXPECT_EQ(log.attempts[i].t_end, 1.0125);
  }
  EXPECT_EQ(log.attempts[3].rung, "nlp");
  EXPECT_EQ(log.attempts[3].detail, "nlp test-window-b");
  EXPECT_EQ(log.attempts[3].status, "success");
  EXPECT_EQ(log.attempts[4].rung, "primary");
  EXPECT_EQ(log.attempts[4].t_start, 1.0125);
  EXPECT_EQ(log.attempts[4].status, "success");
  EXPECT_EQ(log.attempts[4].t_reached, 2.0);
  ExpectLikePlain(r);
}

TEST_F(ReferenceRetry, RescuedByTheRelaxedTolerance) {
  g_window.fail_a_tight_only = true;
  g_window.fail_b = true;
  ReferenceRetryLog log;
  const SimulationResult r =
      ComputeNumericalReference(PaperScene(), WindowSettings(), nullptr, &log);
  EXPECT_TRUE(r.success()) << r.stop_reason;
  EXPECT_EQ(log.stop, "end");
  ASSERT_EQ(log.attempts.size(), 6u);
  EXPECT_EQ(log.attempts[3].rung, "nlp");
  EXPECT_EQ(log.attempts[3].status, "SOLVER_FAILURE");
  EXPECT_EQ(log.attempts[4].rung, "relaxed");
  EXPECT_EQ(log.attempts[4].detail, "residual 1e-09");
  EXPECT_EQ(log.attempts[4].status, "success");
  EXPECT_EQ(log.attempts[5].status, "success");
  // The relaxed interval's solves are accepted at 1e-9, not 1e-12: the
  // trajectory agrees with the plain one to the twist's error there,
  // 1e-9 v0 over 0.0125 s, far below 1e-6 m.
  ASSERT_EQ(r.samples.size(), plain_.samples.size());
  for (std::size_t k = 0; k < r.samples.size(); ++k)
    EXPECT_LT((r.samples[k].position - plain_.samples[k].position).norm(),
              1e-6);
}

// A rung whose backend throws inside a solve (misuse of the backend) fails
// like any other rung (the quasi-static solver reports SOLVER_FAILURE), and
// the ladder goes on to the next rung.
TEST_F(ReferenceRetry, AThrowingRungIsAFailedAttempt) {
  g_window.fail_a_tight_only = true;
  g_window.b_throws = true;
  ReferenceRetryLog log;
  const SimulationResult r =
      ComputeNumericalReference(PaperScene(), WindowSettings(), nullptr, &log);
  EXPECT_TRUE(r.success()) << r.stop_reason;
  ASSERT_EQ(log.attempts.size(), 6u);
  EXPECT_EQ(log.attempts[3].rung, "nlp");
  EXPECT_EQ(log.attempts[3].status, "SOLVER_FAILURE");
  EXPECT_EQ(r.samples.size(), plain_.samples.size());
  EXPECT_EQ(log.attempts[4].rung, "relaxed");
  EXPECT_EQ(log.attempts[4].status, "success");
}

TEST_F(ReferenceRetry, PersistentFailureIsAReferenceFailure) {
  g_window.fail_b = true;
  const std::filesystem::path dir = FreshTempDir("quasiroll_refretry_");
  const Scene scene = PaperScene();
  Reference ref = LoadOrComputeReference(dir.string(), scene, TerrainSpec{}, "",
                                         WindowSettings(), "paper");
  EXPECT_EQ(ref.stop, "reference_failure");
  EXPECT_EQ(ref.rescues, 0);
  EXPECT_EQ(ref.status, "SOLVER_FAILURE");
  ASSERT_FALSE(ref.samples.empty());
  EXPECT_LT(ref.samples.back().t, 1.0125 + 1e-9);
  // The json records the stop and every attempt: the primary, the four
  // rungs, the whole DP5(4) rerun.
  const std::string json_path =
      (dir / "references" / (ref.hash + ".json")).string();
  const JsonValue json = ParseJson(ReadAll(json_path), json_path);
  ASSERT_NE(json.Find("reference_stop"), nullptr);
  EXPECT_EQ(json.Find("reference_stop")->str(), "reference_failure");
  const JsonValue* retries = json.Find("retries");
  ASSERT_NE(retries, nullptr);
  ASSERT_TRUE(retries->is_array());
  const std::vector<JsonValue>& items = retries->items();
  ASSERT_EQ(items.size(), 6u);
  const char* rungs[] = {"primary", "step/4",  "step/16",
                         "nlp",     "relaxed", "rerun"};
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(items[i].Find("rung")->str(), rungs[i]);
    EXPECT_NE(items[i].Find("status")->str(), "success");
  }
  // From the cache: the same stop.
  const Reference again = LoadOrComputeReference(
      dir.string(), scene, TerrainSpec{}, "", WindowSettings(), "paper");
  EXPECT_EQ(again.stop, "reference_failure");
  std::filesystem::remove_all(dir);
}

// A suite whose reference fails for good: every run row says so, and the
// methods that go on past it are not missed_event.
TEST_F(ReferenceRetry, RunRowsCarryTheReferenceStop) {
  g_window.fail_b = true;
  const std::filesystem::path root = FreshTempDir("quasiroll_refretry_rows_");
  RunSuiteText(root,
               "reference: {nlp: test-window-a}\n"
               "scenes:\n"
               "  - {name: paper, file: " +
                   kScenes +
                   "paper.yaml, overrides: {time: {t_end: 2}}}\n"
                   "groups:\n"
                   "  g:\n"
                   "    scenes: [paper]\n"
                   "    coupling: [zoh]\n",
               1);
  std::stringstream in(ReadAll(root / "out" / "runs.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = SplitCsvLine(line);
  std::map<std::string, std::size_t> col;
  for (std::size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  ASSERT_TRUE(col.count("reference_stop"));
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = SplitCsvLine(line);
    ++rows;
    EXPECT_EQ(cells[col["reference_stop"]], "reference_failure");
    EXPECT_EQ(cells[col["status"]], "success");  // newton passes the window
    EXPECT_NE(cells[col["cause_detail"]], "missed_event");
  }
  EXPECT_EQ(rows, 1);
  std::filesystem::remove_all(root);
}

// A physical stop is not retried: pvc on R1 at mu 0.3 meets the friction
// limit at ~14.26 s (tests/bench/verdict_test.cc), and the reference's log
// has the primary attempt only.
TEST(ReferenceRetryPhysical, PhysicalStopIsUnchanged) {
  RegisterWindowBackends();
  g_window = FailureWindow{};
  Scene scene = PaperScene(15.0);
  scene.mode = ActuationMode::kPvc;
  scene.mu = 0.3;
  ReferenceRetryLog log;
  const SimulationResult r =
      ComputeNumericalReference(scene, ReferenceSettings{}, nullptr, &log);
  EXPECT_EQ(r.status, "INFEASIBLE_FRICTION") << r.stop_reason;
  EXPECT_EQ(log.stop, "physical:friction_limit");
  EXPECT_EQ(log.rescues, 0);
  EXPECT_EQ(log.attempts.size(), 1u);
  EXPECT_GT(r.t_reached, 14.0);
}

// A breakaway is not passed: on R1 with its bumps 8x higher (the default
// suite's stability_roughness) the quasi-static twist diverges at ~5.84564 s
// (model.md §8.8). The reference's fixed RK4 steps give up there, and so
// did the ladder's rungs step/4, step/16 and nlp; its rung relaxed (the
// residual tolerance at 1e-9) used to step across it and went on 0.3 m to
// a tread-angle "limit" at 5.84588 s (mu_min 9.16 there). Now a stop whose own
// twist leaves the quasi-static domain is the model's: reference_stop
// model:breakaway, within the ~2e-5 s window where every method's solves give
// up, with mu_min just under mu (0.49988).
TEST(ReferenceRetryPhysical, BreakawayIsNotPassed) {
  RegisterWindowBackends();
  g_window = FailureWindow{};
  Scene scene = PaperScene(6.0);
  std::vector<GaussianBump> bumps =
      dynamic_cast<const GaussianTerrain&>(*scene.terrain).bumps();
  for (GaussianBump& b : bumps) b.amplitude *= 8;
  scene.terrain = std::make_shared<GaussianTerrain>(bumps);
  ReferenceRetryLog log;
  const SimulationResult r =
      ComputeNumericalReference(scene, ReferenceSettings{}, nullptr, &log);
  EXPECT_EQ(log.stop, "model:breakaway") << r.stop_reason;
  EXPECT_EQ(r.status, "SOLVER_FAILURE") << r.stop_reason;
  EXPECT_GT(r.t_reached, 5.8455);
  EXPECT_LT(r.t_reached, 5.8457);
  EXPECT_LT(r.mu_min_at_stop, scene.mu);
  EXPECT_GT(r.mu_min_at_stop, scene.mu - 1e-3);
  ASSERT_TRUE(r.stop_retry.has_value());
  EXPECT_GT(StopInertiaRatio(r, scene), 1.0);
  for (const ReferenceAttempt& a : log.attempts)
    EXPECT_LT(a.t_reached, 5.8457) << a.rung;
}

}  // namespace
}  // namespace quasiroll::bench
