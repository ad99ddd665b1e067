// StressServo: a piston driven to a target stress on a settled bed holds that stress.
#include <gtest/gtest.h>

#include "core/lab/bed.hpp"
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

}  // namespace
}  // namespace demcal
