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

TEST(Study, RunsTheJournalHoldsAreTakenInsteadOfRunAgain) {
  RunOptions o;
  o.seed = 3;
  std::vector<std::pair<double, StudyReplicate>> added;
  const StudyJournal record{{},
                            [&](double v, const StudyReplicate& r) { added.emplace_back(v, r); }};
  const auto first =
      run_study("packing", glass(), {}, o, StudyAxis::kParticles, {60, 120}, 2, record);
  ASSERT_EQ(added.size(), 4u);  // every value and seed, as they finish
  EXPECT_EQ(added[1].first, 60.0);
  EXPECT_EQ(added[1].second.seed, 4u);
  EXPECT_EQ(added[3].first, 120.0);
  // A journal that holds the 60-particle runs (marked by their wall time): those are taken, the
  // 120-particle runs are run and added again, and the study comes out the same.
  std::vector<std::pair<double, StudyReplicate>> again;
  const StudyJournal half{[&](double v, std::uint64_t seed) -> std::optional<StudyReplicate> {
                            for (auto [value, r] : added)
                              if (value == v && r.seed == seed && v == 60.0) {
                                r.wall_seconds = 1e6;
                                return r;
                              }
                            return std::nullopt;
                          },
                          [&](double v, const StudyReplicate& r) { again.emplace_back(v, r); }};
  const auto second =
      run_study("packing", glass(), {}, o, StudyAxis::kParticles, {60, 120}, 2, half);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[0].first, 120.0);
  EXPECT_EQ(second.runs[0].replicates[0].wall_seconds, 1e6);
  EXPECT_NE(second.runs[1].replicates[0].wall_seconds, 1e6);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(second.runs[i].metrics, first.runs[i].metrics);
    EXPECT_EQ(second.runs[i].spread, first.runs[i].spread);
  }
  EXPECT_EQ(second.converged_from, first.converged_from);
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

/// A study value with the given means and spreads of metric "m", as if from three seeds.
StudyRun summary(double value, double mean, double sd, bool flagged = false) {
  StudyRun r;
  r.value = value;
  r.metrics["m"] = mean;
  r.spread["m"] = sd;
  if (flagged) r.flagged.insert("m");
  return r;
}

TEST(Study, ConvergedFromTheFirstValueEveryLaterOneMatchesWithinTheSpread) {
  // 1.00 -> 1.50 is far beyond the combined spread 0.14; 1.50, 1.52, 1.45 agree pairwise.
  std::vector<StudyRun> runs{summary(250, 1.0, 0.1), summary(500, 1.5, 0.1),
                             summary(1000, 1.52, 0.1), summary(2000, 1.45, 0.05)};
  EXPECT_EQ(converged_index(runs, "m"), std::optional<std::size_t>(1));
  // Agreement with the next value alone is not enough: every later one must agree.
  runs[3] = summary(2000, 1.8, 0.05);
  EXPECT_EQ(converged_index(runs, "m"), std::nullopt);
  // A flagged run never counts as agreeing.
  runs[3] = summary(2000, 1.5, 0.05, true);
  EXPECT_EQ(converged_index(runs, "m"), std::nullopt);
  // Without spread only equal means agree (a yes/no metric that stays the same).
  EXPECT_EQ(converged_index({summary(1, 0.0, 0.0), summary(2, 0.0, 0.0)}, "m"),
            std::optional<std::size_t>(0));
  EXPECT_EQ(converged_index({summary(1, 0.3, 0.0), summary(2, 0.31, 0.0)}, "m"), std::nullopt);
  // The last value alone has nothing to agree with.
  EXPECT_EQ(converged_index({summary(1, 1.0, 0.1)}, "m"), std::nullopt);
}

TEST(Study, SeedsGiveMeansSpreadsAndTheChosenSize) {
  RunOptions o;
  o.seed = 7;
  const auto r = run_study("packing", glass(), {}, o, StudyAxis::kParticles, {60, 120}, 2);
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_EQ(r.seeds, 2);
  bool every = true;
  for (const auto& metric : find_lab_info("packing").metrics) {
    ASSERT_TRUE(r.converged_from.count(metric.name)) << metric.name;
    const auto& from = r.converged_from.at(metric.name);
    if (!from) every = false;
    if (from) {
      EXPECT_EQ(*from, 60.0) << metric.name;  // the only value before the last
    }
  }
  EXPECT_EQ(r.chosen.has_value(), every);
  if (r.chosen) {
    EXPECT_EQ(*r.chosen, 60.0);
  }
  for (const auto& run : r.runs) {
    ASSERT_EQ(run.replicates.size(), 2u);
    EXPECT_EQ(run.replicates[0].seed, 7u);
    EXPECT_EQ(run.replicates[1].seed, 8u);
    const double a = run.replicates[0].metrics.at("solid_fraction");
    const double b = run.replicates[1].metrics.at("solid_fraction");
    EXPECT_NE(a, b);  // different beds
    EXPECT_DOUBLE_EQ(run.metrics.at("solid_fraction"), 0.5 * (a + b));
    EXPECT_NEAR(run.spread.at("solid_fraction"), std::abs(a - b) / std::sqrt(2.0), 1e-12);
  }
  EXPECT_THROW(run_study("packing", glass(), {}, o, StudyAxis::kParticles, {60, 120}, 0),
               InputError);
  EXPECT_THROW(
      run_study("packing", glass(), {}, o, StudyAxis::kParticles, {60, 120}, kMaxStudySeeds + 1),
      InputError);
}

TEST(Study, CoarseGrainingAtAFixedCountIsASimilarity) {
  // Both scaling laws map a bed onto a geometrically similar one: lengths x l, masses kept, forces
  // kept (stiffness / l times overlap x l; van der Waals A_H l R l / (l D_min)^2), so the time
  // step and every process time grow as sqrt(l) and the settings' stresses are scaled by 1 / l^2.
  // At a fixed particle count the factor changes no metric; with l = 4 every product is exact (the
  // time step doubles), so not a bit. (It matters through the size of the real system only, which
  // a scale study keeps: fewer particles at a larger factor.)
  for (auto law : {contact::ScalingLaw::kKottlan2018, contact::ScalingLaw::kTiscar2019}) {
    auto m = testing::soft_luding(1e7, 5.0, 0.5, 1e-16);
    m.scaling = law;
    Settings s{{"particles", 60}};
    const auto base = run_lab_test("packing", m, s, {});
    m.scale_factor = law == contact::ScalingLaw::kKottlan2018 ? 4.0 : 64.0;  // l = 4 for both
    const auto scaled = run_lab_test("packing", m, s, {});
    EXPECT_EQ(scaled.metrics, base.metrics);
    EXPECT_EQ(scaled.cost.steps, base.cost.steps);
    EXPECT_GT(base.metrics.at("solid_fraction"), 0.2);
  }
}

TEST(Study, ScaleStudyNeedsAScalingLaw) {
  EXPECT_THROW(run_study("packing", glass(), {}, {}, StudyAxis::kScaleFactor, {1, 2}), InputError);
}

}  // namespace
}  // namespace demcal::lab
