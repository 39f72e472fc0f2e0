#include "quasiroll/bench/harness/run_request.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll::bench {

namespace {

[[noreturn]] void Fail(const KeyNamer& namer, const std::string& key,
                       const std::string& problem) {
  throw std::invalid_argument(namer(key) + ": " + problem);
}

void RequirePositive(const KeyNamer& namer, const std::string& key,
                     const std::optional<double>& v) {
  if (v && !(std::isfinite(*v) && *v > 0))
    Fail(namer, key, "must be a finite number > 0, got " + Num(*v));
}

void RequireNonNegative(const KeyNamer& namer, const std::string& key,
                        const std::optional<double>& v) {
  if (v && !(std::isfinite(*v) && *v >= 0))
    Fail(namer, key, "must be a finite number >= 0, got " + Num(*v));
}

void RequireIn(const KeyNamer& namer, const std::string& key,
               const std::optional<int>& v, int lo, int hi) {
  if (v && (*v < lo || *v > hi))
    Fail(namer, key,
         "must be an integer in [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "], got " + Num(*v));
}

template <typename RegistryT>
std::string Backend(const KeyNamer& namer, const std::string& key,
                    const std::string& given) {
  const std::string name =
      given.empty() ? RegistryT::WithRole(BackendRole::kDefault) : given;
  if (!RegistryT::Has(name)) {
    std::string list;
    for (const std::string& k : RegistryT::Names())
      list += (list.empty() ? "" : ", ") + k;
    Fail(namer, key, "must be one of " + list + ", got '" + name + "'");
  }
  return name;
}

// A backend whose option table uses a run setting's name is refused.
void RequireNoShadowing(const KeyNamer& namer, const std::string& options_key,
                        const std::string& backend, const OptionTable& table) {
  const std::string key = ShadowedRunSetting(table);
  if (!key.empty())
    Fail(namer, options_key,
         "backend '" + backend +
             "' declares an option named like the run "
             "setting " +
             namer(key) +
             " (a backend option may not shadow a run setting), got '" + key +
             "'");
}

void CheckValues(const RunRequest& r, const KeyNamer& namer) {
  RequirePositive(namer, "dt", r.dt);
  RequirePositive(namer, "t_end", r.t_end);
  RequireNonNegative(namer, "sigma", r.sigma);
  RequirePositive(namer, "tol", r.tol);
  RequirePositive(namer, "atol", r.atol);
  RequirePositive(namer, "nlp_tol", r.nlp_tol);
  RequireIn(namer, "nlp_max_iter", r.nlp_max_iter, 1, 1000000);
  RequireIn(namer, "dae_index", r.dae_index, 1, 2);
  RequireIn(namer, "substeps", r.substeps, 1, 100000);
  RequireIn(namer, "contact_check", r.contact_check, 0, 1000000000);
  RequireIn(namer, "event_points", r.event_points, 0, 1000);
  RequirePositive(namer, "event_tolerance", r.event_tolerance);
  RequirePositive(namer, "mu", r.mu);
  RequirePositive(namer, "eps", r.eps);
}

// dt <= t_end, named by whichever of the two the caller gave.
void CheckTimes(const RunRequest& r, const KeyNamer& namer, double dt,
                double t_end) {
  if (dt <= t_end) return;
  if (r.dt)
    Fail(namer, "dt",
         "must be <= the end time " + Num(t_end) + " s (" +
             (r.t_end ? namer("t_end") : std::string("scene time.t_end")) +
             "), got " + Num(dt));
  Fail(namer, "t_end",
       "must be >= the hold interval " + Num(dt) + " s (scene time.dt), got " +
           Num(t_end));
}

// The shorthands onto the integrator's options: a note where the
// integrator has no such option, an error where the option is also given.
void ApplyShorthands(const RunRequest& r, const KeyNamer& namer,
                     const OptionTable& table, ResolvedRun* out) {
  for (const IntegratorShorthand& sh : IntegratorShorthands()) {
    const std::string key = sh.key;
    const std::optional<std::string> value = ShorthandText(r, key);
    if (!value) continue;
    if (FindOption(table, sh.option) == nullptr) {
      out->notes.push_back(namer(key) + " does not apply to " +
                           out->options.dae + " (ignored)");
      continue;
    }
    if (out->options.dae_options.count(sh.option))
      Fail(namer, key,
           "also given as " + namer("dae_options") + " " + sh.option);
    out->options.dae_options[sh.option] = *value;
  }
}

}  // namespace

std::optional<std::string> ShorthandText(const RunRequest& r,
                                         const std::string& key) {
  if (key == "rk_method") return r.rk_method;
  if (key == "sigma" && r.sigma) return Num(*r.sigma);
  if (key == "dae_index" && r.dae_index) return std::to_string(*r.dae_index);
  return std::nullopt;
}

const std::vector<IntegratorShorthand>& IntegratorShorthands() {
  static const std::vector<IntegratorShorthand> shorthands = {
      {"rk_method", "rk_method"},
      {"sigma", "baumgarte_sigma"},
      {"dae_index", "dae_index"}};
  return shorthands;
}

ResolvedRun ResolveRunRequest(const Scene& base, const RunRequest& r,
                              const KeyNamer& namer) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  ResolvedRun out;
  SimulationOptions& o = out.options;
  o.nlp = Backend<NlpSolverRegistry>(namer, "nlp", r.nlp);
  o.dae = Backend<IntegratorRegistry>(namer, "dae", r.dae);
  CheckValues(r, namer);
  out.scene = base;
  if (r.mu) out.scene.mu = *r.mu;
  if (r.eps) out.scene.epsilon = *r.eps;
  if (r.mode) out.scene.mode = *r.mode;
  o.coupling = r.coupling;
  o.dt = r.dt.value_or(out.scene.dt);
  o.t_end = r.t_end.value_or(out.scene.t_end);
  CheckTimes(r, namer, o.dt, o.t_end);
  if (r.tol) o.integrator.rtol = *r.tol;
  if (r.atol) o.integrator.atol = *r.atol;
  o.nlp_options = r.nlp_options;
  o.dae_options = r.dae_options;
  const OptionTable dae_table =
      IntegratorRegistry::Create(o.dae)->option_table();
  RequireNoShadowing(namer, "nlp_options", o.nlp,
                     NlpSolverRegistry::Create(o.nlp)->option_table());
  RequireNoShadowing(namer, "dae_options", o.dae, dae_table);
  ApplyShorthands(r, namer, dae_table, &out);
  if (r.substeps) o.integrator.step = o.dt / *r.substeps;
  if (r.nlp_tol) o.quasi_static.residual_tolerance = *r.nlp_tol;
  if (r.nlp_max_iter) o.quasi_static.max_iterations = *r.nlp_max_iter;
  if (r.contact_check) o.second_contact_check_every = *r.contact_check;
  if (r.locate_events) o.locate_events = *r.locate_events;
  if (r.event_points) o.event_points = *r.event_points;
  if (r.event_tolerance) o.event_tolerance = *r.event_tolerance;
  if (r.locate_switches) o.locate_switches = *r.locate_switches;
  return out;
}

ResolvedSolve ResolveSolveRequest(const Scene& base, const RunRequest& r,
                                  const KeyNamer& namer) {
  ResolvedRun run = ResolveRunRequest(base, r, namer);
  return {std::move(run.scene), run.options.nlp,
          std::move(run.options.nlp_options), run.options.quasi_static};
}

}  // namespace quasiroll::bench
