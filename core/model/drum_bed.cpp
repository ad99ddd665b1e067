// The drum's bed from its geometry (seed 001 §3.2.2: 100 x 44 mm, 43 % fill): metadata without
// physics, so the coordinator can refuse a drum too large for the resource limit at submission.
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/common/error.hpp"
#include "core/model/material.hpp"
#include "core/model/rotating_drum_settings.hpp"

namespace demcal::lab {
namespace {

std::string number(double v) {
  std::ostringstream o;
  o << std::setprecision(4) << v;
  return o.str();
}

/// Room for a bed with a free surface and a flowing layer: D >= 6 d_max, W >= 1.25 d_max.
void check_room(const RotatingDrumSettings& s, double d_max, const std::string& where) {
  if (1e-3 * s.diameter < 6.0 * d_max)
    throw InputError(where + ".diameter", "the drum (" + number(s.diameter) +
                                              " mm) is narrower than 6 of the largest simulated "
                                              "particles (" +
                                              number(1e3 * d_max) +
                                              " mm each): widen it or coarse-grain less");
  if (1e-3 * s.length < 1.25 * d_max)
    throw InputError(where + ".length", "the drum (" + number(s.length) +
                                            " mm deep) is shallower than 1.25 of the largest "
                                            "simulated particles (" +
                                            number(1e3 * d_max) + " mm)");
}

}  // namespace

std::string drum_rpm_label(double rpm) {
  return number(rpm);
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
    throw InputError(where + ".max_particles",
                     "the drum " + number(s.diameter) + " x " + number(s.length) + " mm at fill " +
                         number(s.fill) + " holds " + number(count) +
                         " particles of the simulated sizes (D/d = " + number(bed.diameter_ratio) +
                         "), above the limit of " + number(s.max_particles) +
                         ": raise max_particles or coarse-grain more (material.scaling.factor)");
  if (count < 20)
    throw InputError(where + ".diameter", "the drum holds only " + number(count) +
                                              " particles of the simulated sizes: at least 20");
  bed.particles = static_cast<std::size_t>(count);
  return bed;
}

std::size_t RotatingDrumTest::admit(const MaterialModel& material, const RotatingDrumSettings& s,
                                    const std::string& where) {
  return drum_bed(s, material.simulated_sizes(), where).particles;
}

}  // namespace demcal::lab
