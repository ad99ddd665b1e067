#include "core/sim/health.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/common/error.hpp"
#include "core/walls/mesh.hpp"

namespace demcal::sim {

namespace {

/// The walls particle i overlaps, named, for the message of an escaped particle: a particle that
/// leaves the test volume while touching a wall has usually been carried out along it (an
/// adhesive wall holds it while it slides or rolls), one touching none was thrown.
std::string touched_walls(const World& w, std::size_t i) {
  const Vec3& x = w.particles.x[i];
  const double r = w.particles.radius[i];
  std::string names;
  for (const walls::Wall& wall : w.walls) {
    const bool touching = std::visit(
        [&](const auto& shape) {
          walls::WallGeometry g[walls::Mesh::kMaxContacts];
          if constexpr (std::is_same_v<std::decay_t<decltype(shape)>, walls::Mesh>)
            return walls::mesh_contacts(shape, x, r, 0.0, g) > 0;
          else
            return walls::primitive_geometry(shape, x, r, 0.0, g[0]);
        },
        wall.shape);
    if (touching) names += (names.empty() ? "'" : ", '") + wall.name + "'";
  }
  return names.empty() ? "touching no wall" : "touching wall " + names;
}

}  // namespace

void check_health(const World& w, const HealthLimits& limits) {
  const auto& p = w.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!is_finite(p.x[i]) || !is_finite(p.v[i]) || !is_finite(p.omega[i])) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "particle %zu has a non-finite position or velocity at t = %.6g s", i, w.time);
      throw SimulationFailure(SimulationFailure::Reason::kNotFinite, msg);
    }
    for (int k = 0; k < 3; ++k)
      if (!w.domain.periodic[k] && (p.x[i][k] < limits.lo[k] || p.x[i][k] > limits.hi[k])) {
        char msg[200];
        std::snprintf(msg, sizeof msg,
                      "particle %zu left the test volume at t = %.6g s (position %.4g %.4g %.4g m, "
                      "velocity %.3g %.3g %.3g m/s, ",
                      i, w.time, p.x[i].x, p.x[i].y, p.x[i].z, p.v[i].x, p.v[i].y, p.v[i].z);
        throw SimulationFailure(SimulationFailure::Reason::kEscaped,
                                msg + touched_walls(w, i) + ")");
      }
  }
  const double ke = p.kinetic_energy();
  if (ke > limits.max_kinetic_energy) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "kinetic energy %.4g J exceeds the plausible maximum %.4g J at t = %.6g s", ke,
                  limits.max_kinetic_energy, w.time);
    throw SimulationFailure(SimulationFailure::Reason::kEnergyExplosion, msg);
  }
}

namespace {

/// The smallest particle radius of each material present (0: none of it).
std::vector<double> smallest_radius(const particles::ParticleStore& p, int materials) {
  std::vector<double> r(static_cast<std::size_t>(materials), 0.0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    double& m = r[p.material.empty() ? 0 : p.material[i]];
    m = m > 0.0 ? std::min(m, p.radius[i]) : p.radius[i];
  }
  return r;
}

}  // namespace

void check_pair_range(const contact::ContactLaw& law, double r_i, double r_j,
                      const std::string& what) {
  const double r_eff = 2.0 * r_i * r_j / (r_i + r_j);
  const double radius = std::min(r_i, r_j);
  const double overlap = law.adhesion_overlap(r_eff);
  if (overlap < radius) return;
  const double force =
      std::visit([&](const auto& c) { return c.contact_force(r_eff); }, law.cohesion);
  throw SimulationFailure(
      SimulationFailure::Reason::kContactOutOfRange,
      "the particle-particle law of " + what + ": its attraction at contact (" +
          message_number(force, 4) + " N) holds a particle of radius " + message_number(radius, 4) +
          " m at an overlap of " + message_number(overlap / radius, 3) +
          " radii under the law's repulsion: outside the range of a soft-sphere contact (an "
          "overlap below the radius); a larger radius, a weaker attraction or a stiffer law "
          "brings it back");
}

void check_contact_range(const World& w) {
  const auto r = smallest_radius(w.particles, w.materials());
  for (int a = 0; a < w.materials(); ++a)
    for (int b = a; b < w.materials(); ++b)
      if (r[a] > 0.0 && r[b] > 0.0)
        check_pair_range(w.pair_law(a, b), r[a], r[b],
                         "materials " + std::to_string(a) + " and " + std::to_string(b));
}

double attraction_energy_bound(const World& w) {
  const auto& p = w.particles;
  if (p.size() == 0) return 0.0;
  const double r_max = *std::max_element(p.radius.begin(), p.radius.end());
  double pair = 0.0, wall = 0.0;
  for (int a = 0; a < w.materials(); ++a) {
    for (int b = 0; b < w.materials(); ++b)
      pair = std::max(pair, w.pair_law(a, b).attraction_energy(r_max));
    // A particle-wall contact's effective radius is 2 R* = 2 r.
    for (const auto& wall_k : w.walls)
      wall = std::max(wall, w.wall_law(wall_k.material, a).attraction_energy(2.0 * r_max));
  }
  return static_cast<double>(p.size()) * (6.0 * pair + wall);
}

double kinetic_energy_limit(const World& world, double potential_energy) {
  return 1e3 * potential_energy + attraction_energy_bound(world);
}

}  // namespace demcal::sim
