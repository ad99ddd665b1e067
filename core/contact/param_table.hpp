#pragma once
// One table per model: the names, units, valid ranges and meaning of its parameters.
// The same table drives spec parsing, validation of factor paths and bounds, and docs.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/common/error.hpp"

namespace demcal::contact {

inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();
inline bool is_set(double v) {
  return !std::isnan(v);
}

template <class P>
struct ParamInfo {
  std::string_view name;
  std::string_view unit;
  double lo;        ///< smallest valid value (inclusive)
  double hi;        ///< largest valid value (inclusive)
  double fallback;  ///< default; kUnset = must be given (unless the model says otherwise)
  std::string_view doc;
  double P::*field;
};

/// Refuses a key of `values` that is not among `own` (the parameters of the kind chosen, e.g. a
/// shape or a preparation method), naming `where.<key>`, `kind` and the known ones.
inline void require_own_params(const std::map<std::string, double>& values,
                               const std::vector<std::string>& own, const std::string& where,
                               const std::string& kind) {
  for (const auto& [name, value] : values) {
    if (std::find(own.begin(), own.end(), name) != own.end()) continue;
    std::string known;
    for (const auto& o : own) known += (known.empty() ? "" : ", ") + o;
    throw InputError(where + "." + name, "not a parameter of " + kind + " (known: " +
                                             (known.empty() ? "none" : known) + ")");
  }
}

/// Reads `values` into a parameter struct through its table. Every key must be known and every
/// value inside its range; `where` is the field path used in error messages. The model's
/// finalize() then checks the combination and derives its constants.
template <class P>
P params_from_map(const std::map<std::string, double>& values, const std::string& where) {
  P p{};
  const auto table = P::table();
  for (const auto& info : table) p.*info.field = info.fallback;
  for (const auto& [key, value] : values) {
    const ParamInfo<P>* found = nullptr;
    for (const auto& info : table)
      if (info.name == key) found = &info;
    if (!found) {
      std::string known;
      for (const auto& info : table) known += (known.empty() ? "" : ", ") + std::string(info.name);
      throw InputError(where + "." + key, "unknown parameter of model '" + std::string(P::kName) +
                                              "' (known: " + known + ")");
    }
    if (!(value >= found->lo && value <= found->hi))
      throw InputError(where + "." + key,
                       "value " + std::to_string(value) + " outside the valid range [" +
                           std::to_string(found->lo) + ", " + std::to_string(found->hi) + "] " +
                           std::string(found->unit));
    p.*found->field = value;
  }
  p.finalize(where);
  return p;
}

}  // namespace demcal::contact
