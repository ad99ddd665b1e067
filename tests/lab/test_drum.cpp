// rotating_drum (seed 001 §3.2.2-3.2.3): the drum in real units decides the particle count; the
// dynamic angle of repose rises with sliding and with rolling friction (the shape of seed 001
// Fig. 13); the occupied cross-sectional area rises with the drum speed (eq. 20); a bed driven far
// beyond Froude number 1 is reported as centrifuging.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/rotating_drum.hpp"

namespace demcal::lab {
namespace {

MaterialModel granules(double mu_s, double mu_r) {
  MaterialModel m;
  m.particle_law.normal = {"hertz",
                           {{"youngs_modulus", 5e6}, {"poisson_ratio", 0.3}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", mu_s}}};
  if (mu_r > 0.0) m.particle_law.rolling = {"epsd", {{"mu_r", mu_r}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{0.001};
  m.density = 2500;
  return m;
}

/// A 25 x 11 mm drum 43 % full holds 332 granules of 1 mm radius (D/d = 12.5).
const Settings kSmallDrum = {{"diameter", 25}, {"length", 11}};

Settings small_drum(Settings more) {
  more.insert(kSmallDrum.begin(), kSmallDrum.end());
  return more;
}

RotatingDrumSettings drum_settings(const Settings& values) {
  return read_settings<RotatingDrumSettings>(values, "settings");
}

TEST(LabRotatingDrum, ParticleCountFollowsFromTheGeometry) {
  const particles::SizeDistribution mm{particles::Monodisperse{0.001}};
  const DrumBed bed = drum_bed(drum_settings(kSmallDrum), mm, "settings");
  // fill pi R^2 W solid_fraction / (4/3 pi r^3), every setting at its default but D and W.
  const double expected = 0.43 * M_PI * 0.0125 * 0.0125 * 0.011 * 0.6 / (4.0 / 3.0 * M_PI * 1e-9);
  EXPECT_EQ(bed.particles, static_cast<std::size_t>(std::round(expected)));
  EXPECT_NEAR(bed.diameter_ratio, 12.5, 1e-9);
  // Twice the diameter holds four times the particles, half the fill half of them.
  const auto wide = drum_bed(drum_settings({{"diameter", 50}, {"length", 11}}), mm, "settings");
  EXPECT_NEAR(double(wide.particles), 4.0 * double(bed.particles), 2.0);
  EXPECT_NEAR(wide.diameter_ratio, 25.0, 1e-9);
  const auto half = drum_bed(drum_settings(small_drum({{"fill", 0.215}})), mm, "settings");
  EXPECT_NEAR(double(half.particles), 0.5 * double(bed.particles), 1.0);
}

TEST(LabRotatingDrum, SeedDrumAtLambda64HoldsTheSeedsGranuleCount) {
  // Seed 001: log-normal number median 200 um, sigma_g 1.43 (§3.1); the 100 x 44 mm drum 43 %
  // full (§3.2.2) simulated with 200,000 granules at lambda = 64 (§4.2), radii x4 (eq. 15).
  // Built whole: a size variant assigned after default construction draws a false
  // -Wmaybe-uninitialized from GCC 12 at -O1.
  const MaterialModel m{.particle_law = {},
                        .wall_law = {},
                        .sizes = particles::LogNormal{100e-6, 1.43},
                        .scaling = contact::ScalingLaw::kTiscar2019,
                        .scale_factor = 64,
                        .shape = {},
                        .preparation = {}};
  const DrumBed bed = drum_bed(drum_settings({{"max_particles", 1e6}}), m.simulated_sizes(), "s");
  EXPECT_NEAR(double(bed.particles), 2e5, 0.1 * 2e5) << bed.diameter_ratio;  // solid fraction 0.6
  // D/d with d the number-mean simulated diameter (~4 x 208 um)
  EXPECT_NEAR(bed.diameter_ratio, 100.0 / (4 * 0.208), 2.0);
  // Without the limit raised the count is refused, naming the setting.
  try {
    drum_bed(drum_settings({}), m.simulated_sizes(), "spec.tests[0].settings");
    ADD_FAILURE() << "200,000 particles accepted under the default limit";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "spec.tests[0].settings.max_particles") << e.what();
  }
  // A drum narrower than 6 of its largest particles is refused, naming the diameter.
  try {
    drum_bed(drum_settings({{"diameter", 5}}), m.simulated_sizes(), "settings");
    ADD_FAILURE() << "5 mm drum accepted for 2 mm granules";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "settings.diameter") << e.what();
  }
  // ... and one shallower than 1.25 of them, naming the length.
  try {
    drum_bed(drum_settings({{"length", 1}}), m.simulated_sizes(), "settings");
    ADD_FAILURE() << "1 mm deep drum accepted for 2 mm granules";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "settings.length") << e.what();
  }
}

/// The mean angle of two beds (lab seeds 1, 2): one short run of 332 granules scatters by a few
/// degrees with the rounding of the build (25.7 deg at mu_s 0.15 in one portable build).
double angle(double mu_s, double mu_r) {
  double sum = 0.0;
  for (std::uint64_t seed : {1, 2}) {
    RunOptions opt;
    opt.seed = seed;
    sum += run_lab_test("rotating_drum", granules(mu_s, mu_r),
                        small_drum({{"angle_time", 0.8}, {"area_time", 0.05}}), opt)
               .metrics.at("dynamic_angle_of_repose");
  }
  return 0.5 * sum;
}

TEST(LabRotatingDrum, AngleRisesWithSlidingFriction) {
  const double low = angle(0.15, 0.0), high = angle(0.6, 0.0);
  EXPECT_GT(low, 10.0);
  EXPECT_GT(high, low + 3.0);
}

TEST(LabRotatingDrum, AngleRisesWithRollingFriction) {
  const double plain = angle(0.6, 0.0), rolling = angle(0.6, 0.3);
  EXPECT_GT(rolling, plain + 2.0);
  EXPECT_LT(rolling, 70.0);
}

TEST(LabRotatingDrum, OccupiedAreaRisesAtHighSpeed) {
  RunOptions opt;
  const auto out = run_lab_test("rotating_drum", granules(0.5, 0.0),
                                small_drum({{"angle_time", 0.1}, {"area_time", 0.4}}), opt);
  // The bed the geometry asked for, and its D/d.
  EXPECT_EQ(
      out.metrics.at("particles"),
      double(drum_bed(drum_settings(kSmallDrum), particles::Monodisperse{0.001}, "s").particles));
  EXPECT_NEAR(out.metrics.at("drum_diameter_ratio"), 12.5, 1e-9);
  EXPECT_GT(out.metrics.at("csa_occupied_4"), 35.0);
  EXPECT_LT(out.metrics.at("csa_occupied_4"), 65.0);
  EXPECT_GT(out.metrics.at("csa_occupied_116"), out.metrics.at("csa_occupied_4") + 5.0);
  EXPECT_EQ(out.metrics.at("centrifuging_116"), 0.0);
}

TEST(LabRotatingDrum, CentrifugingBedIsReportedAsSuch) {
  RunOptions opt;
  // Speeds x3: the Froude number at "116 rpm" is ~7, the bed is pinned to the wall.
  const auto out =
      run_lab_test("rotating_drum", granules(0.5, 0.0),
                   small_drum({{"angle_time", 0.05}, {"area_time", 0.3}, {"speed_scale", 3}}), opt);
  EXPECT_EQ(out.metrics.at("centrifuging_116"), 1.0);
  EXPECT_EQ(out.metrics.at("centrifuging_4"), 0.0);
}

}  // namespace
}  // namespace demcal::lab
