#pragma once
// Small materials for the lab-test tests: soft Luding spheres of 1 mm radius so that a
// few hundred particles run in seconds, and cohesionless Hertz spheres.
#include "core/lab/lab_run.hpp"
#include "core/lab/piston.hpp"

namespace demcal::lab::testing {

inline MaterialModel soft_luding(double youngs = 1e7, double k2_ratio = 5.0, double kc_ratio = 0.0,
                                 double hamaker = 0.0, double mu_wall = 0.3) {
  MaterialModel m;
  m.particle_law.normal = {"luding",
                           {{"youngs_modulus", youngs},
                            {"k2_ratio", k2_ratio},
                            {"kc_ratio", kc_ratio},
                            {"phi_f", 0.05},
                            {"restitution", 0.3}}};
  if (hamaker > 0.0)
    m.particle_law.cohesion = {"van_der_waals", {{"hamaker", hamaker}, {"d_max", 1e-5}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.3}}};
  m.wall_law = m.particle_law;
  m.wall_law.tangential.params["mu_s"] = mu_wall;
  m.sizes = particles::Monodisperse{1e-3};
  m.density = 1500.0;
  return m;
}

/// Cohesionless Hertz spheres of 1 mm radius with sliding friction mu_s (no rolling resistance).
inline MaterialModel hertz_spheres(double mu_s) {
  MaterialModel m;
  m.particle_law.normal = {
      "hertz", {{"youngs_modulus", 5e7}, {"poisson_ratio", 0.25}, {"restitution", 0.5}}};
  m.particle_law.tangential = {"history", {{"mu_s", mu_s}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{1e-3};
  m.density = 2500.0;
  return m;
}

/// A bare die bed of `particles`: time-step safety 0.2, settled against gravity alone, the
/// material's wall laws.
inline PistonBedRequest bare_bed(std::size_t particles) {
  PistonBedRequest request;
  request.particles = particles;
  request.safety = 0.2;
  return request;
}

}  // namespace demcal::lab::testing
