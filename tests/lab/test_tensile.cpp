// tensile (seed 000 §2.7.3): about zero without cohesion; rises with the Hamaker constant and
// with kc/k1; a bed conditioned at a low stress keeps its height through the unload; a peak at
// the end of the pull is flagged; starts from the bed a confined compression of the same settings
// conditioned, taken from the stage cache to the bit; a material out of the contact range is
// refused also when the stage cache holds its bed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>

#include "core/common/error.hpp"
#include "core/lab/bed.hpp"
#include "core/lab/confinement.hpp"
#include "core/lab/lab_run.hpp"
#include "core/lab/stage_cache.hpp"
#include "core/model/tensile_settings.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

Settings small() {
  return {{"particles", 100},    {"wall_stiffness_factor", 1},   {"wall_hamaker_factor", 10},
          {"wall_k2_factor", 1}, {"consolidation_stress", 5000}, {"pull_distance", 1},
          {"cycles", 1}};
}
/// The confined compression whose bed small() starts from.
Settings conditioning() {
  return {{"particles", 100}, {"wall_stiffness_factor", 1}, {"max_stress", 5000}, {"cycles", 1}};
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

/// Cohesive spheres with sliding and rolling friction (CDT) against each other and the die: a bed
/// whose die friction screens much of a consolidation of 1.5 kPa from its lower part.
MaterialModel screened_bed() {
  MaterialModel m = testing::soft_luding(1e7, 5.0, 0.5, 4e-18, 0.6);
  m.particle_law.tangential.params["mu_s"] = 0.6;
  m.particle_law.rolling = {"cdt", {{"mu_r", 0.1}}};
  m.wall_law.rolling = m.particle_law.rolling;
  return m;
}

/// small() with the bed conditioned at 1.5 kPa, cycled to 50 Pa.
Settings low_consolidation(int particles) {
  Settings low = small();
  low["particles"] = particles;
  low["consolidation_stress"] = 1500;
  low["min_stress"] = 50;
  return low;
}

TEST(Tensile, ABedConditionedAtALowStressKeepsItsHeightThroughTheUnload) {
  const LabOutput out = run_lab_test("tensile", screened_bed(), low_consolidation(200), {});
  EXPECT_TRUE(out.flags.empty());
  // The unload to 50 Pa runs against the die the bed was consolidated in. Made frictionless
  // before it, the die let this bed compact by 2.5 % under the unload's stress.
  const auto& fracture = out.series.at("fracture");
  const auto column = [&](const std::string& name) {
    const auto at = std::find(fracture.columns.begin(), fracture.columns.end(), name);
    return fracture.rows.at(0).at(static_cast<std::size_t>(at - fracture.columns.begin()));
  };
  const double conditioned = column("conditioned_height_m");
  EXPECT_NEAR(column("unloaded_height_m"), conditioned, 1e-3 * conditioned);
  EXPECT_GT(out.metrics.at("tensile_strength"), 0.03);
}

TEST(Tensile, APeakInThePullsLastTenthFlagsTheStrength) {
  Settings low = low_consolidation(150);
  // This bed still stretches at the end of a pull of one diameter: its stress has not peaked.
  const LabOutput short_pull = run_lab_test("tensile", screened_bed(), low, {});
  ASSERT_EQ(short_pull.flags.count("tensile_strength"), 1u);
  EXPECT_NE(short_pull.flags.at("tensile_strength").find("peak"), std::string::npos);
  // Pulled twice as far, it breaks: the peak lies inside the pull, nothing is flagged.
  low["pull_distance"] = 2;
  EXPECT_TRUE(run_lab_test("tensile", screened_bed(), low, {}).flags.empty());
}

/// A fresh stage cache in a directory of its own.
std::shared_ptr<const StageCache> fresh_cache(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("demcal_stage_cache_" + name);
  std::filesystem::remove_all(dir);
  return std::make_shared<const StageCache>(dir);
}

std::int64_t steps_of(const LabOutput& out) {
  std::int64_t steps = 0;
  for (const auto& p : out.cost.phases) steps += p.steps;
  return steps;
}

TEST(Tensile, StartsFromTheBedAConfinedCompressionConditionedToTheBit) {
  const auto m = testing::soft_luding(1e7, 5.0, 0.5, 1e-18);
  const LabOutput alone = run_lab_test("tensile", m, small(), {});
  RunOptions cached;
  cached.stage_cache = fresh_cache("tensile");
  const LabOutput compression = run_lab_test("confined_compression", m, conditioning(), cached);
  ASSERT_TRUE(compression.flags.empty());
  const LabOutput reused = run_lab_test("tensile", m, small(), cached);
  // The same bits as the run that conditioned its own bed, for a fraction of its steps.
  EXPECT_EQ(reused.metrics.at("tensile_strength"), alone.metrics.at("tensile_strength"));
  EXPECT_EQ(reused.series.at("tensile").rows, alone.series.at("tensile").rows);
  // The fracture record too, the conditioned bed's height included.
  EXPECT_EQ(reused.series.at("fracture").rows, alone.series.at("fracture").rows);
  EXPECT_LT(steps_of(reused), steps_of(alone) / 2);
  ASSERT_FALSE(reused.notes.empty());
  EXPECT_NE(reused.notes.back().find("stage cache"), std::string::npos);
  std::vector<std::string> phases;
  for (const auto& p : reused.cost.phases) phases.push_back(p.name);
  EXPECT_EQ(phases, (std::vector<std::string>{"unload", "pull"}));
  // A record this build cannot read counts as absent: the bed is conditioned afresh.
  const auto cs = read_settings<ConfinedCompressionSettings>(conditioning(), "settings");
  cached.stage_cache->keep(conditioned_bed_identity(m, cs, cached), "not a bed");
  const LabOutput unreadable = run_lab_test("tensile", m, small(), cached);
  EXPECT_EQ(unreadable.metrics.at("tensile_strength"), alone.metrics.at("tensile_strength"));
  EXPECT_EQ(steps_of(unreadable), steps_of(alone));
  // Another seed is another bed: conditioned afresh, the same as without the cache.
  RunOptions other = cached;
  other.seed = 2;
  RunOptions other_alone;
  other_alone.seed = 2;
  EXPECT_EQ(run_lab_test("tensile", m, small(), other).metrics.at("tensile_strength"),
            run_lab_test("tensile", m, small(), other_alone).metrics.at("tensile_strength"));
}

// A material whose attraction alone overlaps a pair beyond its radius is refused before the
// first step (sim::check_contact_range), also when the conditioned bed it would start from is in
// the stage cache: a record made by a build that did not refuse the law (here another material's
// bed, kept under this one's identity) is never simulated on.
TEST(Tensile, AMaterialOutOfTheContactRangeIsRefusedAlsoFromAStageRecord) {
  const auto in_range = testing::soft_luding(1e7, 5.0, 0.5, 1e-18);
  const auto out_of_range = testing::soft_luding(1e7, 5.0, 0.5, 1e-14);
  EXPECT_NO_THROW(check_contact_range(in_range));
  EXPECT_THROW(check_contact_range(out_of_range), SimulationFailure);
  RunOptions cached;
  cached.stage_cache = fresh_cache("out_of_range");
  run_lab_test("confined_compression", in_range, conditioning(), cached);
  const auto cs = read_settings<ConfinedCompressionSettings>(conditioning(), "settings");
  const auto record = cached.stage_cache->find(conditioned_bed_identity(in_range, cs, cached));
  ASSERT_TRUE(record);
  cached.stage_cache->keep(conditioned_bed_identity(out_of_range, cs, cached), *record);
  try {
    run_lab_test("tensile", out_of_range, small(), cached);
    ADD_FAILURE() << "the tensile test ran on a material out of the contact range";
  } catch (const SimulationFailure& e) {
    EXPECT_EQ(e.reason(), SimulationFailure::Reason::kContactOutOfRange) << e.what();
  }
}

TEST(StageCache, KeepsARecordUnderItsWholeIdentity) {
  const auto cache = fresh_cache("records");
  EXPECT_FALSE(cache->find("a").has_value());
  cache->keep("a", std::string("record\0a", 8));
  cache->keep("b", "record b");
  EXPECT_EQ(*cache->find("a"), std::string("record\0a", 8));
  EXPECT_EQ(*cache->find("b"), "record b");
  cache->keep("a", "again");
  EXPECT_EQ(*cache->find("a"), "again");
  // A damaged file counts as absent.
  for (const auto& entry : std::filesystem::directory_iterator(cache->directory()))
    std::ofstream(entry.path(), std::ios::trunc) << "xy";
  EXPECT_FALSE(cache->find("a").has_value());
  EXPECT_FALSE(cache->find("b").has_value());
  // No half-written files are left behind.
  for (const auto& entry : std::filesystem::directory_iterator(cache->directory()))
    EXPECT_EQ(entry.path().extension(), ".stage");
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
