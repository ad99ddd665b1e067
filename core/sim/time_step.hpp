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

/// The bound at the stiffness a contact has when it forms: the loading stiffness k1 of a Luding
/// law (or its adhesive kc where steeper), kn of a linear law, the Rayleigh time of a Hertz law
/// (which bounds an impact at any speed). A contact may form at any step, so an adapted step
/// never exceeds safety times this bound.
TimeStepLimit fresh_contact_time_step(const World& world);

/// dt = safety * critical; seed 001 used 0.6 sqrt(m/k), 0.1-0.3 of the Rayleigh time is common.
double recommended_time_step(const World& world, double safety);

/// The mass a contact on particle i moves: its own for a lone sphere; for a clump member the
/// body's effective mass at the member in its worst normal direction.
double contact_mass(const particles::ParticleStore& p, std::size_t i);

/// omega dt of a contact the step keeps stable without resolving it: below the velocity-Verlet
/// limit 2 (sqrt(1 + z^2) - z) of a spring-dashpot at any damping ratio z <= 1 (0.83 at z = 1).
constexpr double kStableFraction = 0.7;

/// A step for the stiffness in use, as Yade's GlobalStiffnessTimeStepper bounds the step by the
/// stiffness of the current contacts: safety x sqrt(m*/k) of the stiffest contact of the last
/// force evaluation (World::contact_rate2), at most safety x fresh_contact_time_step(); a Hertz
/// contact, whose accuracy the Rayleigh time of fresh_contact_time_step() sets as in common
/// practice (0.1-0.3 of it), only has to stay stable: kStableFraction x sqrt(m*/k) at its tangent
/// stiffness (World::contact_stable_rate2). A
/// Luding contact's un-/reloading stiffness k2* grows with its largest overlap from k1 to k2
/// (seed 000 eq. 5), so a bed under a light load needs far less than the law's largest
/// stiffness, and a stiff wall that no particle touches does not count.
double adapted_time_step(const World& world, double safety);

/// The step after a force evaluation of an adaptive world (World::adaptive_safety > 0), with
/// the safeguards of Yade's GlobalStiffnessTimeStepper: it shrinks at once to safety x
/// sqrt(m*/k) of the stiffest contact when a contact has stiffened; on a re-tuning step
/// (`retune`, every World::kRetuneSteps) it may grow, by World::kStepGrowth at most, up to that
/// bound and to safety x fresh_contact_time_step().
double next_time_step(const World& world, bool retune);

/// Throws SimulationFailure(kUnstableTimeStep) naming both numbers when a fixed dt exceeds the
/// limit (an adaptive world's step follows its contacts instead), or when dt is not > 0.
void check_time_step(const World& world);

}  // namespace demcal::sim
