// The time-step bound of a world: the Rayleigh time for Hertz laws (seed 000 eq. 1),
// sqrt(m/k) for linear and Luding laws (seed 001 eq. 14), and a step above it is an error that
// names both numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "core/common/error.hpp"
#include "core/particles/clump_shape.hpp"
#include "core/sim/step.hpp"
#include "core/sim/time_step.hpp"

namespace demcal {
namespace {

contact::ContactLaw law(contact::SlotSpec normal) {
  contact::ContactLawSpec s;
  s.normal = std::move(normal);
  s.tangential = {"history", {{"mu_s", 0.5}}};
  return contact::ContactLaw::from_spec(s, "law");
}

/// Two resting spheres (radii 1 mm and 2 mm, density 2500) above a plane floor.
sim::World two_spheres(const contact::ContactLaw& pair, const contact::ContactLaw& wall) {
  sim::World w;
  w.set_pair_law(0, 0, pair);
  w.set_wall_law(0, 0, wall);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  w.particles.add_sphere({0, 0, 0.01}, 0.001, 2500, 0);
  w.particles.add_sphere({0.01, 0, 0.01}, 0.002, 2500, 0);
  return w;
}

std::string g4(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

TEST(SimTimeStep, HertzBoundIsTheRayleighTimeOfTheSmallestSphere) {
  const double y = 1e7, nu = 0.3, rho = 2500, r = 0.001;
  const auto hertz = law({"hertz", {{"youngs_modulus", y}, {"poisson_ratio", nu}}});
  const sim::World w = two_spheres(hertz, hertz);
  // Seed 000 eq. 1: T_R = pi R sqrt(rho / G) / (0.163 nu + 0.8766), G = Y / (2 (1 + nu)).
  const double g = y / (2.0 * (1.0 + nu));
  const double expected = M_PI * r * std::sqrt(rho / g) / (0.163 * nu + 0.8766);
  const auto limit = sim::critical_time_step(w);
  EXPECT_NEAR(limit.critical, expected, 1e-12 * expected);
  EXPECT_NEAR(limit.critical, 8.6543e-5, 1e-9);  // the number itself, for this Y, nu, rho, R
  EXPECT_NE(limit.basis.find("Rayleigh"), std::string::npos) << limit.basis;
  EXPECT_NEAR(sim::recommended_time_step(w, 0.2), 0.2 * expected, 1e-12 * expected);
}

TEST(SimTimeStep, ClumpBoundUsesTheBodysEffectiveMassAtTheMember) {
  const double y = 1e7, nu = 0.3, rho = 2500, r = 0.001;
  const auto hertz = law({"hertz", {{"youngs_modulus", y}, {"poisson_ratio", nu}}});
  sim::World w;
  w.set_pair_law(0, 0, hertz);
  particles::ShapeSpec rod;
  rod.kind = particles::ShapeKind::kRod;
  rod.aspect_ratio = 2.0;
  w.particles.add_clump({0, 0, 0.01}, Quat{}, particles::make_template(rod), r, rho, 0);
  const auto& p = w.particles;
  const auto& c = p.clumps;
  ASSERT_GE(p.size(), 3u);
  // Brute force over directions n: the smallest 1 / (1/M + (a x n) . I^-1 (a x n)) of any member.
  double m_eff = c.mass[0];
  std::size_t worst = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int t = 0; t <= 180; ++t)
      for (int f = 0; f < 360; ++f) {
        const double th = t * M_PI / 180, ph = f * M_PI / 180;
        const Vec3 n{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
        const Vec3 u = cross(p.body_offset[i], n);
        const Vec3& in = c.inertia[0];
        const double m =
            1.0 / (1.0 / c.mass[0] + u.x * u.x / in.x + u.y * u.y / in.y + u.z * u.z / in.z);
        if (m < m_eff) m_eff = m, worst = i;
      }
  // The body moves as a whole: more mass than the member's share, less than the body's.
  EXPECT_GT(m_eff, p.mass[worst]);
  EXPECT_LT(m_eff, c.mass[0]);
  const double rm = p.radius[worst];
  const double g = y / (2.0 * (1.0 + nu));
  const double expected =
      M_PI * rm * std::sqrt(m_eff / (4.0 / 3.0 * M_PI * rm * rm * rm) / g) / (0.163 * nu + 0.8766);
  EXPECT_NEAR(sim::critical_time_step(w).critical, expected, 1e-3 * expected);
  std::printf("rod AR 2: member radius %.3g r, member mass share %.3g M, effective mass %.3g M\n",
              rm / r, p.mass[worst] / c.mass[0], m_eff / c.mass[0]);
}

TEST(SimTimeStep, LinearBoundIsSqrtOfLightestMassOverStiffestSpring) {
  const auto pair = law({"linear", {{"kn", 1e4}}});
  const auto wall = law({"linear", {{"kn", 3e4}}});  // seed 000/001 use stiffer walls
  const sim::World w = two_spheres(pair, wall);
  const double m_light = 2500 * 4.0 / 3.0 * M_PI * 1e-9;
  const double expected = std::sqrt(m_light / 3e4);  // seed 001 eq. 14
  const auto limit = sim::critical_time_step(w);
  EXPECT_NEAR(limit.critical, expected, 1e-12 * expected);
  EXPECT_NE(limit.basis.find("sqrt(m/k)"), std::string::npos) << limit.basis;
  EXPECT_NE(limit.basis.find("wall"), std::string::npos) << limit.basis;
}

TEST(SimTimeStep, LudingBoundUsesTheUnloadingStiffness) {
  const auto luding = law({"luding", {{"k1", 1e4}, {"k2_ratio", 5.0}}});
  const sim::World w = two_spheres(luding, luding);
  const double m_light = 2500 * 4.0 / 3.0 * M_PI * 1e-9;
  EXPECT_NEAR(sim::critical_time_step(w).critical, std::sqrt(m_light / 5e4),
              1e-12 * std::sqrt(m_light / 5e4));
}

TEST(SimTimeStep, LudingReachedStiffnessIsTheUnloadingSlopeOfEq5) {
  // Seed 000 eq. 4-5: k2*(delta_max) = k1 + (k2 - k1) delta_max / delta*_max,
  // delta*_max = k2 / (k2 - k1) phi_f r_eff; beyond it k2.
  const double k1 = 1e4, f1 = 5.0, phi_f = 0.05, r_eff = 1e-3;
  const auto luding =
      law({"luding", {{"k1", k1}, {"k2_ratio", f1}, {"phi_f", phi_f}, {"kc_ratio", 0.5}}});
  const double limit = f1 / (f1 - 1.0) * phi_f * r_eff;
  EXPECT_DOUBLE_EQ(luding.reached_stiffness(r_eff, 0.0), k1);
  EXPECT_DOUBLE_EQ(luding.reached_stiffness(r_eff, 0.5 * limit), k1 + 0.5 * (f1 - 1.0) * k1);
  EXPECT_DOUBLE_EQ(luding.reached_stiffness(r_eff, 3.0 * limit), f1 * k1);
  EXPECT_DOUBLE_EQ(luding.max_stiffness(r_eff), f1 * k1);
  EXPECT_TRUE(luding.keeps_reached_overlap());
  // The slope the force law itself shows on unloading from delta_max = limit / 4.
  const auto& model = std::get<contact::normal::Luding>(luding.normal);
  contact::PairInput in;
  in.r_star = 0.5 * r_eff;
  in.m_star = 1e-6;
  double history[1] = {0.25 * limit};
  in.delta = 0.2 * limit;
  const double f_a = model.force(in, history).fn;
  in.delta = 0.15 * limit;
  const double f_b = model.force(in, history).fn;
  EXPECT_NEAR((f_a - f_b) / (0.05 * limit), luding.reached_stiffness(r_eff, 0.25 * limit),
              1e-9 * k1);
  // An adhesive branch steeper than k2 bounds the step itself.
  const auto sticky = law({"luding", {{"k1", k1}, {"k2_ratio", f1}, {"kc_ratio", 8.0}}});
  EXPECT_DOUBLE_EQ(sticky.max_stiffness(r_eff), 8.0 * k1);
  EXPECT_DOUBLE_EQ(sticky.reached_stiffness(r_eff, 0.0), 8.0 * k1);
  EXPECT_FALSE(law({"linear", {{"kn", 1e4}}}).keeps_reached_overlap());
}

TEST(SimTimeStep, AdaptedStepFollowsTheDeepestOverlapAndStaysStable) {
  const double k1 = 1e4, f1 = 16.0, phi_f = 0.05;
  const auto luding = law({"luding", {{"k1", k1}, {"k2_ratio", f1}, {"phi_f", phi_f}}});
  sim::World w = two_spheres(luding, luding);
  w.dt = 1e-6;
  w.prepare();
  const double m_light = 2500 * 4.0 / 3.0 * M_PI * 1e-9;
  // No contact has pressed yet: the bound is the loading stiffness k1.
  EXPECT_NEAR(sim::reached_time_step(w).critical, std::sqrt(m_light / k1),
              1e-12 * std::sqrt(m_light / k1));
  EXPECT_NEAR(sim::critical_time_step(w).critical, std::sqrt(m_light / (f1 * k1)),
              1e-12 * std::sqrt(m_light / (f1 * k1)));
  // A step of 0.2 of the reached bound is 0.8 of the law maximum: capped at kStableFraction.
  EXPECT_NEAR(sim::adapted_time_step(w, 0.2),
              sim::kStableFraction * sim::critical_time_step(w).critical, 1e-15);
  EXPECT_NEAR(sim::adapted_time_step(w, 0.1), 0.1 * std::sqrt(m_light / k1), 1e-15);
  // The floor contact of the small sphere has pressed to delta_max: bounded at twice that.
  ASSERT_EQ(w.wall_history.size(), 1u);
  const double delta = 0.01 * 1e-3;
  w.wall_history[0][0] = delta;
  const double k_expected = luding.reached_stiffness(2e-3, 2.0 * delta);
  EXPECT_GT(k_expected, k1);
  EXPECT_NEAR(sim::reached_time_step(w).critical, std::sqrt(m_light / k_expected),
              1e-12 * std::sqrt(m_light / k_expected));
  EXPECT_NE(sim::reached_time_step(w).basis.find("wall 'floor'"), std::string::npos);
}

TEST(SimTimeStep, AdaptiveStepsSettleABedAsTheFixedStepDoes) {
  // Twenty Luding spheres dropped on a floor: with the step re-tuned to the overlaps reached, the
  // bed comes to rest at the height the law-maximum step gives, in fewer steps (the drop presses
  // the contacts well into their plastic range, k2* near k2: the gain is less than f1^(1/2)).
  const auto luding =
      law({"luding", {{"k1", 200.0}, {"k2_ratio", 16.0}, {"phi_f", 0.05}, {"restitution", 0.3}}});
  auto bed = [&](bool adaptive) {
    sim::World w;
    w.set_pair_law(0, 0, luding);
    w.set_wall_law(0, 0, luding);
    w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
    w.walls.push_back(walls::make_wall("tube", walls::Cylinder{{0, 0, 0}, {0, 0, 1}, 2.6e-3}));
    for (int k = 0; k < 20; ++k)
      w.particles.add_sphere(
          {(k % 2) * 2.1e-3 - 1.05e-3, ((k / 2) % 2) * 2.1e-3 - 1.05e-3, 1.2e-3 + 2.2e-3 * (k / 4)},
          1e-3, 2500, 0);
    w.dt = sim::recommended_time_step(w, 0.2);
    if (adaptive) w.adaptive_safety = 0.2;
    while (w.time < 0.3) sim::step(w);
    double top = 0.0;
    for (std::size_t i = 0; i < w.particles.size(); ++i)
      top = std::max(top, w.particles.x[i].z + w.particles.radius[i]);
    return std::pair{top, w.step_count};
  };
  const auto [fixed_top, fixed_steps] = bed(false);
  const auto [adapted_top, adapted_steps] = bed(true);
  EXPECT_NEAR(adapted_top, fixed_top, 0.05 * fixed_top);
  EXPECT_LT(adapted_steps, 0.8 * static_cast<double>(fixed_steps));
  std::printf("bed top: fixed %.5g m in %lld steps, adapted %.5g m in %lld steps\n", fixed_top,
              static_cast<long long>(fixed_steps), adapted_top,
              static_cast<long long>(adapted_steps));
}

TEST(SimTimeStep, StepAboveTheLimitThrowsNamingBothNumbers) {
  const auto pair = law({"linear", {{"kn", 1e4}, {"damping_ratio", 0.3}}});
  sim::World w = two_spheres(pair, pair);
  const double critical = sim::critical_time_step(w).critical;
  w.dt = 1.01 * critical;
  try {
    sim::step(w);
    FAIL() << "a time step above the stability limit was accepted";
  } catch (const SimulationFailure& e) {
    EXPECT_EQ(e.reason(), SimulationFailure::Reason::kUnstableTimeStep);
    const std::string msg = e.what();
    EXPECT_NE(msg.find(g4(w.dt)), std::string::npos) << msg;
    EXPECT_NE(msg.find(g4(critical)), std::string::npos) << msg;
  }
  EXPECT_EQ(w.step_count, 0);

  w.dt = 0.0;
  EXPECT_THROW(sim::step(w), SimulationFailure);

  // Just below the limit the world runs.
  w.dt = 0.99 * critical;
  EXPECT_NO_THROW(sim::run(w, 10));
  EXPECT_EQ(w.step_count, 10);
}

}  // namespace
}  // namespace demcal
