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
#include <vector>

#include "core/common/domain.hpp"
#include "core/particles/particle_store.hpp"

namespace demcal::integrate {

/// The rotation matrix of a unit quaternion (body frame -> world frame), by rows. A body turns
/// many vectors per step (member arms, angular momentum); a matrix does each in 9 products.
struct Rotation {
  Vec3 row[3];
  Vec3 to_world(const Vec3& v) const { return {dot(row[0], v), dot(row[1], v), dot(row[2], v)}; }
  Vec3 to_body(const Vec3& v) const { return row[0] * v.x + row[1] * v.y + row[2] * v.z; }
};

/// What one half step of the clumps hands to the next, per body: the rotation matrix of its
/// orientation (with the orientation it was made from), its inverse principal moments, and the
/// wrench of its members' forces plus its weight. Each is a pure function of the state, so
/// reusing it gives the same bits as computing it again: the second half kick reuses the drift's
/// rotation, the next first half kick the second's wrench (the members' forces do not change in
/// between). A body's entries count only while its orientation is the one they were made from
/// (the wrench also only while gravity is the same); `reset` drops them all, and
/// `World::prepare` calls it whenever the store may have changed.
struct ClumpFrames {
  std::vector<Quat> q;  ///< the orientation `rotation` belongs to (NaN: none yet)
  std::vector<Rotation> rotation;
  std::vector<Vec3> inv_inertia;  ///< 1 / principal moments (1/(kg m^2))
  std::vector<Vec3> force;        ///< members' forces + weight at the last second half kick (N)
  std::vector<Vec3> torque;       ///< members' torques about the centre of mass, then (N m)
  std::vector<char> has_wrench;   ///< 1: force and torque belong to the body's members' forces
  Vec3 gravity;                   ///< the gravity in `force`
  std::vector<Quat> q_mid;        ///< scratch of the drift: the orientation turned by half a step
  /// Sizes the frames for the store's bodies, none of them known.
  void reset(const particles::ParticleStore& p);
};

/// First half of a step for the clumps: kick with the members' last forces, drift, turn, and
/// place the members (positions wrapped into periodic boxes, velocities v + omega x R b).
/// Both halves share the bodies among the threads of the enclosing parallel region (an
/// orphaned `omp for`, ending in a barrier); called outside one, a single thread does all.
void clump_kick_drift(particles::ParticleStore& p, ClumpFrames& frames, const Domain& domain,
                      const Vec3& gravity, double dt);
/// Second half: kick with the members' new forces and update the members' velocities.
void clump_kick(particles::ParticleStore& p, ClumpFrames& frames, const Vec3& gravity,
                double half_dt);
/// The angular velocity of body b from its angular momentum and orientation.
Vec3 body_angular_velocity(const particles::Clumps& c, std::size_t b);

}  // namespace demcal::integrate
