#pragma once
// Velocity Verlet for translation and rotation of spheres, split as LIGGGHTS' nve/sphere:
//   kick:  v += dt/2 f/m,  omega += dt/2 torque/I   (before and after the force evaluation)
//   drift: x += dt v
// Kinematic particles (inverse mass and inertia 0) keep their prescribed velocities and only drift.
// Both act on the particles [lo, hi), so that each thread of the step's parallel regions updates
// the particles it owns.
#include "core/particles/particle_store.hpp"

namespace demcal::integrate {

/// The first half of a step: kick with the last forces, then drift.
void kick_drift(particles::ParticleStore& p, double dt, int lo, int hi);
/// The second half: kick with the new forces.
void kick(particles::ParticleStore& p, double half_dt, int lo, int hi);

}  // namespace demcal::integrate
