#pragma once
// Shared helpers of the single-contact tests: run an experiment from a YAML string.
#include <string>
#include <vector>

#include "core/lab/single_contact.hpp"

namespace demcal::test {

inline lab::SingleContactSummary run_contact(
    const lab::SingleContactSpec& spec, std::vector<lab::SingleContactSample>* samples = nullptr) {
  return lab::run_single_contact(spec, [&](const lab::SingleContactSample& s) {
    if (samples) samples->push_back(s);
  });
}

inline lab::SingleContactSummary run_contact(
    const std::string& yaml, std::vector<lab::SingleContactSample>* samples = nullptr) {
  return run_contact(lab::read_single_contact(io::YamlNode::load_string(yaml, "test.yaml")),
                     samples);
}

/// The Luding load/unload/reload path of examples/contact_luding_path.yaml (the path of
/// tests/data/liggghts/in.luding_cycle), sampled at every step.
inline lab::SingleContactSpec luding_path_example() {
  auto spec = lab::read_single_contact(io::YamlNode::load_file(
      std::string(DEMCAL_SOURCE_DIR) + "/examples/contact_luding_path.yaml"));
  spec.output_every = 1;
  return spec;
}

inline double sphere_mass(double r, double rho) {
  return rho * 4.0 / 3.0 * M_PI * r * r * r;
}

}  // namespace demcal::test
