// Checks the example plugins from outside the quasiroll tree:
//   1. the NLP backend against the shared reference problems
//      (conformance/nlp_reference_problems.h) and the NlpSolver contract;
//   2. the integrator on a constrained ODE with a known solution (accuracy,
//      order, H = 0, events, failure statuses);
//   3. a short paper-scene simulation with both plugins (zoh and coupled),
//      compared with the built-in newton + rk-projection;
//   4. if the package has the benchmark harness: a smoke suite with the
//      plugins next to the built-in backends.
// Prints one line per check; exits 1 if any check failed.
//
//   plugin_demo [--data-dir DIR] [--t-end SECONDS] [--no-suite] [--jobs N]
#include <unistd.h>  // getpid

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <quasiroll/conformance/nlp_reference_problems.h>
#include <quasiroll/core/dae.h>
#include <quasiroll/core/nlp.h>
#include <quasiroll/core/scene.h>
#include <quasiroll/core/simulator.h>

#include "register_plugins.h"
#ifdef EXAMPLE_HAVE_HARNESS
#include <quasiroll/bench/harness/harness.h>
#include <quasiroll/bench/harness/suite.h>
#endif

namespace {

using namespace quasiroll;

int g_failures = 0;

void Check(bool ok, const std::string& what) {
  std::printf("[%s] %s\n", ok ? " ok " : "FAIL", what.c_str());
  if (!ok) ++g_failures;
}

template <class F>
bool Throws(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument&) {
    return true;
  }
  return false;
}

// ----------------------------------------------------------- 1. NLP -----

void CheckNlpBackend(const std::string& backend) {
  std::printf("== NLP backend '%s' on the reference problems\n",
              backend.c_str());
  auto solver = NlpSolverRegistry::Create(backend);
  NlpOptions options;
  options.feasibility_tolerance = 1e-12;  // the quasi-static solver's setting
  options.optimality_tolerance = 1e-12;
  options.max_iterations = 500;
  for (const auto& p : MakeReferenceProblems()) {
    NlpResult r;
    if (solver->RequiresSquareSystem() && !p->IsSquareSystem()) {
      // Contract: a problem the backend cannot take is misuse.
      Check(
          Throws([&] { solver->Solve(*p, p->starting_point(), options, &r); }),
          p->name() + ": not a square system -> std::invalid_argument");
      continue;
    }
    const NlpStatus status =
        solver->Solve(*p, p->starting_point(), options, &r);
    char line[256];
    std::snprintf(line, sizeof line,
                  "%s: %s in %d iterations, viol %.1e, |x - x*| %.1e (%s)",
                  p->name().c_str(), ToString(status), r.iterations,
                  r.max_constraint_violation,
                  p->is_feasible()
                      ? (r.x - p->known_solution()).lpNorm<Eigen::Infinity>()
                      : std::numeric_limits<double>::quiet_NaN(),
                  r.backend_status.c_str());
    if (p->is_feasible()) {
      Check(status == NlpStatus::kConverged &&
                r.max_constraint_violation <= options.feasibility_tolerance &&
                (r.x - p->known_solution()).lpNorm<Eigen::Infinity>() <= 1e-8,
            line);
    } else {
      Check(status == NlpStatus::kInfeasible, line);
    }
  }

  // Misuse throws; numerics never do.
  CircleLineSystem circle;
  NlpResult r;
  Check(Throws([&] {
          solver->Solve(circle, Eigen::VectorXd::Ones(3), options, &r);
        }),
        "x0 of the wrong size -> std::invalid_argument");
  Eigen::VectorXd x_nan = circle.starting_point();
  x_nan(0) = std::numeric_limits<double>::quiet_NaN();
  Check(Throws([&] { solver->Solve(circle, x_nan, options, &r); }),
        "non-finite x0 -> std::invalid_argument");
  NlpOptions bad = options;
  bad.max_iterations = 0;
  Check(
      Throws([&] { solver->Solve(circle, circle.starting_point(), bad, &r); }),
      "invalid options -> std::invalid_argument");

  // NaN in the functions near the root: a status, not an exception.
  struct NanNearRoot final : public NlpProblem {
    CircleLineSystem inner;
    int num_variables() const override { return inner.num_variables(); }
    int num_constraints() const override { return inner.num_constraints(); }
    void GetBounds(Eigen::Ref<Eigen::VectorXd> a, Eigen::Ref<Eigen::VectorXd> b,
                   Eigen::Ref<Eigen::VectorXd> c,
                   Eigen::Ref<Eigen::VectorXd> d) const override {
      inner.GetBounds(a, b, c, d);
    }
    double Objective(
        const Eigen::Ref<const Eigen::VectorXd>& x) const override {
      return inner.Objective(x);
    }
    void ObjectiveGradient(const Eigen::Ref<const Eigen::VectorXd>& x,
                           Eigen::Ref<Eigen::VectorXd> g) const override {
      inner.ObjectiveGradient(x, g);
    }
    void Constraints(const Eigen::Ref<const Eigen::VectorXd>& x,
                     Eigen::Ref<Eigen::VectorXd> g) const override {
      inner.Constraints(x, g);
      if (x(0) > 1.2) g.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                            Eigen::Ref<Eigen::MatrixXd> j) const override {
      inner.ConstraintJacobian(x, j);
    }
  } nan_problem;
  NlpStatus status = NlpStatus::kNotRun;
  bool threw = false;
  try {
    status = solver->Solve(nan_problem, circle.starting_point(), options, &r);
  } catch (const std::exception&) {
    threw = true;
  }
  Check(
      !threw && status != NlpStatus::kConverged && status != NlpStatus::kNotRun,
      std::string("NaN near the root -> ") + ToString(status) +
          ", no exception");

  ContactLikeSystem contact;
  NlpOptions one = options;
  one.max_iterations = 1;
  status = solver->Solve(contact, contact.starting_point(), one, &r);
  Check(status == NlpStatus::kIterationLimit,
        std::string("max_iterations = 1 -> ") + ToString(status));
}

// ---------------------------------------------------- 2. integrator -----

// y' = R(pi/2) y + c y (rotation plus a radial drift that the projection
// removes), H = |y|^2 - 1, roots g = y_2. On H = 0 the angle grows at rate 1:
// y(t) = (cos(t + a0), sin(t + a0)).
class CircleOde final : public ConstrainedOde {
 public:
  double fail_after = std::numeric_limits<double>::infinity();
  bool roots = false;
  int state_size() const override { return 2; }
  int num_constraints() const override { return 1; }
  bool Rhs(double t, const Eigen::Ref<const Eigen::VectorXd>& y,
           Eigen::Ref<Eigen::VectorXd> ydot) override {
    if (t > fail_after) return false;
    ydot(0) = -y(1) + 0.3 * y(0);
    ydot(1) = y(0) + 0.3 * y(1);
    return true;
  }
  void Constraints(const Eigen::Ref<const Eigen::VectorXd>& y,
                   Eigen::Ref<Eigen::VectorXd> h) const override {
    h(0) = y.squaredNorm() - 1.0;
  }
  void ConstraintJacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                          Eigen::Ref<Eigen::MatrixXd> jac) const override {
    jac = 2.0 * y.transpose();
  }
  int num_roots() const override { return roots ? 1 : 0; }
  void Roots(double, const Eigen::Ref<const Eigen::VectorXd>& y,
             Eigen::Ref<Eigen::VectorXd> g) const override {
    g(0) = y(1);
  }
};

void CheckIntegrator(const std::string& backend) {
  std::printf("== integrator '%s' on the unit circle\n", backend.c_str());
  auto integrator = IntegratorRegistry::Create(backend);
  CircleOde ode;
  double errors[2];
  for (int k = 0; k < 2; ++k) {
    IntegratorOptions options;
    options.step = k == 0 ? 0.02 : 0.01;
    Eigen::VectorXd y(2);
    y << 1.0, 0.0;
    IntegratorResult r;
    const IntegratorStatus status =
        integrator->Integrate(ode, 0.0, 2.0, y, options, &r);
    errors[k] = (y - Eigen::Vector2d(std::cos(2.0), std::sin(2.0))).norm();
    char line[200];
    std::snprintf(line, sizeof line,
                  "h = %.2f: %s, %d steps, error %.2e, |H| %.1e", options.step,
                  ToString(status), r.steps, errors[k],
                  std::abs(y.squaredNorm() - 1.0));
    Check(
        status == IntegratorStatus::kSuccess && errors[k] < 1e-3 &&
            std::abs(y.squaredNorm() - 1.0) <=
                integrator->backend_options().GetDouble("projection_tolerance"),
        line);
  }
  Check(errors[0] / errors[1] > 3.0 && errors[0] / errors[1] < 5.0,
        "second order: error ratio for h/2 = " +
            std::to_string(errors[0] / errors[1]));

  {  // event at y_2 = 0, i.e. t = pi - 0.5 from angle 0.5
    ode.roots = true;
    IntegratorOptions options;
    options.step = 0.01;  // event time error ~ the O(h^2) phase error
    Eigen::VectorXd y(2);
    y << std::cos(0.5), std::sin(0.5);
    IntegratorResult r;
    const IntegratorStatus status =
        integrator->Integrate(ode, 0.0, 5.0, y, options, &r);
    const double expected = std::numbers::pi - 0.5;
    Check(status == IntegratorStatus::kEvent && r.root_index == 0 &&
              std::abs(r.t_reached - expected) < 1e-4 && std::abs(y(1)) < 1e-4,
          std::string("event: ") + ToString(status) +
              " at t = " + std::to_string(r.t_reached) + " (expected " +
              std::to_string(expected) + ")");
    ode.roots = false;
  }
  {  // Rhs failure: y is the last accepted state
    ode.fail_after = 0.5;
    IntegratorOptions options;
    options.step = 0.1;
    Eigen::VectorXd y(2);
    y << 1.0, 0.0;
    IntegratorResult r;
    const IntegratorStatus status =
        integrator->Integrate(ode, 0.0, 1.0, y, options, &r);
    Check(status == IntegratorStatus::kRhsFailure && r.t_reached <= 0.5 &&
              y.allFinite(),
          std::string("Rhs failure -> ") + ToString(status) +
              " at t = " + std::to_string(r.t_reached));
    ode.fail_after = std::numeric_limits<double>::infinity();
  }
  {
    Eigen::VectorXd y(2);
    y << 1.0, 0.0;
    IntegratorResult r;
    Check(Throws([&] { integrator->Integrate(ode, 1.0, 1.0, y, {}, &r); }),
          "t1 <= t0 -> std::invalid_argument");
  }
}

// --------------------------------------------------- 3. simulation -----

SimulationResult Simulate(const Scene& scene, const std::string& nlp,
                          const std::string& dae, Coupling coupling) {
  SimulationOptions options;
  options.nlp = nlp;
  options.dae = dae;
  options.coupling = coupling;
  Simulator simulator(scene, options);
  SimulationResult result = simulator.Run();
  double drift = 0;
  for (const auto& s : result.samples) drift = std::max(drift, s.drift);
  std::printf(
      "   %-20s %-20s %-7s %s: t = %.2f s, %zu samples, %d NLP solves "
      "(%lld iterations), %lld RHS, max drift %.1e, %.3f s\n",
      nlp.c_str(), dae.c_str(), ToString(coupling), result.status.c_str(),
      result.t_reached, result.samples.size(), result.nlp_solves,
      result.nlp_iterations, result.rhs_evaluations, drift,
      result.wall_seconds);
  return result;
}

void CheckSimulation(const std::string& data_dir, double t_end) {
  const std::string path = data_dir + "/bench/scenes/paper.yaml";
  std::printf("== paper scene (%s), t_end = %g s\n", path.c_str(), t_end);
  Scene scene = LoadScene(path);
  scene.t_end = t_end;
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  const SimulationResult ref =
      Simulate(scene, "newton", "rk-projection", Coupling::kZoh);
  Check(ref.success(), "built-in newton + rk-projection: " + ref.status);
  for (Coupling coupling : {Coupling::kZoh, Coupling::kCoupled}) {
    const SimulationResult res =
        Simulate(scene, example::kNlpName, example::kDaeName, coupling);
    double drift = 0;
    for (const auto& s : res.samples) drift = std::max(drift, s.drift);
    Check(res.success() && res.samples.size() == ref.samples.size() &&
              drift <= 1e-10,
          std::string("plugins, ") + ToString(coupling) + ": " + res.status +
              (res.stop_reason.empty() ? "" : " (" + res.stop_reason + ")"));
    if (coupling == Coupling::kZoh && res.success() && ref.success() &&
        !res.samples.empty()) {
      // Same NLP solution; midpoint (order 2) vs RK4 at h = dt.
      const double dx =
          (res.samples.back().position - ref.samples.back().position).norm();
      char line[120];
      std::snprintf(line, sizeof line,
                    "final COM position vs newton + rk-projection: %.2e m", dx);
      Check(dx < 1e-3, line);
    }
  }
}

// ------------------------------------------------------ 4. harness -----

#ifdef EXAMPLE_HAVE_HARNESS
// Splits one runs.csv line (fields with , or " are quoted, "" escapes ").
std::vector<std::string> CsvFields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

// The plugin_options group swept the plugins' own options: runs.csv records
// them (nlp_options / dae_options, the options used) and they took effect
// (midpoint_steps 2 takes twice the midpoint steps of midpoint_steps 1).
void CheckOptionSweep(const std::filesystem::path& runs_csv) {
  std::ifstream in(runs_csv);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = CsvFields(line);
  auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(
        std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f = CsvFields(line);
    if (f.size() == header.size() && f[col("suite_group")] == "plugin_options")
      rows.push_back(std::move(f));
  }
  Check(rows.size() == 4, "plugin_options group: " +
                              std::to_string(rows.size()) + " rows (want 4)");
  if (rows.size() != 4) return;
  // Grid order: lambda_init_scale, then midpoint_steps (innermost).
  for (std::size_t i = 0; i < 4; ++i) {
    const std::string& dae = rows[i][col("dae_options")];
    const std::string& nlp = rows[i][col("nlp_options")];
    const std::string want_sub =
        i % 2 == 0 ? "\"midpoint_steps\":1" : "\"midpoint_steps\":2";
    const std::string want_lambda =
        i < 2 ? "\"lambda_init_scale\":1e-06" : "\"lambda_init_scale\":0.001";
    Check(dae.find(want_sub) != std::string::npos &&
              nlp.find(want_lambda) != std::string::npos &&
              rows[i][col("status")] == "success",
          "row " + std::to_string(i) + ": nlp_options " + nlp +
              ", dae_options " + dae + ", " + rows[i][col("status")]);
  }
  for (std::size_t i : {0, 2}) {
    const long steps1 = std::stol(rows[i][col("steps")]);
    const long steps2 = std::stol(rows[i + 1][col("steps")]);
    Check(steps2 == 2 * steps1,
          "midpoint_steps 2 doubles the midpoint steps: " +
              std::to_string(steps1) + " -> " + std::to_string(steps2));
  }
}

void CheckSuite(const std::string& data_dir, int jobs) {
  // The shipped smoke suite's shape, with the plugins added to its grid.
  const std::string text = std::string(R"(
name: plugin-smoke
description: example plugins next to the built-in backends, 1 s paper scene
scenes:
  - name: paper
    file: ../scenes/paper.yaml
    overrides: {time: {t_end: 1}}
groups:
  pairs:
    nlp: [)") + example::kNlpName +
                           R"(, newton]
    dae: [)" + example::kDaeName +
                           R"(, rk-projection]
    coupling: [zoh, coupled]
    dt: [0.05]
  plugin_options:           # a sweep over the plugins' own options
    nlp: [)" + example::kNlpName +
                           R"(]
    dae: [)" + example::kDaeName +
                           R"(]
    dt: [0.05]
    nlp_options: {lambda_init_scale: [1.0e-6, 1.0e-3]}
    dae_options: {midpoint_steps: [1, 2]}
)";
  const std::string suites = data_dir + "/bench/suites";
  const bench::Suite suite =
      bench::LoadSuiteFromString(text, "<plugin-smoke>", suites);
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() /
      ("quasiroll-plugin-smoke-" + std::to_string(::getpid()));
  bench::HarnessOptions options;
  options.out_dir = out.string();
  options.jobs = jobs;
  options.progress = 0;
  std::printf("== suite runner (bench/harness/harness.h): %zu runs -> %s\n",
              suite.runs.size(), options.out_dir.c_str());
  const bench::HarnessSummary summary = bench::RunSuite(suite, options);
  Check(summary.executed == summary.selected && summary.failures == 0,
        "plugin smoke suite: " + std::to_string(summary.executed) + " runs, " +
            std::to_string(summary.failures) + " failures, " +
            std::to_string(summary.wall_seconds) + " s (runs.csv in " +
            options.out_dir + ")");
  CheckOptionSweep(out / "runs.csv");
  // An option the plugin does not have is refused before anything runs,
  // naming it and the known ones.
  try {
    bench::LoadSuiteFromString(text + "  bad:\n    dae: [" + example::kDaeName +
                                   "]\n    dae_options: {no_such_option: 1}\n",
                               "<bad>", suites);
    Check(false, "unknown plugin option accepted");
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    Check(msg.find("no_such_option") != std::string::npos &&
              msg.find("known: ") != std::string::npos &&
              msg.find("midpoint_steps") != std::string::npos,
          "unknown plugin option refused: " + msg);
  }
  if (g_failures == 0) std::filesystem::remove_all(out);
}
#endif

}  // namespace

int main(int argc, char** argv) {
  std::string data_dir = QUASIROLL_DATA_DIR;
  double t_end = 1.0;
  bool suite = true;
  int jobs = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--data-dir" && i + 1 < argc) {
      data_dir = argv[++i];
    } else if (arg == "--t-end" && i + 1 < argc) {
      t_end = std::atof(argv[++i]);
    } else if (arg == "--jobs" && i + 1 < argc) {
      jobs = std::atoi(argv[++i]);
    } else if (arg == "--no-suite") {
      suite = false;
    } else {
      std::fprintf(stderr,
                   "usage: %s [--data-dir DIR] [--t-end SECONDS] [--no-suite] "
                   "[--jobs N]\n",
                   argv[0]);
      return 2;
    }
  }
  try {
    example::RegisterExamplePlugins();
    CheckNlpBackend(example::kNlpName);
    CheckIntegrator(example::kDaeName);
    CheckSimulation(data_dir, t_end);
#ifdef EXAMPLE_HAVE_HARNESS
    if (suite) CheckSuite(data_dir, jobs);
#else
    if (suite)
      std::printf("(package without quasiroll::harness: suite skipped)\n");
#endif
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plugin_demo: unexpected exception: %s\n", e.what());
    return 1;
  }
  std::printf("%s: %d failed check(s)\n", g_failures ? "FAILED" : "PASSED",
              g_failures);
  return g_failures ? 1 : 0;
}
