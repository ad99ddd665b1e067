// Rigid multisphere clumps in motion (seed 004 §2.2.2.1): torque-free rotation keeps the angular
// momentum and the rotational energy, a body spinning about a principal axis turns by omega t,
// members of one clump never push each other, a clump falls freely like a point mass, an elastic
// rod bounces off a floor keeping its energy (and a flat one without starting to turn), a rod at
// rest loads the floor with its weight, and contacts are counted between bodies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/integrate/rigid_body.hpp"
#include "core/metrics/bulk.hpp"
#include "core/particles/clump_shape.hpp"
#include "core/sim/step.hpp"
#include "core/sim/world.hpp"

namespace demcal {
namespace {

constexpr double kG = 9.81;
constexpr double kRadius = 0.01;    // volume-equivalent radius (m)
constexpr double kDensity = 1000;   // kg/m^3
constexpr double kStiffness = 1e3;  // N/m

contact::ContactLaw linear_law(double kn, double damping_ratio, double mu_s) {
  contact::ContactLawSpec s;
  s.normal = {"linear",
              {{"kn", kn},
               {"damping_ratio", damping_ratio},
               {"damp_approach_only", 0.0},
               {"clip_attraction", 0.0}}};
  s.tangential = {"history", {{"mu_s", mu_s}}};
  return contact::ContactLaw::from_spec(s, "law");
}

sim::World empty_world(const Vec3& gravity, double damping_ratio = 0.0, double mu_s = 0.0,
                       double kn = kStiffness) {
  sim::World w;
  w.gravity = gravity;
  const auto law = linear_law(kn, damping_ratio, mu_s);
  w.set_pair_law(0, 0, law);
  w.set_wall_law(0, 0, law);
  return w;
}

particles::ClumpTemplate shape(const std::string& kind, const std::map<std::string, double>& p) {
  return particles::make_template(particles::make_shape_spec(kind, p, "shape"));
}

/// A world for a lone body that touches nothing: soft laws, so the time step is set by the
/// rotation alone.
sim::World contact_free_world() {
  return empty_world({}, 0.0, 0.0, 1e-3);
}

/// L = R I R^T omega for body b.
Vec3 momentum_for(const particles::Clumps& c, std::size_t b, const Vec3& omega) {
  const Vec3 l = c.q[b].unrotate(omega);
  const Vec3& i = c.inertia[b];
  return c.q[b].rotate({i.x * l.x, i.y * l.y, i.z * l.z});
}

void set_spin(particles::ParticleStore& p, std::size_t b, const Vec3& omega) {
  p.clumps.omega[b] = omega;
  p.clumps.angular_momentum[b] = momentum_for(p.clumps, b, omega);
}

double rotational_energy(const particles::Clumps& c, std::size_t b) {
  return 0.5 * dot(integrate::body_angular_velocity(c, b), c.angular_momentum[b]);
}

/// 1/2 M v^2 + 1/2 omega . L - M g . x of body 0, plus 1/2 kn delta^2 of every member touching a
/// wall (computed here from the positions).
double body_energy(const sim::World& w) {
  const auto& c = w.particles.clumps;
  double e = 0.5 * c.mass[0] * norm2(c.v[0]) + rotational_energy(c, 0) -
             c.mass[0] * dot(w.gravity, c.x[0]);
  for (std::size_t i = 0; i < w.particles.size(); ++i)
    for (const auto& wall : w.walls) {
      walls::WallGeometry g;
      if (walls::wall_geometry(wall.shape, w.particles.x[i], w.particles.radius[i], 0.0, g) &&
          g.delta > 0.0)
        e += 0.5 * kStiffness * g.delta * g.delta;
    }
  return e;
}

TEST(SimClumps, TorqueFreeRotationKeepsAngularMomentumAndEnergy) {
  sim::World w = contact_free_world();
  const auto cluster = shape("cluster", {{"spheres", 5.0}, {"irregularity", 0.6}, {"seed", 1.0}});
  const auto b = w.particles.add_clump({0.1, 0.2, 0.3}, rotation_quat({0.4, -0.7, 0.2}), cluster,
                                       kRadius, kDensity, 0);
  const auto& c = w.particles.clumps;
  // Truly asymmetric, spinning off every principal axis (a tumbling body).
  ASSERT_GT(c.inertia[b].y / c.inertia[b].x, 1.05);
  ASSERT_GT(c.inertia[b].z / c.inertia[b].y, 1.05);
  const Vec3 omega0{3.0, -2.0, 4.0};
  set_spin(w.particles, b, omega0);
  w.dt = 0.01 / norm(omega0);
  const Vec3 l0 = c.angular_momentum[b];
  const double e0 = rotational_energy(c, b);
  const Vec3 x0 = c.x[b];
  double worst_e = 0.0, worst_l = 0.0, omega_change = 0.0;
  for (int s = 0; s < 20000; ++s) {
    sim::step(w);
    worst_e = std::max(worst_e, std::abs(rotational_energy(c, b) - e0) / e0);
    worst_l = std::max(worst_l, norm(c.angular_momentum[b] - l0) / norm(l0));
    omega_change = std::max(omega_change, norm(c.omega[b] - omega0) / norm(omega0));
  }
  std::printf("tumbling cluster: |L| drift %.2e, energy drift %.2e, omega changed by %.2f\n",
              worst_l, worst_e, omega_change);
  EXPECT_LT(worst_l, 1e-10);
  EXPECT_LT(worst_e, 1e-4);
  EXPECT_GT(omega_change, 0.1);  // it tumbles: omega is not conserved, L and E are
  EXPECT_NEAR(norm(c.x[b] - x0), 0.0, 1e-15);
  // Members rigidly attached: their distances to the centre stay those of the template.
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k)
    EXPECT_NEAR(norm(w.particles.x[k] - c.x[b]), norm(w.particles.body_offset[k]), 1e-14);
}

TEST(SimClumps, RodSpinningAboutItsAxisKeepsItsOmega) {
  sim::World w = contact_free_world();
  const auto rod = shape("rod", {{"aspect_ratio", 4.0}});
  const auto b =
      w.particles.add_clump({}, rotation_quat({0.3, 0.5, -0.1}), rod, kRadius, kDensity, 0);
  const auto& c = w.particles.clumps;
  const Vec3 omega0 = 7.0 * c.q[b].rotate({1, 0, 0});  // body x: the rod axis
  set_spin(w.particles, b, omega0);
  w.dt = 0.01 / 7.0;
  sim::run(w, 5000);
  EXPECT_NEAR(norm(c.omega[b] - omega0), 0.0, 1e-12 * 7.0);
  EXPECT_NEAR(norm(integrate::body_angular_velocity(c, b) - omega0), 0.0, 1e-12 * 7.0);
}

TEST(SimClumps, SpinAboutAPrincipalAxisTurnsByOmegaT) {
  sim::World w = contact_free_world();
  const auto cluster = shape("cluster", {{"spheres", 4.0}, {"seed", 9.0}});
  const Quat q0 = rotation_quat({-0.2, 0.9, 0.4});
  const Vec3 x0{0.05, -0.02, 0.01};
  const auto b = w.particles.add_clump(x0, q0, cluster, kRadius, kDensity, 0);
  const auto& c = w.particles.clumps;
  for (int axis = 0; axis < 3; ++axis) {
    Vec3 e{};
    e[axis] = 1.0;
    const double rate = 5.0;
    const Vec3 n = c.q[b].rotate(e);
    set_spin(w.particles, b, rate * n);
    const Quat q_start = c.q[b];
    const double t_start = w.time;
    w.dt = 0.01 / rate;
    const int steps = 1000;  // 10 rad
    sim::run(w, steps);
    const double angle = rate * (w.time - t_start);
    EXPECT_NEAR(angle, 10.0, 1e-9);
    for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k) {
      const Vec3 arm0 = q_start.rotate(w.particles.body_offset[k]);
      const Vec3 expected = rotate(arm0, n, angle);  // Rodrigues about n
      const Vec3 arm = w.particles.x[k] - c.x[b];
      EXPECT_NEAR(norm(arm - expected), 0.0, 1e-9 * norm(arm0)) << "axis " << axis << " " << k;
    }
    EXPECT_NEAR(norm(c.x[b] - x0), 0.0, 1e-15);
  }
}

TEST(SimClumps, MembersOfOneClumpExertNoForcesOnEachOther) {
  sim::World w = empty_world({});
  const auto rod = shape("rod", {{"aspect_ratio", 3.0}, {"spacing", 0.3}});
  const auto b = w.particles.add_clump({0.1, 0.2, 0.3}, rotation_quat({0.2, 0.1, 0.3}), rod,
                                       kRadius, kDensity, 0);
  auto& p = w.particles;
  const auto& c = p.clumps;
  // Overlapping members, which would repel each other if they were listed.
  ASSERT_LT(norm(p.x[1] - p.x[0]), p.radius[0] + p.radius[1]);
  // A lone sphere within the skin of the last member, not touching: the list holds pairs.
  const std::size_t last = c.first[b] + c.count[b] - 1;
  const Vec3 out = normalized(p.x[last] - c.x[b]);
  const double r_lone = 0.5 * p.radius[last];
  const auto lone = p.add_sphere(p.x[last] + (p.radius[last] + r_lone + 0.02 * r_lone) * out,
                                 r_lone, kDensity, 0);
  w.dt = 1e-4;
  const auto x0 = p.x;
  sim::run(w, 200);
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int k = w.list.row_start[i]; k < w.list.row_start[i + 1]; ++k) {
      const int j = w.list.nbr[k];
      ++pairs;
      EXPECT_TRUE(p.body[i] < 0 || p.body[i] != p.body[j]) << i << " " << j;
    }
  EXPECT_GT(pairs, 0u);
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(norm(p.f[i]), 0.0) << i;
    EXPECT_NEAR(norm(p.x[i] - x0[i]), 0.0, 1e-15) << i;
  }
  EXPECT_EQ(norm(c.v[b]), 0.0);
  EXPECT_EQ(norm(c.angular_momentum[b]), 0.0);
  EXPECT_EQ(norm(p.v[lone]), 0.0);
}

TEST(SimClumps, FreeFallFollowsHalfGTSquared) {
  // A rod (its members' masses are placed symmetrically about the centre of mass).
  sim::World w = empty_world({0, 0, -kG});
  const auto rod = shape("rod", {{"aspect_ratio", 3.0}});
  const Quat q0 = rotation_quat({0.3, -0.6, 0.8});
  const Vec3 x0{0.01, 0.02, 1.0}, v0{0.3, -0.1, 0.5};
  const auto b = w.particles.add_clump(x0, q0, rod, kRadius, kDensity, 0);
  auto& c = w.particles.clumps;
  c.v[b] = v0;
  w.dt = 1e-4;
  sim::run(w, 2000);
  const double t = w.time;
  const Vec3 expected = x0 + v0 * t + 0.5 * t * t * w.gravity;
  const Vec3 moved = expected - x0;
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(c.x[b][a] - x0[a], moved[a], 1e-9 * norm(moved)) << a;
  EXPECT_NEAR(norm(c.v[b] - (v0 + t * w.gravity)), 0.0, 1e-9 * norm(v0 + t * w.gravity));
  EXPECT_NEAR(norm(c.angular_momentum[b]), 0.0, 1e-15);
  const Quat& q = c.q[b];
  EXPECT_NEAR(std::abs(q.w * q0.w + q.x * q0.x + q.y * q0.y + q.z * q0.z), 1.0, 1e-14);
}

// KNOWN BUG (disabled until fixed): gravity acts on each member with its mass share by own
// volume (ParticleStore::add_clump), whose centre sum m_k b_k / M is not the union's centroid
// for an asymmetric clump (this cluster: 0.024 equivalent radii off; helix AR 4: 0.011). The
// summed member weights then exert a torque M g x R d about the centre of mass, and a clump
// falling freely from rest starts to turn. Fixing it needs the body kick to take gravity at the
// centre of mass (or member masses whose centre is the centroid).
TEST(SimClumps, AsymmetricClumpInFreeFallDoesNotTurn) {
  sim::World w = empty_world({0, 0, -kG});
  const auto cluster = shape("cluster", {{"spheres", 5.0}, {"irregularity", 0.6}, {"seed", 1.0}});
  const Quat q0 = rotation_quat({0.3, -0.6, 0.8});
  const auto b = w.particles.add_clump({0, 0, 1.0}, q0, cluster, kRadius, kDensity, 0);
  const auto& c = w.particles.clumps;
  w.dt = 1e-4;
  sim::run(w, 2000);
  // Free fall: no torque about the centre of mass, so no angular momentum and no turning.
  const double scale = c.mass[b] * kG * kRadius * w.time;  // M g r t
  EXPECT_LT(norm(c.angular_momentum[b]), 1e-12 * scale);
  const Quat& q = c.q[b];
  EXPECT_NEAR(std::abs(q.w * q0.w + q.x * q0.x + q.y * q0.y + q.z * q0.z), 1.0, 1e-14);
}

TEST(SimClumps, ElasticRodBouncesOffTheFloorKeepingItsEnergy) {
  for (const bool flat : {false, true}) {
    sim::World w = empty_world({0, 0, -kG});
    w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
    const auto rod = shape("rod", {{"aspect_ratio", 3.0}});
    // Tilted: one end lands first and the rod starts to turn. Flat: body x (the axis) along world
    // x, every member lands at once.
    const Quat q0 = flat ? Quat{} : rotation_quat({0.0, 0.5, 0.1});
    const auto b = w.particles.add_clump({0, 0, 0}, q0, rod, kRadius, kDensity, 0);
    auto& p = w.particles;
    auto& c = p.clumps;
    double lowest = 1e300;
    for (std::size_t k = 0; k < p.size(); ++k) lowest = std::min(lowest, p.x[k].z - p.radius[k]);
    const double drop = 0.005;
    c.x[b].z += drop - lowest;
    for (std::size_t k = 0; k < p.size(); ++k) p.x[k].z += drop - lowest;
    double m_member = 1e300;
    for (double m : p.mass) m_member = std::min(m_member, m);
    w.dt = M_PI * std::sqrt(m_member / kStiffness) / 100.0;
    const double e0 = body_energy(w);
    const double v_impact = std::sqrt(2.0 * kG * drop);
    double worst = 0.0, max_omega = 0.0;
    bool touched = false, both_ends = false, left = false;
    const std::size_t end_a = c.first[b], end_b = c.first[b] + c.count[b] - 1;
    for (int s = 0; s < 200000 && !left; ++s) {
      sim::step(w);
      worst = std::max(worst, std::abs(body_energy(w) - e0) / e0);
      max_omega = std::max(max_omega, norm(c.omega[b]));
      const bool a_touches = p.x[end_a].z < p.radius[end_a],
                 b_touches = p.x[end_b].z < p.radius[end_b];
      both_ends |= a_touches && b_touches;
      bool any = false;
      for (std::size_t k = 0; k < p.size(); ++k) any |= p.x[k].z < p.radius[k];
      touched |= any;
      left = touched && !any && c.v[b].z > 0.0;
    }
    ASSERT_TRUE(left) << "the rod did not bounce back";
    std::printf("%s rod: energy deviation %.2e, max |omega| %.3e rad/s, up %.4f m/s (in %.4f)\n",
                flat ? "flat" : "tilted", worst, max_omega, c.v[b].z, v_impact);
    EXPECT_LT(worst, 1e-3);
    if (flat) {
      EXPECT_TRUE(both_ends);
      // By symmetry no turning: |omega| L / 2 stays at roundoff next to the impact speed.
      EXPECT_LT(max_omega * rod.bounding_radius * kRadius, 1e-9 * v_impact);
    } else {
      EXPECT_GT(max_omega, 1.0);  // the tilted rod was set turning
    }
  }
}

TEST(SimClumps, RodRestingOnTheFloorLoadsItWithItsWeight) {
  // Restitution 0.3 of the linear spring-dashpot: xi = -ln e / sqrt(pi^2 + ln^2 e).
  const double e = 0.3, xi = -std::log(e) / std::sqrt(M_PI * M_PI + std::log(e) * std::log(e));
  sim::World w = empty_world({0, 0, -kG}, xi, 0.5);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, 0}, {0, 0, 1}}));
  const auto rod = shape("rod", {{"aspect_ratio", 3.0}});
  const auto b = w.particles.add_clump({0, 0, 0.02}, rotation_quat({0.05, 0.04, 0.7}), rod, kRadius,
                                       kDensity, 0);
  auto& c = w.particles.clumps;
  double m_member = 1e300;
  for (double m : w.particles.mass) m_member = std::min(m_member, m);
  w.dt = M_PI * std::sqrt(m_member / kStiffness) / 50.0;
  const double weight = c.mass[b] * kG;
  sim::run(w, static_cast<std::int64_t>(0.6 / w.dt));
  std::printf("resting rod: weight %.6e N, floor %.6e N, |v| %.2e m/s, |omega| %.2e rad/s\n",
              weight, -w.walls[0].force.z, norm(c.v[b]), norm(c.omega[b]));
  EXPECT_NEAR(-w.walls[0].force.z, weight, 1e-4 * weight);
  EXPECT_NEAR(w.walls[0].force.x, 0.0, 1e-4 * weight);
  EXPECT_NEAR(w.walls[0].force.y, 0.0, 1e-4 * weight);
  // Lying on the floor: the members all touch it (the axis is horizontal).
  for (std::size_t k = c.first[b]; k < c.first[b] + c.count[b]; ++k)
    EXPECT_LT(w.particles.x[k].z, w.particles.radius[k]) << k;
}

/// Lays a 3-member rod (AR 2) along `axis` centred at `centre`; returns its body.
std::size_t lay_rod(sim::World& w, const particles::ClumpTemplate& rod, const Vec3& centre,
                    const Quat& q) {
  return w.particles.add_clump(centre, q, rod, kRadius, kDensity, 0);
}

TEST(SimClumps, CoordinationNumberCountsContactsBetweenBodies) {
  const auto rod = shape("rod", {{"aspect_ratio", 2.0}});
  ASSERT_EQ(rod.size(), 3u);
  const double rm = rod.radii[0] * kRadius;  // member radius
  const Quat along_x{}, along_y = rotation_quat({0, 0, 0.5 * M_PI});
  const double touch = 2.0 * rm * (1.0 - 1e-3);  // centre distance of a touching member pair
  for (const bool crossed : {true, false}) {
    sim::World w = empty_world({});
    w.dt = 1e-5;
    lay_rod(w, rod, {0, 0, 0}, along_x);
    // Crossed: the other rod along y, its middle member on top of this one's. Parallel: side by
    // side, all three member pairs touching.
    lay_rod(w, rod, crossed ? Vec3{0, 0, touch} : Vec3{0, touch, 0}, crossed ? along_y : along_x);
    w.prepare();
    EXPECT_EQ(metrics::contact_count(w), crossed ? 1u : 3u);
    EXPECT_DOUBLE_EQ(metrics::coordination_number(w), 1.0);
    // A lone sphere touching the first rod's end from below: three bodies, contacts A-B and A-S.
    const std::size_t end = w.particles.clumps.first[0];
    const Vec3 below = w.particles.x[end] - Vec3{0, 0, rm + 0.5 * kRadius * (1.0 - 1e-3)};
    w.particles.add_sphere(below, 0.5 * kRadius, kDensity, 0);
    w.prepare();
    EXPECT_EQ(metrics::contact_count(w), crossed ? 2u : 4u);
    EXPECT_DOUBLE_EQ(metrics::coordination_number(w), 4.0 / 3.0);
    // Sampled by centre of mass: a thin cylinder about the z axis holds only the first rod's
    // centre (the second rod lies above or beside it), not the lone sphere's.
    const metrics::SamplingCylinder around_origin{0.2 * rm, -0.5 * rm, 0.5 * rm};
    EXPECT_DOUBLE_EQ(metrics::coordination_number(w, around_origin), 2.0);
    const metrics::SamplingCylinder everything{1.0, -1.0, 1.0};
    EXPECT_DOUBLE_EQ(metrics::coordination_number(w, everything), 4.0 / 3.0);
  }
}

TEST(SimClumps, CoordinationNumberOfSpheresIsTwiceTheContactsPerSphere) {
  sim::World w = empty_world({});
  w.dt = 1e-5;
  // A chain of 4 touching spheres and one apart: 3 contacts over 5 spheres.
  for (int k = 0; k < 4; ++k)
    w.particles.add_sphere({k * 2.0 * kRadius * 0.999, 0, 0}, kRadius, kDensity, 0);
  w.particles.add_sphere({0, 0.1, 0}, kRadius, kDensity, 0);
  w.prepare();
  EXPECT_EQ(metrics::contact_count(w), 3u);
  EXPECT_DOUBLE_EQ(metrics::coordination_number(w), 6.0 / 5.0);
  // The cylinder about the z axis holds only the first sphere (one contact).
  const metrics::SamplingCylinder first{0.5 * kRadius, -kRadius, kRadius};
  EXPECT_DOUBLE_EQ(metrics::coordination_number(w, first), 1.0);
}

}  // namespace
}  // namespace demcal
