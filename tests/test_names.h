// gtest parameter names may contain only [A-Za-z0-9_]; registry names such as
// "ipopt-mumps" or "rk-projection" are mapped onto that alphabet.
#pragma once

#include <cctype>
#include <string>

namespace quasiroll::testing_util {

inline std::string GtestName(std::string name) {
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

// Name generator of INSTANTIATE_TEST_SUITE_P for string parameters:
// INSTANTIATE_TEST_SUITE_P(All, Suite, ValuesIn(names), ParamName()).
struct ParamName {
  template <class ParamInfo>
  std::string operator()(const ParamInfo& info) const {
    return GtestName(info.param);
  }
};

}  // namespace quasiroll::testing_util
