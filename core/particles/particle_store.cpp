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
  body.push_back(-1);
  body_offset.emplace_back();
  set_motion(x.size() - 1, m);
  return x.size() - 1;
}

std::size_t ParticleStore::add_clump(const Vec3& position, const Quat& orientation,
                                     const ClumpTemplate& shape, double r, double density,
                                     std::uint16_t material_id) {
  const double volume = shape.volume * r * r * r;
  const double m = density * volume;
  const auto b = static_cast<std::int32_t>(clumps.size());
  clumps.first.push_back(size());
  clumps.count.push_back(static_cast<std::uint32_t>(shape.size()));
  clumps.x.push_back(position);
  clumps.v.emplace_back();
  clumps.omega.emplace_back();
  clumps.angular_momentum.emplace_back();
  clumps.q.push_back(orientation.normalized());
  clumps.mass.push_back(m);
  clumps.inertia.push_back(shape.inertia * (density * std::pow(r, 5)));
  clumps.volume_weight.push_back(shape.volume_weight());
  clumps.parked.push_back(0);
  const double own_sum = shape.sphere_volume_sum * r * r * r;
  for (std::size_t k = 0; k < shape.size(); ++k) {
    const Vec3 offset = shape.offsets[k] * r;
    const double rk = shape.radii[k] * r;
    const std::size_t i = add_sphere(position + clumps.q.back().rotate(offset), rk, density,
                                     material_id, Motion::kClumpMember);
    mass[i] = m * (4.0 / 3.0 * M_PI * rk * rk * rk) / own_sum;
    inertia[i] = 0.4 * mass[i] * rk * rk;
    body[i] = b;
    body_offset[i] = offset;
  }
  return static_cast<std::size_t>(b);
}

void ParticleStore::set_motion(std::size_t i, Motion m) {
  motion[i] = m;
  // Kinematic particles and clump members are not moved by their own forces.
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
  body.reserve(n);
  body_offset.reserve(n);
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

void ParticleStore::remove_if(const std::vector<char>& flags_in) {
  std::vector<char> flags = flags_in;
  std::vector<char> body_gone(clumps.size(), 0);
  for (std::size_t i = 0; i < size(); ++i)
    if (flags[i] && body[i] >= 0) body_gone[body[i]] = 1;
  for (std::size_t i = 0; i < size(); ++i)
    if (body[i] >= 0 && body_gone[body[i]]) flags[i] = 1;
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
  compact(body, flags);
  compact(body_offset, flags);

  // Renumber the surviving clumps and find their (still contiguous) member ranges.
  std::vector<std::int32_t> renumber(clumps.size(), -1);
  std::int32_t kept = 0;
  for (std::size_t b = 0; b < clumps.size(); ++b)
    if (!body_gone[b]) renumber[b] = kept++;
  compact(clumps.count, body_gone);
  compact(clumps.x, body_gone);
  compact(clumps.v, body_gone);
  compact(clumps.omega, body_gone);
  compact(clumps.angular_momentum, body_gone);
  compact(clumps.q, body_gone);
  compact(clumps.mass, body_gone);
  compact(clumps.inertia, body_gone);
  compact(clumps.volume_weight, body_gone);
  compact(clumps.parked, body_gone);
  clumps.first.assign(clumps.count.size(), 0);
  for (std::size_t i = size(); i-- > 0;)
    if (body[i] >= 0) {
      body[i] = renumber[body[i]];
      clumps.first[body[i]] = i;
    }
}

double ParticleStore::park(std::size_t i, const Vec3& where, std::vector<char>& gone) {
  if (body[i] < 0) {
    x[i] = where;
    v[i] = omega[i] = {};
    set_motion(i, Motion::kKinematic);
    gone[i] = 1;
    return mass[i];
  }
  const auto b = static_cast<std::size_t>(body[i]);
  const Vec3 shift = where - x[i];
  clumps.x[b] += shift;
  clumps.v[b] = clumps.omega[b] = clumps.angular_momentum[b] = {};
  clumps.parked[b] = 1;
  double m = 0.0;
  for (std::size_t k = clumps.first[b]; k < clumps.first[b] + clumps.count[b]; ++k) {
    x[k] += shift;
    v[k] = omega[k] = {};
    gone[k] = 1;
    m += mass[k];
  }
  return m;
}

double ParticleStore::solid_volume(std::size_t i) const {
  const double own = 4.0 / 3.0 * M_PI * radius[i] * radius[i] * radius[i];
  return body[i] < 0 ? own : own * clumps.volume_weight[body[i]];
}

std::size_t ParticleStore::units() const {
  std::size_t lone = 0;
  for (auto b : body) lone += b < 0 ? 1 : 0;
  return lone + clumps.size();
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
