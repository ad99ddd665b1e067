#include "core/lab/lab_run_yaml.hpp"

#include <cmath>
#include <sstream>

#include "core/common/exact_number.hpp"
#include "core/io/material_yaml.hpp"

namespace demcal::lab {

std::string lab_run_yaml(const LabRunSpec& spec) {
  std::ostringstream y;
  y << "test: " << spec.test << "\nsettings: {";
  bool first = true;
  for (const auto& [name, value] : spec.settings) {
    y << (first ? "" : ", ") << name << ": " << exact_number(value);
    first = false;
  }
  y << "}\nseed: " << spec.options.seed << "\nthreads: " << spec.options.threads << "\n"
    << io::material_yaml(spec.material);
  if (!spec.expected.empty()) {
    y << "expected: {";
    first = true;
    for (const auto& [name, value] : spec.expected) {
      y << (first ? "" : ", ") << name << ": " << exact_number(value);
      first = false;
    }
    y << "}\n";
  }
  return y.str();
}

LabRunSpec read_lab_run(const io::YamlNode& root) {
  root.expect_only({"test", "settings", "seed", "threads", "material", "expected"});
  LabRunSpec spec;
  spec.test = root["test"].as_string();
  const auto& info = find_lab_info(spec.test);
  if (auto s = root.child("settings")) {
    for (const auto& key : s->keys()) spec.settings[key] = (*s)[key].as_number();
    try {
      validate_settings(info, spec.settings, "settings");
    } catch (const InputError& e) {
      (*s)[e.where().substr(std::string("settings.").size())].fail(e.message());
    }
  }
  spec.material = io::read_material(root["material"]);
  spec.options.seed = static_cast<std::uint64_t>(root.number("seed", 1));
  spec.options.threads = static_cast<int>(root.number("threads", 1));
  if (auto e = root.child("expected"))
    for (const auto& key : e->keys()) {
      if (!reports_metric(info, key))
        (*e)[key].fail("'" + key + "' is not a metric of the " + spec.test + " test");
      spec.expected[key] = (*e)[key].as_number();
    }
  return spec;
}

std::vector<ExpectedMetric> compare_expected(const LabRunSpec& spec,
                                             const std::map<std::string, double>& metrics,
                                             double tolerance) {
  std::vector<ExpectedMetric> out;
  for (const auto& [name, stored] : spec.expected) {
    ExpectedMetric m{name, stored, std::nan(""), std::nan(""), false};
    if (const auto it = metrics.find(name); it != metrics.end()) {
      m.simulated = it->second;
      const double miss = std::abs(m.simulated - stored);
      m.difference = stored != 0.0 ? miss / std::abs(stored) : miss;
      m.reproduced = m.simulated == stored || m.difference <= tolerance;
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace demcal::lab
