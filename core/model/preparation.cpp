#include "core/model/preparation.hpp"

#include "core/common/error.hpp"

namespace demcal::lab {

PreparationMethod parse_preparation_method(const std::string& text, const std::string& where) {
  for (auto m : kPreparationMethods)
    if (text == preparation_method_name(m)) return m;
  throw InputError(where,
                   "unknown preparation method '" + text +
                       "' (known: clusters, random_motion, terminal_velocity, pour, growth)");
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
    case PreparationMethod::kGrowth:
      return "growth";
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
    case PreparationMethod::kGrowth:
      return {"solid_fraction", "growth_rate"};
    case PreparationMethod::kPour:
      return {};
  }
  return {};
}

std::map<std::string, double> preparation_values(const PreparationSpec& prep) {
  std::map<std::string, double> out;
  for (const auto& name : preparation_params(prep.method))
    for (const auto& info : PreparationSpec::table())
      if (name == info.name) out[name] = prep.*(info.field);
  return out;
}

PreparationSpec make_preparation(const std::string& method,
                                 const std::map<std::string, double>& params,
                                 const std::string& where) {
  const PreparationMethod m = parse_preparation_method(method, where + ".method");
  contact::require_own_params(params, preparation_params(m), where, "preparation '" + method + "'");
  PreparationSpec s = contact::params_from_map<PreparationSpec>(params, where);
  s.method = m;
  return s;
}

}  // namespace demcal::lab
