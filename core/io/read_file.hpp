#pragma once
// Reading a whole input file.
#include <string>

namespace demcal::io {

/// The bytes of the file at `path`; InputError(path, "cannot open " + what) if it cannot be
/// opened (e.g. what = "STL file").
std::string read_file(const std::string& path, const std::string& what = "file");

}  // namespace demcal::io
