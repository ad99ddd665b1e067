#pragma once
// CSV time series: a header row, then one row of numbers per sample (full double precision).
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

}  // namespace demcal::io
