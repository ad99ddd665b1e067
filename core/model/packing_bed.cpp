// The packing test's die bed as its particles size it, checked before anything runs: metadata
// without physics, so the coordinator refuses a bed too small for its sampling volume.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/common/error.hpp"
#include "core/model/material.hpp"
#include "core/model/packing_settings.hpp"

namespace demcal::lab {

std::size_t PackingTest::admit(const MaterialModel& material, const PackingSettings& s,
                               const std::string& where) {
  // The die the bed is built in (die_radius_for); the settled bed is at least 2R 0.6 / 0.74 high
  // (no packing of spheres is denser than 0.74) before the cut. 0.95 covers the sampled solid
  // volume's scatter.
  const double solid = s.particles * particles::number_means(material.simulated_sizes()).volume;
  const double radius = 0.95 * die_radius_for(solid);
  const double top = s.cut_fraction * 2.0 * radius * 0.6 / 0.74;
  // The sampling volume keeps its distance in largest sphere diameters (a clump's largest
  // member, scaled as the template's radii are: in volume-equivalent radii).
  const auto shape = material.clump_template();
  const double member = shape ? *std::max_element(shape->radii.begin(), shape->radii.end()) : 1.0;
  const double d_max = 2.0 * particles::max_radius(material.simulated_sizes()) * member;
  const double margin = s.wall_margin * d_max;
  if (radius <= margin || top <= 2.0 * margin)
    throw InputError(where + ".particles",
                     "the bed of " + std::to_string(std::llround(s.particles)) +
                         " particles is too small for a sampling volume " +
                         std::to_string(s.wall_margin) +
                         " largest diameters from its walls, floor and top: use more particles, a "
                         "smaller wall_margin or a larger cut_fraction");
  return static_cast<std::size_t>(std::llround(s.particles));
}

}  // namespace demcal::lab
