// Fuzzes the CSV table reader of `demcal analyze` (io::parse_csv) with arbitrary text: it must
// return a table whose rows are as long as its header or throw InputError.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/common/error.hpp"
#include "core/io/csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto table = demcal::io::parse_csv(text, "fuzz.csv");
    for (const auto& row : table.rows)
      if (row.size() != table.header.size()) std::abort();
  } catch (const demcal::InputError&) {
  }
  return 0;
}
