// Fuzzes io::read_stl with arbitrary bytes (ASCII or binary STL, truncated, lying counts, NaN
// vertices): it must return a mesh or throw InputError.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "core/common/error.hpp"
#include "core/io/stl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // read_stl reads a file: the input goes to a private file of this process.
  static const std::string path = "/tmp/demcal-fuzz-stl-" + std::to_string(getpid()) + ".stl";
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return 0;
  }
  try {
    const auto mesh = demcal::io::read_stl(path, 1e-3);
    (void)mesh;
  } catch (const demcal::InputError&) {
  }
  return 0;
}
