#include "core/model/campaign_model.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/common/error.hpp"

namespace demcal::lab {
namespace {

std::string lacks(const std::string& path, const CampaignInstance& instance) {
  return "'" + path + "' is not a parameter of test '" + instance.name +
         "' (its own wall_law lacks it)";
}

/// The first instance of `test` with `seed`'s name, empty when none.
std::string first_instance(const std::vector<CampaignInstance>& instances, const std::string& test,
                           std::uint64_t seed) {
  for (const auto& i : instances)
    if (i.test == test && i.seed == seed) return i.name;
  return {};
}

/// Each instance's test in the catalogue and admitted with its settings and material.
std::vector<ModelledInstance> model_instances(const std::vector<CampaignInstance>& instances,
                                              const MaterialModel& campaign) {
  std::vector<ModelledInstance> out;
  for (const auto& i : instances) {
    const LabTestInfo* info = nullptr;
    try {
      info = &find_lab_info(i.test);
    } catch (const InputError& e) {
      throw InputError(i.where + ".test", e.message());
    }
    admit_lab_test(i.test, i.material, i.settings, instance_fields(i.where, i.material, campaign));
    ModelledInstance m{{}, i.settings, i.settings, {}};
    for (const auto& metric : info->metrics) m.metrics.push_back(metric.name);
    if (!info->starts_from.empty())
      m.waits_for = first_instance(instances, info->starts_from, i.seed);
    out.push_back(std::move(m));
  }
  return out;
}

/// The campaign's material with its fixed values, each of them valid there and in every instance.
MaterialModel with_fixed(const CampaignModel& c) {
  MaterialModel material = with_parameters(c.material, c.fixed);
  for (const auto& i : c.instances) {
    for (const auto& f : c.fixed)
      if (!has_parameter(i.material, f.path))
        throw InputError(f.where,
                         "not a parameter of test '" + i.name + "' (its own wall_law lacks it)");
    with_parameters(i.material, c.fixed);
  }
  return material;
}

bool is_fixed(const CampaignModel& c, const std::string& path) {
  return std::any_of(c.fixed.begin(), c.fixed.end(),
                     [&](const ParameterValue& f) { return f.path == path; });
}

/// A factor's bounds: finite, ordered, inside the parameter's valid range, > 0 on a log scale.
void check_factor_bounds(const CampaignFactor& f, const ParameterInfo& info) {
  if (!std::isfinite(f.low)) throw InputError(f.where + ".low", "must be finite");
  if (!std::isfinite(f.high)) throw InputError(f.where + ".high", "must be finite");
  if (!(f.low < f.high))
    throw InputError(f.where + ".high", "must be above low (" + message_number(f.low) + ")");
  const std::string range = " the valid range [" + message_number(info.lo) + ", " +
                            message_number(info.hi) + "] " + info.unit;
  if (f.low < info.lo)
    throw InputError(f.where + ".low", message_number(f.low) + " is below" + range);
  if (f.high > info.hi)
    throw InputError(f.where + ".high", message_number(f.high) + " is above" + range);
  if (f.log && !(f.low > 0)) throw InputError(f.where + ".low", "must be > 0 on a log scale");
}

/// A factor's tied paths: each a parameter of the material and of every instance, taking both
/// of the factor's bounds, and set by nothing else (no factor, no fixed value, no other tie).
void check_tied(const CampaignModel& c, const CampaignFactor& f, const MaterialModel& material,
                std::set<std::string>& seen) {
  for (std::size_t i = 0; i < f.tied.size(); ++i) {
    const std::string& path = f.tied[i];
    const std::string at = f.where + ".tied[" + std::to_string(i) + "]";
    require_parameter(material, path, at);
    const bool a_factor = std::any_of(c.factors.begin(), c.factors.end(),
                                      [&](const CampaignFactor& g) { return g.path == path; });
    if (a_factor || is_fixed(c, path) || !seen.insert(path).second)
      throw InputError(at, "'" + path + "' is set twice (a factor, a fixed value or another tie)");
    with_parameters(material, {{path, f.low, at}, {path, f.high, at}});
    for (const auto& instance : c.instances)
      if (!has_parameter(instance.material, path)) throw InputError(at, lacks(path, instance));
  }
}

void check_factors(const CampaignModel& c, const MaterialModel& material) {
  std::set<std::string> seen;
  for (const auto& f : c.factors) {
    const ParameterInfo info = require_parameter(material, f.path, f.where + ".path");
    if (is_fixed(c, f.path))
      throw InputError(f.where + ".path", "'" + f.path + "' is also in spec.fixed");
    if (!seen.insert(f.path).second)
      throw InputError(f.where + ".path", "'" + f.path + "' is a factor twice");
    check_factor_bounds(f, info);
    with_parameters(material,
                    {{f.path, f.low, f.where + ".low"}, {f.path, f.high, f.where + ".high"}});
    for (const auto& instance : c.instances)
      if (!has_parameter(instance.material, f.path))
        throw InputError(f.where + ".path", lacks(f.path, instance));
    check_tied(c, f, material, seen);
  }
}

bool has_setting(const std::string& test, const std::string& name) {
  const auto& info = find_lab_info(test);
  return std::any_of(info.settings.begin(), info.settings.end(),
                     [&](const contact::ParamDoc& d) { return d.name == name; });
}

/// A fidelity level of a test setting: every instance that has the setting takes the value,
/// checked against the setting's range and the instance's size limit.
void check_setting_level(const CampaignModel& c, const std::string& where,
                         std::vector<ModelledInstance>& out, bool high) {
  const std::string name = c.fidelity->path.substr(kSettingsPrefix.size());
  int users = 0;
  for (std::size_t i = 0; i < c.instances.size(); ++i) {
    const auto& instance = c.instances[i];
    if (!has_setting(instance.test, name)) continue;
    ++users;
    Settings& settings = high ? out[i].high : out[i].low;
    settings = at_fidelity_level(instance.test, settings, *c.fidelity, high);
    try {
      admit_lab_test(instance.test, instance.material, settings);
    } catch (const InputError& e) {
      throw InputError(where, "test '" + instance.name + "': " + e.where() + ": " + e.message());
    }
  }
  if (users == 0)
    throw InputError("spec.fidelity.path",
                     "no test of the campaign has the setting '" + name + "'");
}

/// The fidelity axis: a setting some instance has, admitted at both levels (which the instances'
/// settings then take), or a parameter nothing else sets, valid at both levels.
void check_fidelity(const CampaignModel& c, const MaterialModel& material,
                    std::vector<ModelledInstance>& out) {
  if (!c.fidelity) return;
  const auto& f = *c.fidelity;
  if (f.path.starts_with(kSettingsPrefix)) {
    check_setting_level(c, "spec.fidelity.low", out, false);
    check_setting_level(c, "spec.fidelity.high", out, true);
    return;
  }
  require_parameter(material, f.path, "spec.fidelity.path");
  for (const auto& factor : c.factors) {
    const bool tied =
        std::find(factor.tied.begin(), factor.tied.end(), f.path) != factor.tied.end();
    if (factor.path == f.path || tied)
      throw InputError("spec.fidelity.path", "'" + f.path + "' is also a factor or a tie");
  }
  if (is_fixed(c, f.path))
    throw InputError("spec.fidelity.path", "'" + f.path + "' is also in spec.fixed");
  with_parameters(material,
                  {{f.path, f.low, "spec.fidelity.low"}, {f.path, f.high, "spec.fidelity.high"}});
}

}  // namespace

Settings at_fidelity_level(const std::string& test, Settings settings,
                           const CampaignFidelity& fidelity, bool high) {
  if (!fidelity.path.starts_with(kSettingsPrefix)) return settings;
  const std::string name = fidelity.path.substr(kSettingsPrefix.size());
  if (has_setting(test, name)) settings[name] = high ? fidelity.high : fidelity.low;
  return settings;
}

std::vector<ModelledInstance> model_campaign(const CampaignModel& c) {
  std::vector<ModelledInstance> out = model_instances(c.instances, c.material);
  const MaterialModel material = with_fixed(c);
  check_factors(c, material);
  check_fidelity(c, material, out);
  for (const auto& run : c.runs)
    for (std::size_t i = 0; i < c.instances.size(); ++i) {
      const auto& instance = c.instances[i];
      admit_run(instance.test, instance.material, run.parameters,
                run.high ? out[i].high : out[i].low,
                instance_fields(instance.where, instance.material, c.material), run.row);
    }
  return out;
}

FieldPaths instance_fields(const std::string& where, const MaterialModel& instance,
                           const MaterialModel& campaign) {
  return {where + ".settings",
          instance.preparation == campaign.preparation ? "spec.material" : where};
}

void admit_run(const std::string& test, const MaterialModel& material,
               const std::map<std::string, double>& parameters, const Settings& settings,
               const FieldPaths& paths, int row) {
  try {
    admit_lab_test(test, with_run_parameters(material, parameters), settings, paths);
  } catch (const InputError& e) {
    throw InputError(e.where(), "design run " + std::to_string(row) + ": " + e.message());
  }
}

MaterialModel with_switches(MaterialModel m, const std::map<std::string, std::string>& switches) {
  for (const auto& [what, value] : switches) {
    if (what == "shape") {
      m.shape = particles::make_shape_spec(value, {}, "shape");
    } else if (what == "particle_law.rolling") {
      m.particle_law.rolling.model = value;
      m.particle_law.rolling.params["mu_r"] = 0.0;
    } else if (what == "preparation") {
      m.preparation = make_preparation(value, {}, "preparation");
    } else if (what == "sizes" && value == "lognormal") {
      if (const auto* one = std::get_if<particles::Monodisperse>(&m.sizes))
        m.sizes = particles::LogNormal{one->radius, particles::kNarrowestLogNormal};
    } else {
      throw InputError("diagnose", "unknown model switch " + what);
    }
  }
  m.validate();
  return m;
}

std::map<std::string, std::string> instance_switches(
    const std::string& test, const MaterialModel& instance, const MaterialModel& campaign,
    const std::map<std::string, std::string>& switches) {
  std::map<std::string, std::string> taken;
  for (const auto& [what, value] : switches) {
    const bool skipped =
        what == "preparation" &&
        (!accepts_preparation(test, parse_preparation_method(value, "diagnose." + what)) ||
         !(instance.preparation == campaign.preparation));
    if (!skipped) taken.emplace(what, value);
  }
  return taken;
}

std::map<std::string, double> taken_parameters(std::map<std::string, double> parameters,
                                               const std::map<std::string, std::string>& switches,
                                               const std::map<std::string, std::string>& taken) {
  for (const auto& [what, value] : switches) {
    if (taken.contains(what)) continue;
    // A named prefix, not the binding: clang 14 cannot capture a structured binding.
    const std::string prefix = what + ".";
    std::erase_if(parameters, [&prefix](const auto& p) { return p.first.starts_with(prefix); });
  }
  return parameters;
}

}  // namespace demcal::lab
