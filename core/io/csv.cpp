#include "core/io/csv.hpp"

#include <sstream>

#include "core/common/error.hpp"
#include "core/common/exact_number.hpp"
#include "core/io/read_file.hpp"

namespace demcal::io {

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : out_(path), columns_(columns.size()), path_(path) {
  if (!out_) throw InputError(path, "cannot write file");
  for (std::size_t k = 0; k < columns.size(); ++k) out_ << (k ? "," : "") << columns[k];
  out_ << "\n";
}

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_) throw std::logic_error("CSV row of wrong width for " + path_);
  for (std::size_t k = 0; k < values.size(); ++k) out_ << (k ? "," : "") << exact_number(values[k]);
  out_ << "\n";
}

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (const char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      cells.push_back(cell);
      cell.clear();
    } else if (c != '\r') {
      cell += c;
    }
  }
  cells.push_back(cell);
  for (auto& s : cells) {
    const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
    s = b == std::string::npos ? "" : s.substr(b, e - b + 1);
  }
  return cells;
}

CsvTable parse_csv(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  CsvTable t;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    auto cells = split_csv_line(line);
    if (t.header.empty()) {
      t.header = cells;
      continue;
    }
    if (cells.size() != t.header.size()) {
      throw InputError(
          name + ":" + std::to_string(line_no),
          std::to_string(cells.size()) + " cells, header has " + std::to_string(t.header.size()));
    }
    t.rows.push_back(cells);
  }
  if (t.rows.empty()) throw InputError(name, "no data rows");
  return t;
}

CsvTable read_csv(const std::string& path) {
  return parse_csv(read_file(path), path);
}

}  // namespace demcal::io
