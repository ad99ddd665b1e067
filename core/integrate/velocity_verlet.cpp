#include "core/integrate/velocity_verlet.hpp"

namespace demcal::integrate {

void kick(particles::ParticleStore& p, double half_dt, int threads) {
  const int n = static_cast<int>(p.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    if (p.motion[i] != particles::Motion::kFree) continue;
    p.v[i] += p.f[i] * (half_dt / p.mass[i]);
    p.omega[i] += p.torque[i] * (half_dt / p.inertia[i]);
  }
}

void drift(particles::ParticleStore& p, double dt, int threads) {
  const int n = static_cast<int>(p.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) p.x[i] += p.v[i] * dt;
}

}  // namespace demcal::integrate
