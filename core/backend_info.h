// What a backend says about itself (docs/plugins.md, "BackendInfo"): stored
// with its factory in the NLP / integrator registry, so that the harness, the
// shard planner, the failure classification and the report read a backend's
// properties from it and never name a backend in their own code.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "quasiroll/core/options.h"

namespace quasiroll {

// A job some code needs a backend for, without naming one.
enum class BackendRole {
  kDefault,         // used when a command, suite or script names none
  kReference,       // the fixed-step scheme of numerical references
  kReferenceCheck,  // the independent check of an adaptive reference
  // NLP only: the square-system Newton method whose short solves follow a
  // root in time to locate solution jumps (core/solution_jumps.h), whatever
  // the run's backend.
  kContinuation,
};

struct BackendInfo {
  std::string description;  // one line, shown by `quasiroll list`
  // Method family, e.g. "explicit Runge-Kutta", "BDF", "interior point",
  // "SQP", "least squares", "Newton".
  std::string family;
  // Third-party library doing the numerics and its version ("" for
  // quasiroll's own code).
  std::string library;
  std::string library_version;
  // Separate instances may run concurrently in one process (bench --jobs,
  // the Python module); a backend that is not gets one job at a time. For
  // an NLP backend it must equal NlpSolver::SupportsConcurrentInstances()
  // (the conformance kit checks). Default: not claimed.
  bool thread_safe = false;
  std::vector<BackendRole> roles;

  // Shard planner cost hints (docs/cluster.md, "Cost model"); 0 = unknown
  // (the planner then uses the median of the known ones).
  // NLP backends: time of a quasi-static solve / that of the default NLP.
  double cost_ratio = 0;
  // Integrators: seconds per hold interval with the default NLP, per
  // coupling (calibrated as in docs/cluster.md).
  double seconds_per_hold_zoh = 0;
  double seconds_per_hold_coupled = 0;

  // Whether the step size is error-controlled with these (resolved) backend
  // options; unset = never.
  std::function<bool(const OptionValues&)> adaptive;
  // A failure cause known a priori for these options and integrator step,
  // e.g. "baumgarte_instability" (docs/harness.md, Failure causes); "" when
  // none; unset = none.
  std::function<std::string(const OptionValues&, double step)>
      known_instability;

  bool HasRole(BackendRole role) const {
    for (BackendRole r : roles)
      if (r == role) return true;
    return false;
  }
  bool IsAdaptive(const OptionValues& options) const {
    return adaptive ? adaptive(options) : false;
  }
  std::string KnownInstability(const OptionValues& options, double step) const {
    return known_instability ? known_instability(options, step) : std::string();
  }
};

// The info of a backend whose separate instances may run concurrently
// (thread_safe), with its description, family and library; the cost hints,
// roles and callbacks are left to the caller.
BackendInfo ThreadSafeBackendInfo(std::string description, std::string family,
                                  std::string library = "",
                                  std::string library_version = "");

// "default", "reference", "reference_check".
const char* ToString(BackendRole role);

}  // namespace quasiroll
