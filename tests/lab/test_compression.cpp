// confined_compression (seed 000 §2.7.2): bulk stiffnesses rise with Young's modulus and with
// k2/k1 (seed 000 Fig. 20-21), unload stiffer than load (§3.2.2.1); a cohesive bed built by
// cluster formation is more compressible than a poured one (§2.7.1); blow-ups are typed failures.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/error.hpp"
#include "core/lab/piston.hpp"
#include "core/sim/time_step.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

Settings small() {
  return {{"particles", 120}, {"cycles", 1}, {"wall_stiffness_factor", 1}};
}

void expect_rising(const std::vector<LabOutput>& runs, const char* what) {
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& m = runs[i].metrics;
    EXPECT_GT(m.at("k_unload"), m.at("k_load")) << what << " level " << i;
    EXPECT_GT(m.at("compressibility"), 0.0);
    EXPECT_GT(m.at("final_solid_fraction"), 0.5);
    EXPECT_LT(m.at("final_solid_fraction"), 0.75);
    EXPECT_GT(m.at("confined_modulus"), 0.0);
    if (i > 0) {
      EXPECT_GT(m.at("k_load"), runs[i - 1].metrics.at("k_load")) << what << " level " << i;
      EXPECT_GT(m.at("k_unload"), runs[i - 1].metrics.at("k_unload")) << what << " level " << i;
    }
  }
}

TEST(ConfinedCompression, StiffnessesRiseWithYoungsModulus) {
  std::vector<LabOutput> runs;
  for (double y : {3e6, 1e7, 3e7})
    runs.push_back(run_lab_test("confined_compression", testing::soft_luding(y), small(), {}));
  expect_rising(runs, "Y");
  // The stress-strain series covers the load, the cycle and the final unload.
  const auto& s = runs[0].series.at("stress_strain");
  ASSERT_GT(s.rows.size(), 10u);
  EXPECT_EQ(s.rows.back()[3], 4.0);  // phases: load, unload, reload, final unload
}

TEST(ConfinedCompression, StiffnessesRiseWithK2Ratio) {
  std::vector<LabOutput> runs;
  for (double f : {2.0, 5.0, 15.0})
    runs.push_back(run_lab_test("confined_compression", testing::soft_luding(1e7, f), small(), {}));
  expect_rising(runs, "k2/k1");
}

TEST(ConfinedCompression, ClusterPreparationMakesACohesiveBedMoreCompressible) {
  // Granular Bond number about 100 (A_H 1e-17 J, d_min 0.4 nm, 1 mm spheres): clusters formed
  // without gravity hold open structures that pouring (cohesion only in contact) does not
  // build (seed 000 §2.7.1, Fig. 5; Yang, Zou & Yu 2000: looser with stronger cohesion).
  auto poured = testing::soft_luding(1e7, 5.0, 0.2, 1e-17);
  auto clustered = poured;
  clustered.preparation.method = PreparationMethod::kClusters;
  const auto a = run_lab_test("confined_compression", poured, small(), {});
  const auto b = run_lab_test("confined_compression", clustered, small(), {});
  // Measured in one portable build: 16.6 % poured, 43.4 % from clusters (seed 000 Table 4:
  // LH220 46.3 %, which its poured beds did not reach).
  EXPECT_GT(b.metrics.at("compressibility"), a.metrics.at("compressibility") + 10.0);
  bool prepared = false;
  for (const auto& phase : b.cost.phases) prepared |= phase.name == "prepare clusters";
  EXPECT_TRUE(prepared);
}

TEST(ConfinedCompression, AMuchStifferPistonShortensTheStepAtOnce) {
  // A piston law made 1e4 times stiffer after the time step was chosen: the step follows the
  // stiffest contact in use, so it shrinks at the first step the piston touches the bed (to
  // 0.2 sqrt(m/k) of that contact: a few hundredths of the step before) and the bed stays
  // sound.
  const auto m = testing::soft_luding();
  PistonBed bed = make_piston_bed(m, testing::bare_bed(150), {});
  sim::World& w = bed.world;
  const double dt_before = w.dt;
  const auto stiff = simulated_law(m, stiffen_normal(m.wall_law, 1e4));
  w.change_wall_law(kWallPiston, 0, stiff);
  const double mass = w.particles.mass[0];
  const double k_stiff = stiff.reached_stiffness(2.0 * w.particles.radius[0], 0.0);
  bool touched = false;
  servo_phase(
      w, bed.piston, bed.piston, {0, 0, -1}, bed.area, 1000.0,
      ServoSettings{0.01, 1e-5, 0, 0, 10.0, 1e-4, 2e-4}, bed.limits,
      [&](const sim::World& world, double stress) {
        if (stress <= 0.0) return;
        // At least as stiff as a fresh contact of the stiff law.
        EXPECT_LE(world.dt, (1.0 + 1e-9) * 0.2 * std::sqrt(mass / k_stiff));
        touched = true;
      },
      1);
  EXPECT_TRUE(touched);
  EXPECT_LT(w.dt, 0.05 * dt_before);
}

TEST(ConfinedCompression, AbsurdTimeStepIsATypedFailure) {
  // A piston bed stepped at a fixed step 250 times its stable one (the adapted step would
  // shrink back at once) blows up: a typed failure.
  PistonBed bed = make_piston_bed(testing::soft_luding(), testing::bare_bed(150), {});
  bed.world.adaptive_safety = 0.0;
  bed.world.dt *= 250.0;
  try {
    servo_phase(bed.world, bed.piston, bed.piston, {0, 0, -1}, bed.area, 1000.0,
                ServoSettings{0.01, 1e-5, 0, 0, 10.0, 0.5, 1.0}, bed.limits);
    FAIL() << "expected a SimulationFailure";
  } catch (const SimulationFailure& e) {
    EXPECT_NE(std::string(to_string(e.reason())), "") << e.what();
  }
}
}  // namespace
}  // namespace demcal::lab
