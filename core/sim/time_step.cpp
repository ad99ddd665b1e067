#include "core/sim/time_step.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>

#include "core/common/error.hpp"
#include "core/integrate/time_step.hpp"

namespace demcal::sim {
namespace {

void tighten(TimeStepLimit& limit, const contact::ContactLaw& law, const std::string& which,
             const World& world) {
  const auto& p = world.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double r = p.radius[i];
    double t;
    if (const auto* hertz = std::get_if<contact::normal::Hertz>(&law.normal)) {
      const double density = p.mass[i] / (4.0 / 3.0 * M_PI * r * r * r);
      t = integrate::rayleigh_time(r, density, hertz->youngs_modulus, hertz->poisson_ratio);
    } else {
      // r_eff = 2 r covers equal spheres and sphere-wall contacts alike.
      t = integrate::spring_time(p.mass[i], law.max_stiffness(2.0 * r));
    }
    if (t < limit.critical) {
      limit.critical = t;
      limit.basis =
          (std::holds_alternative<contact::normal::Hertz>(law.normal) ? "Rayleigh time of "
                                                                      : "sqrt(m/k) of ") +
          which;
    }
  }
}

}  // namespace

TimeStepLimit critical_time_step(const World& world) {
  TimeStepLimit limit{std::numeric_limits<double>::infinity(), "no contacts"};
  for (int a = 0; a < world.materials(); ++a)
    for (int b = a; b < world.materials(); ++b)
      tighten(limit, world.pair_law(a, b),
              "particle-particle law " + std::to_string(a) + "-" + std::to_string(b), world);
  for (const auto& w : world.walls)
    for (int a = 0; a < world.materials(); ++a)
      tighten(limit, world.wall_law(w.material, a), "wall '" + w.name + "' law", world);
  return limit;
}

double recommended_time_step(const World& world, double safety) {
  return safety * critical_time_step(world).critical;
}

void check_time_step(const World& world) {
  if (!(world.dt > 0.0))
    throw SimulationFailure(SimulationFailure::Reason::kUnstableTimeStep, "time step must be > 0");
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
