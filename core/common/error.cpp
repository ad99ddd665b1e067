#include "core/common/error.hpp"

#include <iomanip>
#include <sstream>

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
    case SimulationFailure::Reason::kContactOutOfRange:
      return "contact_out_of_range";
  }
  return "unknown";
}

std::string message_number(double value, int digits) {
  std::ostringstream s;
  s << std::setprecision(digits) << value;
  return s.str();
}

}  // namespace demcal
