// The time-step bound of a world: the Rayleigh time for Hertz laws (seed 000 eq. 1),
// sqrt(m/k) for linear and Luding laws (seed 001 eq. 14), and a step above it is an error that
// names both numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <utility>

#include "core/common/error.hpp"
#include "core/particles/clump_shape.hpp"
#include "core/sim/forces.hpp"
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
  // The force law reports that slope as the stiffness in use, after updating delta_max.
  in.delta = 0.4 * limit;
  EXPECT_DOUBLE_EQ(model.force(in, history).k_step, luding.reached_stiffness(r_eff, 0.4 * limit));
}

TEST(SimTimeStep, ElasticLawsReportTheirTangentStiffness) {
  contact::PairInput in;
  in.r_star = 1e-3;
  in.m_star = 1e-6;
  in.delta = 1e-5;
  const auto hertz = law({"hertz", {{"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}}});
  const auto& h = std::get<contact::normal::Hertz>(hertz.normal);
  // d/d(delta) of 4/3 Y* sqrt(R*) delta^(3/2) = 2 Y* sqrt(R* delta), against a difference.
  const double eps = 1e-9;
  contact::PairInput up = in;
  up.delta += eps;
  const double slope = (h.force(up, nullptr).fn - h.force(in, nullptr).fn) / eps;
  EXPECT_NEAR(h.force(in, nullptr).k_step, slope, 1e-4 * slope);
  EXPECT_DOUBLE_EQ(h.force(in, nullptr).k_step, 2.0 * h.y_star * std::sqrt(1e-3 * 1e-5));
  const auto linear = law({"linear", {{"kn", 3e4}}});
  EXPECT_DOUBLE_EQ(std::get<contact::normal::Linear>(linear.normal).force(in, nullptr).k_step, 3e4);
}

TEST(SimTimeStep, AdaptedStepFollowsTheStiffestContactInUse) {
  const double k1 = 1e4, f1 = 16.0, phi_f = 0.05;
  const auto luding = law({"luding", {{"k1", k1}, {"k2_ratio", f1}, {"phi_f", phi_f}}});
  sim::World w = two_spheres(luding, luding);
  w.dt = 1e-6;
  w.prepare();
  const double m_light = 2500 * 4.0 / 3.0 * M_PI * 1e-9;
  // No contact yet: the bound of a fresh contact, at the loading stiffness k1.
  EXPECT_EQ(w.contact_rate2, 0.0);
  EXPECT_NEAR(sim::fresh_contact_time_step(w).critical, std::sqrt(m_light / k1),
              1e-12 * std::sqrt(m_light / k1));
  EXPECT_NEAR(sim::critical_time_step(w).critical, std::sqrt(m_light / (f1 * k1)),
              1e-12 * std::sqrt(m_light / (f1 * k1)));
  EXPECT_NEAR(sim::adapted_time_step(w, 0.2), 0.2 * std::sqrt(m_light / k1), 1e-15);
  // The small sphere pressed into the floor, its contact's delta_max deeper still: the step is
  // 0.2 sqrt(m / k2*(delta_max)), whichever branch the contact is on.
  const double delta = 0.018 * 1e-3, delta_max = 0.02 * 1e-3;  // on the unloading branch
  w.particles.x[0].z = 1e-3 - delta;
  w.prepare();
  w.wall_history[0][0] = delta_max;
  sim::compute_forces(w);
  const double k_in_use = luding.reached_stiffness(2e-3, delta_max);
  EXPECT_GT(k_in_use, k1);
  EXPECT_NEAR(w.contact_rate2, k_in_use / m_light, 1e-9 * k_in_use / m_light);
  EXPECT_NEAR(sim::adapted_time_step(w, 0.2), 0.2 * std::sqrt(m_light / k_in_use), 1e-15);
  EXPECT_NE(sim::fresh_contact_time_step(w).basis.find("sqrt(m/k)"), std::string::npos);
}

TEST(SimTimeStep, AHertzContactBoundsTheStepOnlyForStability) {
  // The Rayleigh time sets a Hertz step's accuracy (0.2 of it here); the tangent stiffness of a
  // contact pressed deep enough bounds it at 0.7 sqrt(m* / k), at once.
  const double y = 1e7, nu = 0.3;
  const auto hertz = law({"hertz", {{"youngs_modulus", y}, {"poisson_ratio", nu}}});
  sim::World w = two_spheres(hertz, hertz);
  w.dt = 1e-7;
  w.prepare();
  const double rayleigh = sim::fresh_contact_time_step(w).critical;
  EXPECT_NEAR(sim::adapted_time_step(w, 0.2), 0.2 * rayleigh, 1e-15);
  const double m_light = 2500 * 4.0 / 3.0 * M_PI * 1e-9;
  for (const double delta : {1e-7, 1e-4}) {
    w.particles.x[0].z = 1e-3 - delta;
    w.prepare();
    const auto& model = std::get<contact::normal::Hertz>(hertz.normal);
    const double k = 2.0 * model.y_star * std::sqrt(1e-3 * delta);  // R* = r at a wall
    EXPECT_EQ(w.contact_rate2, 0.0);
    EXPECT_NEAR(w.contact_stable_rate2, k / m_light, 1e-9 * k / m_light);
    EXPECT_NEAR(sim::adapted_time_step(w, 0.2),
                std::min(0.2 * rayleigh, sim::kStableFraction * std::sqrt(m_light / k)), 1e-15);
  }
  // Stability binds only for a coarse step: 10 % of the radius deep, 0.7 sqrt(m* / k) is 0.44
  // of the Rayleigh time, so at safety 0.2 the Rayleigh time sets the step, at 0.6 the contact.
  EXPECT_NEAR(sim::adapted_time_step(w, 0.2), 0.2 * rayleigh, 1e-15);
  EXPECT_LT(sim::adapted_time_step(w, 0.6), 0.5 * rayleigh);
}

TEST(SimTimeStep, StepShrinksAtOnceAndGrowsBackByBoundedSteps) {
  // A Luding sphere thrown onto a Luding floor (no gravity): its contact stiffens from k1
  // towards k2 as it presses in, and lets go on the rebound. At every step dt <= 0.2 sqrt(m / k)
  // of the stiffest contact of that step's forces (the shrink is immediate), dt never exceeds
  // 0.2 x the bound of a fresh contact, and it grows only at re-tuning steps, by at most 10 %.
  const double k1 = 1e4, f1 = 100.0;
  const auto luding =
      law({"luding", {{"k1", k1}, {"k2_ratio", f1}, {"phi_f", 0.01}, {"restitution", 0.5}}});
  sim::World w;
  w.gravity = {};
  w.set_pair_law(0, 0, luding);
  w.set_wall_law(0, 0, luding);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  w.particles.add_sphere({0, 0, 1.2e-3}, 1e-3, 2500, 0);
  w.particles.v[0] = {0, 0, -2.0};
  w.adaptive_safety = 0.2;
  w.dt = sim::adapted_time_step(w, 0.2);
  const double m = w.particles.mass[0];
  const double ceiling = 0.2 * std::sqrt(m / k1);
  double smallest = w.dt;
  int shrinks = 0;
  bool touched = false, left = false;
  for (int s = 0; s < 20000 && !left; ++s) {
    const double before = w.dt;
    sim::step(w);
    if (w.contact_rate2 > 0.0) {
      touched = true;
      EXPECT_LE(w.dt, (1.0 + 1e-12) * 0.2 / std::sqrt(w.contact_rate2)) << "step " << s;
    }
    EXPECT_LE(w.dt, (1.0 + 1e-12) * ceiling);
    if (w.dt < before) ++shrinks;
    if (w.dt > before) {
      EXPECT_EQ(w.step_count % sim::World::kRetuneSteps, 0);
      EXPECT_LE(w.dt, (1.0 + 1e-12) * sim::World::kStepGrowth * before);
    }
    smallest = std::min(smallest, w.dt);
    left = touched && w.contact_rate2 == 0.0;
  }
  ASSERT_TRUE(left);
  EXPECT_GT(w.particles.v[0].z, 0.0);
  // The contact reached its plastic limit (k2 = 100 k1): the step fell by more than half.
  EXPECT_LT(smallest, 0.5 * ceiling);
  EXPECT_GT(shrinks, 0);
  // In flight again it grows back, 10 % per re-tuning, to the fresh-contact bound.
  const double after_contact = w.dt;
  sim::run(w, 2 * sim::World::kRetuneSteps);
  EXPECT_GT(w.dt, after_contact);
  EXPECT_LE(w.dt,
            (1.0 + 1e-12) * sim::World::kStepGrowth * sim::World::kStepGrowth * after_contact);
  sim::run(w, 30 * sim::World::kRetuneSteps);
  EXPECT_NEAR(w.dt, ceiling, 1e-12 * ceiling);
}

TEST(SimTimeStep, CohesiveCollisionKeepsItsEnergyBalanceWithTheAdaptedStep) {
  // Two cohesive Luding spheres (kc = 0.05 k1, k2 = 5 k1, e = 0.65, van der Waals) collide
  // head on at 1 m/s. The kinetic energy left after the collision, with the step adapted at safety
  // 0.2, against a fixed step of 0.02 x the bound at the law's largest stiffness (ten times finer
  // than the adapted step ever is): within 0.2 % of the impact energy.
  contact::ContactLawSpec spec;
  spec.normal = {
      "luding",
      {{"k1", 1e3}, {"k2_ratio", 5.0}, {"kc_ratio", 0.05}, {"phi_f", 0.05}, {"restitution", 0.65}}};
  spec.cohesion = {"van_der_waals", {{"hamaker", 1e-19}, {"d_max", 1e-6}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  const auto cohesive = contact::ContactLaw::from_spec(spec, "law");
  auto collide = [&](bool adaptive) {
    sim::World w;
    w.gravity = {};
    w.set_pair_law(0, 0, cohesive);
    w.particles.add_sphere({0, 0, 0}, 1e-3, 2500, 0);
    w.particles.add_sphere({2.05e-3, 0, 0}, 1e-3, 2500, 0);
    w.particles.v[0] = {0.5, 0, 0};
    w.particles.v[1] = {-0.5, 0, 0};
    const double impact = w.particles.kinetic_energy();
    if (adaptive) {
      w.adaptive_safety = 0.2;
      w.dt = sim::adapted_time_step(w, 0.2);
    } else {
      w.dt = sim::recommended_time_step(w, 0.02);
    }
    while (w.time < 5e-3) sim::step(w);
    return std::tuple{w.particles.kinetic_energy() / impact, w.step_count,
                      w.particles.x[1].x - w.particles.x[0].x};
  };
  const auto [fixed_ratio, fixed_steps, fixed_gap] = collide(false);
  const auto [adapted_ratio, adapted_steps, adapted_gap] = collide(true);
  // Some energy is lost, some kept: the spheres separate.
  EXPECT_GT(fixed_ratio, 0.005);
  EXPECT_LT(fixed_ratio, 0.65 * 0.65);
  EXPECT_GT(fixed_gap, 2.05e-3);
  EXPECT_NEAR(adapted_ratio, fixed_ratio, 0.002);
  EXPECT_LT(adapted_steps, fixed_steps / 5);
  std::printf("kinetic energy kept: fixed %.5f (%lld steps), adapted %.5f (%lld steps)\n",
              fixed_ratio, static_cast<long long>(fixed_steps), adapted_ratio,
              static_cast<long long>(adapted_steps));
}

TEST(SimTimeStep, AdaptiveStepsSettleABedAsTheFixedStepDoes) {
  // Twenty Luding spheres dropped on a floor: with the step following the contacts in use, the
  // bed comes to rest at the height the law-maximum step gives, in fewer steps (the drop presses
  // the contacts well into their plastic range, k2* near k2: the gain is small, 15 %).
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
  EXPECT_LT(adapted_steps, 0.9 * static_cast<double>(fixed_steps));
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
