// Scale and convergence studies (seed 001 App. B; seed 004 §3.1).
#include <gtest/gtest.h>

#include "core/common/error.hpp"
#include "core/lab/study.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

MaterialModel glass() {
  MaterialModel m;
  m.particle_law.normal = {"hertz", {{"youngs_modulus", 5e6}, {"restitution", 0.3}}};
  m.particle_law.tangential = {"history", {{"mu_s", 0.3}}};
  m.wall_law = m.particle_law;
  m.sizes = particles::Monodisperse{5e-4};
  m.density = 2500.0;
  return m;
}

TEST(Study, ParticleCountsReportEveryMetric) {
  const auto r = run_study("packing", glass(), {}, {}, StudyAxis::kParticles, {100, 200});
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_EQ(r.runs[1].particles, 200.0);
  for (const char* name : {"solid_fraction", "coordination_number"}) {
    ASSERT_EQ(r.relative_change.at(name).size(), 1u);
    const double a = r.runs[0].metrics.at(name), b = r.runs[1].metrics.at(name);
    EXPECT_NEAR(r.relative_change.at(name)[0], (b - a) / a, 1e-12);
    EXPECT_LT(r.max_deviation_from_last.at(name), 0.15) << name;  // converging packing
  }
}

TEST(Study, ScaleFactorsKeepTheRealSystem) {
  auto m = glass();
  m.scaling = contact::ScalingLaw::kKottlan2018;
  const auto r =
      run_study("packing", m, {{"particles", 270}}, {}, StudyAxis::kScaleFactor, {1.0, 1.5});
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_EQ(r.runs[0].particles, 270.0);
  EXPECT_EQ(r.runs[1].particles, 80.0);  // 270 / 1.5^3
  EXPECT_NEAR(r.runs[1].metrics.at("solid_fraction"), r.runs[0].metrics.at("solid_fraction"), 0.08);
}

TEST(Study, ScaleStudyNeedsAScalingLaw) {
  EXPECT_THROW(run_study("packing", glass(), {}, {}, StudyAxis::kScaleFactor, {1, 2}), InputError);
}

}  // namespace
}  // namespace demcal::lab
