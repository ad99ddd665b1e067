#pragma once
// The checkpoint stages of a lab test run (docs/worker.md, "Checkpoints"). A test names its
// stages in the order it reaches them; at each it offers a record of its whole state there: the
// world's state, the output so far and the runner's own fields (what its phases measured, the
// geometry it built). A run resumed from a stage restores them instead of simulating up to it
// and goes on with the stage after, so that its metrics are bitwise those of a run that was
// never interrupted (the steps are deterministic for a thread count). A value the test derives
// from the world once and uses later belongs in the record: the time step adapts as the run
// goes, so a servo's hold time or a frame's steps derived again at a later stage would differ.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/bytes.hpp"
#include "core/lab/lab_run.hpp"
#include "core/sim/world.hpp"

namespace demcal::lab {

/// A series in a record: its columns and rows.
template <class A, RecordOf<Series> S>
void record_fields(A& a, S& series) {
  a.field(series.columns);
  a.field(series.rows);
}

/// What a lab output has so far, in record order. The run's cost is its phases (the rest is
/// filled at the run's end) and `resumed_from` is the resuming run's own.
template <class A, RecordOf<LabOutput> O>
void record_fields(A& a, O& out) {
  a.field(out.metrics);
  a.field(out.series);
  a.field(out.snapshots);
  a.field(out.notes);
  a.field(out.flags);
  a.field(out.cost.phases);
}

/// `Fields` is called with a ByteWriter or a ByteReader and hands the runner's own state to its
/// `field` (e.g. `[&](auto& a) { a.field(bed); a.field(cycles); }`).
template <class Fields>
class Stages {
 public:
  Stages(const RunOptions& options, std::vector<std::string> names, LabOutput& out, Fields fields)
      : options_(options), names_(std::move(names)), out_(out), fields_(std::move(fields)) {}

  const std::string& name(std::size_t k) const { return names_.at(k); }
  /// The run goes on from a checkpoint: resume() then needs the world the test sets up.
  bool resuming() const { return !options_.resume.stage.empty(); }
  std::size_t size() const { return names_.size(); }

  /// The index of the first stage still to reach: 0 for a run from the start. A run resumed
  /// from one of the stages gets its record restored into `world` (made as the test makes it:
  /// its laws, its threads), the output and the fields, and the index after that stage; a
  /// stage that is not one of them is refused naming `checkpoint`.
  /// A run resumed from a checkpoint inside the phases before a stage (add_within) gets the
  /// index of that stage, and the phase's own fields from read_within.
  std::size_t resume(sim::World& world) {
    if (!resuming()) return 0;
    const std::string& stage = options_.resume.stage;
    const auto at = std::find(names_.begin(), names_.end(), stage);
    const auto inside = find_within(stage);
    if (at == names_.end() && inside == within_.end())
      throw InputError("checkpoint", "stage '" + stage + "' is not one this test goes on from");
    ByteReader in(options_.resume.state, "checkpoint");
    if (const auto format = in.get<std::uint32_t>(); format != kFormat)
      throw InputError("checkpoint", "a record of format " + std::to_string(format) +
                                         ", this build reads format " + std::to_string(kFormat));
    std::string state;
    in.get(state);
    world.restore_state(state);
    in.field(out_);
    fields_(in);
    if (inside != within_.end()) in.get(within_record_);
    in.expect_end();
    // The run's wall time counts the phases the earlier attempt ran (run_lab_test adds this
    // attempt's), so that its particle-steps per second stay those of the steps it counts.
    out_.cost.wall_seconds = out_.cost.phases_wall_seconds();
    out_.resumed_from = stage;
    out_.notes.push_back("went on from the checkpoint '" + stage +
                         "': the phases up to it ran in an earlier attempt (their costs are its)");
    if (inside != within_.end()) return inside->second;
    return static_cast<std::size_t>(at - names_.begin()) + 1;
  }

  /// Names a checkpoint inside the phases before stage `k` (e.g. "settling", before "piston
  /// bed"), which a long phase offers with offer_within.
  void add_within(std::string name, std::size_t k) { within_.emplace_back(std::move(name), k); }
  /// The run goes on from a checkpoint inside a phase: read_within has the phase's fields.
  bool resuming_within() const { return find_within(options_.resume.stage) != within_.end(); }
  /// The run goes on from the checkpoint `name` inside a phase (add_within).
  bool resuming_within(const std::string& name) const {
    return options_.resume.stage == name && find_within(name) != within_.end();
  }

  /// Offers the checkpoint `name` (add_within) from inside a phase with `world`: its record is
  /// a stage's with the phase's own fields after the runner's (`phase` is called as `Fields`).
  template <class Phase>
  void offer_within(const std::string& name, const sim::World& world, Phase phase) const {
    if (!options_.checkpoint) return;
    options_.checkpoint(name, clock_of(world), [&] {
      ByteWriter inner;
      phase(inner);
      ByteWriter record = stage_record(world);
      record.put(inner.take());
      return record.take();
    });
  }

  /// Hands the phase's fields of the record the run went on from (resuming_within) to `phase`.
  template <class Phase>
  void read_within(Phase phase) const {
    ByteReader in(within_record_, "checkpoint");
    phase(in);
    in.expect_end();
  }

  /// Stage `k` is reached with `world`: offers its checkpoint (the record is made only when
  /// the receiver keeps it).
  void reached(std::size_t k, const sim::World& world) const {
    if (!options_.checkpoint) return;
    options_.checkpoint(names_.at(k), clock_of(world), [&] { return stage_record(world).take(); });
  }

 private:
  auto find_within(const std::string& name) const {
    return std::find_if(within_.begin(), within_.end(),
                        [&](const auto& w) { return w.first == name; });
  }
  static CheckpointClock clock_of(const sim::World& world) {
    return {world.time, world.step_count};
  }
  /// A stage's record: the format, the world's state, the output, the runner's fields.
  ByteWriter stage_record(const sim::World& world) const {
    ByteWriter record;
    record.put(kFormat);
    record.put(world.save_state());
    record.field(out_);
    fields_(record);
    return record;
  }

  /// The record's layout: the world's state, the output, the runner's fields (1: the bed
  /// alone, without this number).
  static constexpr std::uint32_t kFormat = 2;
  const RunOptions& options_;
  std::vector<std::string> names_;
  LabOutput& out_;
  Fields fields_;
  std::vector<std::pair<std::string, std::size_t>> within_;  ///< in-phase checkpoints, their stage
  std::string within_record_;  ///< the phase's fields of the record the run went on from
};

}  // namespace demcal::lab
