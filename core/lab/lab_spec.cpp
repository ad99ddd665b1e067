#include "core/lab/lab_spec.hpp"

#include "core/io/contact_law_yaml.hpp"
#include "core/io/scene_yaml.hpp"

namespace demcal::lab {

MaterialModel read_material(const io::YamlNode& n) {
  n.expect_only({"particle_law", "wall_law", "sizes", "size_scale", "density", "scaling", "shape"});
  MaterialModel m;
  m.particle_law = io::read_contact_law_spec(n["particle_law"]);
  m.wall_law = n.has("wall_law") ? io::read_contact_law_spec(n["wall_law"]) : m.particle_law;
  m.sizes = io::read_size_distribution(n["sizes"]);
  m.size_scale = n.number("size_scale", 1.0);
  m.density = n["density"].as_number();
  if (auto s = n.child("scaling")) {
    s->expect_only({"law", "factor"});
    m.scaling = contact::scaling_law_from_name((*s)["law"].as_string(), s->where() + ".law");
    m.scale_factor = s->number("factor", 1.0);
  }
  if (auto s = n.child("shape")) {
    std::map<std::string, double> params;
    for (const auto& key : s->keys())
      if (key != "kind") params[key] = (*s)[key].as_number();
    try {
      m.shape = particles::make_shape_spec((*s)["kind"].as_string(), params, "shape");
    } catch (const InputError& e) {
      const std::string key = e.where().substr(std::string("shape.").size());
      (*s)[key].fail(e.message());
    }
  }
  try {
    m.validate();
  } catch (const InputError& e) {
    throw InputError(n.where() + "." + e.where(), e.message());
  }
  return m;
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
  spec.material = read_material(root["material"]);
  spec.options.seed = static_cast<std::uint64_t>(root.number("seed", 1));
  spec.options.threads = static_cast<int>(root.number("threads", 1));
  return spec;
}

}  // namespace demcal::lab
