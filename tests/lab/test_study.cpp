// Scale and convergence studies (seed 001 App. B; seed 004 §3.1).
#include <gtest/gtest.h>

#include <cmath>

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

TEST(Study, DrumScaleStudyKeepsTheDrumAndCoarsensItsBed) {
  // The drum is sized by its geometry: at twice lambda (seed 001 eq. 15) the same 25 x 11 mm drum
  // holds half the particles, each 2^(1/3) larger, so D/d falls by 2^(1/3) (App. B).
  auto m = glass();
  m.sizes = particles::Monodisperse{1e-3};
  m.scaling = contact::ScalingLaw::kTiscar2019;
  const Settings drum{{"diameter", 25}, {"length", 11}, {"angle_time", 0.1}, {"area_time", 0.02}};
  const auto r = run_study("rotating_drum", m, drum, {}, StudyAxis::kScaleFactor, {1.0, 2.0});
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_NEAR(r.runs[0].particles / r.runs[1].particles, 2.0, 0.02);
  EXPECT_EQ(r.runs[0].metrics.at("drum_diameter"), r.runs[1].metrics.at("drum_diameter"));
  EXPECT_NEAR(
      r.runs[0].metrics.at("drum_diameter_ratio") / r.runs[1].metrics.at("drum_diameter_ratio"),
      std::cbrt(2.0), 1e-9);
  // A particle-count study of a test that has no count is refused.
  EXPECT_THROW(run_study("rotating_drum", m, drum, {}, StudyAxis::kParticles, {100, 200}),
               InputError);
}

TEST(Study, ScaleStudyNeedsAScalingLaw) {
  EXPECT_THROW(run_study("packing", glass(), {}, {}, StudyAxis::kScaleFactor, {1, 2}), InputError);
}

}  // namespace
}  // namespace demcal::lab
