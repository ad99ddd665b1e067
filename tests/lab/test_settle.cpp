// Settling (docs/lab-tests.md, "Settling"): a bed ends its settle phase when its motion is
// quiet against its weight stress, or when it no longer sinks and its motion is quasi-static
// against the test's stress level; with the creep rule (growth preparation) only once its height
// has also stopped changing, within a budget.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/rng.hpp"
#include "core/lab/bed.hpp"

namespace demcal {
namespace {

constexpr double kRadius = 1e-3, kDensity = 2500.0, kStiffness = 2000.0;

/// A layer of 10 x 10 spheres on a floor, apart from each other, on undamped frictionless (mu_s 0)
/// springs: each keeps ringing in its floor contact at amplitude `ring` / omega (m/s over rad/s)
/// with its own phase, so the layer stands while its kinetic energy stays. With `sink` the whole
/// layer also moves down at that speed, without gravity and above the floor.
sim::World ringing_layer(double ring, double sink) {
  sim::World w;
  const auto law =
      contact::ContactLaw::from_spec({{"linear", {{"kn", kStiffness}, {"damping_ratio", 0.0}}},
                                      {"none", {}},
                                      {"history", {{"mu_s", 0.0}}},
                                      {"none", {}}},
                                     "law");
  w.set_pair_law(0, 0, law);
  w.set_wall_law(0, 0, law);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  const double mass = kDensity * 4.0 / 3.0 * M_PI * std::pow(kRadius, 3);
  const double rest_overlap = sink > 0.0 ? -kRadius : mass * 9.81 / kStiffness;
  if (sink > 0.0) w.gravity = {};
  const double omega = std::sqrt(kStiffness / mass);
  Rng rng(7);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      const double phase = 2.0 * M_PI * rng.uniform();
      const double z = kRadius - rest_overlap + ring / omega * std::sin(phase);
      const std::size_t k =
          w.particles.add_sphere({2.2 * kRadius * i, 2.2 * kRadius * j, z}, kRadius, kDensity, 0);
      w.particles.v[k] = {0.0, 0.0, ring * std::cos(phase) - sink};
    }
  w.dt = 0.05 * std::sqrt(mass / kStiffness);
  return w;
}

lab::PhaseCost settle(sim::World w, double sink_rate) {
  lab::BedSpec spec;
  spec.rest_stress = 1e3;  // a test's stress level far above the layer's weight stress (~30 Pa)
  spec.rest_sink_rate = sink_rate;
  spec.max_settle_time = 0.1;
  sim::HealthLimits limits;
  limits.lo = {-0.01, -0.01, -0.01};
  limits.hi = {0.03, 0.03, 0.01};
  return lab::settle(w, spec, limits, 1.0);
}

TEST(Settle, ALayerThatStandsWhileItsContactsRingIsSettledByNoLongerSinking) {
  // Speeds of 5e-4 m/s: a kinetic energy about ten times the quiet limit of the weight stress and
  // a third of the one of the test's stress level; the centre of mass rings by ~1e-9 m.
  const lab::PhaseCost standing = settle(ringing_layer(5e-4, 0.0), 1e-3);
  EXPECT_TRUE(standing.reached) << standing.target;
  EXPECT_LT(standing.simulated_time, 0.05);
  const lab::PhaseCost quiet_only = settle(ringing_layer(5e-4, 0.0), 0.0);
  EXPECT_FALSE(quiet_only.reached) << "rings to the time limit without the sinking criterion";
  EXPECT_NEAR(quiet_only.simulated_time, 0.1, 0.01);
}

TEST(Settle, ALayerStillSinkingIsNotSettledHoweverSlow) {
  // 1e-4 m/s down (5 % of the layer's height per second): a motion quasi-static against the
  // test's stress level, but the bed is not standing.
  const lab::PhaseCost sinking = settle(ringing_layer(0.0, 1e-4), 1e-3);
  EXPECT_FALSE(sinking.reached) << sinking.target;
  const lab::PhaseCost tolerated = settle(ringing_layer(0.0, 1e-4), 0.1);
  EXPECT_TRUE(tolerated.reached) << "a sinking rate of 0.1 height per second lets it through";
}

/// A layer of 10 x 10 spheres at rest on a floor under gravity (no ringing); with `creep` the
/// floor sinks at that speed (m/s) and the layer rides down on it: a bed whose motion is far
/// below every kinetic limit while its height keeps changing.
sim::World creeping_layer(double creep) {
  sim::World w = ringing_layer(0.0, 0.0);
  w.walls[0].velocity = {0.0, 0.0, -creep};
  for (auto& v : w.particles.v) v = {0.0, 0.0, -creep};
  return w;
}

lab::PhaseCost settle_with_creep_rule(sim::World w, double budget) {
  lab::BedSpec spec;
  spec.rest_sink_rate = 1e3;  // the static rule's own sinking check out of the way
  spec.creep_window = 0.01;
  spec.creep_inertial_number = 1e-5;
  spec.settle_budget = budget;
  sim::HealthLimits limits;
  limits.lo = {-0.01, -0.01, -0.01};
  limits.hi = {0.03, 0.03, 0.01};
  return lab::settle(w, spec, limits, 1.0);
}

TEST(Settle, TheCreepRuleWaitsForTheHeightAndEndsFlaggedOnItsBudget) {
  // A standing layer: settled after its first window.
  const lab::PhaseCost standing = settle_with_creep_rule(creeping_layer(0.0), 0.1);
  EXPECT_TRUE(standing.reached) << standing.target;
  EXPECT_LT(standing.simulated_time, 0.02);
  // Sinking at 1e-5 m/s (1 % of its height per second): its kinetic stress is ~1e-8 of its
  // weight stress, so the quiet rule alone ends it at once ...
  lab::BedSpec quiet_only;
  quiet_only.rest_sink_rate = 1e3;
  sim::HealthLimits limits;
  limits.lo = {-0.01, -0.01, -0.01};
  limits.hi = {0.03, 0.03, 0.01};
  sim::World quiet = creeping_layer(1e-5);
  EXPECT_TRUE(lab::settle(quiet, quiet_only, limits, 1.0).reached);
  // ... but its height changes at I_h = (1e-5 / 1e-3 m) x 2 mm x sqrt(2500 / 30 Pa) ~ 2e-4, so
  // the creep rule keeps it going, and it ends on the budget, flagged.
  const lab::PhaseCost creeping = settle_with_creep_rule(creeping_layer(1e-5), 0.05);
  EXPECT_FALSE(creeping.reached) << creeping.target;
  EXPECT_NEAR(creeping.simulated_time, 0.05, 0.01);
  EXPECT_NE(creeping.target.find("I_h < 1e-05"), std::string::npos) << creeping.target;
}

}  // namespace
}  // namespace demcal
