#include "server/run_key.hpp"

#include <openssl/evp.h>

#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/lab/protocol.hpp"
#include "core/model/catalog.hpp"
#include "core/model/material.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

nlohmann::json law_models(const contact::ContactLawSpec& law) {
  return {{"normal", law.normal.model},
          {"cohesion", law.cohesion.model},
          {"tangential", law.tangential.model},
          {"rolling", law.rolling.model}};
}

/// What the parameter table leaves out: the models of each slot, the kind of size distribution
/// with its values that are not parameters, and the scaling law, shape and preparation chosen.
nlohmann::json material_choices(const lab::MaterialModel& m) {
  nlohmann::json sizes = std::visit(
      [](const auto& d) -> nlohmann::json {
        using D = std::decay_t<decltype(d)>;
        if constexpr (std::is_same_v<D, particles::Monodisperse>)
          return {{"kind", "monodisperse"}};
        else if constexpr (std::is_same_v<D, particles::DiscreteClasses>)
          return {{"kind", "discrete"}, {"radii", d.radii}, {"mass_fractions", d.mass_fractions}};
        else
          return {{"kind", "lognormal"}, {"truncate_k", d.truncate_k}};
      },
      m.sizes);
  return {{"particle_law", law_models(m.particle_law)},
          {"wall_law", law_models(m.wall_law)},
          {"sizes", std::move(sizes)},
          {"scaling", contact::scaling_law_name(m.scaling)},
          {"shape", particles::shape_kind_name(m.shape.kind)},
          {"preparation", lab::preparation_method_name(m.preparation.method)}};
}

/// Every parameter of the material (lab::parameters: the laws' parameters by path, density,
/// sizes, scaling factor, shape and preparation) with its value, defaults included, so that a
/// value written out and the same value left to its default give one key.
nlohmann::json material_values(const lab::MaterialModel& m) {
  nlohmann::json values = nlohmann::json::object();
  for (const auto& p : lab::parameters(m)) values[p.path] = lab::get_parameter(m, p.path);
  return values;
}

/// The test's settings table at its defaults, overridden by the settings given.
nlohmann::json settings_values(const v1::JobSpec& job) {
  nlohmann::json values = nlohmann::json::object();
  for (const auto& s : lab::find_lab_info(job.test()).settings) values[s.name] = s.fallback;
  for (const auto& [name, value] : job.settings()) values[name] = value;
  return values;
}

}  // namespace

std::string sha256_hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int size = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &size, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("SHA-256 failed");
  std::string hex;
  for (unsigned int i = 0; i < size; ++i) {
    hex += "0123456789abcdef"[digest[i] >> 4];
    hex += "0123456789abcdef"[digest[i] & 15];
  }
  return hex;
}

RunKey run_key(const v1::JobSpec& job) {
  const lab::MaterialModel material = rpc::job_material(job);
  // nlohmann::json keeps object keys sorted: the dump is canonical, and its numbers are the
  // shortest text that reads back to the same double.
  const int protocol = lab::protocol_version(job.test());
  const nlohmann::json canonical = {{"protocol", protocol},
                                    {"test", job.test()},
                                    {"settings", settings_values(job)},
                                    {"seed", rpc::job_seed(job)},
                                    {"material", material_choices(material)},
                                    {"parameters", material_values(material)}};
  return {sha256_hex(canonical.dump()), protocol};
}

RunKey payload_run_key(const std::string& payload) {
  try {
    return run_key(job_from_payload(payload));
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace demcal::server
