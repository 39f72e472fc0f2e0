// The runs.csv schema (bench/io/runs_schema.h): the embedded table is the
// source file bench/io/runs_columns.tsv, and malformed tables are refused.
#include "quasiroll/bench/io/runs_schema.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "quasiroll/bench/harness/harness.h"

namespace quasiroll::bench {
namespace {

std::string SourceTsv() {
  std::ifstream in(std::string(QUASIROLL_SOURCE_DIR) +
                   "/bench/io/runs_columns.tsv");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(RunsSchema, EmbedsTheSourceTable) {
  const std::vector<RunsColumn> source = ParseRunsColumns(SourceTsv());
  const std::vector<RunsColumn>& embedded = RunsCsvSchema();
  ASSERT_EQ(embedded.size(), source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    EXPECT_EQ(embedded[i].name, source[i].name);
    EXPECT_EQ(embedded[i].type, source[i].type);
    EXPECT_EQ(embedded[i].unit, source[i].unit);
    EXPECT_EQ(embedded[i].doc, source[i].doc);
    EXPECT_EQ(RunsCsvColumns()[i], source[i].name);
  }
}

TEST(RunsSchema, RefusesMalformedTables) {
  const std::string header = "name\ttype\tunit\tdoc\n";
  EXPECT_NO_THROW(ParseRunsColumns(header + "a\tint\t-\tA.\n"));
  for (const std::string& bad :
       {std::string("a\tint\t-\tA.\n"),             // no header
        header + "a\tint\t-\n",                     // 3 fields
        header + "a\tfloat\t-\tA.\n",               // unknown type
        header + "a\tint\t-\tA.\na\tint\t-\tA.\n",  // repeated name
        header + "a\tint\t\tA.\n",                  // empty unit
        header})                                    // no columns
    EXPECT_THROW(ParseRunsColumns(bad), std::logic_error) << bad;
}

}  // namespace
}  // namespace quasiroll::bench
