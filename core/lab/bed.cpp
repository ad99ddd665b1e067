#include "core/lab/bed.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/rng.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal::lab {
namespace {

double mean_particle_volume(const particles::SizeDistribution& sizes, Rng rng) {
  double v = 0.0;
  constexpr int kSamples = 2000;
  for (int k = 0; k < kSamples; ++k)
    v += 4.0 / 3.0 * M_PI * std::pow(particles::sample_radius(sizes, rng), 3);
  return v / kSamples;
}

}  // namespace

sim::World make_die_world(const MaterialModel& material, const BedSpec& spec,
                          const RunOptions& options) {
  sim::World w;
  w.threads = options.threads;
  const auto sizes = material.simulated_sizes();
  const double density = material.simulated_density();
  w.set_pair_law(0, 0, material.simulated_particle_law());
  const auto wall_law = material.simulated_wall_law();
  for (std::uint16_t m : {kWallDefault, kWallDie, kWallPiston, kWallBottom})
    w.set_wall_law(m, 0, wall_law);

  Rng rng(options.seed);
  const double solid =
      static_cast<double>(spec.particles) * mean_particle_volume(sizes, Rng(options.seed ^ 0x5eed));
  // A settled bed of solid fraction ~0.6 as high as it is wide: pi R^2 2R 0.6 = solid volume.
  const double radius =
      spec.die_radius > 0.0 ? spec.die_radius : std::cbrt(solid / (0.6 * 2.0 * M_PI));
  const double r_max = particles::max_radius(sizes);
  const double height = spec.insert_height > 0.0
                            ? spec.insert_height
                            : std::max(solid / (0.25 * M_PI * radius * radius), 4.0 * r_max);

  w.walls.push_back(walls::make_wall("bottom", walls::Plane{{0, 0, 0}, {0, 0, 1}}, kWallBottom));
  w.walls.push_back(
      walls::make_wall("die", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, radius}, kWallDie));
  particles::InsertRequest req;
  req.region = particles::CylinderRegion{{0, 0, 0}, radius, 0.0, height};
  req.sizes = sizes;
  req.count = spec.particles;
  req.density = density;
  particles::insert_random(w.particles, req, rng);
  w.dt = sim::recommended_time_step(w, spec.time_step_safety);
  return w;
}

sim::HealthLimits die_limits(const sim::World& world, double die_radius, double height) {
  sim::HealthLimits h;
  // Far more than the potential energy of the whole bed falling through the die: a bed whose
  // kinetic energy exceeds it has been blown up by a too-stiff contact or a runaway wall.
  h.max_kinetic_energy = 1e3 * world.particles.total_mass() * std::max(norm(world.gravity), 1.0) *
                         (height + die_radius);
  h.lo = {-2.0 * die_radius, -2.0 * die_radius, -0.5 * die_radius};
  h.hi = {2.0 * die_radius, 2.0 * die_radius, 2.0 * height + 2.0 * die_radius};
  return h;
}

long run_checked(sim::World& world, long steps, const sim::HealthLimits& limits,
                 const std::function<bool(sim::World&)>& each, int check_every) {
  for (long s = 0; s < steps; ++s) {
    sim::step(world);
    if ((s + 1) % check_every == 0) sim::check_health(world, limits);
    if (each && !each(world)) {
      sim::check_health(world, limits);
      return s + 1;
    }
  }
  sim::check_health(world, limits);
  return steps;
}

double settle(sim::World& w, const BedSpec& spec, const sim::HealthLimits& limits) {
  const auto& p = w.particles;
  double mgd = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) mgd += p.mass[i] * norm(w.gravity) * 2.0 * p.radius[i];
  mgd /= static_cast<double>(std::max<std::size_t>(p.size(), 1));
  const double t0 = w.time;
  const long chunk = std::max<long>(200, std::lround(0.002 / w.dt));
  while (w.time - t0 < spec.max_settle_time) {
    run_checked(w, chunk, limits);
    if (p.kinetic_energy() / static_cast<double>(p.size()) < spec.settle_energy * mgd) break;
  }
  return w.time - t0;
}

}  // namespace demcal::lab
