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

/// The same bound with the stiffness the contacts have reached: a Luding contact's un-/reloading
/// stiffness k2* grows with its largest overlap from k1 to k2 (seed 000 eq. 5), and a bed under
/// its own weight stays near k1. Each law is bounded at twice the deepest overlap its contacts
/// reached (a contact may press that much deeper before the next re-tuning). Laws whose stiffness
/// does not follow the overlap give critical_time_step()'s bound. As Yade's
/// GlobalStiffnessTimeStepper, which bounds the step by the stiffness of the current contacts.
TimeStepLimit reached_time_step(const World& world);

/// dt = safety * critical; seed 001 used 0.6 sqrt(m/k), 0.1-0.3 of the Rayleigh time is common.
double recommended_time_step(const World& world, double safety);

/// A step so that even a contact at the law's largest stiffness stays stable:
/// omega dt = kStableFraction, below the velocity-Verlet limit 2 (sqrt(1 + z^2) - z) of a
/// spring-dashpot at any damping ratio z <= 1 (0.83 at z = 1).
constexpr double kStableFraction = 0.7;

/// dt = safety * reached_time_step(), at most kStableFraction * critical_time_step(): accurate for
/// the stiffness the contacts have, stable for the stiffness they could reach before the next
/// re-tuning.
double adapted_time_step(const World& world, double safety);

/// Throws SimulationFailure(kUnstableTimeStep) naming both numbers when dt exceeds the limit.
void check_time_step(const World& world);

}  // namespace demcal::sim
