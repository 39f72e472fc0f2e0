// A method's identity (docs/harness.md, "Method identity"): what ran is the
// backends, the coupling and the options given to the backends, so option
// variants of one backend pair are different methods (runs.csv `method`,
// and every chart, table and finding of the report).
#pragma once

#include <string>

#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/core/options.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll::bench {

// "[name=value,...]": the options of `given` whose value differs from
// `table`'s default, sorted by name, values in the output files' format
// (Num for numbers, so "1.0e-10" and "1e-10" read alike); "" when every
// option is at its default. Throws std::invalid_argument for an option the
// table lacks or an ill-typed value (as ResolveOptions, naming `context`).
std::string NonDefaultOptions(const OptionTable& table,
                              const GivenOptions& given,
                              const std::string& context);

// "<nlp>[opts]/<dae>[opts]/<coupling>", e.g.
// "newton/rk-projection[rk_method=dp54]/coupled". `nlp_options` and
// `dae_options` are the options handed to the backends, the shorthands
// (rk_method, sigma, dae_index) already applied, so a CLI run and a suite
// run of the same method agree. A backend not in its registry (a plugin not
// loaded) lists every given option: its defaults are unknown.
std::string MethodId(const std::string& nlp, const GivenOptions& nlp_options,
                     const std::string& dae, const GivenOptions& dae_options,
                     Coupling coupling);

// The method of a grid point (its RunSpec::nlp_options / dae_options).
std::string MethodId(const RunSpec& run);

}  // namespace quasiroll::bench
