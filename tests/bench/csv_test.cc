// bench/io/csv: RFC 4180 quoting, splitting and the join -> split round trip.
#include "quasiroll/bench/io/csv.h"

#include <gtest/gtest.h>

namespace quasiroll {
namespace {

using Row = std::vector<std::string>;

TEST(Csv, QuotesOnlyFieldsThatNeedIt) {
  EXPECT_EQ(CsvField("plain 1.5e-3"), "plain 1.5e-3");
  EXPECT_EQ(CsvField(""), "");
  EXPECT_EQ(CsvField("a,b"), "\"a,b\"");
  EXPECT_EQ(CsvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(CsvField("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(CsvField("cr\r"), "\"cr\r\"");
  EXPECT_EQ(JoinCsvRow({"a", "b,c", "", "d"}), "a,\"b,c\",,d");
  EXPECT_EQ(JoinCsvRow({}), "");
}

TEST(Csv, SplitsQuotedCommasDoubledQuotesAndEmptyFields) {
  EXPECT_EQ(SplitCsvLine("a,\"b,c\",d"), (Row{"a", "b,c", "d"}));
  EXPECT_EQ(SplitCsvLine("\"x \"\"q\"\" y\",z"), (Row{"x \"q\" y", "z"}));
  EXPECT_EQ(SplitCsvLine(",,"), (Row{"", "", ""}));
  EXPECT_EQ(SplitCsvLine("a,"), (Row{"a", ""}));
  EXPECT_EQ(SplitCsvLine(""), (Row{""}));
  EXPECT_EQ(SplitCsvLine("\"\",x"), (Row{"", "x"}));
  // A line is one row: a line break is data, as is an unclosed quote's rest.
  EXPECT_EQ(SplitCsvLine("a\nb,c"), (Row{"a\nb", "c"}));
  EXPECT_EQ(SplitCsvLine("a,\"b,c"), (Row{"a", "b,c"}));
}

TEST(Csv, JoinThenSplitGivesTheFieldsBack) {
  const std::vector<Row> rows = {
      {"run_id", "stop_reason", "", "x"},
      {"a,b", "\"", "\"\"", ",\","},
      {"", "", ""},
      {"lone"},
      {"tab\there", "semi;colon", "trailing ", " leading"}};
  for (const Row& row : rows)
    EXPECT_EQ(SplitCsvLine(JoinCsvRow(row)), row) << JoinCsvRow(row);
}

TEST(Csv, ParsesRowsWithLineBreaksInsideQuotes) {
  const std::string text = JoinCsvRow({"h1", "h2"}) + "\n" +
                           JoinCsvRow({"multi\nline", "v"}) + "\n" +
                           JoinCsvRow({"", "last"});  // no final line break
  EXPECT_EQ(
      ParseCsv(text),
      (std::vector<Row>{{"h1", "h2"}, {"multi\nline", "v"}, {"", "last"}}));
  EXPECT_EQ(ParseCsv("a\n\nb\n"), (std::vector<Row>{{"a"}, {""}, {"b"}}));
  EXPECT_EQ(ParseCsv("\"\""), (std::vector<Row>{{""}}));
  EXPECT_TRUE(ParseCsv("").empty());
}

}  // namespace
}  // namespace quasiroll
