// The drum's bed from its geometry (seed 001 §3.2.2: 100 x 44 mm, 43 % fill): metadata without
// physics, so the coordinator can refuse a drum too large for the resource limit at submission.
#include <cmath>

#include "core/common/error.hpp"
#include "core/model/material.hpp"
#include "core/model/rotating_drum_settings.hpp"

namespace demcal::lab {
namespace {

/// Room for a bed with a free surface and a flowing layer: D >= 6 d_max, W >= 1.25 d_max.
void check_room(const RotatingDrumSettings& s, double d_max, const std::string& where) {
  if (1e-3 * s.diameter < 6.0 * d_max)
    throw InputError(where + ".diameter", "the drum (" + message_number(s.diameter, 4) +
                                              " mm) is narrower than 6 of the largest simulated "
                                              "particles (" +
                                              message_number(1e3 * d_max, 4) +
                                              " mm each): widen it or coarse-grain less");
  if (1e-3 * s.length < 1.25 * d_max)
    throw InputError(where + ".length", "the drum (" + message_number(s.length, 4) +
                                            " mm deep) is shallower than 1.25 of the largest "
                                            "simulated particles (" +
                                            message_number(1e3 * d_max, 4) + " mm)");
}

}  // namespace

std::string drum_rpm_label(double rpm) {
  return message_number(rpm, 4);
}

DrumBed drum_bed(const RotatingDrumSettings& s, const particles::SizeDistribution& simulated,
                 const std::string& where) {
  DrumBed bed;
  bed.radius = 0.5e-3 * s.diameter;
  bed.length = 1e-3 * s.length;
  const auto [volume, diameter] = particles::number_means(simulated);
  bed.mean_diameter = diameter;
  bed.diameter_ratio = 2.0 * bed.radius / diameter;
  check_room(s, 2.0 * particles::max_radius(simulated), where);
  const double bulk = s.fill * M_PI * bed.radius * bed.radius * bed.length;
  const double count = std::round(bulk * s.solid_fraction / volume);
  if (count > s.max_particles)
    throw InputError(
        where + ".max_particles",
        "the drum " + message_number(s.diameter, 4) + " x " + message_number(s.length, 4) +
            " mm at fill " + message_number(s.fill, 4) + " holds " + message_number(count, 4) +
            " particles of the simulated sizes (D/d = " + message_number(bed.diameter_ratio, 4) +
            "), above the limit of " + message_number(s.max_particles, 4) +
            ": raise max_particles or coarse-grain more (material.scaling.factor)");
  if (count < 20)
    throw InputError(where + ".diameter", "the drum holds only " + message_number(count, 4) +
                                              " particles of the simulated sizes: at least 20");
  bed.particles = static_cast<std::size_t>(count);
  return bed;
}

std::size_t RotatingDrumTest::admit(const MaterialModel& material, const RotatingDrumSettings& s,
                                    const std::string& where) {
  return drum_bed(s, material.simulated_sizes(), where).particles;
}

}  // namespace demcal::lab
