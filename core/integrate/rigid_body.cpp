#include "core/integrate/rigid_body.hpp"

#include <limits>

namespace demcal::integrate {
namespace {

Rotation rotation_of(const Quat& q) {
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  return {{{1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)},
           {2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)},
           {2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)}}};
}

/// omega = R I^-1 R^T L, with the principal moments' inverses.
Vec3 angular_velocity(const Rotation& r, const Vec3& inv_inertia, const Vec3& angular_momentum) {
  const Vec3 l = r.to_body(angular_momentum);
  return r.to_world({l.x * inv_inertia.x, l.y * inv_inertia.y, l.z * inv_inertia.z});
}

Vec3 inverse(const Vec3& inertia) {
  return {1.0 / inertia.x, 1.0 / inertia.y, 1.0 / inertia.z};
}

bool same(const Quat& a, const Quat& b) {
  return a.w == b.w && a.x == b.x && a.y == b.y && a.z == b.z;
}

/// The rotation of body b's orientation, from the frames when they hold it.
Rotation body_rotation(const particles::Clumps& c, const ClumpFrames& frames, std::size_t b) {
  return same(frames.q[b], c.q[b]) ? frames.rotation[b] : rotation_of(c.q[b]);
}

/// The force and the torque about the centre of mass on body b: its members' forces (lever arm
/// R b_k) and torques, and its weight.
void body_wrench(const particles::ParticleStore& p, std::size_t b, const Rotation& r,
                 const Vec3& gravity, ClumpFrames& frames) {
  const auto& c = p.clumps;
  Vec3 force = gravity * c.mass[b], torque{};
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
    force += p.f[k];
    torque += cross(r.to_world(p.body_offset[k]), p.f[k]) + p.torque[k];
  }
  frames.force[b] = force;
  frames.torque[b] = torque;
}

/// Half a kick of body b with its wrench: velocity and angular momentum.
void kick_body(particles::Clumps& c, std::size_t b, const ClumpFrames& frames, double half_dt) {
  c.v[b] += frames.force[b] * (half_dt / c.mass[b]);
  c.angular_momentum[b] += frames.torque[b] * half_dt;
}

/// Members from their body: velocity v + omega x R b_k, angular velocity omega, and with a domain
/// also the position (wrapped into periodic boxes).
void place_members(particles::ParticleStore& p, std::size_t b, const Rotation& r,
                   const Domain* domain) {
  const auto& c = p.clumps;
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
    const Vec3 arm = r.to_world(p.body_offset[k]);
    if (domain) {
      p.x[k] = c.x[b] + arm;
      domain->wrap(p.x[k]);
    }
    p.v[k] = c.v[b] + cross(c.omega[b], arm);
    p.omega[k] = c.omega[b];
  }
}

/// The first half kick of body b: with the wrench of the last second half kick when the frames
/// hold it for this orientation and gravity, otherwise with the members' forces now.
void first_kick(particles::ParticleStore& p, std::size_t b, const Rotation& r0, const Vec3& gravity,
                double half_dt, ClumpFrames& frames) {
  const auto& c = p.clumps;
  const bool known = frames.has_wrench[b] && same(frames.q[b], c.q[b]) &&
                     frames.gravity.x == gravity.x && frames.gravity.y == gravity.y &&
                     frames.gravity.z == gravity.z;
  if (!known) body_wrench(p, b, r0, gravity, frames);
  kick_body(p.clumps, b, frames, half_dt);
}

// The drift runs in three passes over the bodies, each ending where the next needs a whole
// quaternion: the kick and the half turn, the full turn, the new pose. A body's drift is one long
// chain of dependent square roots, divisions and sines (each turn: |phi|, sin/cos, normalise);
// in one loop the processor works on one body at a time, in passes on the next bodies while a
// chain waits. The arithmetic of every body is the same as in one loop.

/// Pass 1 of the drift of body b: the first half kick, the move of the centre of mass, and the
/// orientation turned by half a step at the kicked angular velocity (q_mid).
void kick_and_half_turn(particles::ParticleStore& p, std::size_t b, ClumpFrames& frames,
                        const Domain& domain, const Vec3& gravity, double dt) {
  auto& c = p.clumps;
  const double half = 0.5 * dt;
  const Rotation r0 = body_rotation(c, frames, b);
  first_kick(p, b, r0, gravity, half, frames);
  c.x[b] += c.v[b] * dt;
  domain.wrap(c.x[b]);
  const Vec3 omega0 = angular_velocity(r0, frames.inv_inertia[b], c.angular_momentum[b]);
  frames.q_mid[b] = (rotation_quat(omega0 * half) * c.q[b]).normalized();
}

/// Pass 2: the orientation turned by a whole step at the angular velocity of q_mid.
void full_turn(particles::Clumps& c, std::size_t b, const ClumpFrames& frames, double dt) {
  const Vec3 omega_mid =
      angular_velocity(rotation_of(frames.q_mid[b]), frames.inv_inertia[b], c.angular_momentum[b]);
  c.q[b] = (rotation_quat(omega_mid * dt) * c.q[b]).normalized();
}

/// Pass 3: the new rotation (kept in the frames), angular velocity and members.
void new_pose(particles::ParticleStore& p, std::size_t b, ClumpFrames& frames,
              const Domain& domain) {
  auto& c = p.clumps;
  const Rotation r = rotation_of(c.q[b]);
  frames.q[b] = c.q[b];
  frames.rotation[b] = r;
  frames.has_wrench[b] = 0;
  c.omega[b] = angular_velocity(r, frames.inv_inertia[b], c.angular_momentum[b]);
  place_members(p, b, r, &domain);
}

}  // namespace

Vec3 body_angular_velocity(const particles::Clumps& c, std::size_t b) {
  return angular_velocity(rotation_of(c.q[b]), inverse(c.inertia[b]), c.angular_momentum[b]);
}

void ClumpFrames::reset(const particles::ParticleStore& p) {
  const std::size_t n = p.clumps.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  q.assign(n, Quat{nan, nan, nan, nan});
  rotation.assign(n, Rotation{});
  inv_inertia.resize(n);
  for (std::size_t b = 0; b < n; ++b) inv_inertia[b] = inverse(p.clumps.inertia[b]);
  force.assign(n, Vec3{});
  torque.assign(n, Vec3{});
  has_wrench.assign(n, 0);
  gravity = {};
  q_mid.assign(n, Quat{});
}

void clump_kick_drift(particles::ParticleStore& p, ClumpFrames& frames, const Domain& domain,
                      const Vec3& gravity, double dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
  // The same static schedule in every pass gives each thread the same bodies: no barrier between.
#pragma omp for schedule(static) nowait
  for (int b = 0; b < n; ++b)
    if (!c.parked[b]) kick_and_half_turn(p, b, frames, domain, gravity, dt);
#pragma omp for schedule(static) nowait
  for (int b = 0; b < n; ++b)
    if (!c.parked[b]) full_turn(c, b, frames, dt);
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b)
    if (!c.parked[b]) new_pose(p, b, frames, domain);
}

void clump_kick(particles::ParticleStore& p, ClumpFrames& frames, const Vec3& gravity,
                double half_dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b) {
    if (c.parked[b]) continue;
    // The drift of this step left the rotation and the arms of this orientation.
    const Rotation r = frames.rotation[b];
    body_wrench(p, b, r, gravity, frames);
    frames.has_wrench[b] = 1;
    kick_body(c, b, frames, half_dt);
    c.omega[b] = angular_velocity(r, frames.inv_inertia[b], c.angular_momentum[b]);
    place_members(p, b, r, nullptr);
  }
  if (n > 0) {
#pragma omp single nowait
    frames.gravity = gravity;
  }
}

}  // namespace demcal::integrate
