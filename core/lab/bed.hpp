#pragma once
// Building a powder bed in a cylindrical die from a material model: the shared first phase of
// the lab tests (seed 000 §2.7.1: random non-overlapping insertion in a cylinder, then settling
// under gravity). Tests then add pistons, cut the bed, or shear it.
#include <functional>

#include "core/lab/lab_test.hpp"
#include "core/sim/health.hpp"
#include "core/sim/world.hpp"

namespace demcal::lab {

struct BedSpec {
  std::size_t particles = 300;
  double die_radius = 0.0;  ///< (m); 0 = chosen so the settled bed is about as high as wide
  double insert_height =
      0.0;  ///< height of the insertion region (m); 0 = from a loose fraction 0.25
  double time_step_safety = 0.2;  ///< dt = safety * critical time step
  double settle_energy =
      1e-5;  ///< settled when the mean kinetic energy per particle < this * m g d
  double max_settle_time = 2.0;  ///< (s) of simulated time
};

/// Wall materials used by the lab tests: the particle-wall law of the material model is given
/// to every wall material unless a test overrides one (e.g. adhesive piston, frictionless die).
enum WallMaterial : std::uint16_t {
  kWallDefault = 0,
  kWallDie = 1,
  kWallPiston = 2,
  kWallBottom = 3
};

/// A world with the material's simulated laws, a floor (kWallBottom) and a die (kWallDie, an
/// inner cylinder about the z axis), and the particles inserted at random without overlap.
sim::World make_die_world(const MaterialModel& material, const BedSpec& spec,
                          const RunOptions& options);

/// Steps until the bed is at rest (mean kinetic energy criterion of BedSpec) or max time; checks
/// health every few hundred steps. Returns the simulated time spent.
double settle(sim::World& world, const BedSpec& spec, const sim::HealthLimits& limits);

/// Steps `steps` steps with a health check every `check_every`, calling `each` (if given) after
/// every step; stops early when `each` returns false. Returns the steps done.
long run_checked(sim::World& world, long steps, const sim::HealthLimits& limits,
                 const std::function<bool(sim::World&)>& each = {}, int check_every = 200);

/// Health limits for a die world: particles must stay within a box around the die.
sim::HealthLimits die_limits(const sim::World& world, double die_radius, double height);

}  // namespace demcal::lab
