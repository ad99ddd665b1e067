#include "core/lab/preparation.hpp"

#include <algorithm>

#include "core/common/error.hpp"

namespace demcal::lab {

PreparationMethod parse_preparation_method(const std::string& text, const std::string& where) {
  for (auto m : {PreparationMethod::kClusters, PreparationMethod::kRandomMotion,
                 PreparationMethod::kTerminalVelocity, PreparationMethod::kPour})
    if (text == preparation_method_name(m)) return m;
  throw InputError(where, "unknown preparation method '" + text +
                              "' (known: clusters, random_motion, terminal_velocity, pour)");
}

std::string preparation_method_name(PreparationMethod method) {
  switch (method) {
    case PreparationMethod::kClusters:
      return "clusters";
    case PreparationMethod::kRandomMotion:
      return "random_motion";
    case PreparationMethod::kTerminalVelocity:
      return "terminal_velocity";
    case PreparationMethod::kPour:
      return "pour";
  }
  return "pour";
}

std::vector<std::string> preparation_params(PreparationMethod method) {
  switch (method) {
    case PreparationMethod::kClusters:
    case PreparationMethod::kRandomMotion:
      return {"agitation_speed", "agitation_time", "cluster_time"};
    case PreparationMethod::kTerminalVelocity:
      return {"terminal_velocity"};
    case PreparationMethod::kPour:
      return {};
  }
  return {};
}

bool pours_only(const std::string& test) {
  return test == "rotating_drum" || test == "shear_cell";
}

PreparationSpec make_preparation(const std::string& method,
                                 const std::map<std::string, double>& params,
                                 const std::string& where) {
  const PreparationMethod m = parse_preparation_method(method, where + ".method");
  const auto own = preparation_params(m);
  for (const auto& [name, value] : params)
    if (std::find(own.begin(), own.end(), name) == own.end()) {
      std::string known;
      for (const auto& o : own) known += (known.empty() ? "" : ", ") + o;
      throw InputError(where + "." + name, "not a parameter of preparation '" + method +
                                               "' (known: " + (known.empty() ? "none" : known) +
                                               ")");
    }
  PreparationSpec s = contact::params_from_map<PreparationSpec>(params, where);
  s.method = m;
  return s;
}

}  // namespace demcal::lab
