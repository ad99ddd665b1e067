// tensile (seed 000 §2.7.3): about zero without cohesion; rises with the Hamaker constant and
// with kc/k1.
#include <gtest/gtest.h>

#include "core/lab/lab_test.hpp"
#include "core/model/tensile_settings.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

Settings small() {
  return {{"particles", 100},    {"wall_stiffness_factor", 1},   {"wall_hamaker_factor", 10},
          {"wall_k2_factor", 1}, {"consolidation_stress", 5000}, {"pull_distance", 1}};
}
double strength(const MaterialModel& m) {
  return run_lab_test("tensile", m, small(), {}).metrics.at("tensile_strength");
}

TEST(Tensile, AboutZeroWithoutCohesion) {
  const double t0 = strength(testing::soft_luding(1e7, 5.0, 0.0, 0.0));
  EXPECT_LT(std::abs(t0), 0.03) << "kPa";
}

TEST(Tensile, RisesWithHamakerConstant) {
  const double a = strength(testing::soft_luding(1e7, 5.0, 0.0, 1e-18));
  const double b = strength(testing::soft_luding(1e7, 5.0, 0.0, 4e-18));
  EXPECT_GT(a, 0.03);
  EXPECT_GT(b, 1.5 * a);
}

TEST(Tensile, RisesWithCohesionStiffness) {
  const double a = strength(testing::soft_luding(1e7, 5.0, 0.0, 1e-18));
  const double b = strength(testing::soft_luding(1e7, 5.0, 1.0, 1e-18));
  EXPECT_GT(b, 1.5 * a);
}

TEST(Tensile, WallAdhesionFactorsOfEq34And35) {
  // seed 000 eq. 34-35 at the ends of the fitted radius range (5 and 50 um), clamped beyond.
  EXPECT_DOUBLE_EQ(wall_hamaker_ratio_eq34(5.0), 10.0);
  EXPECT_DOUBLE_EQ(wall_hamaker_ratio_eq34(50.0), 100.0);
  EXPECT_DOUBLE_EQ(wall_k2_ratio_eq35(50.0), 15.0);
  EXPECT_DOUBLE_EQ(wall_k2_ratio_eq35(1000.0), 15.0);
}

}  // namespace
}  // namespace demcal::lab
