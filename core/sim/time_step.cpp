#include "core/sim/time_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/common/error.hpp"
#include "core/integrate/time_step.hpp"

namespace demcal::sim {

/// The mass a contact on sphere i accelerates, in the direction where it is smallest.
///
/// A lone sphere's contact moves the sphere: its own mass. A clump member's contact moves its
/// whole rigid body, which along the contact normal n responds like the point mass
///   m_eff(n) = 1 / (1/M + (a x n) . I^-1 (a x n))
/// (the effective mass of a rigid body at a contact point, as in impulse-based rigid-body
/// dynamics, Mirtich & Canny 1995; a = the member centre's arm from the centre of mass: the
/// surface point a + r n has the same a x n). The stability limit of the contact's spring is set
/// by this mass, as it is by a lone sphere's mass, so the bounds below take m_eff in its worst
/// direction. The member's mass share by volume (ParticleStore::add_clump) is only a
/// bookkeeping device for mass sums: no part of the body moves with that mass alone, and
/// bounding the step by it (as before) made clump runs take needlessly many steps.
/// The worst direction: a x n sweeps the plane normal to a with length up to |a|, so the largest
/// (a x n) . I^-1 (a x n) is |a|^2 times the larger eigenvalue of I^-1 restricted to that plane
/// (I diagonal in the body frame, where a is given).
double contact_mass(const particles::ParticleStore& p, std::size_t i) {
  if (p.body[i] < 0) return p.mass[i];
  const auto b = static_cast<std::size_t>(p.body[i]);
  const double body_mass = p.clumps.mass[b];
  const Vec3 a = p.body_offset[i];
  const double a2 = norm2(a);
  if (a2 == 0.0) return body_mass;
  // An orthonormal pair (e1, e2) spanning the plane normal to a.
  const Vec3 axis = a * (1.0 / std::sqrt(a2));
  const Vec3 helper = std::abs(axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 e1 = normalized(cross(axis, helper));
  const Vec3 e2 = cross(axis, e1);
  const Vec3 inv_i{1.0 / p.clumps.inertia[b].x, 1.0 / p.clumps.inertia[b].y,
                   1.0 / p.clumps.inertia[b].z};
  auto form = [&](const Vec3& u, const Vec3& v) {
    return u.x * v.x * inv_i.x + u.y * v.y * inv_i.y + u.z * v.z * inv_i.z;
  };
  const double m11 = form(e1, e1), m22 = form(e2, e2), m12 = form(e1, e2);
  const double mean = 0.5 * (m11 + m22);
  const double largest = mean + std::sqrt(0.25 * (m11 - m22) * (m11 - m22) + m12 * m12);
  return 1.0 / (1.0 / body_mass + a2 * largest);
}

namespace {

/// Both bounds of a world, found in one pass over its laws and particles.
struct Bounds {
  TimeStepLimit law_max{std::numeric_limits<double>::infinity(), "no contacts"};
  TimeStepLimit fresh{std::numeric_limits<double>::infinity(), "no contacts"};
};

void lower(TimeStepLimit& limit, double t, bool hertz, const std::string& which) {
  if (t < limit.critical) {
    limit.critical = t;
    limit.basis = (hertz ? "Rayleigh time of " : "sqrt(m/k) of ") + which;
  }
}

/// Tightens both bounds by a law's for every particle: at the law's largest stiffness, and at the
/// stiffness a contact has when it forms.
void tighten(Bounds& bounds, const contact::ContactLaw& law, const std::string& which,
             const World& world) {
  const auto& p = world.particles;
  const bool hertz = std::holds_alternative<contact::normal::Hertz>(law.normal);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.radius[i];
    const double m = contact_mass(p, i);
    double t_max, t_fresh;
    if (hertz) {
      // The Rayleigh time pi r sqrt(rho / G) / (0.163 nu + 0.8766) is a bound in sqrt(m / r)
      // (rho = m / (4/3 pi r^3)); with m the mass the contact moves, it keeps for a member sphere
      // (whose radius sets the Hertz stiffness) the margin it has for a lone sphere. It does not
      // depend on the overlap, so it bounds an impact at any speed.
      const auto& model = std::get<contact::normal::Hertz>(law.normal);
      const double density = m / (4.0 / 3.0 * M_PI * r * r * r);
      t_max = t_fresh =
          integrate::rayleigh_time(r, density, model.youngs_modulus, model.poisson_ratio);
    } else {
      // r_eff = 2 r covers equal spheres and sphere-wall contacts alike (and gives the larger
      // stiffness of the two: k1 grows with r_eff, k2*(delta) - k1 does not depend on it).
      t_max = integrate::spring_time(m, law.max_stiffness(2.0 * r));
      t_fresh = integrate::spring_time(m, law.reached_stiffness(2.0 * r, 0.0));
    }
    lower(bounds.law_max, t_max, hertz, which);
    lower(bounds.fresh, t_fresh, hertz, which);
  }
}

Bounds bounds_over_laws(const World& world) {
  Bounds bounds;
  for (int a = 0; a < world.materials(); ++a)
    for (int b = a; b < world.materials(); ++b)
      tighten(bounds, world.pair_law(a, b),
              "particle-particle law " + std::to_string(a) + "-" + std::to_string(b), world);
  for (const auto& wall : world.walls)
    for (int a = 0; a < world.materials(); ++a)
      tighten(bounds, world.wall_law(wall.material, a), "wall '" + wall.name + "' law", world);
  return bounds;
}

/// safety x sqrt(m*/k) of the stiffest contact of the last force evaluation whose stiffness
/// sets the accuracy, kStableFraction x sqrt(m*/k) of the stiffest of the others (infinite
/// without contacts).
double in_use_time_step(const World& world, double safety) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const double accurate =
      world.contact_rate2 > 0.0 ? safety / std::sqrt(world.contact_rate2) : kNone;
  const double stable = world.contact_stable_rate2 > 0.0
                            ? kStableFraction / std::sqrt(world.contact_stable_rate2)
                            : kNone;
  return std::min(accurate, stable);
}

}  // namespace

TimeStepLimit critical_time_step(const World& world) {
  return bounds_over_laws(world).law_max;
}

TimeStepLimit fresh_contact_time_step(const World& world) {
  return bounds_over_laws(world).fresh;
}

double recommended_time_step(const World& world, double safety) {
  return safety * critical_time_step(world).critical;
}

double adapted_time_step(const World& world, double safety) {
  return std::min(safety * fresh_contact_time_step(world).critical,
                  in_use_time_step(world, safety));
}

double next_time_step(const World& world, bool retune) {
  const double in_use = in_use_time_step(world, world.adaptive_safety);
  if (!retune) return std::min(world.dt, in_use);
  return std::min({world.dt * World::kStepGrowth, in_use,
                   world.adaptive_safety * fresh_contact_time_step(world).critical});
}

void check_time_step(const World& world) {
  if (!(world.dt > 0.0))
    throw SimulationFailure(SimulationFailure::Reason::kUnstableTimeStep, "time step must be > 0");
  if (world.adaptive_safety > 0.0) return;  // the step follows the contacts (next_time_step)
  const TimeStepLimit limit = critical_time_step(world);
  if (world.dt > limit.critical) {
    char msg[256];
    std::snprintf(msg, sizeof msg,
                  "time step %.4g s exceeds the stability limit %.4g s (%s); use at most %.4g s",
                  world.dt, limit.critical, limit.basis.c_str(), 0.5 * limit.critical);
    throw SimulationFailure(SimulationFailure::Reason::kUnstableTimeStep, msg);
  }
}

}  // namespace demcal::sim
