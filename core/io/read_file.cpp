#include "core/io/read_file.hpp"

#include <fstream>
#include <sstream>

#include "core/common/error.hpp"

namespace demcal::io {

std::string read_file(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open " + what);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace demcal::io
