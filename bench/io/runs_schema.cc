#include "quasiroll/bench/io/runs_schema.h"

#include <set>
#include <sstream>
#include <stdexcept>

#include "runs_columns_tsv.h"

namespace quasiroll::bench {

namespace {

std::vector<std::string> SplitTabs(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t tab = line.find('\t', start);
    fields.push_back(line.substr(start, tab - start));
    if (tab == std::string::npos) return fields;
    start = tab + 1;
  }
}

}  // namespace

std::vector<RunsColumn> ParseRunsColumns(const std::string& tsv) {
  static const std::set<std::string> kTypes = {"string", "int", "double",
                                               "json"};
  std::istringstream in(tsv);
  std::string line;
  std::vector<RunsColumn> columns;
  std::set<std::string> names;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const auto bad = [&](const std::string& why) {
      return std::logic_error("runs_columns.tsv line " +
                              std::to_string(line_no) + ": " + why);
    };
    if (line_no == 1) {
      if (line != "name\ttype\tunit\tdoc")
        throw bad("expected the header name<TAB>type<TAB>unit<TAB>doc");
      continue;
    }
    const std::vector<std::string> f = SplitTabs(line);
    if (f.size() != 4) throw bad("expected 4 tab-separated fields");
    if (f[0].empty() || !names.insert(f[0]).second)
      throw bad("empty or repeated column name '" + f[0] + "'");
    if (!kTypes.count(f[1])) throw bad("unknown type '" + f[1] + "'");
    if (f[2].empty() || f[3].empty()) throw bad("empty unit or doc");
    columns.push_back({f[0], f[1], f[2], f[3]});
  }
  if (columns.empty()) throw std::logic_error("runs_columns.tsv: no columns");
  return columns;
}

const std::vector<RunsColumn>& RunsCsvSchema() {
  static const std::vector<RunsColumn> schema =
      ParseRunsColumns(generated::kRunsColumnsTsv);
  return schema;
}

}  // namespace quasiroll::bench
