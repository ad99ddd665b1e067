#pragma once
// How the command line prints a number: `precision` significant digits in the shortest of fixed
// and scientific notation (printf's %g), "n/a" for a value that is not finite.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace demcal::cli {

inline std::string fmt(double v, int precision = 5) {
  if (!std::isfinite(v)) return "n/a";
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

}  // namespace demcal::cli
