#pragma once
// CSV files: time series written (a header row, then one row of numbers per sample, full double
// precision), and tables read (a header row and rows of text cells, e.g. a design for `analyze`).
#include <fstream>
#include <string>
#include <vector>

namespace demcal::io {

class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);
  void row(const std::vector<double>& values);

 private:
  std::ofstream out_;
  std::size_t columns_;
  std::string path_;
};

/// A table read from CSV: the header's names and the rows' cells, each row as long as the header.
struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

/// One line's cells: commas split them except inside double quotes, quotes and CR dropped, spaces
/// and tabs trimmed.
std::vector<std::string> split_csv_line(const std::string& line);
/// Parses CSV text: empty lines and lines starting with '#' skipped, the first other line the
/// header. InputError "NAME:LINE" for a row whose cell count differs from the header's, and for a
/// table without data rows.
CsvTable parse_csv(const std::string& text, const std::string& name);
/// parse_csv of a file; InputError naming it if it cannot be opened.
CsvTable read_csv(const std::string& path);

}  // namespace demcal::io
