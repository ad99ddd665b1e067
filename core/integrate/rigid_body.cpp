#include "core/integrate/rigid_body.hpp"

namespace demcal::integrate {
namespace {

struct Wrench {
  Vec3 force, torque;
};

/// Sum of the member forces and of their torques about the centre of mass.
Wrench body_wrench(const particles::ParticleStore& p, std::size_t b, const Vec3& gravity) {
  const auto& c = p.clumps;
  Wrench w{gravity * c.mass[b], {}};
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
    w.force += p.f[k];
    w.torque += cross(c.q[b].rotate(p.body_offset[k]), p.f[k]) + p.torque[k];
  }
  return w;
}

Vec3 angular_velocity(const Quat& q, const Vec3& inertia, const Vec3& angular_momentum) {
  const Vec3 l = q.unrotate(angular_momentum);
  return q.rotate({l.x / inertia.x, l.y / inertia.y, l.z / inertia.z});
}

void place_members(particles::ParticleStore& p, std::size_t b, const Domain* domain) {
  const auto& c = p.clumps;
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
    const Vec3 arm = c.q[b].rotate(p.body_offset[k]);
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
  return angular_velocity(c.q[b], c.inertia[b], c.angular_momentum[b]);
}

namespace {

/// Half a kick of body b with its members' forces and its weight: velocity and angular momentum.
void kick_body(particles::ParticleStore& p, std::size_t b, const Vec3& gravity, double half_dt) {
  auto& c = p.clumps;
  const Wrench w = body_wrench(p, b, gravity);
  c.v[b] += w.force * (half_dt / c.mass[b]);
  c.angular_momentum[b] += w.torque * half_dt;
}

}  // namespace

void clump_kick_drift(particles::ParticleStore& p, const Domain& domain, const Vec3& gravity,
                      double dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
  const double half = 0.5 * dt;
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b) {
    if (c.parked[b]) continue;
    kick_body(p, b, gravity, half);
    c.x[b] += c.v[b] * dt;
    domain.wrap(c.x[b]);
    const Vec3 omega0 = body_angular_velocity(c, b);
    const Quat q_mid = (rotation_quat(omega0 * half) * c.q[b]).normalized();
    const Vec3 omega_mid = angular_velocity(q_mid, c.inertia[b], c.angular_momentum[b]);
    c.q[b] = (rotation_quat(omega_mid * dt) * c.q[b]).normalized();
    c.omega[b] = body_angular_velocity(c, b);
    place_members(p, b, &domain);
  }
}

void clump_kick(particles::ParticleStore& p, const Vec3& gravity, double half_dt) {
  auto& c = p.clumps;
  const int n = static_cast<int>(c.size());
#pragma omp for schedule(static)
  for (int b = 0; b < n; ++b) {
    if (c.parked[b]) continue;
    kick_body(p, b, gravity, half_dt);
    c.omega[b] = body_angular_velocity(c, b);
    place_members(p, b, nullptr);
  }
}

}  // namespace demcal::integrate
