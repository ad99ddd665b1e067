#pragma once
// Velocity Verlet for translation and rotation of spheres, split as LIGGGHTS' nve/sphere:
//   kick:  v += dt/2 f/m,  omega += dt/2 torque/I   (before and after the force evaluation)
//   drift: x += dt v
// Kinematic particles keep their prescribed velocities and only drift.
#include "core/particles/particle_store.hpp"

namespace demcal::integrate {

void kick(particles::ParticleStore& p, double half_dt, int threads);
void drift(particles::ParticleStore& p, double dt, int threads);

}  // namespace demcal::integrate
