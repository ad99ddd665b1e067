#pragma once
// Checks that a simulation is still physical; a failing check is a typed SimulationFailure with
// its reason (not_finite, energy_explosion, escaped_particles, contact_out_of_range), never
// numbers.
#include <limits>
#include <string>

#include "core/sim/world.hpp"

namespace demcal::sim {

struct HealthLimits {
  double max_kinetic_energy = std::numeric_limits<double>::infinity();  ///< (J)
  Vec3 lo{-1e30, -1e30, -1e30};  ///< a particle centre outside [lo, hi] has escaped
  Vec3 hi{1e30, 1e30, 1e30};
};

void check_health(const World& world, const HealthLimits& limits);

/// Throws SimulationFailure(kContactOutOfRange) when a particle-particle law of the world, between
/// the smallest particles of its materials, holds a pair by its attraction alone at an overlap
/// (ContactLaw::adhesion_overlap) as deep as the smaller particle's radius: a soft-sphere contact
/// stands for a small overlap, and one that reaches a particle's centre makes neither force nor
/// geometry of the pair meaningful (the bed collapses into itself and ejects particles). The
/// message names the materials, the force and the overlap in radii. Wall laws are not checked: a
/// test's device may hold particles harder than any contact of the material (the tensile test's
/// adhesive piston, seed 000 eq. 34).
void check_contact_range(const World& world);

/// The check of check_contact_range for one law between particles of radii r_i and r_j; `what`
/// names the pair's materials in the message.
void check_pair_range(const contact::ContactLaw& law, double r_i, double r_j,
                      const std::string& what);

/// An upper bound of the kinetic energy the attraction of the world's laws can set free (J), for
/// the energy limit of a cohesive bed, where it can far exceed the bed's potential energy (small
/// particles with a large Hamaker constant snap together at metres per second): every particle
/// with six pairs (coordination 12, each pair shared by two) and one wall contact, each pulled
/// from its law's range into the deepest well (ContactLaw::attraction_energy) at the largest
/// particle radius. Zero when no law attracts.
double attraction_energy_bound(const World& world);

/// The lab tests' limit on a bed's kinetic energy (J): 1,000 times the potential energy
/// `potential_energy` its test can set free (the bed falling through its vessel, a drum's
/// rotation), plus attraction_energy_bound(world). A bed above it has been blown up by a too-stiff
/// contact or a runaway wall.
double kinetic_energy_limit(const World& world, double potential_energy);

}  // namespace demcal::sim
