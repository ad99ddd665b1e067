#include "core/common/error.hpp"

namespace demcal {

const char* to_string(SimulationFailure::Reason reason) {
  switch (reason) {
    case SimulationFailure::Reason::kNotFinite:
      return "not_finite";
    case SimulationFailure::Reason::kEnergyExplosion:
      return "energy_explosion";
    case SimulationFailure::Reason::kEscaped:
      return "escaped_particles";
    case SimulationFailure::Reason::kUnstableTimeStep:
      return "unstable_time_step";
  }
  return "unknown";
}

}  // namespace demcal
