// hopper (seed 000 §2.7.6): cohesionless mono-sized spheres discharge within 20 % of Beverloo's
// slot law with Rose and Tanaka's wall factor (15 % at 1,000 particles and more: bench/hopper.sh);
// strong van der Waals cohesion arches a narrow outlet.
#include <gtest/gtest.h>

#include <cmath>

#include "core/lab/hopper.hpp"
#include "core/lab/lab_run.hpp"

namespace demcal::lab {
namespace {

MaterialModel spheres(double hamaker) {
  MaterialModel m;
  m.particle_law.normal = {"hertz",
                           {{"youngs_modulus", 5e6}, {"poisson_ratio", 0.3}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.5}}};
  if (hamaker > 0.0)
    m.particle_law.cohesion = {"van_der_waals", {{"hamaker", hamaker}, {"d_max", 1e-5}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{0.001};
  m.density = 2500;
  return m;
}

TEST(LabHopper, RoseTanakaFactorOfSteepWalls) {
  // (tan 20 deg)^-0.35 = 0.363970^-0.35 = exp(0.35 x 1.010683) = 1.42438; none from 45 deg on.
  EXPECT_NEAR(rose_tanaka_factor(20.0 * M_PI / 180.0), 1.42438, 1e-5);
  EXPECT_DOUBLE_EQ(rose_tanaka_factor(45.0 * M_PI / 180.0), 1.0);
  EXPECT_DOUBLE_EQ(rose_tanaka_factor(60.0 * M_PI / 180.0), 1.0);
}

TEST(LabHopper, CohesionlessSpheresDischargeAtBeverlooWithTheWallFactor) {
  RunOptions opt;
  const auto out = run_lab_test("hopper", spheres(0.0), {{"particles", 400}}, opt);
  EXPECT_EQ(out.metrics.at("arched"), 0.0);
  EXPECT_GT(out.metrics.at("discharged_fraction"), 0.99);
  EXPECT_GT(out.metrics.at("discharge_rate"), 0.0);
  EXPECT_NEAR(out.metrics.at("beverloo_ratio"), 1.0, 0.2);
}

TEST(LabHopper, StrongCohesionArchesANarrowOutlet) {
  RunOptions opt;
  // Bond number (pull-off over weight) ~100 and a slot of three diameters.
  const auto out = run_lab_test("hopper", spheres(1e-17), {{"particles", 300}, {"outlet", 3}}, opt);
  EXPECT_EQ(out.metrics.at("arched"), 1.0);
  EXPECT_LT(out.metrics.at("discharged_fraction"), 0.5);
}

}  // namespace
}  // namespace demcal::lab
