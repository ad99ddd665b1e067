#include "core/lab/lab_run_yaml.hpp"

#include <sstream>

#include "core/io/material_yaml.hpp"

namespace demcal::lab {

std::string lab_run_yaml(const LabRunSpec& spec) {
  std::ostringstream y;
  y << "test: " << spec.test << "\nsettings: {";
  bool first = true;
  for (const auto& [name, value] : spec.settings) {
    y << (first ? "" : ", ") << name << ": " << io::yaml_number(value);
    first = false;
  }
  y << "}\nseed: " << spec.options.seed << "\nthreads: " << spec.options.threads << "\n"
    << io::material_yaml(spec.material);
  return y.str();
}

LabRunSpec read_lab_run(const io::YamlNode& root) {
  root.expect_only({"test", "settings", "seed", "threads", "material"});
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
  return spec;
}

}  // namespace demcal::lab
