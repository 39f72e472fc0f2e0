#include "quasiroll/bench/harness/method_id.h"

#include <variant>

#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll::bench {

namespace {

std::string ValueText(const OptionValue& v) {
  if (std::holds_alternative<double>(v)) return Num(std::get<double>(v));
  return OptionValueText(v);
}

std::string Bracketed(const std::string& list) {
  return list.empty() ? "" : "[" + list + "]";
}

// Without a table the given texts are all there is (names are map-ordered).
std::string AllGiven(const GivenOptions& given) {
  std::string list;
  for (const auto& [name, text] : given)
    list += (list.empty() ? "" : ",") + name + "=" + text;
  return Bracketed(list);
}

template <typename RegistryT>
std::string BackendPart(const std::string& name, const GivenOptions& given,
                        const std::string& kind) {
  if (!RegistryT::Has(name)) return name + AllGiven(given);
  return name + NonDefaultOptions(RegistryT::Create(name)->option_table(),
                                  given, kind + " '" + name + "'");
}

}  // namespace

std::string NonDefaultOptions(const OptionTable& table,
                              const GivenOptions& given,
                              const std::string& context) {
  // Resolving gives typed values, so a default spelled differently ("5.0"
  // for 5) is recognised as the default.
  const OptionValues used = ResolveOptions(table, given, context);
  std::string list;
  for (const auto& [name, value] : used.values()) {  // std::map: by name
    const OptionSpec* spec = FindOption(table, name);
    if (spec == nullptr || value == spec->default_value) continue;
    list += (list.empty() ? "" : ",") + name + "=" + ValueText(value);
  }
  return Bracketed(list);
}

std::string MethodId(const std::string& nlp, const GivenOptions& nlp_options,
                     const std::string& dae, const GivenOptions& dae_options,
                     Coupling coupling) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  return BackendPart<NlpSolverRegistry>(nlp, nlp_options, "NLP backend") + "/" +
         BackendPart<IntegratorRegistry>(dae, dae_options, "integrator") + "/" +
         ToString(coupling);
}

std::string MethodId(const RunSpec& run) {
  return MethodId(run.nlp, run.nlp_options, run.dae, run.dae_options,
                  run.coupling);
}

}  // namespace quasiroll::bench
