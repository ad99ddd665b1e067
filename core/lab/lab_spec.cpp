#include "core/lab/lab_spec.hpp"

#include "core/io/contact_law_yaml.hpp"
#include "core/io/scene_yaml.hpp"

namespace demcal::lab {
namespace {

/// A block of a kind and its parameters (`shape: {kind: rod, aspect_ratio: 2}`, `preparation:
/// {method: clusters, cluster_time: 0.02}`) built by `make(kind, params, name)`; an error of
/// `make` is reported at the line of the key it names.
template <class Make>
auto read_kind_block(const io::YamlNode& s, const std::string& kind_key, const std::string& name,
                     Make make) {
  std::map<std::string, double> params;
  for (const auto& key : s.keys())
    if (key != kind_key) params[key] = s[key].as_number();
  try {
    return make(s[kind_key].as_string(), params, name);
  } catch (const InputError& e) {
    s[e.where().substr(name.size() + 1)].fail(e.message());
  }
}

}  // namespace

MaterialModel read_material(const io::YamlNode& n) {
  n.expect_only({"particle_law", "wall_law", "sizes", "size_scale", "density", "scaling", "shape",
                 "preparation", "real_median_radius"});
  MaterialModel m;
  m.particle_law = io::read_contact_law_spec(n["particle_law"]);
  m.wall_law = n.has("wall_law") ? io::read_contact_law_spec(n["wall_law"]) : m.particle_law;
  m.sizes = io::read_size_distribution(n["sizes"]);
  m.size_scale = n.number("size_scale", 1.0);
  m.density = n["density"].as_number();
  m.real_median_radius = n.number("real_median_radius", 0.0);
  if (auto s = n.child("scaling")) {
    s->expect_only({"law", "factor"});
    m.scaling = contact::scaling_law_from_name((*s)["law"].as_string(), s->where() + ".law");
    m.scale_factor = s->number("factor", 1.0);
  }
  if (auto s = n.child("shape"))
    m.shape = read_kind_block(*s, "kind", "shape", particles::make_shape_spec);
  if (auto s = n.child("preparation"))
    m.preparation = read_kind_block(*s, "method", "preparation", make_preparation);
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
