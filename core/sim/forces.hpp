#pragma once
// The force stages of the step: gravity + particle-particle contacts, and particle-wall contacts.
#include "core/sim/world.hpp"

namespace demcal::sim {

/// Sets every particle's force to m g plus its pair contact forces, and its torque to the pair
/// torques. Deterministic for a given thread count (see the owner ranges in forces.cpp).
void compute_pair_forces(World& world);

/// Adds particle-wall contact forces to the particles and stores each wall's force and torque.
void compute_wall_forces(World& world);

}  // namespace demcal::sim
