// A GoogleTest fixture for tests that share one tiny suite (WriteTinySuite)
// across a test suite: written and loaded once, removed at the end. CRTP so
// that each fixture has statics of its own.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/suite.h"
#include "test_support.h"

namespace quasiroll::bench {

template <class Fixture>
class TinySuiteTest : public ::testing::Test {
 protected:
  // Call from the fixture's SetUpTestSuite(): a fresh directory named
  // `prefix` with tiny.yaml holding `groups`, loaded into suite_.
  static void PrepareTinySuite(const std::string& prefix,
                               const std::string& groups) {
    root_ = FreshTempDir(prefix);
    suite_path_ = WriteTinySuite(root_, groups);
    suite_ = LoadSuite(suite_path_);
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(root_); }

  // Harness options writing to ROOT/sub with `jobs` workers, no progress.
  static HarnessOptions Options(const std::string& sub, int jobs) {
    return QuietHarnessOptions(root_ / sub, jobs);
  }

  static inline std::filesystem::path root_;
  static inline std::string suite_path_;
  static inline Suite suite_;
};

}  // namespace quasiroll::bench
