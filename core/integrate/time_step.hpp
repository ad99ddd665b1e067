#pragma once
// Time-step bounds of explicit DEM.
#include <cmath>

namespace demcal::integrate {

/// Rayleigh time (seed 000 eq. 1): the time a Rayleigh wave needs to cross a particle; the usual
/// bound for Hertzian contacts. G = Y / (2 (1 + nu)).
inline double rayleigh_time(double radius, double density, double youngs_modulus, double poisson) {
  const double shear_modulus = youngs_modulus / (2.0 * (1.0 + poisson));
  return M_PI * radius * std::sqrt(density / shear_modulus) / (0.163 * poisson + 0.8766);
}

/// Spring time sqrt(m/k) (seed 001 eq. 14) for linear contacts: m the lightest particle, k the
/// stiffest spring. Velocity Verlet is stable up to 2 sqrt(m*/k) = sqrt(2) sqrt(m/k) for a pair of
/// equal particles, so sqrt(m/k) itself keeps a margin.
inline double spring_time(double mass, double stiffness) {
  return std::sqrt(mass / stiffness);
}

}  // namespace demcal::integrate
