// The per-wall candidate lists (walls/reach.hpp, World::wall_reach): the test that lists a
// particle never refuses one the exact geometry accepts after a relative movement below the
// margin, the bound on a wall's movement is never below the movement, and a world whose walls
// visit only their listed particles gives the same forces as one that tests every particle.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/rng.hpp"
#include "core/sim/forces.hpp"
#include "core/sim/step.hpp"
#include "core/walls/reach.hpp"

namespace demcal::walls {
namespace {

Vec3 random_unit(Rng& rng) {
  const double z = rng.uniform(-1.0, 1.0), a = rng.uniform(0.0, 2.0 * M_PI);
  const double s = std::sqrt(1.0 - z * z);
  return {s * std::cos(a), s * std::sin(a), z};
}

Vec3 random_in_ball(Rng& rng, double radius) {
  return random_unit(rng) * (radius * std::cbrt(rng.uniform()));
}

/// True when the exact geometry accepts the sphere (primitive_geometry or mesh_contacts).
bool touches(const Shape& shape, const Vec3& x, double r, double range) {
  WallGeometry g;
  return wall_geometry(shape, x, r, range, g);
}

/// The shape moved rigidly: translated by `shift` and turned by `angle` about `axis` through
/// its reference point (as walls::advance moves a wall).
Shape moved(const Shape& shape, const Vec3& shift, const Vec3& axis, double angle) {
  Wall w = make_wall("w", shape);
  w.pivot = reference_point(shape);
  w.velocity = shift;
  w.omega = axis * angle;
  advance(w, 1.0);
  return w.shape;
}

// Spheres near each kind of wall, the wall and the sphere then moved by random amounts whose
// sum stays below the margin (as bounded by surface_shift): a sphere the exact geometry accepts
// afterwards was listed before.
TEST(WallReach, AListedParticleIsNeverMissedAfterAMoveBelowTheMargin) {
  const std::vector<Shape> shapes = {
      Plane{{0, 0, 0}, {0, 0, 1}},
      Cylinder{{0, 0, 0}, {0, 0, 1}, 0.01, -0.002, 0.02},
      Disk{{0, 0, 0.01}, {0, 0, -1}, 0.008},
      make_vane_head({0, 0, 0.01}, {0, 0, 1}, 0.008, 0.004, 4),
  };
  Rng rng(7);
  const double r = 1e-3, range = 2e-4, margin = 3e-4;
  int accepted_after = 0;
  for (const Shape& shape : shapes) {
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec3 x = Vec3{0, 0, 0.008} + random_in_ball(rng, 0.014);
      const bool listed = ReachTest(shape, range, margin).may_reach(x, r);
      // The wall moves, then the sphere moves by what is left of the margin.
      const Shape now = moved(shape, random_in_ball(rng, 0.3 * margin), random_unit(rng),
                              rng.uniform(0.0, 0.003));
      const double extent = norm(x - reference_point(shape)) + 2.0 * margin;
      const double wall_move = surface_shift(shape, now, extent);
      if (wall_move >= margin) continue;
      const Vec3 x_now = x + random_unit(rng) * (rng.uniform() * (margin - wall_move));
      if (!touches(now, x_now, r, range)) continue;
      ++accepted_after;
      EXPECT_TRUE(listed) << "shape " << shape.index() << ", trial " << trial;
    }
  }
  EXPECT_GT(accepted_after, 1000) << "the trials must meet the walls";
}

// For every point within `extent` of the cylinder's axis point, its distance from the surface
// (R - rho) and its axial coordinate change by no more than the bound when the cylinder is moved
// and turned (a turn about its own axis moves the surface's points, not the gaps).
TEST(WallReach, TheShiftBoundsTheChangeOfEveryGap) {
  Rng rng(11);
  const Cylinder c{{0.001, 0, 0}, {0, 0, 1}, 0.01, 0.0, 0.02};
  auto rho_and_s = [](const Cylinder& cyl, const Vec3& x) {
    const Vec3 rel = x - cyl.point;
    const double s = dot(rel, cyl.axis);
    return std::pair{norm(rel - cyl.axis * s), s};
  };
  const double extent = 0.03;
  for (int trial = 0; trial < 2000; ++trial) {
    const Shape now = moved(c, random_in_ball(rng, 1e-3), random_unit(rng), rng.uniform(0.0, 0.05));
    const Cylinder& d = std::get<Cylinder>(now);
    const double bound = surface_shift(c, now, extent);
    const Vec3 x = c.point + random_in_ball(rng, extent);
    const auto [rho0, s0] = rho_and_s(c, x);
    const auto [rho1, s1] = rho_and_s(d, x);
    EXPECT_LE(std::abs(rho1 - rho0), bound + 1e-15) << trial;
    EXPECT_LE(std::abs(s1 - s0), bound + 1e-15) << trial;
  }
  EXPECT_EQ(surface_shift(c, c, 1.0), 0.0);
  EXPECT_TRUE(std::isinf(surface_shift(c, Plane{{0, 0, 0}, {0, 0, 1}}, 1.0)));
  EXPECT_TRUE(std::isinf(surface_shift(make_disk({0, 0, 0}, {0, 0, 1}, 0.01, 8),
                                       make_disk({0, 0, 0}, {0, 0, 1}, 0.01, 12), 1.0)));
}

}  // namespace
}  // namespace demcal::walls

namespace demcal::sim {
namespace {

/// A box of particles on a floor under a piston disk, Hertz spheres.
World piston_world() {
  World w;
  w.dt = 2e-6;
  w.gravity = {0, 0, -9.81};
  contact::ContactLawSpec spec;
  spec.normal = {"hertz", {{"youngs_modulus", 1e7}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  const auto law = contact::ContactLaw::from_spec(spec, "law");
  w.set_pair_law(0, 0, law);
  w.set_wall_law(0, 0, law);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 4; ++k)
        w.particles.add_sphere({0.002 * i + 1e-4 * k, 0.002 * j, 0.001 + 0.00199 * k}, 0.001,
                               2500.0, 0);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  w.walls.push_back(
      walls::make_wall("piston", walls::Disk{{0.005, 0.005, 0.0081}, {0, 0, -1}, 0.02}));
  return w;
}

// A wall the caller moves between steps (outside walls::advance, as a lab test may) is seen at
// the next force evaluation: its listed particles are listed again.
TEST(WallReach, AWallMovedBetweenStepsIsSeenAtTheNextStep) {
  World w = piston_world();
  for (int s = 0; s < 200; ++s) step(w);
  const double before = w.walls[1].force.z;
  auto& disk = std::get<walls::Disk>(w.walls[1].shape);
  disk.centre.z -= 0.0004;  // a jump of twice the skin into the top layer
  step(w);
  EXPECT_GT(w.walls[1].force.z, before + 1.0) << "the piston pressed into the top layer";
}

// The forces with the lists equal those of a world that lists every particle for every wall
// (a margin larger than the box): the same bits after many steps of a moving piston.
TEST(WallReach, ListsChangeNoForce) {
  World listed = piston_world();
  World everyone = piston_world();
  listed.walls[1].velocity = everyone.walls[1].velocity = {0, 0, -0.05};
  for (int s = 0; s < 3000; ++s) {
    step(listed);
    step(everyone);
    for (auto& reach : everyone.wall_reach) reach.near.resize(0);
    for (std::size_t k = 0; k < everyone.walls.size(); ++k)
      for (std::size_t i = 0; i < everyone.particles.size(); ++i)
        everyone.wall_reach[k].near.push_back(static_cast<int>(i));
  }
  for (std::size_t i = 0; i < listed.particles.size(); ++i) {
    EXPECT_EQ(listed.particles.x[i].z, everyone.particles.x[i].z) << i;
    EXPECT_EQ(listed.particles.v[i].x, everyone.particles.v[i].x) << i;
  }
  EXPECT_EQ(listed.walls[1].force.z, everyone.walls[1].force.z);
  EXPECT_GT(listed.walls[1].force.z, 0.0) << "the piston reached the bed";
}

}  // namespace
}  // namespace demcal::sim
