#include "core/integrate/velocity_verlet.hpp"

namespace demcal::integrate {

void kick_drift(particles::ParticleStore& p, double dt, int lo, int hi) {
  const double half = 0.5 * dt;
  for (int i = lo; i < hi; ++i) {
    p.v[i] += p.f[i] * (half * p.inv_mass[i]);
    p.omega[i] += p.torque[i] * (half * p.inv_inertia[i]);
    p.x[i] += p.v[i] * dt;
  }
}

void kick(particles::ParticleStore& p, double half_dt, int lo, int hi) {
  for (int i = lo; i < hi; ++i) {
    p.v[i] += p.f[i] * (half_dt * p.inv_mass[i]);
    p.omega[i] += p.torque[i] * (half_dt * p.inv_inertia[i]);
  }
}

}  // namespace demcal::integrate
