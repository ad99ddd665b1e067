// Settling (docs/lab-tests.md, "Settling"): a die bed is at rest when the kinetic stress of its
// translation, rho_p <v^2>, is below I_rest^2 times the reference stress; spins do not count.
#include <gtest/gtest.h>

#include "core/lab/bed.hpp"

namespace demcal::lab {
namespace {

/// Frictionless linear spheres without rolling resistance: a spin does not couple to anything.
MaterialModel frictionless() {
  MaterialModel m;
  m.particle_law.normal = {"linear", {{"kn", 2000.0}, {"damping_ratio", 0.5}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.0}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{1e-3};
  m.density = 2500.0;
  return m;
}

struct SettledBed {
  sim::World world;
  sim::HealthLimits limits;
  BedSpec spec;
};

SettledBed settled_bed() {
  BedSpec spec;
  spec.particles = 80;
  RunOptions options;
  sim::World w = make_die_world(frictionless(), spec, options);
  const double radius = std::get<walls::Cylinder>(w.walls[1].shape).radius;
  const sim::HealthLimits limits = die_limits(w, radius, 0.05);
  const PhaseCost first = settle(w, spec, limits);
  EXPECT_TRUE(first.reached) << first.target;
  return {std::move(w), limits, spec};
}

TEST(Settle, TranslationalKineticEnergyLeavesSpinsOut) {
  particles::ParticleStore p;
  p.add_sphere({0, 0, 0}, 1e-3, 2500.0, 0);
  p.v[0] = {1.0, 2.0, 2.0};
  p.omega[0] = {0.0, 0.0, 100.0};
  EXPECT_DOUBLE_EQ(p.translational_kinetic_energy(), 0.5 * p.mass[0] * 9.0);
  EXPECT_DOUBLE_EQ(p.kinetic_energy(),
                   0.5 * p.mass[0] * 9.0 + 0.5 * p.inertia[0] * 100.0 * 100.0);
}

// A bed at rest whose particles spin in place is at rest: it settles again within the free-fall
// time of its column and the first check after it. Counting the spins (which nothing here damps)
// kept it "moving" until the settling time ran out.
TEST(Settle, ABedAtRestWhoseParticlesSpinIsAtRest) {
  SettledBed bed = settled_bed();
  auto& p = bed.world.particles;
  double rotational = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.omega[i] = {0.0, 0.0, 50.0};
    rotational += 0.5 * p.inertia[i] * 2500.0;
  }
  ASSERT_GT(rotational, 1e3 * p.translational_kinetic_energy());
  const PhaseCost again = settle(bed.world, bed.spec, bed.limits);
  EXPECT_TRUE(again.reached) << again.target;
  EXPECT_LT(again.simulated_time, 0.2 * bed.spec.max_settle_time);
  EXPECT_GT(p.kinetic_energy(), 0.5 * rotational) << "the spins were not damped away";
}

// The other way round: a bed whose particles move is not at rest, whatever they spin.
TEST(Settle, ABedWhoseParticlesMoveIsNotAtRestWithinAShortTime) {
  SettledBed bed = settled_bed();
  auto& p = bed.world.particles;
  for (std::size_t i = 0; i < p.size(); ++i) p.v[i] = {0.0, 0.0, 0.5};
  bed.spec.max_settle_time = 0.01;
  const PhaseCost again = settle(bed.world, bed.spec, bed.limits);
  EXPECT_FALSE(again.reached) << again.target;
}

}  // namespace
}  // namespace demcal::lab
