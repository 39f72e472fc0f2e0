// The option-table check shared by the NLP and the integrator conformance
// suites (ExpectOptionTableValid in nlp_conformance.h and
// integrator_conformance.h): both backend kinds have the same option API.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>
#include <string>

#include "quasiroll/core/options.h"

namespace quasiroll::conformance {

// Options-table name alphabet (core/options.h: [a-z0-9_]+).
inline bool IsOptionName(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::islower(static_cast<unsigned char>(c)) ||
           std::isdigit(static_cast<unsigned char>(c)) || c == '_';
  });
}

// Every option of `table` at its default, as SetBackendOptions() text.
inline GivenOptions DefaultsAsGiven(const OptionTable& table) {
  GivenOptions defaults;
  for (const OptionSpec& spec : table)
    defaults[spec.name] = OptionValueText(spec.default_value);
  return defaults;
}

// `Backend`: NlpSolver or Integrator (name(), option_table(),
// backend_options(), SetBackendOptions()).
template <typename Backend>
void ExpectBackendOptionTableValid(Backend& backend) {
  SCOPED_TRACE(backend.name());
  const OptionTable table = backend.option_table();
  std::set<std::string> names;
  for (const OptionSpec& spec : table) {
    std::string why;
    EXPECT_TRUE(spec.Accepts(spec.default_value, &why))
        << spec.name << ": default outside its own range: " << why;
    EXPECT_TRUE(names.insert(spec.name).second)
        << spec.name << ": duplicate name";
    EXPECT_TRUE(IsOptionName(spec.name)) << spec.name << ": not [a-z0-9_]+";
    EXPECT_FALSE(spec.doc.empty()) << spec.name << ": no doc line";
    EXPECT_EQ(ShadowedRunSetting({spec}), "")
        << spec.name << ": named like a run setting (RunSettingNames())";
  }
  EXPECT_EQ(backend.backend_options().values().size(), table.size());
  EXPECT_NO_THROW(backend.SetBackendOptions(DefaultsAsGiven(table)))
      << "the defaults, given as text, are not accepted";
  // An unknown option is rejected with a message naming it and the known
  // ones.
  try {
    backend.SetBackendOptions({{"no_such_option", "1"}});
    ADD_FAILURE() << "unknown option accepted";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'no_such_option'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("known: "), std::string::npos) << msg;
    if (!table.empty()) {
      EXPECT_NE(msg.find(table.front().name), std::string::npos) << msg;
    }
  }
}

}  // namespace quasiroll::conformance
