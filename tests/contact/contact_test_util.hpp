#pragma once
// Shared helpers of the single-contact tests: run an experiment from a YAML string.
#include <string>
#include <vector>

#include "core/lab/single_contact.hpp"

namespace demcal::test {

inline lab::SingleContactSummary run_contact(const std::string& yaml,
                                             std::vector<lab::SingleContactSample>* samples = nullptr) {
  const auto spec = lab::read_single_contact(io::YamlNode::load_string(yaml, "test.yaml"));
  return lab::run_single_contact(spec, [&](const lab::SingleContactSample& s) {
    if (samples) samples->push_back(s);
  });
}

inline double sphere_mass(double r, double rho) { return rho * 4.0 / 3.0 * M_PI * r * r * r; }

}  // namespace demcal::test
