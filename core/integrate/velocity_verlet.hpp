#pragma once
// Velocity Verlet for translation and rotation of spheres, split as LIGGGHTS' nve/sphere:
//   kick:  v += dt/2 f/m,  omega += dt/2 torque/I   (before and after the force evaluation)
//   drift: x += dt v
// Kinematic particles (inverse mass and inertia 0) keep their prescribed velocities and only drift.
#include "core/particles/particle_store.hpp"

namespace demcal::integrate {

/// The first half of a step: kick with the last forces, then drift.
void kick_drift(particles::ParticleStore& p, double dt, int threads);
/// The second half: kick with the new forces.
void kick(particles::ParticleStore& p, double half_dt, int threads);

}  // namespace demcal::integrate
