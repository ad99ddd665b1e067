// Checkpoints of lab tests: a run that goes on from any checkpoint an earlier run offered gives
// the metrics, flags, curves and step counts of the uninterrupted run to the last bit (the runs
// are deterministic for a thread count, and the checkpoint holds the whole state the steps
// carry: the world, the output so far and what the test's phases measured), for every lab test
// that offers stages; a stage the test never reaches, or a damaged record, is refused naming
// `checkpoint`.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "core/common/error.hpp"
#include "core/lab/lab_run.hpp"
#include "lab_test_util.hpp"

namespace demcal::lab {
namespace {

/// Runs the test once from the start, keeping every checkpoint it offers. The clock of each
/// (its world's simulated time and steps) is past the first step and within the run's whole.
LabOutput run_keeping_checkpoints(const std::string& test, const MaterialModel& material,
                                  const Settings& settings, std::vector<Checkpoint>& kept) {
  RunOptions options;
  options.seed = 3;
  std::vector<std::pair<std::string, CheckpointClock>> clocks;
  options.checkpoint = [&kept, &clocks](const std::string& stage, const CheckpointClock& clock,
                                        const std::function<std::string()>& record) {
    clocks.emplace_back(stage, clock);
    kept.push_back({stage, record()});
  };
  LabOutput out = run_lab_test(test, material, settings, options);
  for (const auto& [stage, clock] : clocks) {
    EXPECT_GT(clock.steps, 0) << stage;
    EXPECT_GT(clock.simulated_seconds, 0.0) << stage;
    EXPECT_LE(clock.steps, out.cost.steps) << stage;
    EXPECT_LE(clock.simulated_seconds, out.cost.simulated_time * (1.0 + 1e-12)) << stage;
  }
  return out;
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
  for (std::size_t k = 0; k < whole.cost.phases.size(); ++k) {
    EXPECT_EQ(whole.cost.phases[k].name, resumed_run.cost.phases[k].name);
    EXPECT_EQ(whole.cost.phases[k].steps, resumed_run.cost.phases[k].steps)
        << whole.cost.phases[k].name;
  }
  EXPECT_EQ(whole.cost.steps, resumed_run.cost.steps);
  ASSERT_EQ(whole.series.size(), resumed_run.series.size());
  for (const auto& [name, series] : whole.series) {
    EXPECT_EQ(series.columns, resumed_run.series.at(name).columns) << name;
    EXPECT_EQ(series.rows, resumed_run.series.at(name).rows) << name;
  }
}

/// Runs `test` from the start, then from each of its checkpoints whose stage is in `resume_at`
/// (all when empty; of a stage offered again and again inside a phase, the first and the last
/// offer), and expects the same run every time; returns the stages offered, in order, a stage
/// offered several times in a row once.
std::vector<std::string> expect_resumes_to_the_same_bits(const std::string& test,
                                                         const MaterialModel& material,
                                                         const Settings& settings,
                                                         const std::set<std::string>& resume_at) {
  std::vector<Checkpoint> kept;
  const LabOutput whole = run_keeping_checkpoints(test, material, settings, kept);
  EXPECT_TRUE(whole.resumed_from.empty());
  std::vector<std::string> stages;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const Checkpoint& from = kept[k];
    const bool repeated_before = k > 0 && kept[k - 1].stage == from.stage;
    const bool repeated_after = k + 1 < kept.size() && kept[k + 1].stage == from.stage;
    if (!repeated_before) stages.push_back(from.stage);
    if (repeated_before && repeated_after) continue;
    if (!resume_at.empty() && !resume_at.count(from.stage)) continue;
    SCOPED_TRACE(test + " from '" + from.stage + "'");
    const LabOutput again = resumed(test, material, settings, from);
    EXPECT_EQ(again.resumed_from, from.stage);
    EXPECT_TRUE(std::any_of(again.notes.begin(), again.notes.end(), [&](const std::string& n) {
      return n.find("checkpoint '" + from.stage + "'") != std::string::npos;
    })) << "a note names the stage the run went on from";
    expect_same_run(whole, again);
    // The run's wall time covers its phases, those of the earlier attempt included, so that its
    // particle-steps per second are of the steps it counts.
    double phases_wall = 0.0;
    for (const auto& phase : again.cost.phases) phases_wall += phase.wall_seconds;
    EXPECT_GE(again.cost.wall_seconds, phases_wall);
  }
  return stages;
}

TEST(Checkpoint, ACohesiveCompressionGoesOnFromEveryStageToTheSameBits) {
  // Van der Waals cohesion: the bed settles with cohesion in contact only and then gets the full
  // law back, so the resumed world must be the one of the full law.
  const auto material = testing::soft_luding(1e7, 5.0, 0.2, 1e-17);
  const Settings settings{{"particles", 80}, {"cycles", 1}, {"wall_stiffness_factor", 1}};
  const auto stages =
      expect_resumes_to_the_same_bits("confined_compression", material, settings, {});
  // Offered again at each check of the settle, which a cohesive bed takes many of.
  EXPECT_EQ(stages, (std::vector<std::string>{"settling", "piston bed", "load 1", "unload 1",
                                              "load 2", "final unload"}));
}

TEST(Checkpoint, AGrownBedGoesOnFromInsideItsSettleToTheSameBits) {
  // Growth settles by the creep rule in critical times of the grown bed, which the record of a
  // checkpoint inside the settle carries with the settle's checks.
  MaterialModel grown = testing::soft_luding(1e7, 5.0, 0.2, 1e-17);
  grown.preparation.method = PreparationMethod::kGrowth;
  const Settings settings{{"particles", 80}, {"cycles", 1}, {"wall_stiffness_factor", 1}};
  const auto stages = expect_resumes_to_the_same_bits("confined_compression", grown, settings,
                                                      {"settling", "piston bed"});
  ASSERT_GE(stages.size(), 2u);
  EXPECT_EQ(stages[0], "settling");
  EXPECT_EQ(stages[1], "piston bed");
}

TEST(Checkpoint, RodsInTheWallFrictionTestGoOnFromEveryStageToTheSameBits) {
  MaterialModel rods = testing::soft_luding();
  rods.shape = particles::make_shape_spec("rod", {{"aspect_ratio", 1.5}}, "shape");
  const auto stages =
      expect_resumes_to_the_same_bits("wall_friction", rods, {{"particles", 30}}, {});
  ASSERT_GE(stages.size(), 4u);
  EXPECT_EQ(stages[0], "settling");
  EXPECT_EQ(stages[1], "piston bed");
  for (std::size_t k = 2; k < stages.size(); ++k)
    EXPECT_EQ(stages[k].rfind("turn ", 0), 0u) << stages[k];  // one per normal stress
}

TEST(Checkpoint, TheTensileTestGoesOnFromEveryStageToTheSameBits) {
  const auto material = testing::soft_luding(1e7, 5.0, 0.2, 1e-17);
  const Settings settings{{"particles", 60}, {"wall_stiffness_factor", 1}, {"cycles", 1}};
  // The stages of the confined compression that conditions the bed, then the adhesive unload.
  EXPECT_EQ(expect_resumes_to_the_same_bits("tensile", material, settings, {}),
            (std::vector<std::string>{"settling", "piston bed", "load 1", "unload 1", "load 2",
                                      "final unload", "unload"}));
}

TEST(Checkpoint, TheShearCellGoesOnFromEveryStageAndFromInsideItsLongPhasesToTheSameBits) {
  const Settings settings{{"particles", 120},
                          {"pre_shear_travel", 1},
                          {"torque_ramp_time", 0.05},
                          {"consolidation_time", 0.01}};
  const auto stages = expect_resumes_to_the_same_bits(
      "shear_cell", testing::hertz_spheres(0.5), settings,
      {"settling", "cell built", "consolidating", "consolidated", "pre-shearing", "re-consolidated",
       "shearing 1.75 kPa", "shear step 1.5 kPa"});
  // The settle is offered again after each of its checks, the consolidation after each block of
  // consolidation_time, the pre-shear after each third of its travel that does not end them, and
  // each step's shear every 10,000 steps while the head has not yielded.
  EXPECT_EQ(stages,
            (std::vector<std::string>{
                "settling", "cell built", "consolidating", "consolidated", "pre-shearing",
                "re-consolidated", "shearing 2 kPa", "shear step 2 kPa", "shearing 1.75 kPa",
                "shear step 1.75 kPa", "shearing 1.5 kPa", "shear step 1.5 kPa",
                "shearing 1.25 kPa", "shear step 1.25 kPa", "shearing 1 kPa", "shear step 1 kPa"}));
}

TEST(Checkpoint, TheDrumGoesOnFromItsBedTheAngleAndASpeedToTheSameBits) {
  const Settings settings{
      {"diameter", 25}, {"length", 11}, {"angle_time", 0.1}, {"area_time", 0.05}};
  const auto stages = expect_resumes_to_the_same_bits(
      "rotating_drum", testing::hertz_spheres(0.5), settings, {"drum bed", "angle", "area 80 rpm"});
  EXPECT_EQ(stages, (std::vector<std::string>{"drum bed", "angle", "area 4 rpm", "area 40 rpm",
                                              "area 80 rpm", "area 105 rpm", "area 116 rpm"}));
}

TEST(Checkpoint, TheHopperAndTheCompactionGoOnFromTheirStageToTheSameBits) {
  EXPECT_EQ(expect_resumes_to_the_same_bits("hopper", testing::hertz_spheres(0.5),
                                            {{"particles", 150}}, {}),
            (std::vector<std::string>{"hopper bed"}));
  const Settings compaction{{"particles", 40},  {"phi_start", 0.1},    {"phi_max", 0.6},
                            {"points", 2},      {"strain_rate", 1e-4}, {"probe_strain", 0.002},
                            {"yield_probes", 0}};
  EXPECT_EQ(
      expect_resumes_to_the_same_bits("compaction", testing::hertz_spheres(0.0), compaction, {}),
      (std::vector<std::string>{"compacted"}));
}

TEST(Checkpoint, AStageTheTestNeverReachesOrADamagedRecordIsRefused) {
  const auto material = testing::soft_luding();
  const Settings settings{{"particles", 30}};
  std::vector<Checkpoint> kept;
  run_keeping_checkpoints("wall_friction", material, settings, kept);
  const auto first_bed = std::find_if(kept.begin(), kept.end(),
                                      [](const Checkpoint& c) { return c.stage == "piston bed"; });
  ASSERT_NE(first_bed, kept.end());
  const Checkpoint bed = *first_bed;
  auto refusal = [&](const std::string& test, const Checkpoint& from) {
    try {
      resumed(test, material, settings, from);
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "checkpoint");
      return e.message();
    }
    return std::string("accepted");
  };
  // A test with stages refuses another's before it runs; the packing test has none at all.
  EXPECT_NE(refusal("tensile", kept.back()).find("is not one this test goes on from"),
            std::string::npos);
  EXPECT_NE(refusal("packing", bed).find("'piston bed' is not one the packing test"),
            std::string::npos);
  Checkpoint damaged = bed;
  damaged.state.resize(damaged.state.size() - 9);
  EXPECT_NE(refusal("wall_friction", damaged).find("truncated"), std::string::npos);
  // A record from inside the settle ends with the settle's own fields.
  ASSERT_EQ(kept.front().stage, "settling");
  Checkpoint damaged_settle = kept.front();
  damaged_settle.state.resize(damaged_settle.state.size() - 9);
  EXPECT_NE(refusal("wall_friction", damaged_settle).find("truncated"), std::string::npos);
  Checkpoint other_format = bed;
  other_format.state[0] = static_cast<char>(other_format.state[0] + 1);
  EXPECT_NE(refusal("wall_friction", other_format).find("a record of format 3"), std::string::npos);
  // Another material's laws (a Hertz law keeps no reached overlap: another history size).
  try {
    RunOptions options;
    options.resume = bed;
    run_lab_test("wall_friction", testing::hertz_spheres(0.3), settings, options);
    ADD_FAILURE() << "a checkpoint of other laws was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("other contact laws"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace demcal::lab
