#include "core/integrate/rigid_body.hpp"

namespace demcal::integrate {
namespace {

/// The rotation matrix of a unit quaternion (body frame -> world frame), by rows. A body turns
/// many vectors per step (member arms, angular momentum); a matrix does each in 9 products.
struct Rotation {
  Vec3 row[3];
  Vec3 to_world(const Vec3& v) const { return {dot(row[0], v), dot(row[1], v), dot(row[2], v)}; }
  Vec3 to_body(const Vec3& v) const { return row[0] * v.x + row[1] * v.y + row[2] * v.z; }
};

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

/// Half a kick of body b with its members' forces (torques about the centre of mass, lever arm
/// R b_k) and its weight: velocity and angular momentum.
void kick_body(particles::ParticleStore& p, std::size_t b, const Rotation& r, const Vec3& gravity,
               double half_dt) {
  auto& c = p.clumps;
  Vec3 force = gravity * c.mass[b], torque{};
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
    force += p.f[k];
    torque += cross(r.to_world(p.body_offset[k]), p.f[k]) + p.torque[k];
  }
  c.v[b] += force * (half_dt / c.mass[b]);
  c.angular_momentum[b] += torque * half_dt;
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

}  // namespace

Vec3 body_angular_velocity(const particles::Clumps& c, std::size_t b) {
  return angular_velocity(rotation_of(c.q[b]), inverse(c.inertia[b]), c.angular_momentum[b]);
}

void clump_kick_drift(particles::ParticleStore& p, const Domain& domain, const Vec3& gravity,
                      double dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
  const double half = 0.5 * dt;
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b) {
    if (c.parked[b]) continue;
    const Vec3 inv_inertia = inverse(c.inertia[b]);
    const Rotation r0 = rotation_of(c.q[b]);
    kick_body(p, b, r0, gravity, half);
    c.x[b] += c.v[b] * dt;
    domain.wrap(c.x[b]);
    const Vec3 omega0 = angular_velocity(r0, inv_inertia, c.angular_momentum[b]);
    const Quat q_mid = (rotation_quat(omega0 * half) * c.q[b]).normalized();
    const Vec3 omega_mid = angular_velocity(rotation_of(q_mid), inv_inertia, c.angular_momentum[b]);
    c.q[b] = (rotation_quat(omega_mid * dt) * c.q[b]).normalized();
    const Rotation r = rotation_of(c.q[b]);
    c.omega[b] = angular_velocity(r, inv_inertia, c.angular_momentum[b]);
    place_members(p, b, r, &domain);
  }
}

void clump_kick(particles::ParticleStore& p, const Vec3& gravity, double half_dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b) {
    if (c.parked[b]) continue;
    const Rotation r = rotation_of(c.q[b]);
    kick_body(p, b, r, gravity, half_dt);
    c.omega[b] = angular_velocity(r, inverse(c.inertia[b]), c.angular_momentum[b]);
    place_members(p, b, r, nullptr);
  }
}

}  // namespace demcal::integrate
