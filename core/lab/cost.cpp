#include "core/lab/cost.hpp"

#include <cmath>
#include <cstdio>

#include "core/sim/time_step.hpp"
#include "core/sim/world.hpp"

namespace demcal::lab {

double RunCost::particle_steps_per_second() const {
  return wall_seconds > 0.0
             ? static_cast<double>(particles) * static_cast<double>(steps) / wall_seconds
             : 0.0;
}

double RunCost::phases_wall_seconds() const {
  double sum = 0.0;
  for (const auto& p : phases) sum += p.wall_seconds;
  return sum;
}

void RunCost::close(const sim::World& world) {
  time_step = world.dt;
  const sim::TimeStepLimit limit = sim::critical_time_step(world);
  critical_time_step = limit.critical;
  char text[384];
  if (world.adaptive_safety > 0.0) {
    const sim::TimeStepLimit fresh = sim::fresh_contact_time_step(world);
    std::snprintf(text, sizeof text,
                  "%.3g x sqrt(m*/k) of the stiffest contact in use (shrinks at once, grows by "
                  "at most %.3g x every %d steps), at most %.3g x the bound of a fresh contact, "
                  "%s (%.4g s); at the end %.4g s, %.3g x the bound at the laws' largest "
                  "stiffness (%.4g s)",
                  world.adaptive_safety, sim::World::kStepGrowth, sim::World::kRetuneSteps,
                  world.adaptive_safety, fresh.basis.c_str(), fresh.critical, world.dt,
                  world.dt / limit.critical, limit.critical);
  } else {
    std::snprintf(text, sizeof text, "%.3g x %s (%.4g s)", world.dt / limit.critical,
                  limit.basis.c_str(), limit.critical);
  }
  time_step_limit = text;
  particles = world.particles.size();
  steps = 0;
  simulated_time = 0.0;
  for (const auto& p : phases) {
    steps += p.steps;
    simulated_time += p.simulated_time;
  }
}

PhaseClock::PhaseClock(const sim::World& world)
    : steps0_(world.step_count), time0_(world.time), wall0_(std::chrono::steady_clock::now()) {}

PhaseClock::PhaseClock() : wall0_(std::chrono::steady_clock::now()) {}

PhaseClock::PhaseClock(const PhaseMark& mark)
    : steps0_(mark.steps0),
      time0_(mark.time0),
      wall0_(std::chrono::steady_clock::now() -
             std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                 std::chrono::duration<double>(mark.wall_seconds))) {}

double PhaseClock::wall_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
}

PhaseCost PhaseClock::stop(const sim::World& world, std::string name, std::string target,
                           bool reached) const {
  PhaseCost c;
  c.name = std::move(name);
  c.target = std::move(target);
  c.steps = world.step_count - steps0_;
  c.simulated_time = world.time - time0_;
  c.wall_seconds = wall_seconds();
  c.reached = reached;
  return c;
}

std::string stress_text(double pa) {
  char text[64];
  if (std::abs(pa) >= 1e3)
    std::snprintf(text, sizeof text, "%.4g kPa", pa / 1e3);
  else
    std::snprintf(text, sizeof text, "%.4g Pa", pa);
  return text;
}

}  // namespace demcal::lab
