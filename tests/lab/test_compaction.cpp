// compaction (seed 004 §2.3-2.4): the contact stress tensor of two spheres touching across a
// periodic face against its analytic value, and of a lattice between walls against the walls'
// stress; frictionless spheres compacted in a periodic cell
// jam near random close packing (O'Hern, Silbert, Liu and Nagel, Phys. Rev. E 68 (2003) 011306:
// phi_J = 0.639 as N grows), frictional ones looser (random loose packing), the pressure rises
// steeply past jamming, and the constant-volume shear probe finds a macroscopic friction that
// frictionless spheres have too and friction raises. Reloaded from an unloaded reference state,
// a packing yields isotropically just past the pressure it was compacted to (its
// preconsolidation, the cap of a critical-state yield surface), and along deviatoric paths at
// the stress ratio of its friction.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/contact/contact_law.hpp"
#include "core/lab/lab_test.hpp"
#include "core/metrics/stress.hpp"
#include "core/metrics/yield_surface.hpp"
#include "core/sim/world.hpp"
#include "core/walls/wall.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
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

TEST(Compaction, ContactStressOfOnePairAcrossAPeriodicFace) {
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
  const auto s = metrics::contact_stress(w, volume);
  EXPECT_NEAR(s[0][0], fn * gap / volume, 1e-9 * fn * gap / volume);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (a != 0 || b != 0) {
        EXPECT_NEAR(s[a][b], 0.0, 1e-12 * s[0][0]) << a << b;
      }
  EXPECT_DOUBLE_EQ(metrics::mean_stress(s), s[0][0] / 3);
  EXPECT_NEAR(metrics::deviatoric_stress(s), s[0][0], 1e-12 * s[0][0]);  // |sigma_1 - sigma_3|
}

TEST(Compaction, ContactStressEqualsTheWallStressOfALatticeBetweenWalls) {
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
  const auto s = metrics::contact_stress(w, area * (nz - 1) * a);
  EXPECT_NEAR(s[2][2], wall_stress, 1e-9 * wall_stress);
  // Lateral: nx^2 nz bonds along x, each kn delta over a, in the same volume.
  const double lateral = nx * nx * nz * kn * delta * a / (area * (nz - 1) * a);
  EXPECT_NEAR(s[0][0], lateral, 1e-9 * lateral);
  EXPECT_NEAR(s[1][1], lateral, 1e-9 * lateral);
  EXPECT_NEAR(s[0][1], 0.0, 1e-12 * lateral);
}

TEST(Compaction, ContactPressureIsTheEnergyRoutePressureOfARandomPacking) {
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
  const auto s = metrics::contact_stress(w, volume);
  ASSERT_GT(p_energy, 0.0);
  EXPECT_NEAR(metrics::mean_stress(s), p_energy, 1e-6 * p_energy);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < a; ++b) EXPECT_NEAR(s[a][b], s[b][a], 1e-12 * p_energy) << a << b;
}

TEST(Compaction, ModifiedCamClayFitRecoversTheEllipse) {
  // q^2 = M^2 p (p_c - p) at M = 0.8, p_c = 300, on five pressures.
  std::vector<metrics::YieldPoint> points;
  for (double p : {20.0, 80.0, 150.0, 240.0, 299.0})
    points.push_back({p, 0.8 * std::sqrt(p * (300.0 - p))});
  const auto fit = metrics::fit_modified_cam_clay(points);
  ASSERT_TRUE(fit.valid);
  EXPECT_NEAR(fit.slope, 0.8, 1e-9);
  EXPECT_NEAR(fit.cap, 300.0, 1e-7);
  EXPECT_NEAR(fit.rms_q, 0.0, 1e-6);
  // Points on a straight line through the origin (a friction line, no cap) are no ellipse.
  std::vector<metrics::YieldPoint> line;
  for (double p : {20.0, 80.0, 150.0}) line.push_back({p, 0.5 * p});
  EXPECT_FALSE(metrics::fit_modified_cam_clay(line).valid);
  EXPECT_FALSE(metrics::fit_modified_cam_clay({{100.0, 10.0}}).valid);
}

TEST(Compaction, JammingShearAndYieldOfFrictionlessAndFrictionalSpheres) {
  double jam[2] = {0, 0}, steady[2] = {0, 0}, shear_yield[2] = {0, 0};
  for (int f = 0; f < 2; ++f)
    for (std::uint64_t seed : {1, 2}) {
      RunOptions o;
      o.seed = seed;
      const auto out = run_lab_test("compaction", testing::hertz_spheres(f == 0 ? 0.0 : 0.5),
                                    {{"particles", 200}}, o);
      // Frictionless yield points lie on a friction line up to the cap (q / p 0.13-0.18 in one
      // build): the ellipse may not fit them, and then its two metrics are flagged.
      for (const auto& [metric, why] : out.flags)
        EXPECT_TRUE(f == 0 && (metric == "yield_cap_pressure" || metric == "yield_slope"))
            << metric << ": " << why;
      jam[f] += 0.5 * out.metrics.at("jamming_fraction");
      // Reloaded isotropically from a tenth of it, the packing yields just past the pressure it
      // was compacted to (1.03-1.08 times in one build).
      const double p_final = out.metrics.at("final_pressure");
      EXPECT_GT(out.metrics.at("isotropic_yield_pressure"), p_final);
      EXPECT_LT(out.metrics.at("isotropic_yield_pressure"), 1.15 * p_final);
      const auto& yield = out.series.at("yield_points").rows;
      ASSERT_EQ(yield.size(), 5u);
      EXPECT_EQ(yield.back()[0], 90.0);  // the constant-volume path
      shear_yield[f] += 0.5 * yield.back()[3];
      // Held at phi_max, the packing is near equilibrium: its tensor symmetric with friction too
      // (the contacts' torques balance), to 0.2 % of the pressure (0.02 % at seed 1, mu_s 0.5).
      const auto& last = out.series.at("held").rows.back();  // ..., s_xy, s_xz, s_yz, s_yx, ...
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(last[7 + k], last[10 + k], 0.002 * last[1]) << k;
      if (f == 1) {  // an ellipse whose slope is near the friction line of the shear probe
        EXPECT_GT(out.metrics.at("yield_cap_pressure"), p_final);
        EXPECT_GT(out.metrics.at("yield_slope"), 0.3);
        EXPECT_LT(out.metrics.at("yield_slope"), out.metrics.at("peak_stress_ratio"));
      }
      steady[f] += 0.5 * out.metrics.at("steady_stress_ratio");
      EXPECT_GE(out.metrics.at("peak_stress_ratio"), out.metrics.at("steady_stress_ratio"));
      // Past jamming the held pressure rises steeply: at phi_max it is over 100 times that of
      // the last held state below the jamming fraction.
      const auto& held = out.series.at("held").rows;
      double below = 0.0;
      for (const auto& row : held)
        if (row[0] < out.metrics.at("jamming_fraction")) below = row[1];
      EXPECT_GT(held.back()[1], 100.0 * below);
      EXPECT_NEAR(held.back()[1], out.metrics.at("final_pressure"), 1e-12);
    }
  // 200 particles: 0.634 and 0.624 in one build (seeds 1, 2); finite cells jam a little below
  // the large-N value.
  EXPECT_GT(jam[0], 0.61);
  EXPECT_LT(jam[0], 0.66);
  // mu_s 0.5: 0.576 and 0.572 in the same build.
  EXPECT_LT(jam[1], jam[0] - 0.03);
  // Sheared at constant volume, frictionless spheres keep a macroscopic friction (Peyneau and
  // Roux, Phys. Rev. E 78 (2008) 011307: tau / p ~ 0.1, i.e. q / p ~ 0.2 in axisymmetric
  // shear; 0.24 at seed 1), frictional ones far more (0.59 at seed 1).
  EXPECT_GT(steady[0], 0.1);
  EXPECT_LT(steady[0], 0.4);
  EXPECT_GT(steady[1], 1.5 * steady[0]);
  // The constant-volume path yields at the packing's friction: q / p 0.16 frictionless, 0.62 at
  // mu_s 0.5 (seed 1).
  EXPECT_GT(shear_yield[1], 2.0 * shear_yield[0]);
}

TEST(Compaction, HelicesPackLooserThanSpheresAtTheSamePressure) {
  // Seed 004's helical fibres (Table 2.1's kind: aspect ratio 4, offset 0.267 of the diameter,
  // half a revolution) against spheres of the same volume, 60 frictionless bodies each,
  // compacted to 0.62 (below random close packing of spheres). The pressure rises with the solid
  // fraction, so a larger pressure at the same fraction is a looser packing at the same pressure.
  const Settings settings{{"particles", 60},  {"phi_start", 0.06},   {"phi_max", 0.62},
                          {"points", 2},      {"strain_rate", 1e-4}, {"probe_strain", 0},
                          {"yield_probes", 0}};
  MaterialModel helix = testing::hertz_spheres(0.0);
  helix.shape = particles::make_shape_spec(
      "helix", {{"aspect_ratio", 4}, {"offset_ratio", 0.267}, {"revolutions", 0.5}}, "shape");
  for (std::uint64_t seed : {1, 2}) {
    RunOptions o;
    o.seed = seed;
    const auto spheres = run_lab_test("compaction", testing::hertz_spheres(0.0), settings, o);
    const auto helices = run_lab_test("compaction", helix, settings, o);
    // 0.19 against 7.0 kPa at seed 1, 0.06 against 3.2 kPa at seed 2, in one build.
    EXPECT_GT(helices.metrics.at("final_pressure"), 10.0 * spheres.metrics.at("final_pressure"))
        << "seed " << seed;
    EXPECT_GT(helices.metrics.at("final_coordination_number"),
              spheres.metrics.at("final_coordination_number"))
        << "seed " << seed;
  }
}

}  // namespace
}  // namespace demcal::lab
