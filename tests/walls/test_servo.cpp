// StressServo: a piston driven to a target stress on a settled bed holds that stress; on a
// contact far stiffer than its speed limit allows for, the speed limit alone flips it between its
// limits, and the bound by the wall's contact stiffness (Chareyre's rule) brings it to the target
// without crossing it.
#include <gtest/gtest.h>

#include "core/lab/bed.hpp"
#include "core/sim/step.hpp"
#include "core/walls/servo.hpp"

namespace demcal {
namespace {

TEST(StressServo, PistonReachesAndHoldsTheTargetStress) {
  lab::MaterialModel m;
  m.particle_law.normal = {"linear", {{"kn", 2000.0}, {"damping_ratio", 0.5}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.3}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{1e-3};
  m.density = 2500.0;
  lab::BedSpec bed;
  bed.particles = 150;
  lab::RunOptions opt;
  sim::World w = lab::make_die_world(m, bed, opt);
  const double radius = std::get<walls::Cylinder>(w.walls[1].shape).radius;
  const auto limits = lab::die_limits(w, radius, 0.05);
  lab::settle(w, bed, limits, m.factors().time);

  double top = 0.0;
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    top = std::max(top, w.particles.x[i].z + 1e-3);
  w.walls.push_back(walls::make_wall("piston", walls::Disk{{0, 0, top + 1e-3}, {0, 0, -1}, radius},
                                     lab::kWallPiston));
  walls::StressServo servo;
  servo.area = M_PI * radius * radius;
  servo.target = 2000.0;
  servo.max_speed = 0.05;
  servo.kp = servo.max_speed / servo.target;
  servo.ki = 20.0 * servo.kp;
  auto& piston = w.walls.back();
  double sum = 0.0;
  int samples = 0;
  const long steps = std::lround(0.4 / w.dt);
  const double t_measure = w.time + 0.3;
  lab::run_checked(w, steps, limits, [&](sim::World& world) {
    servo.update(world.walls.back(), world.dt);
    if (std::getenv("SERVO_TRACE") && world.step_count % 500 == 0)
      std::printf("%g %g %g\n", world.time, servo.stress(world.walls.back()),
                  world.walls.back().velocity.z);
    if (world.time > t_measure) {
      sum += servo.stress(world.walls.back());
      ++samples;
    }
    return true;
  });
  ASSERT_GT(samples, 100);
  EXPECT_NEAR(sum / samples, servo.target, 0.02 * servo.target);
  EXPECT_LT(piston.displacement.z, 0.0) << "the piston moved down into the bed";
  // The particles push the bottom down with the piston load plus their weight, less what the die
  // wall takes by friction.
  EXPECT_LT(w.walls[0].force.z, -0.5 * servo.target * servo.area);
}

/// A piston pressing on one sphere held in place (kinematic) through an undamped linear contact of
/// stiffness kn: the piston's stress is kn x overlap / area, and its contact stiffness is kn.
struct StiffContact {
  static constexpr double kn = 1e3, radius = 1e-3, area = 1e-5;
  sim::World w;
  StiffContact() {
    contact::ContactLawSpec law;
    law.normal = {"linear", {{"kn", kn}}};
    law.tangential = {"history", {{"mu_s", 0.0}}};
    w.set_pair_law(0, 0, contact::ContactLaw::from_spec(law, "law"));
    w.set_wall_law(0, 0, contact::ContactLaw::from_spec(law, "wall law"));
    const std::size_t i = w.particles.add_sphere({0, 0, 0}, radius, 2500, 0);
    w.particles.set_motion(i, particles::Motion::kKinematic);
    w.gravity = {};
    w.walls.push_back(
        walls::make_wall("piston", walls::Disk{{0, 0, radius - 1e-8}, {0, 0, -1}, 5e-3}));
    w.dt = 1e-6;
  }
  /// The servo: a target of 100 Pa (an overlap of 1 um) and a speed limit that moves the piston by
  /// that whole overlap in one step.
  walls::StressServo servo() const {
    walls::StressServo s;
    s.area = area;
    s.target = 100.0;
    s.max_speed = 1.0;
    s.kp = 1.0;
    return s;
  }
};

TEST(StressServo, TheWallsStiffnessIsTheSumOfItsContactsStiffnesses) {
  StiffContact c;
  sim::step(c.w);
  EXPECT_DOUBLE_EQ(c.w.walls[0].stiffness, StiffContact::kn);
  EXPECT_NEAR(c.w.walls[0].force.z, StiffContact::kn * 1e-8, 1e-15);
  c.w.walls[0].velocity = {0, 0, 1.0};  // away from the sphere: the contact opens
  sim::run(c.w, 2);
  EXPECT_EQ(c.w.walls[0].stiffness, 0.0);
}

TEST(StressServo, OnAStiffContactTheSpeedLimitAloneFlipsBetweenItsLimits) {
  StiffContact c;
  walls::StressServo servo = c.servo();
  int crossings = 0;
  double last_error = servo.target;
  for (int k = 0; k < 200; ++k) {
    sim::step(c.w);
    const double error = servo.target - servo.stress(c.w.walls[0]);
    if (k > 100 && error * last_error < 0.0) ++crossings;
    last_error = error;
    servo.update(c.w.walls[0], c.w.dt);
  }
  EXPECT_GT(crossings, 90) << "the stress crosses the target at almost every step";
}

TEST(StressServo, BoundedByTheContactStiffnessItReachesTheTargetWithoutCrossingIt) {
  StiffContact c;
  walls::StressServo servo = c.servo();
  double error = servo.target;
  for (int k = 0; k < 60; ++k) {
    sim::step(c.w);
    error = servo.target - servo.stress(c.w.walls[0]);
    ASSERT_GE(error, 0.0) << "step " << k << ": the stress crossed the target";
    servo.update(c.w.walls[0], c.w.dt, 0.5);
  }
  // Each step closes half the error (the contact is linear and its stiffness is known exactly).
  EXPECT_LT(error, 1e-12 * servo.target);
}

}  // namespace
}  // namespace demcal
