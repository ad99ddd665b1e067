#include "core/doe/factor.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace demcal::doe {

void Factor::validate() const {
  const std::string where = "factor " + name;
  if (!(std::isfinite(low) && std::isfinite(high)) || !(low < high)) {
    throw InputError(where, "needs finite bounds with low < high, got low = " +
                                std::to_string(low) + ", high = " + std::to_string(high));
  }
  if (scale == Scale::kLog && low <= 0.0) {
    throw InputError(where, "a log-scaled factor needs low > 0, got " + std::to_string(low));
  }
}

double Factor::xi(double natural) const {
  return scale == Scale::kLog ? std::log10(natural) : natural;
}

double Factor::to_coded(double natural) const {
  if (scale == Scale::kLog && natural <= 0.0) {
    throw InputError("factor " + name,
                     "value " + std::to_string(natural) + " is not positive on a log scale");
  }
  const double lo = xi(low), hi = xi(high);
  return (2.0 * xi(natural) - lo - hi) / (hi - lo);
}

double Factor::to_natural(double coded) const {
  const double lo = xi(low), hi = xi(high);
  const double v = 0.5 * (lo + hi) + 0.5 * coded * (hi - lo);
  return scale == Scale::kLog ? std::pow(10.0, v) : v;
}

}  // namespace demcal::doe
