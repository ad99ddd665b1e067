// Fuzzes the STL reader (io::parse_stl, the body of io::read_stl) with arbitrary bytes (ASCII or
// binary STL, truncated, lying facet counts, NaN vertices): it must return a mesh or throw
// InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/common/error.hpp"
#include "core/io/stl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const auto mesh = demcal::io::parse_stl(bytes, "fuzz.stl", 1e-3);
    (void)mesh;
  } catch (const demcal::InputError&) {
  }
  return 0;
}
