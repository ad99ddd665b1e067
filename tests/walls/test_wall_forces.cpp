// What walls report: the floor under a bed at rest carries the bed's weight, a
// frictionless cylinder around it carries (almost) nothing axially; a wall moving with a
// prescribed velocity has moved v t; a wall rotating about its pivot reports the torque of the
// particle forces about that pivot.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/rng.hpp"
#include "core/particles/insertion.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal {
namespace {

constexpr double kG = 9.81;

contact::ContactLaw linear_law(double kn, double mu_s, double mu_r) {
  contact::ContactLawSpec s;
  s.normal = {"linear", {{"kn", kn}, {"damping_ratio", 0.5}, {"damp_approach_only", 0.0}}};
  s.tangential = {"history", {{"mu_s", mu_s}}};
  if (mu_r > 0.0) s.rolling = {"epsd", {{"mu_r", mu_r}}};
  return contact::ContactLaw::from_spec(s, "law");
}

TEST(SimWalls, SettledBedFloorCarriesTheWeightAndMovingLidMovesVt) {
  sim::World w;
  w.gravity = {0, 0, -kG};
  w.set_pair_law(0, 0, linear_law(1e3, 0.5, 0.1));
  w.set_wall_law(0, 0, linear_law(1e3, 0.5, 0.1));  // floor: frictional
  w.set_wall_law(1, 0, linear_law(1e3, 0.0, 0.0));  // cylinder: frictionless, so no Janssen arching
  const double rc = 0.008;
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  w.walls.push_back(walls::make_wall("cylinder", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, rc}, 1));
  // A lid far above the bed, moving up: it never touches a sphere.
  const Vec3 lid_velocity{0.003, -0.002, 0.1};
  w.walls.push_back(walls::make_wall("lid", walls::Plane{{0, 0, 0.06}, {0, 0, -1}}));
  w.walls.back().velocity = lid_velocity;
  w.walls.back().pivot = {0, 0, 0.06};
  Rng rng(99);
  particles::InsertRequest req;
  req.region = particles::CylinderRegion{{0, 0, 0}, rc, 0.0, 0.04};
  req.sizes = particles::Monodisperse{0.001};
  req.count = 300;
  req.density = 2500;
  particles::insert_random(w.particles, req, rng);
  w.dt = sim::recommended_time_step(w, 0.2);

  const double weight = w.particles.total_mass() * kG;
  const double ref_energy = w.particles.mass[0] * kG * 0.001;  // m g r of one sphere
  // Settle until a block of kAverage steps stays at rest (the bed's last rattles end at a step
  // that depends on the rounding of the build, e.g. FMA in a native build), at most kMaxBlocks.
  constexpr int kAverage = 1000, kMaxBlocks = 60;
  Vec3 floor_force{}, cylinder_force{};
  double max_ke = 0.0;
  for (int block = 0; block < kMaxBlocks; ++block) {
    floor_force = cylinder_force = {};
    max_ke = 0.0;
    for (int s = 0; s < kAverage; ++s) {
      sim::step(w);
      floor_force += w.walls[0].force / kAverage;
      cylinder_force += w.walls[1].force / kAverage;
      max_ke = std::max(max_ke, w.particles.kinetic_energy());
    }
    if (block >= 14 && max_ke < 1e-2 * ref_energy) break;
  }
  std::printf(
      "bed of 300: weight %.6e N, floor force z %.6e N (rel. error %.2e), cylinder axial "
      "%.3e N, max KE %.3e J (m g r = %.3e J), %ld steps of %.3e s\n",
      weight, floor_force.z, (-floor_force.z - weight) / weight, cylinder_force.z, max_ke,
      ref_energy, static_cast<long>(w.step_count), w.dt);
  // At rest: the kinetic energy of the whole bed is a small fraction of one sphere's m g r.
  EXPECT_LT(max_ke, 1e-2 * ref_energy);
  // The particles push the floor down with their whole weight.
  EXPECT_NEAR(-floor_force.z, weight, 0.01 * weight);
  // A frictionless cylinder takes no axial load.
  EXPECT_LT(std::abs(cylinder_force.z), 1e-3 * weight);
  // Sideways, a bed at rest may lock in a friction force against the floor (about 1.6 % of the
  // weight here); the cylinder must then push back by as much: horizontal equilibrium.
  EXPECT_NEAR(floor_force.x + cylinder_force.x, 0.0, 1e-3 * weight);
  EXPECT_NEAR(floor_force.y + cylinder_force.y, 0.0, 1e-3 * weight);
  // All inside: above the floor (less a small overlap), inside the cylinder.
  for (std::size_t i = 0; i < w.particles.size(); ++i) {
    EXPECT_GT(w.particles.x[i].z, 0.001 * 0.9);
    EXPECT_LT(std::hypot(w.particles.x[i].x, w.particles.x[i].y), rc - 0.001 * 0.9);
  }
  // The lid moved v t, and its plane moved with it.
  const double t = w.time;
  const Vec3 expected = lid_velocity * t;
  EXPECT_NEAR(w.walls[2].displacement.x, expected.x, 1e-12);
  EXPECT_NEAR(w.walls[2].displacement.y, expected.y, 1e-12);
  EXPECT_NEAR(w.walls[2].displacement.z, expected.z, 1e-12);
  EXPECT_NEAR(t, static_cast<double>(w.step_count) * w.dt, 1e-12);
  const auto& lid = std::get<walls::Plane>(w.walls[2].shape);
  EXPECT_NEAR(lid.point.z, 0.06 + expected.z, 1e-12);
  EXPECT_NEAR(w.walls[2].pivot.z, 0.06 + expected.z, 1e-12);
  EXPECT_EQ(norm2(w.walls[2].force), 0.0);
  EXPECT_NEAR(w.walls[0].displacement.x, 0.0, 0.0);
}

TEST(SimWalls, RotatingFloorReportsTorqueAboutItsPivot) {
  // One sphere resting at x = d on a floor that spins about the z axis through the origin: the
  // floor slides under it at omega d in +y, friction drags the sphere along and the sphere holds
  // the floor back, a torque -d mu m g about z; its weight gives +d m g about y.
  sim::World w;
  w.gravity = {0, 0, -kG};
  const double kn = 1e3, mu = 0.5, r = 0.001, d = 0.01;
  w.set_pair_law(0, 0, linear_law(kn, mu, 0.0));
  w.set_wall_law(0, 0, linear_law(kn, mu, 0.0));
  const auto i = w.particles.add_sphere({d, 0, 0}, r, 2500, 0);
  const double m = w.particles.mass[i];
  w.particles.x[i].z = r - m * kG / kn;  // at its equilibrium overlap
  w.walls.push_back(walls::make_wall("turntable", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  w.walls.back().omega = {0, 0, 2.0};  // pivot: the origin
  w.dt = sim::recommended_time_step(w, 0.2);
  sim::run(w, 20);
  const auto& wall = w.walls[0];
  const Vec3 x = w.particles.x[i];
  const Vec3 contact{x.x, x.y, 0.0};
  std::printf("turntable: force (%.4e, %.4e, %.4e) N, torque (%.4e, %.4e, %.4e) N m\n",
              wall.force.x, wall.force.y, wall.force.z, wall.torque.x, wall.torque.y,
              wall.torque.z);
  // The reported torque is that of the reported force applied at the contact point.
  const Vec3 expected = cross(contact - wall.pivot, wall.force);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(wall.torque[k], expected[k], 1e-9 * m * kG * d) << k;
  // Its numbers: weight at lever d about y; sliding friction mu m g at lever d against the spin.
  EXPECT_NEAR(wall.force.z, -m * kG, 0.01 * m * kG);
  EXPECT_NEAR(wall.torque.y, d * m * kG, 0.01 * d * m * kG);
  EXPECT_NEAR(wall.torque.z, -d * mu * m * kG, 0.02 * d * mu * m * kG);
  EXPECT_GT(w.particles.v[i].y, 0.0);  // dragged along with the floor's surface
  // The turntable has turned by omega t and its pivot has not moved.
  EXPECT_NEAR(norm(wall.pivot), 0.0, 0.0);
  EXPECT_NEAR(norm(wall.displacement), 0.0, 0.0);
}

}  // namespace
}  // namespace demcal
