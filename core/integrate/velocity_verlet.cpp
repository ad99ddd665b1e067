#include "core/integrate/velocity_verlet.hpp"

namespace demcal::integrate {

void kick_drift(particles::ParticleStore& p, double dt, int threads) {
  const int n = static_cast<int>(p.size());
  const double half = 0.5 * dt;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    p.v[i] += p.f[i] * (half * p.inv_mass[i]);
    p.omega[i] += p.torque[i] * (half * p.inv_inertia[i]);
    p.x[i] += p.v[i] * dt;
  }
}

void kick(particles::ParticleStore& p, double half_dt, int threads) {
  const int n = static_cast<int>(p.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    p.v[i] += p.f[i] * (half_dt * p.inv_mass[i]);
    p.omega[i] += p.torque[i] * (half_dt * p.inv_inertia[i]);
  }
}

}  // namespace demcal::integrate
