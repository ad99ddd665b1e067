#pragma once
// A double as text that reads back to the same double: 17 significant digits (printf's %.17g),
// for files and identities that must round-trip (YAML specs, CSV tables, a material's identity).
#include <cstdio>
#include <string>

namespace demcal {

/// `value` in 17 significant digits ("0.10000000000000001", "1e-19", "nan").
inline std::string exact_number(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", value);
  return buf;
}

}  // namespace demcal
