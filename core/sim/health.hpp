#pragma once
// Checks that a simulation is still physical; a failing check is a typed SimulationFailure with
// its reason (not_finite, energy_explosion, escaped_particles), never numbers.
#include <limits>

#include "core/sim/world.hpp"

namespace demcal::sim {

struct HealthLimits {
  double max_kinetic_energy = std::numeric_limits<double>::infinity();  ///< (J)
  Vec3 lo{-1e30, -1e30, -1e30};  ///< a particle centre outside [lo, hi] has escaped
  Vec3 hi{1e30, 1e30, 1e30};
};

void check_health(const World& world, const HealthLimits& limits);

}  // namespace demcal::sim
