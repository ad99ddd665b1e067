#include "rpc/material_convert.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "core/common/error.hpp"

namespace demcal::rpc {
namespace {

contact::SlotSpec to_slot(const v1::ContactSlot& s, const std::string& fallback_model) {
  contact::SlotSpec out;
  out.model = s.model().empty() ? fallback_model : s.model();
  for (const auto& [k, v] : s.params()) out.params[k] = v;
  return out;
}

contact::ContactLawSpec to_law(const v1::ContactLaw& law, const std::string& where) {
  if (!law.has_normal())
    throw InputError(where + ".normal", "missing (the normal slot is required)");
  if (!law.has_tangential())
    throw InputError(where + ".tangential", "missing (the tangential slot is required)");
  if (law.normal().model().empty()) throw InputError(where + ".normal.model", "missing");
  if (law.tangential().model().empty()) throw InputError(where + ".tangential.model", "missing");
  contact::ContactLawSpec spec;
  spec.normal = to_slot(law.normal(), "");
  spec.tangential = to_slot(law.tangential(), "");
  if (law.has_cohesion()) spec.cohesion = to_slot(law.cohesion(), "none");
  if (law.has_rolling()) spec.rolling = to_slot(law.rolling(), "none");
  return spec;
}

/// ContactLaw::from_spec names "<where>.<slot>.<param>"; the proto path has ".params." between.
std::string proto_path(const std::string& core_where, const std::string& base) {
  if (core_where.rfind(base + ".", 0) != 0) return core_where;
  std::string rest = core_where.substr(base.size() + 1);
  const auto dot = rest.find('.');
  if (dot == std::string::npos) return core_where;
  const std::string slot = rest.substr(0, dot), param = rest.substr(dot + 1);
  if (param == "model") return core_where;
  return base + "." + slot + ".params." + param;
}

/// The valid range of the material parameter `path` of `model` (lab::parameters).
lab::ParameterInfo range_of(const lab::MaterialModel& model, const std::string& path) {
  for (const auto& p : lab::parameters(model))
    if (p.path == path) return p;
  throw std::logic_error("no parameter " + path);
}

/// `value` inside the range of `info`, else an InputError naming `where` (a NaN never is).
void check_in_range(double value, const lab::ParameterInfo& info, const std::string& where) {
  if (value >= info.lo && value <= info.hi) return;
  std::ostringstream s;
  s << std::setprecision(6) << value << " is outside the valid range [" << info.lo << ", "
    << info.hi << "] " << info.unit;
  throw InputError(where, s.str());
}

/// The truncation of a log-normal size distribution, in geometric standard deviations: below
/// 0.1 sampling a radius rejects almost every draw, beyond 5 the tails hold nothing.
constexpr double kMinTruncateK = 0.1, kMaxTruncateK = 5.0;

/// Every number of the size distribution inside its parameter's range; a discrete class's radius
/// has the range of a monodisperse radius.
void check_sizes(const v1::SizeDistribution& sizes, const lab::MaterialModel& model,
                 const std::string& where) {
  switch (sizes.kind_case()) {
    case v1::SizeDistribution::kMonodisperse:
      check_in_range(sizes.monodisperse().radius(), range_of(model, "sizes.radius"),
                     where + ".monodisperse.radius");
      break;
    case v1::SizeDistribution::kDiscrete: {
      const lab::MaterialModel mono;  // monodisperse by default
      const lab::ParameterInfo radius = range_of(mono, "sizes.radius");
      const auto& d = sizes.discrete();
      for (int k = 0; k < d.radii_size(); ++k)
        check_in_range(d.radii(k), radius, where + ".discrete.radii[" + std::to_string(k) + "]");
      for (int k = 0; k < d.mass_fractions_size(); ++k)
        if (!std::isfinite(d.mass_fractions(k)))
          throw InputError(where + ".discrete.mass_fractions[" + std::to_string(k) + "]",
                           "must be finite");
      break;
    }
    case v1::SizeDistribution::kLognormal: {
      const auto& l = sizes.lognormal();
      check_in_range(l.median_radius(), range_of(model, "sizes.median_radius"),
                     where + ".lognormal.median_radius");
      check_in_range(l.sigma_g(), range_of(model, "sizes.sigma_g"), where + ".lognormal.sigma_g");
      if (l.truncate_k() != 0.0)
        check_in_range(l.truncate_k(), {"", "standard deviations", kMinTruncateK, kMaxTruncateK},
                       where + ".lognormal.truncate_k");
      break;
    }
    default:
      break;
  }
}

/// Every number of the material that no parameter table read (the contact laws', the shape's
/// and the preparation's are checked as they are read) inside its parameter's range: a value
/// sent over gRPC has not passed the spec reader's checks.
void check_material_values(const v1::Material& m, const lab::MaterialModel& model,
                           const std::string& where) {
  check_in_range(m.density(), range_of(model, "density"), where + ".density");
  if (m.size_scale() != 0.0)
    check_in_range(m.size_scale(), range_of(model, "sizes.scale"), where + ".size_scale");
  if (m.has_scaling() && m.scaling().factor() != 0.0)
    check_in_range(m.scaling().factor(), range_of(model, "scaling.factor"),
                   where + ".scaling.factor");
  check_sizes(m.sizes(), model, where + ".sizes");
  if (m.real_median_radius() != 0.0)
    check_in_range(
        m.real_median_radius(),
        {"real_median_radius", "m", lab::kRealMedianRadiusMin, lab::kRealMedianRadiusMax},
        where + ".real_median_radius");
}

}  // namespace

lab::MaterialModel to_material_model(const v1::Material& m, const std::string& where) {
  lab::MaterialModel model;
  if (!m.has_particle_law()) throw InputError(where + ".particle_law", "missing");
  model.particle_law = to_law(m.particle_law(), where + ".particle_law");
  model.wall_law =
      m.has_wall_law() ? to_law(m.wall_law(), where + ".wall_law") : model.particle_law;
  switch (m.sizes().kind_case()) {
    case v1::SizeDistribution::kMonodisperse:
      model.sizes = particles::Monodisperse{m.sizes().monodisperse().radius()};
      break;
    case v1::SizeDistribution::kDiscrete: {
      particles::DiscreteClasses d;
      d.radii.assign(m.sizes().discrete().radii().begin(), m.sizes().discrete().radii().end());
      d.mass_fractions.assign(m.sizes().discrete().mass_fractions().begin(),
                              m.sizes().discrete().mass_fractions().end());
      model.sizes = d;
      break;
    }
    case v1::SizeDistribution::kLognormal: {
      const auto& l = m.sizes().lognormal();
      model.sizes = particles::LogNormal{l.median_radius(), l.sigma_g(),
                                         l.truncate_k() > 0 ? l.truncate_k() : 2.5};
      break;
    }
    default:
      throw InputError(where + ".sizes", "needs one of: monodisperse, discrete, lognormal");
  }
  model.size_scale = m.size_scale() != 0.0 ? m.size_scale() : 1.0;
  if (m.density() == 0.0) throw InputError(where + ".density", "missing");
  model.density = m.density();
  model.real_median_radius = m.real_median_radius();
  if (m.has_scaling()) {
    const std::string law = m.scaling().law().empty() ? "none" : m.scaling().law();
    model.scaling = contact::scaling_law_from_name(law, where + ".scaling.law");
    model.scale_factor = m.scaling().factor() != 0.0 ? m.scaling().factor() : 1.0;
  }
  if (m.has_shape()) {
    std::map<std::string, double> params(m.shape().params().begin(), m.shape().params().end());
    model.shape = particles::make_shape_spec(m.shape().kind().empty() ? "sphere" : m.shape().kind(),
                                             params, where + ".shape.params");
  }
  if (m.has_preparation()) {
    std::map<std::string, double> params(m.preparation().params().begin(),
                                         m.preparation().params().end());
    model.preparation =
        lab::make_preparation(m.preparation().method().empty() ? "pour" : m.preparation().method(),
                              params, where + ".preparation.params");
  }
  check_material_values(m, model, where);
  try {
    model.validate();
  } catch (const InputError& e) {
    std::string path = proto_path(e.where(), "particle_law");
    if (path == e.where()) path = proto_path(e.where(), "wall_law");
    throw InputError(where + "." + path, e.message());
  }
  return model;
}

namespace {

void set_slot(v1::ContactSlot& out, const contact::SlotSpec& slot) {
  out.set_model(slot.model);
  for (const auto& [name, value] : slot.params) (*out.mutable_params())[name] = value;
}

void set_law(v1::ContactLaw& out, const contact::ContactLawSpec& law) {
  set_slot(*out.mutable_normal(), law.normal);
  set_slot(*out.mutable_cohesion(), law.cohesion);
  set_slot(*out.mutable_tangential(), law.tangential);
  set_slot(*out.mutable_rolling(), law.rolling);
}

void set_sizes(v1::SizeDistribution& out, const particles::SizeDistribution& sizes) {
  if (const auto* one = std::get_if<particles::Monodisperse>(&sizes)) {
    out.mutable_monodisperse()->set_radius(one->radius);
  } else if (const auto* ln = std::get_if<particles::LogNormal>(&sizes)) {
    auto* o = out.mutable_lognormal();
    o->set_median_radius(ln->median_radius);
    o->set_sigma_g(ln->sigma_g);
    o->set_truncate_k(ln->truncate_k);
  } else {
    const auto& d = std::get<particles::DiscreteClasses>(sizes);
    auto* o = out.mutable_discrete();
    for (const double r : d.radii) o->add_radii(r);
    for (const double f : d.mass_fractions) o->add_mass_fractions(f);
  }
}

}  // namespace

v1::ContactLaw to_law_message(const contact::ContactLawSpec& law) {
  v1::ContactLaw out;
  set_law(out, law);
  return out;
}

v1::Preparation to_preparation_message(const lab::PreparationSpec& preparation) {
  v1::Preparation p;
  p.set_method(lab::preparation_method_name(preparation.method));
  for (const auto& [name, value] : lab::preparation_values(preparation))
    (*p.mutable_params())[name] = value;
  return p;
}

v1::Material to_material_message(const lab::MaterialModel& model) {
  v1::Material m;
  set_law(*m.mutable_particle_law(), model.particle_law);
  set_law(*m.mutable_wall_law(), model.wall_law);
  set_sizes(*m.mutable_sizes(), model.sizes);
  m.set_size_scale(model.size_scale);
  m.set_density(model.density);
  m.mutable_scaling()->set_law(contact::scaling_law_name(model.scaling));
  m.mutable_scaling()->set_factor(model.scale_factor);
  m.mutable_shape()->set_kind(particles::shape_kind_name(model.shape.kind));
  for (const auto& [name, value] : particles::shape_values(model.shape))
    (*m.mutable_shape()->mutable_params())[name] = value;
  *m.mutable_preparation() = to_preparation_message(model.preparation);
  m.set_real_median_radius(model.real_median_radius);
  return m;
}

v1::CampaignSpec canonical_spec(const v1::CampaignSpec& spec) {
  v1::CampaignSpec out = spec;
  if (!spec.has_material()) return out;
  *out.mutable_material() =
      to_material_message(to_material_model(spec.material(), "spec.material"));
  for (int i = 0; i < out.tests_size(); ++i) {
    auto& test = *out.mutable_tests(i);
    if (!test.has_wall_law() && !test.has_preparation()) continue;
    v1::Material own = spec.material();
    if (test.has_wall_law()) *own.mutable_wall_law() = test.wall_law();
    if (test.has_preparation()) *own.mutable_preparation() = test.preparation();
    const auto where = "spec.tests[" + std::to_string(i) + "]";
    const v1::Material full = to_material_message(to_material_model(own, where));
    if (test.has_wall_law()) *test.mutable_wall_law() = full.wall_law();
    if (test.has_preparation()) *test.mutable_preparation() = full.preparation();
  }
  return out;
}

v1::Material instance_material(const v1::Material& material, const v1::LabTest& test) {
  v1::Material m = material;
  if (test.has_wall_law()) *m.mutable_wall_law() = test.wall_law();
  if (test.has_preparation()) *m.mutable_preparation() = test.preparation();
  return m;
}

lab::MaterialModel job_material(const v1::JobSpec& job) {
  return lab::with_run_parameters(
      to_material_model(job.material(), "job.material"),
      std::map<std::string, double>(job.parameters().begin(), job.parameters().end()));
}

std::string instance_name(const v1::LabTest& t) {
  return t.name().empty() ? t.test() : t.name();
}

const v1::LabTest* find_instance(const v1::CampaignSpec& spec, const std::string& name) {
  for (const auto& t : spec.tests())
    if (instance_name(t) == name) return &t;
  return nullptr;
}

lab::MaterialModel job_material(const v1::CampaignSpec& spec, const v1::LabTest* instance,
                                const std::map<std::string, double>& parameters) {
  v1::JobSpec job;
  *job.mutable_material() =
      instance ? instance_material(spec.material(), *instance) : spec.material();
  job.mutable_parameters()->insert(parameters.begin(), parameters.end());
  return job_material(job);
}

std::uint64_t job_seed(const v1::JobSpec& job) {
  return job.seed() ? job.seed() : 1;
}

lab::Settings to_settings(const google::protobuf::Map<std::string, double>& settings) {
  return lab::Settings(settings.begin(), settings.end());
}

std::map<std::string, double> run_parameters(const v1::CampaignSpec& spec,
                                             const std::map<std::string, double>& factors) {
  std::map<std::string, double> out(spec.fixed().begin(), spec.fixed().end());
  for (const auto& [path, value] : factors) out[path] = value;
  for (const auto& f : spec.factors())
    if (const auto it = factors.find(f.path()); it != factors.end())
      for (const auto& tied : f.tied()) out[tied] = it->second;
  return out;
}

}  // namespace demcal::rpc
