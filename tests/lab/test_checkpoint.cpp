// Checkpoints of lab tests: a run that goes on from the checkpoint an earlier run offered gives
// the metrics of the uninterrupted run to the last bit (the runs are deterministic for a thread
// count, and the checkpoint holds the whole state the steps carry), for a cohesive bed whose
// preparation changes the contact law and for rigid rods; a checkpoint the test never reaches,
// or a damaged one, is refused naming it.
#include <gtest/gtest.h>

#include "core/common/error.hpp"
#include "core/lab/lab_test.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

/// Runs the test once from the start, keeping the checkpoint it offers.
LabOutput run_keeping_checkpoint(const std::string& test, const MaterialModel& material,
                                 const Settings& settings, Checkpoint& kept) {
  RunOptions options;
  options.seed = 3;
  options.checkpoint = [&kept](const std::string& stage,
                               const std::function<std::string()>& record) {
    kept = {stage, record()};
  };
  return run_lab_test(test, material, settings, options);
}

LabOutput resumed(const std::string& test, const MaterialModel& material, const Settings& settings,
                  const Checkpoint& from) {
  RunOptions options;
  options.seed = 3;
  options.resume = from;
  return run_lab_test(test, material, settings, options);
}

void expect_same_run(const LabOutput& whole, const LabOutput& resumed_run) {
  ASSERT_EQ(whole.metrics.size(), resumed_run.metrics.size());
  for (const auto& [name, value] : whole.metrics)
    EXPECT_EQ(value, resumed_run.metrics.at(name)) << name;  // exact: the same bits
  EXPECT_EQ(whole.flags, resumed_run.flags);
  ASSERT_EQ(whole.cost.phases.size(), resumed_run.cost.phases.size());
  for (std::size_t k = 0; k < whole.cost.phases.size(); ++k)
    EXPECT_EQ(whole.cost.phases[k].steps, resumed_run.cost.phases[k].steps)
        << whole.cost.phases[k].name;
  EXPECT_EQ(whole.cost.steps, resumed_run.cost.steps);
  for (const auto& [name, series] : whole.series)
    EXPECT_EQ(series.rows, resumed_run.series.at(name).rows) << name;
}

TEST(Checkpoint, ACohesiveCompressionGoesOnFromItsBedToTheSameBits) {
  // Van der Waals cohesion: the bed settles with cohesion in contact only and then gets the full
  // law back, so the resumed world must be the one of the full law.
  const auto material = testing::soft_luding(1e7, 5.0, 0.2, 1e-17);
  const Settings settings{{"particles", 80}, {"cycles", 1}, {"wall_stiffness_factor", 1}};
  Checkpoint kept;
  const LabOutput whole = run_keeping_checkpoint("confined_compression", material, settings, kept);
  ASSERT_EQ(kept.stage, "piston bed");
  EXPECT_TRUE(whole.resumed_from.empty());
  const LabOutput again = resumed("confined_compression", material, settings, kept);
  EXPECT_EQ(again.resumed_from, "piston bed");
  ASSERT_FALSE(again.notes.empty());
  EXPECT_NE(again.notes.front().find("checkpoint 'piston bed'"), std::string::npos);
  expect_same_run(whole, again);
  EXPECT_GT(whole.metrics.at("compressibility"), 0.0);
}

TEST(Checkpoint, RodsInTheWallFrictionTestGoOnToTheSameBits) {
  MaterialModel rods = testing::soft_luding();
  rods.shape = particles::make_shape_spec("rod", {{"aspect_ratio", 1.5}}, "shape");
  const Settings settings{{"particles", 30}};
  Checkpoint kept;
  const LabOutput whole = run_keeping_checkpoint("wall_friction", rods, settings, kept);
  ASSERT_EQ(kept.stage, "piston bed");
  expect_same_run(whole, resumed("wall_friction", rods, settings, kept));
}

TEST(Checkpoint, AStageTheTestNeverReachesOrADamagedRecordIsRefused) {
  const auto material = testing::soft_luding();
  const Settings settings{{"particles", 30}};
  Checkpoint kept;
  run_keeping_checkpoint("wall_friction", material, settings, kept);
  auto refusal = [&](const std::string& test, const Checkpoint& from) {
    try {
      resumed(test, material, settings, from);
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "checkpoint");
      return e.message();
    }
    return std::string("accepted");
  };
  // The packing test has no piston bed to go on from.
  EXPECT_NE(refusal("packing", kept).find("'piston bed' is not one the packing test"),
            std::string::npos);
  Checkpoint damaged = kept;
  damaged.state.resize(damaged.state.size() - 9);
  EXPECT_NE(refusal("wall_friction", damaged).find("truncated"), std::string::npos);
  // Another material's laws (a Hertz law keeps no reached overlap: another history size).
  try {
    RunOptions options;
    options.resume = kept;
    run_lab_test("wall_friction", testing::hertz_spheres(0.3), settings, options);
    ADD_FAILURE() << "a checkpoint of other laws was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("other contact laws"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace demcal::lab
