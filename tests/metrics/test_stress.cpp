// The contact stress tensor (Love-Weber, core/metrics/stress.hpp; seed 004 §2.3) against
// references written independently of it: two spheres touching across a periodic face (the
// analytic tensor), a lattice between walls (the walls' stress), a random periodic packing (the
// energy-route pressure -dU/dV from the overlaps alone); and the modified Cam-clay fit
// (core/metrics/yield_surface.hpp) on an exact ellipse and on a friction line it must refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/contact/contact_law.hpp"
#include "core/metrics/stress.hpp"
#include "core/metrics/yield_surface.hpp"
#include "core/sim/world.hpp"
#include "core/walls/wall.hpp"

namespace demcal::metrics {
namespace {

/// Undamped linear springs f = kn delta with tangential history (mu_s 0.5).
contact::ContactLaw linear_springs(double kn) {
  contact::ContactLawSpec spec;
  spec.normal = {"linear", {{"kn", kn}, {"damping_ratio", 0.0}}};
  spec.tangential = {"history", {{"mu_s", 0.5}}};
  return contact::ContactLaw::from_spec(spec, "law");
}

/// An empty fully periodic cube of side `side` without gravity, its pairs on linear_springs(kn).
sim::World periodic_cube(double side, double kn) {
  sim::World w;
  w.gravity = {};
  w.domain.lo = {0, 0, 0};
  w.domain.hi = {side, side, side};
  w.domain.periodic = {true, true, true};
  w.set_pair_law(0, 0, linear_springs(kn));
  return w;
}

TEST(ContactStress, OfOnePairAcrossAPeriodicFace) {
  // Two spheres of radius r at x = 0.45 r and x = L - 1.45 r in a periodic cube of side L: their
  // minimum images are 1.9 r apart along x, across the face x = 0. A linear spring: the force
  // kn (2 r - 1.9 r) along x, the branch vector 1.9 r along x.
  const double r = 1e-3, side = 10 * r, kn = 1e4;
  sim::World w = periodic_cube(side, kn);
  w.particles.add_sphere({0.45 * r, 5 * r, 5 * r}, r, 2500, 0);
  w.particles.add_sphere({side - 1.45 * r, 5 * r, 5 * r}, r, 2500, 0);
  w.dt = 1e-7;
  w.prepare();
  const double gap = 1.9 * r, fn = kn * (2 * r - gap), volume = side * side * side;
  const auto s = contact_stress(w, volume);
  EXPECT_NEAR(s[0][0], fn * gap / volume, 1e-9 * fn * gap / volume);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (a != 0 || b != 0) {
        EXPECT_NEAR(s[a][b], 0.0, 1e-12 * s[0][0]) << a << b;
      }
  EXPECT_DOUBLE_EQ(mean_stress(s), s[0][0] / 3);
  EXPECT_NEAR(deviatoric_stress(s), s[0][0], 1e-12 * s[0][0]);  // |sigma_1 - sigma_3|
}

TEST(ContactStress, EqualsTheWallStressOfALatticeBetweenWalls) {
  // A simple cubic lattice of 3 x 3 x 4 spheres, every neighbour pair overlapping by delta,
  // periodic in x and y, between a floor and a lid that overlap the outer layers by delta: a
  // static state in which every contact carries kn delta. Over the volume spanned by the centres
  // (A times the height from the lowest to the highest layer) the tensor's sigma_zz is the walls'
  // normal stress, and sigma_xx = sigma_yy that of the lateral bonds.
  const double r = 1e-3, delta = 1e-5, kn = 1e4, a = 2 * r - delta;
  const int nx = 3, nz = 4;
  sim::World w;
  w.gravity = {};
  w.domain.lo = {0, 0, -1};
  w.domain.hi = {nx * a, nx * a, 1};
  w.domain.periodic = {true, true, false};
  const auto law = linear_springs(kn);
  w.set_pair_law(0, 0, law);
  w.set_wall_law(0, 0, law);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < nx; ++j)
      for (int k = 0; k < nz; ++k)
        w.particles.add_sphere({(i + 0.5) * a, (j + 0.5) * a, k * a}, r, 2500, 0);
  w.walls.push_back(walls::make_wall("floor", walls::Plane{{0, 0, -(r - delta)}, {0, 0, 1}}));
  w.walls.push_back(
      walls::make_wall("lid", walls::Plane{{0, 0, (nz - 1) * a + r - delta}, {0, 0, -1}}));
  w.dt = 1e-8;
  w.prepare();
  const double area = nx * a * nx * a;
  const double wall_stress = -w.walls[0].force.z / area;
  EXPECT_NEAR(wall_stress, nx * nx * kn * delta / area, 1e-9 * wall_stress);
  EXPECT_NEAR(w.walls[1].force.z / area, wall_stress, 1e-9 * wall_stress);
  const auto s = contact_stress(w, area * (nz - 1) * a);
  EXPECT_NEAR(s[2][2], wall_stress, 1e-9 * wall_stress);
  // Lateral: nx^2 nz bonds along x, each kn delta over a, in the same volume.
  const double lateral = nx * nx * nz * kn * delta * a / (area * (nz - 1) * a);
  EXPECT_NEAR(s[0][0], lateral, 1e-9 * lateral);
  EXPECT_NEAR(s[1][1], lateral, 1e-9 * lateral);
  EXPECT_NEAR(s[0][1], 0.0, 1e-12 * lateral);
}

TEST(ContactStress, PressureIsTheEnergyRoutePressureOfARandomPacking) {
  // 60 spheres (radii 0.8-1.2 mm) at random in a periodic cube at a solid fraction of 0.7, held
  // by linear springs f = kn delta (elastic energy kn delta^2 / 2 per contact) with fresh
  // tangential springs. The pressure is -dU/dV under an affine change of the cell (the static
  // virial theorem), computed here from the overlaps alone, and must equal the trace of the
  // Love-Weber tensor over 3; with central forces the tensor is symmetric.
  const double kn = 1e4, side = 1e-2;
  sim::World w = periodic_cube(side, kn);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double solid = 0.0;
  while (solid < 0.7 * side * side * side) {
    const double r = 1e-3 * (0.8 + 0.4 * u(rng));
    w.particles.add_sphere({side * u(rng), side * u(rng), side * u(rng)}, r, 2500, 0);
    solid += 4.0 / 3.0 * M_PI * r * r * r;
  }
  w.dt = 1e-8;
  w.prepare();
  const auto& p = w.particles;
  // U of the cell scaled affinely by f about the origin (minimum images in the scaled cell).
  auto energy = [&](double f) {
    double u_sum = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      for (std::size_t j = i + 1; j < p.size(); ++j) {
        Vec3 d = f * (p.x[j] - p.x[i]);
        for (double* c : {&d.x, &d.y, &d.z}) *c -= f * side * std::round(*c / (f * side));
        const double delta = p.radius[i] + p.radius[j] - norm(d);
        if (delta > 0.0) u_sum += 0.5 * kn * delta * delta;
      }
    return u_sum;
  };
  const double eps = 1e-6, volume = side * side * side;
  const double dv = volume * (std::pow(1 + eps, 3) - std::pow(1 - eps, 3));
  const double p_energy = -(energy(1 + eps) - energy(1 - eps)) / dv;
  const auto s = contact_stress(w, volume);
  ASSERT_GT(p_energy, 0.0);
  EXPECT_NEAR(mean_stress(s), p_energy, 1e-6 * p_energy);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < a; ++b) EXPECT_NEAR(s[a][b], s[b][a], 1e-12 * p_energy) << a << b;
}

TEST(YieldSurface, ModifiedCamClayFitRecoversTheEllipse) {
  // q^2 = M^2 p (p_c - p) at M = 0.8, p_c = 300, on five pressures.
  std::vector<YieldPoint> points;
  for (double p : {20.0, 80.0, 150.0, 240.0, 299.0})
    points.push_back({p, 0.8 * std::sqrt(p * (300.0 - p))});
  const auto fit = fit_modified_cam_clay(points);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.slope, 0.8, 1e-9);
  EXPECT_NEAR(fit.cap, 300.0, 1e-7);
  EXPECT_NEAR(fit.rms_q, 0.0, 1e-6);
  // Points on a straight line through the origin (a friction line, no cap) are no ellipse.
  std::vector<YieldPoint> line;
  for (double p : {20.0, 80.0, 150.0}) line.push_back({p, 0.5 * p});
  EXPECT_FALSE(fit_modified_cam_clay(line).valid);
  EXPECT_FALSE(fit_modified_cam_clay({{100.0, 10.0}}).valid);
}

}  // namespace
}  // namespace demcal::metrics
