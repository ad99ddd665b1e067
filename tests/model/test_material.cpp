// The material model's parameters set by path in one call, as the coordinator validates a
// campaign's fixed values and factor bounds: every value set, or the first wrong one named.
#include <gtest/gtest.h>

#include <cmath>

#include "core/common/error.hpp"
#include "core/model/material.hpp"

namespace demcal::lab {
namespace {

MaterialModel hertz(double mu_s) {
  MaterialModel m;
  m.particle_law.normal = {
      "hertz", {{"youngs_modulus", 5e7}, {"poisson_ratio", 0.25}, {"restitution", 0.5}}};
  m.particle_law.tangential = {"history", {{"mu_s", mu_s}}};
  m.wall_law = m.particle_law;
  m.density = 2500.0;
  return m;
}

std::string where_of(const MaterialModel& m, const std::vector<ParameterValue>& values) {
  try {
    with_parameters(m, values);
  } catch (const InputError& e) {
    return e.where();
  }
  return "";
}

TEST(MaterialParameters, EveryValueIsSetInOneCall) {
  const MaterialModel m =
      with_parameters(hertz(0.3), {{"particle_law.tangential.mu_s", 0.45, "spec.fixed.a"},
                                   {"density", 1800.0, "spec.fixed.b"},
                                   {"wall_law.normal.restitution", 0.7, "spec.fixed.c"}});
  EXPECT_DOUBLE_EQ(get_parameter(m, "particle_law.tangential.mu_s"), 0.45);
  EXPECT_DOUBLE_EQ(get_parameter(m, "density"), 1800.0);
  EXPECT_DOUBLE_EQ(get_parameter(m, "wall_law.normal.restitution"), 0.7);
  EXPECT_DOUBLE_EQ(get_parameter(m, "particle_law.normal.restitution"), 0.5);
}

TEST(MaterialParameters, TheFirstWrongValueIsNamedByItsField) {
  const MaterialModel m = hertz(0.3);
  EXPECT_EQ(where_of(m, {{"density", 1800.0, "spec.fixed.density"},
                         {"particle_law.rolling.mu_r", 0.1, "spec.fixed.rolling"}}),
            "spec.fixed.rolling");  // no rolling model: not a parameter of this material
  EXPECT_EQ(where_of(m, {{"particle_law.tangential.mu_s", -0.1, "spec.factors[0].low"}}),
            "spec.factors[0].low");
  EXPECT_EQ(where_of(m, {{"density", 0.0, "spec.fixed.density"},
                         {"particle_law.tangential.mu_s", -0.1, "spec.fixed.mu_s"}}),
            "spec.fixed.density");
  EXPECT_EQ(where_of(m, {{"density", 1800.0, "a"}}), "");
  // The given model is not changed, whether the call fails or not.
  EXPECT_DOUBLE_EQ(get_parameter(m, "density"), 2500.0);
}

TEST(MaterialParameters, TheRealMedianRadiusIsUnstatedOrInRange) {
  MaterialModel m = hertz(0.3);
  m.validate();  // 0: not stated
  m.real_median_radius = 6.5e-6;
  m.validate();
  for (const double bad : {-1e-5, 1e-10, 11.0, std::nan("")}) {
    m.real_median_radius = bad;
    try {
      m.validate();
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "real_median_radius") << bad;
    }
  }
}

}  // namespace
}  // namespace demcal::lab
