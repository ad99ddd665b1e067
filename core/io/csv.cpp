#include "core/io/csv.hpp"

#include <cstdio>

#include "core/common/error.hpp"

namespace demcal::io {

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : out_(path), columns_(columns.size()), path_(path) {
  if (!out_) throw InputError(path, "cannot write file");
  for (std::size_t k = 0; k < columns.size(); ++k) out_ << (k ? "," : "") << columns[k];
  out_ << "\n";
}

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_) throw std::logic_error("CSV row of wrong width for " + path_);
  char buf[32];
  for (std::size_t k = 0; k < values.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%.17g", values[k]);
    out_ << (k ? "," : "") << buf;
  }
  out_ << "\n";
}

}  // namespace demcal::io
