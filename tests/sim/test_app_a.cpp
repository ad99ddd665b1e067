// Seed 001 Appendix A.1 as an example (examples/app_a_two_particles.yaml): two vertically aligned
// spheres dropped on a flat surface, the upper one spinning. Checked for its invariants:
//  - total energy (kinetic + gravitational + the elastic energy held in the normal, tangential and
//    rolling springs) never increases, and kinetic + gravitational never exceeds its start value;
//  - the spinning sphere is driven sideways in the direction friction must push it, -(omega x n),
//    and the lower sphere the other way;
//  - both end at rest or rolling without slipping, resting on the surface or on each other with
//    no more overlap than the weight they carry explains; nothing leaves the x-y plane or escapes.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/io/scene_yaml.hpp"
#include "core/sim/step.hpp"

namespace demcal {
namespace {

constexpr double kPairK = 200.0, kWallK = 400.0;  // Table A.1 (k_n = k_s = k_r)
constexpr double kG = 9.81;

struct Energies {
  double mechanical;  ///< kinetic (translation + rotation) + gravitational
  double stored;      ///< normal, tangential and rolling springs
};

/// Energies of the two-sphere world. The history layout of linear + history + epsd is
/// [xi (3), F_r (3)]: the tangential spring holds 1/2 k_s |xi|^2, the rolling spring |F_r|^2 / (2
/// k_r).
Energies energies(const sim::World& w) {
  const auto& p = w.particles;
  Energies e{p.kinetic_energy(), 0.0};
  for (std::size_t i = 0; i < p.size(); ++i) e.mechanical += p.mass[i] * kG * p.x[i].y;
  if (!w.prepared()) return e;  // before the first step: no contact, no history yet
  auto springs = [&](const double* h, double delta, double k) {
    if (delta > 0.0) e.stored += 0.5 * k * delta * delta;
    e.stored += 0.5 * k * (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    e.stored += (h[3] * h[3] + h[4] * h[4] + h[5] * h[5]) / (2.0 * k);
  };
  const int stride = w.pair_stride();
  for (int k = w.list.row_start[0]; k < w.list.row_start[1]; ++k)
    springs(&w.pair_history[static_cast<std::size_t>(k) * stride],
            p.radius[0] + p.radius[1] - norm(p.x[1] - p.x[0]), kPairK);
  for (std::size_t i = 0; i < p.size(); ++i)
    springs(&w.wall_history[0][i * static_cast<std::size_t>(w.wall_stride(0))],
            p.radius[i] - p.x[i].y, kWallK);
  return e;
}

TEST(SimAppA, TwoParticlesDroppedOneSpinningKeepTheirInvariants) {
  auto scene = io::read_scene(io::YamlNode::load_file(std::string(DEMCAL_SOURCE_DIR) +
                                                      "/examples/app_a_two_particles.yaml"));
  sim::World& w = scene.world;
  auto& p = w.particles;
  ASSERT_EQ(p.size(), 2u);
  long steps = 0;
  for (const auto& phase : scene.phases) steps += phase.steps;
  ASSERT_EQ(steps, 50000);  // 5 s at 1e-4 s
  EXPECT_EQ(w.dt, 1e-4);

  const double r1 = p.radius[0], r2 = p.radius[1], m1 = p.mass[0], m2 = p.mass[1];
  const Vec3 omega0 = p.omega[0];
  const Energies start = energies(w);
  const double e0 = start.mechanical + start.stored;
  double e_floor = e0, worst_rise = 0.0, worst_mech = -1e300;
  bool pair_contact = false, first_contact_done = false;
  Vec3 v1_after{}, v2_after{}, omega1_after{};
  double first_contact_time = 0.0, impact_speed = 0.0;
  constexpr long kAverage = 5000;  // the last 0.5 s
  Vec3 mean_v[2]{}, mean_omega[2]{};
  double max_pair_overlap = 0.0;
  for (long s = 0; s < steps; ++s) {
    sim::step(w);
    ASSERT_EQ(w.pair_stride(), 6);
    const Energies e = energies(w);
    const double total = e.mechanical + e.stored;
    worst_rise = std::max(worst_rise, total - e_floor);
    e_floor = std::min(e_floor, total);
    worst_mech = std::max(worst_mech, e.mechanical);
    const double pair_overlap = r1 + r2 - norm(p.x[1] - p.x[0]);
    max_pair_overlap = std::max(max_pair_overlap, pair_overlap);
    if (pair_overlap > 0.0 && !pair_contact && !first_contact_done) {
      pair_contact = true;
      first_contact_time = w.time;
      impact_speed = dot(p.v[0] - p.v[1], normalized(p.x[1] - p.x[0]));
    } else if (pair_overlap <= 0.0 && pair_contact && !first_contact_done) {
      pair_contact = false;
      first_contact_done = true;
      v1_after = p.v[0];
      v2_after = p.v[1];
      omega1_after = p.omega[0];
    }
    ASSERT_TRUE(is_finite(p.x[0]) && is_finite(p.x[1]));
    if (s >= steps - kAverage)
      for (int i = 0; i < 2; ++i) {
        mean_v[i] += p.v[i] / kAverage;
        mean_omega[i] += p.omega[i] / kAverage;
      }
  }
  std::printf(
      "App. A: E0 %.6f J, largest rise of the total over its running minimum %.3e J, "
      "largest kinetic+gravitational %.6f J, end total %.6f J\n",
      e0, worst_rise, worst_mech, energies(w).mechanical + energies(w).stored);
  std::printf("impact speed %.4f m/s, largest pair overlap %.4f m, end kinetic energy %.3e J\n",
              impact_speed, max_pair_overlap, p.kinetic_energy());
  std::printf(
      "first 1-2 contact at t = %.4f s; after it v1 = (%.4f, %.4f), v2 = (%.4f, %.4f), "
      "omega1_z = %.2f rad/s\n",
      first_contact_time, v1_after.x, v1_after.y, v2_after.x, v2_after.y, omega1_after.z);
  for (int i = 0; i < 2; ++i)
    std::printf("end: sphere %d x = (%.5f, %.6f, %g) v = (%.2e, %.2e) omega_z = %.3e\n", i + 1,
                p.x[i].x, p.x[i].y, p.x[i].z, p.v[i].x, p.v[i].y, p.omega[i].z);

  // Energy: never created.
  EXPECT_LT(worst_rise, 1e-5 * e0);
  EXPECT_LT(worst_mech, start.mechanical * (1.0 + 1e-6));

  // The two spheres met, and friction drove the spinning one along -(omega x n), n from 1 to 2.
  ASSERT_TRUE(first_contact_done);
  const Vec3 n{0, -1, 0};
  const Vec3 drive = -cross(omega0, n);  // direction of the friction force on sphere 1
  ASSERT_GT(norm(drive), 0.0);
  const Vec3 dir = normalized(drive);
  EXPECT_EQ(dir.x, 1.0);  // (0,0,-300) x (0,-1,0) = (-300,0,0): friction pushes sphere 1 to +x
  EXPECT_GT(dot(v1_after, dir), 0.01);  // m/s
  EXPECT_LT(dot(v2_after, dir), -0.001);
  EXPECT_LT(std::abs(omega1_after.z), std::abs(omega0.z));  // friction slowed the spin

  // The pair impact: a linear spring-dashpot damped on approach reaches
  //   delta_max = v0 sqrt(m*/k) exp(-xi / sqrt(1 - xi^2) atan(sqrt(1 - xi^2) / xi))
  // (sphere 2 sits on the surface meanwhile, so allow 5 %).
  const double xi = 0.7, m_star = m1 * m2 / (m1 + m2);
  const double predicted =
      impact_speed * std::sqrt(m_star / kPairK) *
      std::exp(-xi / std::sqrt(1 - xi * xi) * std::atan(std::sqrt(1 - xi * xi) / xi));
  std::printf("pair impact: largest overlap %.5f m, damped-oscillator prediction %.5f m\n",
              max_pair_overlap, predicted);
  EXPECT_NEAR(max_pair_overlap, predicted, 0.05 * predicted);

  // End: the spheres rock on their undamped tangential and rolling springs (Table A.1 has no
  // tangential or rolling damping) with a tiny amplitude; averaged over the last 0.5 s (~14
  // periods) they are at rest or rolling without slipping.
  EXPECT_LT(p.kinetic_energy(), 1e-4 * e0);
  for (int i = 0; i < 2; ++i) {
    const double r = p.radius[i];
    const double floor_overlap = r - p.x[i].y;
    const Vec3 mean_slip = mean_v[i] + cross(mean_omega[i], Vec3{0, -r, 0});  // at the surface
    std::printf("sphere %d, last 0.5 s: mean v (%.2e, %.2e) m/s, mean slip %.2e m/s\n", i + 1,
                mean_v[i].x, mean_v[i].y, norm(mean_slip));
    if (floor_overlap > 0.0) {
      EXPECT_LT(norm(mean_slip), 2e-3) << "sphere " << i + 1 << " slips";
      // No more overlap than both weights on a 400 N/m spring (plus 10 %).
      EXPECT_LT(floor_overlap, 1.1 * (m1 + m2) * kG / kWallK) << "sphere " << i + 1;
    } else {
      // Not on the surface: it must rest on the other sphere.
      const double pair_overlap = r1 + r2 - norm(p.x[1] - p.x[0]);
      EXPECT_GT(pair_overlap, 0.0) << "sphere " << i + 1 << " floats";
      EXPECT_LT(pair_overlap, 1.1 * m1 * kG / kPairK);
      EXPECT_LT(norm(mean_v[i]), 2e-3);
    }
    // In the plane of the motion, and nowhere far.
    EXPECT_EQ(p.x[i].z, 0.0);
    EXPECT_EQ(p.omega[i].x, 0.0);
    EXPECT_EQ(p.omega[i].y, 0.0);
    EXPECT_LT(std::abs(p.x[i].x), 5.0);
    EXPECT_GT(p.x[i].y, 0.5 * r);
  }
}

}  // namespace
}  // namespace demcal
