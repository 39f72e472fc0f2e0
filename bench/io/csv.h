// CSV text as the harness writes and reads it (RFC 4180 quoting): runs.csv,
// trajectory.csv, runs/<id>.csv, the --plan table.
#pragma once

#include <string>
#include <vector>

namespace quasiroll {

// A CSV field: quoted (with doubled quotes) if it contains , " CR or LF.
std::string CsvField(const std::string& value);
// One row: the fields, each through CsvField, joined by commas (no newline).
std::string JoinCsvRow(const std::vector<std::string>& fields);

// The fields of one line. A quote opens a quoted stretch in which commas are
// data and "" is one quote; the quotes themselves are dropped. An empty line
// is one empty field. Never throws (an unclosed quote runs to the end).
std::vector<std::string> SplitCsvLine(const std::string& line);
// The rows of a CSV text; a line break inside quotes belongs to the field.
// The last row needs no final line break; an empty text has no rows.
std::vector<std::vector<std::string>> ParseCsv(const std::string& text);

}  // namespace quasiroll
