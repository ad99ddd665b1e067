#pragma once
// The critical time step of a world and the check that a requested step respects it.
#include <string>

#include "core/sim/world.hpp"

namespace demcal::sim {

struct TimeStepLimit {
  double critical = 0.0;  ///< the stability limit (s): Rayleigh time or sqrt(m/k)
  std::string basis;      ///< which bound and which law set it, for messages
};

/// The smallest bound over all particle-particle and particle-wall laws in use: the Rayleigh time
/// for Hertz laws, sqrt(m_min / k_max) for linear and Luding laws.
TimeStepLimit critical_time_step(const World& world);

/// dt = safety * critical; seed 001 used 0.6 sqrt(m/k), 0.1-0.3 of the Rayleigh time is common.
double recommended_time_step(const World& world, double safety);

/// Throws SimulationFailure(kUnstableTimeStep) naming both numbers when dt exceeds the limit.
void check_time_step(const World& world);

}  // namespace demcal::sim
