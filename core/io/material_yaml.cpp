#include "core/io/material_yaml.hpp"

#include <sstream>

#include "core/common/exact_number.hpp"
#include "core/io/contact_law_yaml.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/model/preparation.hpp"

namespace demcal::io {
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

/// `{key: model, name: value, ...}` of a slot, a shape or a preparation.
std::string flow_block(const std::string& key, const std::string& kind,
                       const std::map<std::string, double>& params) {
  std::string out = "{" + key + ": " + kind;
  for (const auto& [name, value] : params) out += ", " + name + ": " + exact_number(value);
  return out + "}";
}

void write_law(std::ostream& y, const std::string& name, const contact::ContactLawSpec& law) {
  y << "  " << name << ":\n";
  const std::pair<const char*, const contact::SlotSpec*> slots[] = {{"normal", &law.normal},
                                                                    {"cohesion", &law.cohesion},
                                                                    {"tangential", &law.tangential},
                                                                    {"rolling", &law.rolling}};
  for (const auto& [slot, spec] : slots)
    if (!spec->model.empty() && spec->model != "none")
      y << "    " << slot << ": " << flow_block("model", spec->model, spec->params) << "\n";
}

std::string sizes_yaml(const particles::SizeDistribution& sizes) {
  if (const auto* m = std::get_if<particles::Monodisperse>(&sizes))
    return "{monodisperse: {radius: " + exact_number(m->radius) + "}}";
  if (const auto* l = std::get_if<particles::LogNormal>(&sizes))
    return "{lognormal: {median_radius: " + exact_number(l->median_radius) +
           ", sigma_g: " + exact_number(l->sigma_g) +
           ", truncate_k: " + exact_number(l->truncate_k) + "}}";
  const auto& d = std::get<particles::DiscreteClasses>(sizes);
  std::string radii, fractions;
  for (std::size_t k = 0; k < d.radii.size(); ++k) {
    radii += (k ? ", " : "") + exact_number(d.radii[k]);
    fractions += (k ? ", " : "") + exact_number(d.mass_fractions[k]);
  }
  return "{discrete: {radii: [" + radii + "], mass_fractions: [" + fractions + "]}}";
}

}  // namespace

std::string material_yaml(const lab::MaterialModel& m) {
  std::ostringstream y;
  y << "material:\n";
  write_law(y, "particle_law", m.particle_law);
  write_law(y, "wall_law", m.wall_law);
  y << "  sizes: " << sizes_yaml(m.sizes) << "\n"
    << "  size_scale: " << exact_number(m.size_scale) << "\n"
    << "  density: " << exact_number(m.density) << "\n"
    << "  scaling: {law: " << contact::scaling_law_name(m.scaling)
    << ", factor: " << exact_number(m.scale_factor) << "}\n";
  if (m.shape.kind != particles::ShapeKind::kSphere)
    y << "  shape: "
      << flow_block("kind", particles::shape_kind_name(m.shape.kind),
                    particles::shape_values(m.shape))
      << "\n";
  if (m.preparation.method != lab::PreparationMethod::kPour)
    y << "  preparation: "
      << flow_block("method", lab::preparation_method_name(m.preparation.method),
                    lab::preparation_values(m.preparation))
      << "\n";
  if (m.real_median_radius != 0.0)
    y << "  real_median_radius: " << exact_number(m.real_median_radius) << "\n";
  return y.str();
}

lab::PreparationSpec read_preparation(const YamlNode& node) {
  return read_kind_block(node, "method", "preparation", lab::make_preparation);
}

lab::MaterialModel read_material(const YamlNode& n) {
  n.expect_only({"particle_law", "wall_law", "sizes", "size_scale", "density", "scaling", "shape",
                 "preparation", "real_median_radius"});
  lab::MaterialModel m;
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
  if (auto s = n.child("preparation")) m.preparation = read_preparation(*s);
  try {
    m.validate();
  } catch (const InputError& e) {
    throw InputError(n.where() + "." + e.where(), e.message());
  }
  return m;
}

}  // namespace demcal::io
