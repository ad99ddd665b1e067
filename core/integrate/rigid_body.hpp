#pragma once
// Rigid-body integration of multisphere clumps, paired with the velocity Verlet split of the
// spheres (velocity_verlet.hpp). Translation is velocity Verlet on the centre of mass. Rotation
// is a leapfrog on the world-frame angular momentum L (kicks of torque dt/2, as for the spheres);
// the drift turns the body by the midpoint angular velocity (rotations as rotation vectors)
//   q_mid = Rot(omega_0 dt/2) q,   omega_mid = R(q_mid) I^-1 R(q_mid)^T L,   q <- Rot(omega_mid dt)
//   q
// (a second-order orientation update for the free rotation of an asymmetric body, in the
// manner of the NO_SQUISH / Richardson schemes of LAMMPS rigid and LIGGGHTS multisphere).
// Forces and torques of a body are the sums over its member spheres, torques taken about the
// centre of mass with the member's lever arm R b_k, plus its weight M g at the centre of mass
// (members carry no gravity: their mass shares are by own volume, whose centre is not the
// union's centroid for an asymmetric clump, so weights on members would turn it). Members carry no
// contact with each other (the neighbour list skips pairs of one body).
#include "core/common/domain.hpp"
#include "core/particles/particle_store.hpp"

namespace demcal::integrate {

/// First half of a step for the clumps: kick with the members' last forces, drift, turn, and
/// place the members (positions wrapped into periodic boxes, velocities v + omega x R b).
/// Both halves share the bodies among the threads of the enclosing parallel region (an
/// orphaned `omp for`, ending in a barrier); called outside one, a single thread does all.
void clump_kick_drift(particles::ParticleStore& p, const Domain& domain, const Vec3& gravity,
                      double dt);
/// Second half: kick with the members' new forces and update the members' velocities.
void clump_kick(particles::ParticleStore& p, const Vec3& gravity, double half_dt);
/// The angular velocity of body b from its angular momentum and orientation.
Vec3 body_angular_velocity(const particles::Clumps& c, std::size_t b);

}  // namespace demcal::integrate
