#include "core/particles/particle_store.hpp"

#include <cmath>

namespace demcal::particles {

std::size_t ParticleStore::add_sphere(const Vec3& position, double r, double density,
                                      std::uint16_t material_id, Motion m) {
  const double mass_i = density * 4.0 / 3.0 * M_PI * r * r * r;
  x.push_back(position);
  v.emplace_back();
  omega.emplace_back();
  f.emplace_back();
  torque.emplace_back();
  radius.push_back(r);
  mass.push_back(mass_i);
  inertia.push_back(0.4 * mass_i * r * r);
  inv_mass.push_back(0.0);
  inv_inertia.push_back(0.0);
  material.push_back(material_id);
  motion.push_back(m);
  set_motion(x.size() - 1, m);
  return x.size() - 1;
}

void ParticleStore::set_motion(std::size_t i, Motion m) {
  motion[i] = m;
  inv_mass[i] = m == Motion::kFree ? 1.0 / mass[i] : 0.0;
  inv_inertia[i] = m == Motion::kFree ? 1.0 / inertia[i] : 0.0;
}

void ParticleStore::reserve(std::size_t n) {
  x.reserve(n);
  v.reserve(n);
  omega.reserve(n);
  f.reserve(n);
  torque.reserve(n);
  radius.reserve(n);
  mass.reserve(n);
  inertia.reserve(n);
  inv_mass.reserve(n);
  inv_inertia.reserve(n);
  material.reserve(n);
  motion.reserve(n);
}

namespace {
template <class T>
void compact(std::vector<T>& a, const std::vector<char>& flags) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!flags[i]) a[out++] = a[i];
  a.resize(out);
}
}  // namespace

void ParticleStore::remove_if(const std::vector<char>& flags) {
  compact(x, flags);
  compact(v, flags);
  compact(omega, flags);
  compact(f, flags);
  compact(torque, flags);
  compact(radius, flags);
  compact(mass, flags);
  compact(inertia, flags);
  compact(inv_mass, flags);
  compact(inv_inertia, flags);
  compact(material, flags);
  compact(motion, flags);
}

double ParticleStore::total_mass() const {
  double m = 0.0;
  for (double mi : mass) m += mi;
  return m;
}

double ParticleStore::kinetic_energy() const {
  double e = 0.0;
  for (std::size_t i = 0; i < size(); ++i)
    e += 0.5 * (mass[i] * norm2(v[i]) + inertia[i] * norm2(omega[i]));
  return e;
}

}  // namespace demcal::particles
