// packing (seed 000 §2.7.1, §3.1): cohesionless mono-sized pouring gives 0.57-0.64; every method
// runs; with van der Waals cohesion the solid fraction falls as the particle size falls (Fig. 14).
#include <gtest/gtest.h>

#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

MaterialModel cohesionless() {
  MaterialModel m;
  m.particle_law.normal = {"hertz", {{"youngs_modulus", 5e6}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.2}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{5e-4};
  m.density = 2500.0;
  return m;
}

TEST(Packing, CohesionlessPouringIsRandomPacking) {
  const auto out = run_lab_test("packing", cohesionless(), {{"particles", 400}}, {});
  EXPECT_GE(out.metrics.at("solid_fraction"), 0.57);
  EXPECT_LE(out.metrics.at("solid_fraction"), 0.64);
  EXPECT_GT(out.metrics.at("coordination_number"), 4.0);
}

TEST(Packing, EveryMethodBuildsABed) {
  for (double method : {1.0, 2.0, 3.0}) {
    const auto out =
        run_lab_test("packing", cohesionless(), {{"particles", 200}, {"method", method}}, {});
    EXPECT_GT(out.metrics.at("solid_fraction"), 0.5) << "method " << method;
    EXPECT_LT(out.metrics.at("solid_fraction"), 0.66) << "method " << method;
  }
}

TEST(Packing, VanDerWaalsSolidFractionFallsWithParticleSize) {
  std::vector<double> phi;
  for (double r : {2e-3, 6e-4, 2e-4}) {
    auto m = testing::soft_luding(1e7, 5.0, 0.0, 1e-19);
    m.particle_law.cohesion.params["d_max"] = 1e-6;
    m.sizes = particles::Monodisperse{r};
    phi.push_back(run_lab_test("packing", m, {{"particles", 150}, {"method", 1}}, {})
                      .metrics.at("solid_fraction"));
  }
  EXPECT_GT(phi[0], phi[1]);
  EXPECT_GT(phi[1], phi[2]);
}

}  // namespace
}  // namespace demcal::lab
