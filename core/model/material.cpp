#include "core/model/material.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/common/error.hpp"
#include "core/common/exact_number.hpp"

namespace demcal::lab {
namespace {

/// A number for a message, in six significant digits (1e-09, 10).
std::string short_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

contact::SlotSpec& slot_of(contact::ContactLawSpec& law, const std::string& slot,
                           const std::string& path) {
  if (slot == "normal") return law.normal;
  if (slot == "cohesion") return law.cohesion;
  if (slot == "tangential") return law.tangential;
  if (slot == "rolling") return law.rolling;
  throw InputError(path, "unknown contact-law slot '" + slot + "'");
}

struct Path {
  std::string law, slot, param;
};

/// Splits "particle_law.normal.k2_ratio"; returns false for paths outside the laws.
bool split_law_path(const std::string& path, Path& out) {
  const auto a = path.find('.');
  if (a == std::string::npos) return false;
  out.law = path.substr(0, a);
  if (out.law != "particle_law" && out.law != "wall_law") return false;
  const auto b = path.find('.', a + 1);
  if (b == std::string::npos) throw InputError(path, "expected <law>.<slot>.<parameter>");
  out.slot = path.substr(a + 1, b - a - 1);
  out.param = path.substr(b + 1);
  return true;
}

void append_law(std::vector<ParameterInfo>& out, const contact::ContactLawSpec& law,
                const std::string& name) {
  for (const auto& slot : contact::slot_names()) {
    const contact::SlotSpec& s = slot == "normal"       ? law.normal
                                 : slot == "cohesion"   ? law.cohesion
                                 : slot == "tangential" ? law.tangential
                                                        : law.rolling;
    if (s.model.empty()) continue;
    for (const auto& p : contact::model_params(slot, s.model))
      out.push_back({name + "." + slot + "." + p.name, p.unit, p.lo, p.hi});
  }
}

void radius_params(std::vector<ParameterInfo>& out, const particles::SizeDistribution& sizes) {
  out.push_back({"sizes.scale", "-", 1e-6, 1e6});
  if (std::holds_alternative<particles::Monodisperse>(sizes))
    out.push_back({"sizes.radius", "m", 1e-9, 10.0});
  if (std::holds_alternative<particles::LogNormal>(sizes)) {
    out.push_back({"sizes.median_radius", "m", 1e-9, 10.0});
    out.push_back({"sizes.sigma_g", "-", 1.0 + 1e-9, 10.0});
  }
}

double* size_field(MaterialModel& m, const std::string& path) {
  if (path == "sizes.scale") return &m.size_scale;
  if (auto* mono = std::get_if<particles::Monodisperse>(&m.sizes); mono && path == "sizes.radius")
    return &mono->radius;
  if (auto* ln = std::get_if<particles::LogNormal>(&m.sizes)) {
    if (path == "sizes.median_radius") return &ln->median_radius;
    if (path == "sizes.sigma_g") return &ln->sigma_g;
  }
  return nullptr;
}

double* shape_field(particles::ShapeSpec& shape, const std::string& path) {
  if (path.rfind("shape.", 0) != 0) return nullptr;
  for (const auto& info : particles::ShapeSpec::table())
    if (path.substr(6) == info.name) return &(shape.*info.field);
  return nullptr;
}

double* preparation_field(PreparationSpec& prep, const std::string& path) {
  if (path.rfind("preparation.", 0) != 0) return nullptr;
  const auto own = preparation_params(prep.method);
  const std::string name = path.substr(12);
  if (std::find(own.begin(), own.end(), name) == own.end()) return nullptr;
  for (const auto& info : PreparationSpec::table())
    if (name == info.name) return &(prep.*info.field);
  return nullptr;
}

}  // namespace

contact::ScaleFactors MaterialModel::factors() const {
  return contact::scale_factors(scaling, scale_factor);
}

contact::ContactLaw MaterialModel::simulated_particle_law() const {
  return contact::scale(contact::ContactLaw::from_spec(particle_law, "particle_law"), factors());
}

contact::ContactLaw MaterialModel::simulated_wall_law() const {
  return contact::scale(contact::ContactLaw::from_spec(wall_law, "wall_law"), factors());
}

particles::SizeDistribution MaterialModel::simulated_sizes() const {
  const double k = size_scale * factors().length;
  return std::visit(
      [&](auto d) -> particles::SizeDistribution {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, particles::Monodisperse>)
          d.radius *= k;
        else if constexpr (std::is_same_v<D, particles::DiscreteClasses>)
          for (double& r : d.radii) r *= k;
        else
          d.median_radius *= k;
        return d;
      },
      sizes);
}

double MaterialModel::simulated_density() const {
  return density * factors().density;
}

std::optional<particles::ClumpTemplate> MaterialModel::clump_template() const {
  if (shape.kind == particles::ShapeKind::kSphere) return std::nullopt;
  auto clump = particles::make_template(shape);
  // A clump of one sphere (a cluster without spread) is a sphere, and runs as one.
  if (clump.size() == 1) return std::nullopt;
  return clump;
}

void MaterialModel::validate() const {
  contact::ContactLaw::from_spec(particle_law, "particle_law");
  contact::ContactLaw::from_spec(wall_law, "wall_law");
  particles::validate(sizes, "sizes");
  if (!(density > 0.0)) throw InputError("density", "must be > 0");
  if (!(size_scale > 0.0)) throw InputError("sizes.scale", "must be > 0");
  if (real_median_radius != 0.0 &&
      !(real_median_radius >= kRealMedianRadiusMin && real_median_radius <= kRealMedianRadiusMax))
    throw InputError("real_median_radius", "must be 0 (not stated) or in [" +
                                               short_number(kRealMedianRadiusMin) + ", " +
                                               short_number(kRealMedianRadiusMax) + "] m");
  factors();
}

namespace {

void identify_law(std::string& out, const contact::ContactLawSpec& law, const std::string& name) {
  const std::pair<const char*, const contact::SlotSpec*> slots[] = {{"normal", &law.normal},
                                                                    {"cohesion", &law.cohesion},
                                                                    {"tangential", &law.tangential},
                                                                    {"rolling", &law.rolling}};
  for (const auto& [slot, spec] : slots) {
    out += name + "." + slot + "=" + spec->model + "\n";
    for (const auto& [param, value] : spec->params)
      out += name + "." + slot + "." + param + "=" + exact_number(value) + "\n";
  }
}

std::string size_identity(const particles::SizeDistribution& sizes) {
  if (const auto* m = std::get_if<particles::Monodisperse>(&sizes))
    return "monodisperse " + exact_number(m->radius);
  if (const auto* l = std::get_if<particles::LogNormal>(&sizes))
    return "lognormal " + exact_number(l->median_radius) + " " + exact_number(l->sigma_g) + " " +
           exact_number(l->truncate_k);
  const auto& d = std::get<particles::DiscreteClasses>(sizes);
  std::string out = "discrete";
  for (std::size_t k = 0; k < d.radii.size(); ++k)
    out += " " + exact_number(d.radii[k]) + ":" + exact_number(d.mass_fractions[k]);
  return out;
}

}  // namespace

std::string material_identity(const MaterialModel& model) {
  std::string out;
  identify_law(out, model.particle_law, "particle_law");
  identify_law(out, model.wall_law, "wall_law");
  out += "sizes=" + size_identity(model.sizes) + "\n";
  out += "sizes.scale=" + exact_number(model.size_scale) + "\n";
  out += "density=" + exact_number(model.density) + "\n";
  out += "scaling=" + std::to_string(static_cast<int>(model.scaling)) + " " +
         exact_number(model.scale_factor) + "\n";
  out += "shape=" + std::to_string(static_cast<int>(model.shape.kind)) + "\n";
  for (const auto& [name, value] : particles::shape_values(model.shape))
    out += "shape." + name + "=" + exact_number(value) + "\n";
  out += "preparation=" + preparation_method_name(model.preparation.method) + "\n";
  for (const auto& info : PreparationSpec::table())
    out += "preparation." + std::string(info.name) + "=" +
           exact_number(model.preparation.*(info.field)) + "\n";
  return out;
}

std::vector<ParameterInfo> parameters(const MaterialModel& model) {
  std::vector<ParameterInfo> out;
  append_law(out, model.particle_law, "particle_law");
  append_law(out, model.wall_law, "wall_law");
  out.push_back({"density", "kg/m^3", 1e-3, 1e6});
  radius_params(out, model.sizes);
  out.push_back({"scaling.factor", "-", 1e-6, 1e6});
  const auto shape_now = shape_values(model.shape);
  for (const auto& info : particles::ShapeSpec::table())
    if (shape_now.count(std::string(info.name)))
      out.push_back({"shape." + std::string(info.name), std::string(info.unit), info.lo, info.hi});
  const auto own = preparation_params(model.preparation.method);
  for (const auto& info : PreparationSpec::table())
    if (std::find(own.begin(), own.end(), std::string(info.name)) != own.end())
      out.push_back(
          {"preparation." + std::string(info.name), std::string(info.unit), info.lo, info.hi});
  return out;
}

double default_agitation_time(const MaterialModel& model) {
  constexpr double kG = 9.81;
  const double d = 2.0 * particles::max_radius(model.simulated_sizes());
  return 3.0 * std::sqrt(d / kG);
}

bool has_parameter(const MaterialModel& model, const std::string& path) {
  for (const auto& p : parameters(model))
    if (p.path == path) return true;
  return false;
}

ParameterInfo require_parameter(const MaterialModel& model, const std::string& path,
                                const std::string& where) {
  const auto table = parameters(model);
  std::string known;
  for (const auto& p : table) {
    if (p.path == path) return p;
    known += (known.empty() ? "" : ", ") + p.path;
  }
  throw InputError(
      where, "'" + path + "' is not a parameter of this material model (known: " + known + ")");
}

MaterialModel with_parameters(MaterialModel model, const std::vector<ParameterValue>& values) {
  for (const auto& v : values) {
    require_parameter(model, v.path, v.where);
    try {
      set_parameter(model, v.path, v.value);
      model.validate();
    } catch (const InputError& e) {
      throw InputError(v.where, e.what());
    }
  }
  return model;
}

MaterialModel with_run_parameters(MaterialModel model,
                                  const std::map<std::string, double>& parameters) {
  for (const auto& [path, value] : parameters) set_parameter(model, path, value);
  model.validate();
  return model;
}

void set_parameter(MaterialModel& model, const std::string& path, double value) {
  for (const auto& info : parameters(model))
    if (info.path == path) {
      if (!(value >= info.lo && value <= info.hi))
        throw InputError(path, "value " + std::to_string(value) + " outside the valid range [" +
                                   std::to_string(info.lo) + ", " + std::to_string(info.hi) + "] " +
                                   info.unit);
      Path p;
      if (split_law_path(path, p)) {
        auto& law = p.law == "particle_law" ? model.particle_law : model.wall_law;
        slot_of(law, p.slot, path).params[p.param] = value;
      } else if (path == "density") {
        model.density = value;
      } else if (path == "scaling.factor") {
        model.scale_factor = value;
      } else if (double* shape = shape_field(model.shape, path)) {
        *shape = value;
      } else if (double* prep = preparation_field(model.preparation, path)) {
        *prep = value;
      } else {
        *size_field(model, path) = value;
      }
      return;
    }
  throw InputError(
      path,
      "not a parameter of this material model (see `demcal models` for the models' parameters)");
}

double get_parameter(const MaterialModel& model, const std::string& path) {
  Path p;
  if (split_law_path(path, p)) {
    auto law = p.law == "particle_law" ? model.particle_law : model.wall_law;
    const auto& params = slot_of(law, p.slot, path).params;
    if (auto it = params.find(p.param); it != params.end()) return it->second;
    for (const auto& info : contact::model_params(p.slot, slot_of(law, p.slot, path).model))
      if (info.name == p.param) return info.fallback;
    throw InputError(path, "unknown parameter");
  }
  if (path == "density") return model.density;
  if (path == "scaling.factor") return model.scale_factor;
  MaterialModel copy = model;
  if (double* f = size_field(copy, path)) return *f;
  if (double* f = shape_field(copy.shape, path)) return *f;
  if (double* f = preparation_field(copy.preparation, path)) return *f;
  throw InputError(path, "not a parameter of this material model");
}

}  // namespace demcal::lab
