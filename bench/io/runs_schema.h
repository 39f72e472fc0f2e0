// The runs.csv schema: one definition, bench/io/runs_columns.tsv (name, type,
// unit, doc per column, in runs.csv order), embedded at build time. The
// report (reports/quasiroll_report/data.py) and docs/formats.md read the
// same file, so the writer, the reader and the docs cannot disagree.
#pragma once

#include <string>
#include <vector>

namespace quasiroll::bench {

struct RunsColumn {
  std::string name;
  std::string type;  // "string", "int", "double" or "json"
  std::string unit;  // "s", "m", "rad", "N", "m/s", ...; "-" if none
  std::string doc;   // one sentence
};

// The columns of runs.csv, in order. Throws std::logic_error on a malformed
// table (a build-time file: a bug, not an input error).
const std::vector<RunsColumn>& RunsCsvSchema();

// Parses the text of runs_columns.tsv (header line "name\ttype\tunit\tdoc",
// then one line per column); throws std::logic_error naming the bad line.
std::vector<RunsColumn> ParseRunsColumns(const std::string& tsv);

}  // namespace quasiroll::bench
