#include "quasiroll/bench/io/csv.h"

namespace quasiroll {

std::string CsvField(const std::string& value) {
  if (value.find_first_of(",\"\r\n") == std::string::npos) return value;
  std::string out = "\"";
  for (char c : value) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string JoinCsvRow(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) line += ',';
    line += CsvField(fields[i]);
  }
  return line;
}

namespace {

// The rows of `text`; with `one_row` the whole text is one row (a line break
// is data), as SplitCsvLine has always read a line.
std::vector<std::vector<std::string>> ReadRows(const std::string& text,
                                               bool one_row) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string field;
  bool quoted = false;
  bool pending = false;  // characters read since the last row ended
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    pending = true;
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      row.push_back(std::move(field));
      field.clear();
    } else if (c == '\n' && !one_row) {
      row.push_back(std::move(field));
      field.clear();
      rows.push_back(std::move(row));
      row.clear();
      pending = false;
    } else {
      field += c;
    }
  }
  if (one_row || pending) {
    row.push_back(std::move(field));
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

std::vector<std::string> SplitCsvLine(const std::string& line) {
  return ReadRows(line, true).front();
}

std::vector<std::vector<std::string>> ParseCsv(const std::string& text) {
  return ReadRows(text, false);
}

}  // namespace quasiroll
