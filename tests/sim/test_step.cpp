// The step pipeline on the simplest motion: free fall under gravity is integrated exactly by
// velocity Verlet (constant force), whether or not the caller prepared the world first, and a
// particle added between steps falls exactly too. A law changed during a run keeps the contact
// history when only its parameters change, and starts it afresh when its models change.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/error.hpp"
#include "core/sim/health.hpp"
#include "core/sim/step.hpp"
#include "core/walls/mesh.hpp"

namespace demcal {
namespace {

sim::World falling_sphere() {
  sim::World w;
  w.gravity = {0, 0, -9.81};
  contact::ContactLawSpec s;
  s.normal = {"linear", {{"kn", 1e3}}};
  s.tangential = {"history", {{"mu_s", 0.5}}};
  w.set_pair_law(0, 0, contact::ContactLaw::from_spec(s, "law"));
  w.particles.add_sphere({0, 0, 1.0}, 0.001, 2500, 0);
  w.particles.v[0] = {0.1, 0, 0};
  w.dt = 1e-5;
  return w;
}

void expect_free_fall(const sim::World& w, std::size_t i, const Vec3& x0, const Vec3& v0,
                      double t) {
  const Vec3 x = x0 + v0 * t + w.gravity * (0.5 * t * t);
  const Vec3 v = v0 + w.gravity * t;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(w.particles.x[i][k], x[k], 1e-12) << "x" << k;
    EXPECT_NEAR(w.particles.v[i][k], v[k], 1e-12) << "v" << k;
  }
}

TEST(SimStep, FreeFallIsExact) {
  sim::World w = falling_sphere();
  sim::run(w, 1000);
  expect_free_fall(w, 0, {0, 0, 1.0}, {0.1, 0, 0}, 1000 * w.dt);
}

TEST(SimStep, FreeFallIsExactAfterAnExplicitPrepare) {
  sim::World w = falling_sphere();
  w.prepare();  // World::prepare() is public: checking a world before running must not change it
  sim::run(w, 1000);
  expect_free_fall(w, 0, {0, 0, 1.0}, {0.1, 0, 0}, 1000 * w.dt);
}

TEST(SimStep, ParticleAddedBetweenStepsFallsExactly) {
  sim::World w = falling_sphere();
  sim::run(w, 100);
  const std::size_t j = w.particles.add_sphere({0.5, 0, 1.0}, 0.001, 2500, 0);
  const double t_add = w.time;
  sim::run(w, 500);
  expect_free_fall(w, 0, {0, 0, 1.0}, {0.1, 0, 0}, 600 * w.dt);
  expect_free_fall(w, j, {0.5, 0, 1.0}, {}, w.time - t_add);
}

TEST(SimStep, WallAddedBetweenStepsIsPickedUp) {
  sim::World w = falling_sphere();
  w.set_wall_law(0, 0, w.pair_law(0, 0));
  sim::run(w, 100);
  // A floor appears 0.1 mm into the sphere: the next step must see it (and not index past the
  // per-wall history, which has no row for it yet).
  walls::Wall floor;
  floor.name = "floor";
  floor.shape = walls::Plane{{0, 0, w.particles.x[0].z - 0.0009}, {0, 0, 1}};
  w.walls.push_back(floor);
  sim::step(w);
  ASSERT_EQ(w.wall_history.size(), 1u);
  const double overlap =
      0.001 - (w.particles.x[0].z - std::get<walls::Plane>(w.walls[0].shape).point.z);
  EXPECT_GT(overlap, 0.0);
  EXPECT_NEAR(w.walls[0].force.z, -1e3 * overlap, 0.05 * 1e3 * overlap);
}

}  // namespace
}  // namespace demcal

namespace demcal {
namespace {

contact::ContactLaw sliding_law(const std::string& cohesion, double d_max) {
  contact::ContactLawSpec s;
  s.normal = {"linear", {{"kn", 1e3}}};
  s.tangential = {"history", {{"mu_s", 0.5}}};
  if (cohesion != "none") s.cohesion = {cohesion, {{"hamaker", 1e-19}, {"d_max", d_max}}};
  return contact::ContactLaw::from_spec(s, "law");
}

/// Two touching spheres sheared against each other for a few steps: their tangential spring
/// holds a history.
sim::World sheared_pair(const contact::ContactLaw& law) {
  sim::World w;
  w.gravity = {};
  w.set_pair_law(0, 0, law);
  w.particles.add_sphere({0, 0, 0}, 0.001, 2500, 0);
  w.particles.add_sphere({0.00199, 0, 0}, 0.001, 2500, 0);
  w.particles.v[1] = {0, 0.01, 0};
  w.dt = 1e-6;
  sim::run(w, 50);
  return w;
}

double history_norm(const sim::World& w) {
  double sum = 0.0;
  for (double h : w.pair_history) sum += h * h;
  return std::sqrt(sum);
}

TEST(SimStep, ChangedLawOfTheSameModelsKeepsTheContactHistory) {
  sim::World w = sheared_pair(sliding_law("van_der_waals", 1e-7));
  ASSERT_GT(history_norm(w), 0.0);
  const auto before = w.pair_history;
  const auto shorter = sliding_law("van_der_waals", 4.04e-10);
  w.change_pair_law(0, 0, shorter);
  EXPECT_EQ(w.pair_history, before);
  EXPECT_DOUBLE_EQ(w.pair_law(0, 0).range(), shorter.range());
  EXPECT_TRUE(w.prepared());
}

TEST(SimStep, ChangedWallLawOfTheSameModelsKeepsEveryContactHistory) {
  // The two spheres sheared against each other also slide along a floor: a stiffer floor law of
  // the same models keeps the floor contacts' and the pair's history, and acts at the next step.
  sim::World w = sheared_pair(sliding_law("none", 0.0));
  w.set_wall_law(0, 0, sliding_law("none", 0.0));
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, -0.00099}, {0, 0, 1}}));
  sim::run(w, 50);
  ASSERT_GT(history_norm(w), 0.0);
  const auto pairs = w.pair_history;
  const auto walls = w.wall_history;
  sim::World unchanged = w;
  contact::ContactLawSpec stiff;
  stiff.normal = {"linear", {{"kn", 3e3}}};
  stiff.tangential = {"history", {{"mu_s", 0.5}}};
  w.change_wall_law(0, 0, contact::ContactLaw::from_spec(stiff, "law"));
  EXPECT_TRUE(w.prepared());
  EXPECT_EQ(w.pair_history, pairs);
  EXPECT_EQ(w.wall_history, walls);
  sim::step(w);
  sim::step(unchanged);
  EXPECT_NEAR(w.walls[0].force.z, 3.0 * unchanged.walls[0].force.z,
              1e-6 * std::abs(unchanged.walls[0].force.z));  // pushed three times as hard
  // A law of other models starts the history afresh, as set_wall_law.
  w.change_wall_law(0, 0, sliding_law("van_der_waals", 1e-7));
  EXPECT_FALSE(w.prepared());
}

TEST(SimStep, ChangedLawOfOtherModelsStartsTheContactHistoryAfresh) {
  sim::World w = sheared_pair(sliding_law("van_der_waals", 1e-7));
  const double sheared = history_norm(w);  // 50 steps of sliding
  w.change_pair_law(0, 0, sliding_law("none", 0.0));
  EXPECT_FALSE(w.prepared());
  sim::run(w, 1);
  EXPECT_LT(history_norm(w), 0.1 * sheared);  // one step's worth
}

TEST(SimHealth, AnEscapedParticleIsNamedWithItsVelocityAndTheWallsItTouches) {
  // A particle above the volume's top (z <= 0), placed three times: pressed into a vertical plane
  // wall (the vessel a particle slides up) and a mesh quad above it, 0.1 and 0.3 mm short of
  // both, and against the plane alone.
  sim::World w = falling_sphere();
  w.walls.push_back(walls::make_wall("vessel", walls::Plane{{0, 0, 0}, {1, 0, 0}}));
  w.walls.push_back(walls::make_wall(
      "lid", walls::make_quad({-0.01, -0.01, 0.0112}, {0.02, 0, 0}, {0, 0.02, 0})));
  sim::HealthLimits limits;
  limits.hi = {1.0, 1.0, 0.0};
  auto message = [&](const Vec3& x, const Vec3& v) {
    w.particles.x[0] = x;
    w.particles.v[0] = v;
    try {
      sim::check_health(w, limits);
    } catch (const SimulationFailure& f) {
      EXPECT_EQ(f.reason(), SimulationFailure::Reason::kEscaped);
      return std::string(f.what());
    }
    ADD_FAILURE() << "no escape at z = " << x.z;
    return std::string();
  };
  const std::string both = message({0.0009, 0, 0.0105}, {0.3, -1.8, 0.5});
  EXPECT_NE(both.find("velocity 0.3 -1.8 0.5 m/s, touching wall 'vessel', 'lid')"),
            std::string::npos)
      << both;
  // 0.1 mm from the plane and 0.3 mm below the quad: a gap is not a touch.
  const std::string gap = message({0.0011, 0, 0.0099}, {0, 0, 1});
  EXPECT_NE(gap.find("touching no wall)"), std::string::npos) << gap;
  const std::string vessel = message({0.0005, 0, 0.005}, {0, 0, 1});
  EXPECT_NE(vessel.find("touching wall 'vessel')"), std::string::npos) << vessel;
}

}  // namespace
}  // namespace demcal
